#include "photonsplat/light_sources.h"
#include "photonsplat/direct_light.h"
#include "photonsplat/ray_tracer.h"

#include "photonsplat/material_program.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"

namespace ps {

namespace {
constexpr float kPi = 3.14159265358979323846f;

glm::vec3 point_on_triangle(const WorldTriangle& t, float u1, float u2) {
    const float s = std::sqrt(u1);
    return (1.0f - s) * t.v0 + s * (1.0f - u2) * t.v1 + s * u2 * t.v2;
}
float triangle_area(const WorldTriangle& t) { return 0.5f * glm::length(glm::cross(t.v1 - t.v0, t.v2 - t.v0)); }

// The solid angle of the triangle whose corners lie at a, b, c from the viewer (Van Oosterom and Strackee).
double solid_angle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
    const double numerator = std::fabs(glm::dot(a, glm::cross(b, c)));
    const double denominator = la * lb * lc + glm::dot(a, b) * lc + glm::dot(a, c) * lb + glm::dot(b, c) * la;
    return 2.0 * std::atan2(numerator, denominator);  // numerator >= 0: in [0, 2π]
}
}  // namespace

LightSources::LightSources(const Scene& scene) : scene_(scene), world_(scene.world_light()) {
    center_ = 0.5f * (scene.bounds_min() + scene.bounds_max());
    radius_ = std::max(0.5f * glm::length(scene.bounds_max() - scene.bounds_min()), 1e-6f);
    for (const Light& light : scene.lights())
        sources_.push_back({Kind::light, light.name, light_flux(light, radius_), &light});

    // Emission from both faces, like Cycles: flux of a triangle = 2 · π · area · radiance.
    double total = 0.0;
    glm::dvec3 flux(0.0);
    for (uint32_t i = 0; i < scene.instances().size(); ++i) {
        const MeshData& mesh = scene.meshes()[scene.instances()[i].mesh];
        for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
            const Material& material = scene.materials()[mesh.materials[t]];
            // A program's emission is sampled as constant per triangle, its value at the centroid (what
            // the camera and BSDF-sampled rays see is the program's at each point).
            const glm::vec3 e = material.program_emission
                                    ? emission_at(scene, surface_on_triangle(scene, i, t, 1.0f / 3.0f, 1.0f / 3.0f),
                                                  glm::vec3(0.0f, 0.0f, 1.0f))
                                    : material.emission;
            if (!(luminance(e) > 0.0f)) continue;
            const float area = triangle_area(scene.world_triangle(i, t));
            const double w = area * luminance(e);
            if (!(w > 0.0) || !std::isfinite(w)) continue;  // also a flattened instance
            emitters_.push_back({i, t});
            emissive_area_ += area;
            emitter_emission_.push_back(e);
            total += w;
            emitter_cdf_.push_back(static_cast<float>(total));
            flux += 2.0 * kPi * area * glm::dvec3(e);
        }
    }
    if (!emitters_.empty()) {
        for (size_t k = 0; k < emitters_.size(); ++k) {
            const double previous = k ? emitter_cdf_[k - 1] : 0.0;
            emitter_probability_.push_back(static_cast<float>((emitter_cdf_[k] - previous) / total));
        }
        for (float& c : emitter_cdf_) c = static_cast<float>(c / total);
        emitter_cdf_.back() = 1.0f;
        sources_.push_back({Kind::emissive_surfaces, "emissive surfaces", glm::vec3(flux)});
    }
    // A uniform environment of radiance L sends 4π · πR² · L through the scene's bounding sphere; any world
    // πR² ∫ L dω, or what its portals let in.
    if (!world_->black() && scene.triangle_count() > 0) {
        const glm::vec3 flux = world_->constant() ? 4.0f * kPi * kPi * radius_ * radius_ * scene.background()
                                                  : world_->flux(radius_);
        if (luminance(flux) > 0.0f && std::isfinite(luminance(flux))) sources_.push_back({Kind::world, "world", flux});
    }
    // Cycles' light distribution (cycles_pick_probability): its lamps, and a world only where it varies (Cycles
    // turns a constant background's light sampling off).
    size_t lamps = 0;
    for (const Source& source : sources_)
        if (source.kind == Kind::light || (source.kind == Kind::world && !world_->constant())) ++lamps;
    const bool triangles = !emitters_.empty();
    if (lamps > 0) lamp_pick_ = (triangles ? 0.5f : 1.0f) / static_cast<float>(lamps);
    emissive_pick_ = lamps > 0 ? 0.5f : 1.0f;
}

