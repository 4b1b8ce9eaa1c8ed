#include "photonsplat/world.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/scene.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/shader_program.h"
#include "photonsplat/validation.h"
#include "nodes/sky_texture.h"

namespace ps {

namespace {
constexpr float kPi = 3.14159265358979323846f;
constexpr int kDefaultMapWidth = 1024;  // Cycles' default Map Resolution
constexpr int kMaxMapWidth = 4096;  // 8 M cells, 128 MB with the CDFs: larger maps are capped
// Cells averaged per axis while baking (for maps up to this many cells; larger ones are fine enough as they are).
constexpr size_t kSupersampledCells = size_t(1024) * 512;
// With portals, the share of the world's photons that start on them (the rest come from the disc and are dropped
// where they would enter through a portal, so that no path is counted twice).
constexpr float kPortalPhotons = 0.9f;
// A focus (what the camera sees) is used when it is this much smaller than the scene: otherwise the scene's disc
// is as good.
constexpr float kFocusBelow = 0.7f;

float lum(const glm::vec3& c) { return environment_luminance(c); }

// The largest Environment Texture image the program reads (its width), 0 without one: Cycles' automatic map
// resolution follows the environment image.
int environment_image_width(const Scene& scene, const ShaderProgram& p) {
    int width = 0;
    for (size_t at = 0; at + 4 <= p.code.size();) {
        const int op = p.code[at], n_params = p.code[at + 1], n_in = p.code[at + 2], n_out = p.code[at + 3];
        if (op == static_cast<int>(ShaderOp::environment_texture) && n_params > 0) {
            const int texture = p.code[at + 4];
            if (texture >= 0 && static_cast<size_t>(texture) < scene.textures().size())
                width = std::max(width, scene.textures()[static_cast<size_t>(texture)].width());
        }
        at += 4 + static_cast<size_t>(n_params + n_in + n_out);
    }
    return width;
}

// The sun disc of the program's first Nishita Sky Texture that draws one: its direction (towards it) and
// angular radius. Cycles ignores a Nishita sky's Vector when its disc is on, so the direction is the node's own.
bool nishita_sun(const ShaderProgram& p, glm::vec3& direction, float& half_angle) {
    for (size_t at = 0; at + 4 <= p.code.size();) {
        const int op = p.code[at], n_params = p.code[at + 1], n_in = p.code[at + 2], n_out = p.code[at + 3];
        if (op == static_cast<int>(ShaderOp::sky_texture) && n_params >= 4 && p.code[at + 4] == kSkyNishita &&
            p.code[at + 5] == 1) {
            const int32_t offset = p.code[at + 7];
            if (offset >= 0 && size_t(offset) + kNishitaHeaderFloats <= p.tables.size()) {
                const float* d = p.tables.data() + offset;
                const float elevation = d[6], rotation = d[7], size = d[8];
                if (size > 0.0f && std::isfinite(elevation) && std::isfinite(rotation) && std::isfinite(size)) {
                    const float azimuth = rotation + 0.5f * kPi;
                    direction = glm::vec3(std::cos(elevation) * std::cos(azimuth),
                                          std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
                    half_angle = 0.5f * size;
                    return true;
                }
            }
        }
        at += 4 + static_cast<size_t>(n_params + n_in + n_out);
    }
    return false;
}

// A direction uniformly inside the cone of half-angle α about `axis`; 1 − cos α as 2 sin²(α/2), exact for the
// sun's quarter of a degree.
glm::vec3 sample_cone(const glm::vec3& axis, double one_minus_cos, float u1, float u2) {
    const double c = 1.0 - double(u1) * one_minus_cos;
    const double s = std::sqrt(std::max(0.0, double(u1) * one_minus_cos * (2.0 - double(u1) * one_minus_cos)));
    glm::vec3 b1, b2;
    orthonormal_basis(axis, b1, b2);
    const double phi = 2.0 * kPi * double(u2);
    return glm::normalize(float(s * std::cos(phi)) * b1 + float(s * std::sin(phi)) * b2 + float(c) * axis);
}

}  // namespace

glm::vec3 world_radiance(const Scene& scene, const glm::vec3& direction, ShaderRay ray) {
    const ShaderProgram* program = scene.world_program();
    if (program == nullptr) return scene.background();
    ShaderGlobals g;
    g.background = true;
    g.P = direction;
    g.N = g.Ng = g.I = -direction;
    g.object_position = direction;
    // Light Path as Cycles sets it when a ray meets the world: the camera's own rays, reflected ones; a light
    // sample's evaluation (ShaderRay::shadow here: next-event estimation and photon emission) sets no flag.
    g.camera_ray = ray == ShaderRay::camera;
    g.singular_ray = ray == ShaderRay::reflected;
    g.diffuse_ray = ray == ShaderRay::photon;
    g.shadow_ray = false;
    g.ray_length = std::numeric_limits<float>::max();
    g.ray_depth = ray == ShaderRay::camera ? 0.0f : 1.0f;
    thread_local std::vector<float> registers;
    registers.assign(program->registers.begin(), program->registers.end());
    run_program(*program, scene, g, registers.data());
    glm::vec3 out(0.0f);
    for (const ProgramOutput& o : program->outputs)
        if (o.target == ProgramTarget::emission)
            out = glm::vec3(registers[size_t(o.register_)], registers[size_t(o.register_) + 1],
                            registers[size_t(o.register_) + 2]);
    // As accepted constants: >= 0 and at most kMaxEmission (validation.h), so that sums over a map stay finite.
    for (int c = 0; c < 3; ++c) out[c] = std::isfinite(out[c]) ? std::clamp(out[c], 0.0f, kMaxEmission) : 0.0f;
    return out;
}

WorldLight::WorldLight(const Scene& scene) : scene_(scene), background_(scene.background()) {
    const ShaderProgram* program = scene.world_program();
    for (const Portal& p : scene.portals()) {
        Rect r;
        r.corner = glm::vec3(p.corner - scene.origin());
        r.edge_u = p.edge_u;
        r.edge_v = p.edge_v;
        const glm::vec3 c = glm::cross(p.edge_u, p.edge_v);
        r.area = glm::length(c);
        if (!(r.area > 0.0f) || !std::isfinite(r.area)) continue;
        r.normal = c / r.area;
        r.flux = glm::vec3(0.0f);
        portals_.push_back(r);
    }
    constant_ = program == nullptr && portals_.empty();
    if (constant_) {
        integral_ = 4.0f * kPi * background_;
        black_ = !(lum(background_) > 0.0f);
        return;
    }

    // The map: the program's (or the constant's) radiance averaged over each cell.
    // Automatic: twice the widest Environment Texture's width. The image is interpolated linearly between
    // texel centres, so a sun texel's light spills half a texel into its neighbours' cells; cells of half a texel
    // follow that ramp (measured under city.exr: a sample's relative variance 0.17 with cells of one texel,
    // 0.065 with half, 0.043 with a quarter; tests/python/test_world.py).
    int width = scene.world_map_resolution();
    if (width <= 0) {
        width = program ? 2 * environment_image_width(scene, *program) : 0;
        if (width <= 0) width = program ? kDefaultMapWidth : 64;
    }
    width = std::clamp(width, 8, kMaxMapWidth);
    const int height = std::max(width / 2, 4);
    const int sub = size_t(width) * size_t(height) <= kSupersampledCells ? 2 : 1;
    std::vector<float> rgb(size_t(width) * size_t(height) * 3);
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y < rows.end(); ++y)
            for (int x = 0; x < width; ++x) {
                glm::vec3 sum(0.0f);
                for (int j = 0; j < sub; ++j)
                    for (int i = 0; i < sub; ++i) {
                        const float u = (float(x) + (float(i) + 0.5f) / float(sub)) / float(width);
                        const float v = (float(y) + (float(j) + 0.5f) / float(sub)) / float(height);
                        // The map's direction is where light comes from; the ray that sees it travels along it.
                        sum += world_radiance(scene, equirectangular_to_direction(u, v), ShaderRay::shadow);
                    }
                const size_t at = 3 * (size_t(y) * size_t(width) + size_t(x));
                const glm::vec3 mean = sum / float(sub * sub);
                rgb[at] = mean.x;
                rgb[at + 1] = mean.y;
                rgb[at + 2] = mean.z;
            }
    });
    // ∫ L dω per channel, over the cells' exact solid angles.
    glm::dvec3 integral(0.0);
    std::vector<glm::dvec3> portal_flux(portals_.size(), glm::dvec3(0.0));
    for (int y = 0; y < height; ++y) {
        const double cos_low = std::cos(kPi * (1.0 - double(y) / height));
        const double cos_high = std::cos(kPi * (1.0 - double(y + 1) / height));
        const double solid_angle = 2.0 * kPi / width * (cos_high - cos_low);
        for (int x = 0; x < width; ++x) {
            const size_t at = 3 * (size_t(y) * size_t(width) + size_t(x));
            const glm::dvec3 L(rgb[at], rgb[at + 1], rgb[at + 2]);
            integral += L * solid_angle;
            if (portals_.empty()) continue;
            const glm::vec3 d = equirectangular_to_direction((float(x) + 0.5f) / float(width),
                                                             (float(y) + 0.5f) / float(height));
            for (size_t k = 0; k < portals_.size(); ++k) {
                // Light from d travels along -d: through the portal when -d follows its normal.
                const double cos_in = -glm::dot(d, portals_[k].normal);
                if (cos_in > 0.0) portal_flux[k] += L * (solid_angle * cos_in * portals_[k].area);
            }
        }
    }
    integral_ = glm::vec3(integral);
    map_ = std::make_unique<EnvironmentDistribution>(width, height, std::move(rgb));
    // A Nishita sun disc gets its own sampling (Cycles' background sun), for light samples and photons.
    if (program && nishita_sun(*program, sun_axis_, sun_half_angle_)) {
        const double s = std::sin(0.5 * double(sun_half_angle_));
        sun_one_minus_cos_ = 2.0 * s * s;
        glm::dvec3 sum(0.0);
        constexpr int n = 16;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                sum += glm::dvec3(world_radiance(
                    scene, sample_cone(sun_axis_, sun_one_minus_cos_, (float(i) + 0.5f) / n, (float(j) + 0.5f) / n),
                    ShaderRay::shadow));
        const glm::vec3 sun_integral = glm::vec3(sum / double(n * n) * (2.0 * kPi * sun_one_minus_cos_));
        has_sun_ = lum(sun_integral) > 0.0f;
        if (has_sun_)
            sun_photon_share_ = std::clamp(lum(sun_integral) / std::max(lum(integral_), 1e-30f), 0.05f, 0.95f);
    }
    double total = 0.0;
    for (size_t k = 0; k < portals_.size(); ++k) {
        portals_[k].flux = glm::vec3(portal_flux[k]);
        portal_flux_ += portals_[k].flux;
        total += std::max(0.0, double(lum(portals_[k].flux)));
        portal_cdf_.push_back(float(total));
    }
    if (total > 0.0) {
        for (float& c : portal_cdf_) c = float(c / total);
        portal_cdf_.back() = 1.0f;
    } else {
        portal_cdf_.clear();
    }
    black_ = map_->is_zero();
}

glm::vec3 WorldLight::flux(float scene_radius) const {
    // With portals, what they let in: the light an interior is lit by (photons choose sources by it).
    if (!portal_cdf_.empty()) return portal_flux_;
    return kPi * scene_radius * scene_radius * integral_;
}

float WorldLight::map_pdf(const glm::vec3& wi) const { return map_ ? map_->pdf(wi) : 0.0f; }

namespace {
// Where the ray x + t·wi (t > 0) crosses the rectangle, if it does (the parameters s, t of the crossing).
bool through_rect(const glm::vec3& corner, const glm::vec3& eu, const glm::vec3& ev, const glm::vec3& normal,
                  const glm::vec3& x, const glm::vec3& wi, float& distance) {
    const float denom = glm::dot(wi, normal);
    if (denom == 0.0f) return false;
    const float t = glm::dot(corner - x, normal) / denom;
    if (!(t > 0.0f)) return false;
    const glm::vec3 q = x + t * wi - corner;
    const float s = glm::dot(q, eu) / glm::dot(eu, eu), r = glm::dot(q, ev) / glm::dot(ev, ev);
    if (!(s >= 0.0f && s <= 1.0f && r >= 0.0f && r <= 1.0f)) return false;
    distance = t;
    return true;
}
}  // namespace