bool LightSources::is_delta(size_t i) const {
    return sources_[i].kind == Kind::light && light_is_delta(*sources_[i].light);
}

glm::vec3 LightSources::emission_of(size_t emitter) const { return emitter_emission_[emitter]; }

size_t LightSources::pick_emitter(float u) const {
    const size_t k = static_cast<size_t>(std::upper_bound(emitter_cdf_.begin(), emitter_cdf_.end(), u) - emitter_cdf_.begin());
    return std::min(k, emitters_.size() - 1);
}

LightIncidence LightSources::sample_incidence(size_t i, const glm::vec3& x, const glm::vec3& n, float u1, float u2,
                                              float u3) const {
    const Source& source = sources_[i];
    switch (source.kind) {
        case Kind::light: return sample_light_incidence(*source.light, x, u1, u2);
        case Kind::emissive_surfaces: {
            const size_t k = pick_emitter(u1);
            const WorldTriangle t = scene_.world_triangle(emitters_[k].instance, emitters_[k].triangle);
            const glm::vec3 y = point_on_triangle(t, u2, u3);
            const glm::vec3 to_light = y - x;
            LightIncidence out;
            const float d2 = glm::dot(to_light, to_light);
            out.distance = std::sqrt(d2);
            out.wi = to_light / out.distance;
            const glm::vec3 ng = glm::normalize(glm::cross(t.v1 - t.v0, t.v2 - t.v0));
            const float cos_light = std::fabs(glm::dot(ng, out.wi));
            const float pdf_area = emitter_probability_[k] / triangle_area(t);
            out.value = (d2 > 0.0f && pdf_area > 0.0f)
                            ? emission_of(k) * (cos_light / (d2 * pdf_area))
                            : glm::vec3(0.0f);
            out.pdf = cos_light > 0.0f ? d2 * pdf_area / cos_light : 0.0f;
            return out;
        }
        case Kind::world: return world_->sample_incidence(x, n, u1, u2, u3);
    }
    return {};
}

float LightSources::cycles_lamp_pdf(size_t i, const glm::vec3& x, const glm::vec3& wi) const {
    const Light* light = sources_[i].light;
    if (light == nullptr) return 0.0f;
    const LightHit h = intersect_light(*light, x, wi);
    if (!h.hit) return 0.0f;
    if (light->kind == LightKind::area && !light->ellipse) {
        const glm::dvec3 c = glm::dvec3(light->position) - glm::dvec3(x);
        const glm::dvec3 u = 0.5 * glm::dvec3(light->axis_u), v = 0.5 * glm::dvec3(light->axis_v);
        const double omega = solid_angle(c - u - v, c + u - v, c + u + v) + solid_angle(c - u - v, c + u + v, c - u + v);
        return omega > 0.0 ? static_cast<float>(lamp_pick_ / omega) : 0.0f;
    }
    return h.pdf * lamp_pick_;
}

float LightSources::cycles_emissive_pdf(uint32_t instance, uint32_t triangle, const glm::vec3& x,
                                        const glm::vec3& y) const {
    if (!(emissive_area_ > 0.0) || !(emissive_pdf(instance, triangle, x, y) > 0.0f)) return 0.0f;  // not an emitter
    const WorldTriangle t = scene_.world_triangle(instance, triangle);
    const glm::dvec3 v0(t.v0), v1(t.v1), v2(t.v2), px(x);
    const glm::dvec3 e0 = v1 - v0, e1 = v2 - v0, e2 = v2 - v1;
    const glm::dvec3 n = glm::cross(e0, e1);
    const double area = 0.5 * glm::length(n);
    const double picked = emissive_pick_ * area / emissive_area_;  // this triangle's share of the picks
    const double longest2 = std::max({glm::dot(e0, e0), glm::dot(e1, e1), glm::dot(e2, e2)});
    const double plane_distance = std::fabs(glm::dot(n, v0 - px)) / glm::length(n);
    if (longest2 > plane_distance * plane_distance) {
        const double omega = solid_angle(v0 - px, v1 - px, v2 - px);
        return omega > 0.0 ? static_cast<float>(picked / omega) : 0.0f;
    }
    const glm::dvec3 to_light = glm::dvec3(y) - px;
    const double d2 = glm::dot(to_light, to_light);
    const double cos_light = std::fabs(glm::dot(n, to_light)) / (glm::length(n) * std::sqrt(d2));
    return cos_light > 0.0 ? static_cast<float>(picked / area * d2 / cos_light) : 0.0f;
}