int WorldLight::possible_portals(const glm::vec3& x) const {
    // A portal lights x when x lies on the side its light goes to (Cycles' side check).
    int n = 0;
    for (const Rect& r : portals_)
        if (glm::dot(x - r.corner, r.normal) > 0.0f) ++n;
    return n;
}

float WorldLight::portal_pdf(const glm::vec3& x, const glm::vec3& wi, int& possible) const {
    possible = 0;
    float sum = 0.0f;
    for (const Rect& r : portals_) {
        if (!(glm::dot(x - r.corner, r.normal) > 0.0f)) continue;
        ++possible;
        float d = 0.0f;
        // From x the world lies back through the portal: along wi, against the portal's normal.
        if (!(glm::dot(wi, r.normal) < 0.0f) || !through_rect(r.corner, r.edge_u, r.edge_v, r.normal, x, wi, d))
            continue;
        const float cos_portal = -glm::dot(wi, r.normal);
        sum += d * d / (r.area * cos_portal);  // a uniform point on the rectangle, per unit solid angle
    }
    return possible > 0 ? sum / float(possible) : 0.0f;
}

LightIncidence WorldLight::sample_incidence(const glm::vec3& x, const glm::vec3& n, float u1, float u2,
                                            float u3) const {
    LightIncidence out;
    out.distance = std::numeric_limits<float>::infinity();
    out.value = glm::vec3(0.0f);
    if (constant_) {
        // Cosine-weighted about the surface: f·L·cos/pdf = f·L·π, written as value·cos for the caller.
        out.wi = sample_cosine_hemisphere(n, u1, u2);
        const float cos_n = glm::dot(out.wi, n);
        out.value = cos_n > 1e-6f ? background_ * (kPi / cos_n) : glm::vec3(0.0f);
        out.pdf = cos_n > 1e-6f ? cos_n / kPi : 0.0f;
        return out;
    }
    // Portals, the sun and the map, weighted 1 : 4 : 1 where each can light x (Cycles 3.4's method weights).
    const int possible = portals_.empty() ? 0 : possible_portals(x);
    const Methods m = methods(possible);
    if (m.portal > 0.0f && u3 < m.portal) {
        // One of the possible portals, uniformly, then a uniform point on it.
        int pick = std::min(int(u3 / m.portal * float(possible)), possible - 1);
        const Rect* chosen = nullptr;
        for (const Rect& r : portals_)
            if (glm::dot(x - r.corner, r.normal) > 0.0f && pick-- == 0) {
                chosen = &r;
                break;
            }
        if (chosen == nullptr) return out;
        const glm::vec3 y = chosen->corner + u1 * chosen->edge_u + u2 * chosen->edge_v;
        const glm::vec3 to = y - x;
        const float len = glm::length(to);
        if (!(len > 0.0f)) return out;
        out.wi = to / len;
    } else if (m.sun > 0.0f && u3 < m.portal + m.sun) {
        out.wi = sample_cone(sun_axis_, sun_one_minus_cos_, u1, u2);
    } else if (m.map > 0.0f) {
        const EnvironmentSample s = map_->sample_direction(u1, u2);
        if (!(s.pdf > 0.0f)) return out;
        out.wi = s.direction;
    } else {
        return out;
    }
    out.pdf = pdf(x, n, out.wi);
    if (!(out.pdf > 0.0f) || !std::isfinite(out.pdf)) {
        out.pdf = 0.0f;
        return out;
    }
    out.value = world_radiance(scene_, out.wi, ShaderRay::shadow) / out.pdf;
    return out;
}

WorldLight::Methods WorldLight::methods(int possible_portals) const {
    Methods m;
    m.portal = possible_portals > 0 ? 1.0f : 0.0f;
    m.sun = has_sun_ ? 4.0f : 0.0f;
    m.map = map_ != nullptr && !map_->is_zero() ? 1.0f : 0.0f;
    const float total = m.portal + m.sun + m.map;
    if (total > 0.0f) {
        m.portal /= total;
        m.sun /= total;
        m.map /= total;
    }
    return m;
}

float WorldLight::sun_pdf(const glm::vec3& wi) const {
    if (!has_sun_) return 0.0f;
    // 1 − cos θ = |wi − axis|² / 2 for unit vectors: exact where 1 − dot would lose the quarter-degree cone to
    // float rounding (a cone sample then weighed as the map's alone is a firefly). A sliver of tolerance keeps
    // the cone's own samples at its edge inside it.
    const glm::vec3 chord = wi - sun_axis_;
    const double one_minus_cos = 0.5 * double(glm::dot(chord, chord));
    return one_minus_cos <= sun_one_minus_cos_ * (1.0 + 1e-4) ? float(1.0 / (2.0 * kPi * sun_one_minus_cos_)) : 0.0f;
}

float WorldLight::pdf(const glm::vec3& x, const glm::vec3& n, const glm::vec3& wi) const {
    if (constant_) {
        const float cos_n = glm::dot(wi, n);
        return cos_n > 1e-6f ? cos_n / kPi : 0.0f;
    }
    int possible = 0;
    const float portal = portals_.empty() ? 0.0f : portal_pdf(x, wi, possible);
    const Methods m = methods(possible);
    return m.portal * portal + m.sun * sun_pdf(wi) + m.map * map_pdf(wi);
}