float LightSources::mirror_weight(size_t i, const glm::vec3& x, const glm::vec3& origin, const glm::vec3& n,
                                  const glm::vec3& wi, float mirror_pdf) const {
    if (!found_by_bsdf_rays(i)) return 0.0f;  // no BSDF ray meets it: the light-sample side keeps it all
    if (!(mirror_pdf > 0.0f)) return 1.0f;
    if (is_delta(i)) return 0.0f;
    switch (sources_[i].kind) {
        case Kind::light: {
            const float p = cycles_lamp_pdf(i, x, wi);
            return p > 0.0f ? mirror_emitter_weight(mirror_pdf, p) : 1.0f;
        }
        case Kind::emissive_surfaces: {
            // The emitter the photon left: the first surface along wi.
            Hit hit;
            const Ray ray{origin, wi};
            if (!scene_.ray_tracer().intersect(ray, 0.0f, std::numeric_limits<float>::infinity(), hit, kShadowRays))
                return 1.0f;
            return mirror_emitter_weight(mirror_pdf,
                                         cycles_emissive_pdf(hit.instance, hit.triangle, x, ray.origin + hit.t * wi));
        }
        case Kind::world:
            if (world_->constant() || world_->black()) return 1.0f;  // Cycles samples a constant world by BSDF only
            return mirror_emitter_weight(mirror_pdf, world_->pdf(x, n, wi) * lamp_pick_);
    }
    return 1.0f;
}

float LightSources::emissive_pdf(uint32_t instance, uint32_t triangle, const glm::vec3& x,
                                 const glm::vec3& y) const {
    // Emitters are listed by instance, then triangle: ascending in that pair.
    const auto before = [](const Emitter& e, const Emitter& key) {
        return e.instance < key.instance || (e.instance == key.instance && e.triangle < key.triangle);
    };
    const Emitter key{instance, triangle};
    const auto found = std::lower_bound(emitters_.begin(), emitters_.end(), key, before);
    if (found == emitters_.end() || found->instance != instance || found->triangle != triangle) return 0.0f;
    const WorldTriangle t = scene_.world_triangle(instance, triangle);
    const glm::vec3 to_light = y - x;
    const float d2 = glm::dot(to_light, to_light);
    if (!(d2 > 0.0f)) return 0.0f;
    const glm::vec3 ng = glm::normalize(glm::cross(t.v1 - t.v0, t.v2 - t.v0));
    const float cos_light = std::fabs(glm::dot(ng, to_light)) / std::sqrt(d2);
    const float pdf_area = emitter_probability_[static_cast<size_t>(found - emitters_.begin())] / triangle_area(t);
    return cos_light > 0.0f ? d2 * pdf_area / cos_light : 0.0f;
}

EmissionSample LightSources::sample_emission(size_t i, float u1, float u2, float u3, float u4, float u5) const {
    const Source& source = sources_[i];
    switch (source.kind) {
        case Kind::light: return sample_light_emission(*source.light, center_, radius_, u1, u2, u3, u4);
        case Kind::emissive_surfaces: {
            const size_t k = pick_emitter(u1);
            const WorldTriangle t = scene_.world_triangle(emitters_[k].instance, emitters_[k].triangle);
            glm::vec3 ng = glm::normalize(glm::cross(t.v1 - t.v0, t.v2 - t.v0));
            if (u5 < 0.5f) ng = -ng;  // both faces emit
            EmissionSample out;
            out.origin = offset_ray_origin(point_on_triangle(t, u2, u3), ng,
                                           scene_.ray_tracer().rounding_scale(emitters_[k].instance));
            out.direction = sample_cosine_hemisphere(ng, u4, std::fmod(2.0f * u5, 1.0f));
            // Φ_k / p_k, with Φ_k = 2π·A_k·L_k: the triangle's colour rides on the photon's power.
            out.power = 2.0f * kPi * triangle_area(t) * emission_of(k) / emitter_probability_[k];
            return out;
        }
        case Kind::world:
            return world_->sample_emission(center_, radius_, focus_center_, focus_radius_, u1, u2, u3, u4, u5);
    }
    return {};
}

}  // namespace ps