EmissionSample WorldLight::sample_emission(const glm::vec3& center, float radius, const glm::vec3& focus_center,
                                           float focus_radius, float u1, float u2, float u3, float u4,
                                           float u5) const {
    EmissionSample out;
    out.power = glm::vec3(0.0f);
    out.origin = center;
    out.direction = glm::vec3(0.0f, 0.0f, -1.0f);
    if (constant_) {
        // Parallel rays from a disc covering the bounding sphere, placed outside it, in a uniform direction.
        out.direction = sample_uniform_sphere(u1, u2);
        glm::vec3 b1, b2;
        orthonormal_basis(out.direction, b1, b2);
        const float r = radius * std::sqrt(u3), phi = 2.0f * kPi * u4;
        out.origin = center - 2.0f * radius * out.direction + r * (std::cos(phi) * b1 + std::sin(phi) * b2);
        out.power = 4.0f * kPi * kPi * radius * radius * background_;
        return out;
    }
    if (map_ == nullptr || map_->is_zero()) return out;
    // The direction: from the sun's cone with its share of the world's light, else from the map.
    EnvironmentSample s;
    if (has_sun_ && u3 < sun_photon_share_) {
        s.direction = sample_cone(sun_axis_, sun_one_minus_cos_, u3 / sun_photon_share_, u4);
    } else {
        const float u = has_sun_ ? (u3 - sun_photon_share_) / (1.0f - sun_photon_share_) : u3;
        s = map_->sample_direction(std::min(u, std::nextafter(1.0f, 0.0f)), u4);
        if (!(s.pdf > 0.0f)) return out;
    }
    s.pdf = has_sun_ ? sun_photon_share_ * sun_pdf(s.direction) + (1.0f - sun_photon_share_) * map_pdf(s.direction)
                     : s.pdf;
    if (!(s.pdf > 0.0f) || !std::isfinite(s.pdf)) return out;
    out.direction = -s.direction;  // the photon travels away from where its light comes from
    const glm::vec3 L = world_radiance(scene_, s.direction, ShaderRay::shadow);
    const RayTracer* tracer = portal_cdf_.empty() ? nullptr : &scene_.ray_tracer();
    if (!portal_cdf_.empty() && u5 < kPortalPhotons) {
        // Through a portal: a point on it and the map's direction, if nothing outside blocks the way to the sky.
        const float u = u5 / kPortalPhotons;
        const size_t k = std::min(size_t(std::upper_bound(portal_cdf_.begin(), portal_cdf_.end(), u) -
                                         portal_cdf_.begin()),
                                  portals_.size() - 1);
        const Rect& r = portals_[k];
        const float p_k = portal_cdf_[k] - (k ? portal_cdf_[k - 1] : 0.0f);
        const float cos_in = glm::dot(out.direction, r.normal);
        if (!(cos_in > 0.0f) || !(p_k > 0.0f)) return out;  // would leave the room: no light this way
        out.origin = r.corner + u1 * r.edge_u + u2 * r.edge_v;
        Hit hit;
        if (tracer->intersect(Ray{out.origin, s.direction}, 0.0f, std::numeric_limits<float>::infinity(), hit,
                              kIndirectRays))
            return out;
        // L · A · cos / (pdf(ω) · P(portal)): a point uniform on the portal, a direction from the map.
        out.power = L * (r.area * cos_in / (s.pdf * p_k * kPortalPhotons));
        return out;
    }
    const float share = portal_cdf_.empty() ? 1.0f : 1.0f - kPortalPhotons;
    float pick = portal_cdf_.empty() ? u5 : (u5 - kPortalPhotons) / (1.0f - kPortalPhotons);
    // From the disc covering the scene, or (half of them) from the one covering what the camera sees, both
    // perpendicular to the direction and 2R before the scene's centre; the power divides by the mixture's
    // density at the photon's line (one-sample MIS, balance heuristic), so each disc's photons count once.
    const bool focused = focus_radius > 0.0f && focus_radius < kFocusBelow * radius &&
                         glm::length(focus_center - center) + focus_radius <= 2.0f * radius;
    const bool on_focus = focused && pick < 0.5f;
    const glm::vec3 disc_center = on_focus ? focus_center : center;
    const float disc_radius = on_focus ? focus_radius : radius;
    glm::vec3 b1, b2;
    orthonormal_basis(out.direction, b1, b2);
    const float r = disc_radius * std::sqrt(u1), phi = 2.0f * kPi * u2;
    const glm::vec3 on_line = disc_center + r * (std::cos(phi) * b1 + std::sin(phi) * b2);
    out.origin = on_line - (glm::dot(on_line - center, out.direction) + 2.0f * radius) * out.direction;
    // Area density of the line on a plane perpendicular to it.
    const auto inside = [&](const glm::vec3& c, float rad) {
        const glm::vec3 v = out.origin - c;
        const glm::vec3 across = v - glm::dot(v, out.direction) * out.direction;
        return glm::dot(across, across) <= rad * rad * (1.0f + 1e-5f);
    };
    float density = 1.0f / (kPi * radius * radius);
    if (focused)
        density = 0.5f * ((inside(center, radius) ? 1.0f / (kPi * radius * radius) : 0.0f) +
                          (inside(focus_center, focus_radius) ? 1.0f / (kPi * focus_radius * focus_radius) : 0.0f));
    if (!(density > 0.0f)) return out;
    if (tracer != nullptr) {
        // What enters through a portal is the portal photons' (above): a disc photon that would is dropped.
        Hit hit;
        const float far = tracer->intersect(Ray{out.origin, out.direction}, 0.0f,
                                            std::numeric_limits<float>::infinity(), hit, kIndirectRays)
                              ? hit.t
                              : std::numeric_limits<float>::infinity();
        for (const Rect& p : portals_) {
            float d = 0.0f;
            if (glm::dot(out.direction, p.normal) > 0.0f &&
                through_rect(p.corner, p.edge_u, p.edge_v, p.normal, out.origin, out.direction, d) && d < far)
                return out;
        }
    }
    out.power = L / (s.pdf * density * share);
    return out;
}

}  // namespace ps
