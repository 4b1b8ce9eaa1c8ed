#include "caustic_photons.h"

#include "photonsplat/shading.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "photonsplat/light_sources.h"
#include "photonsplat/lights.h"
#include "photonsplat/materials.h"
#include "photonsplat/photon_shading_normals.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/render_control.h"
#include "photonsplat/rng.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/stats.h"

namespace ps {

namespace {
constexpr uint64_t kChunk = 4096;           // photons per task; chunks are concatenated in order
constexpr int64_t kMaxCellsPerAxis = (int64_t(1) << 21) - 1;
constexpr int kMaxPassedSurfaces = 64;  // surfaces no bounce sees that one photon passes through
constexpr float kCosNormalTolerance = 0.5f;  // τ = 60°, render()'s default
}  // namespace

bool caustics_by_photons(const LightSources& sources, size_t i) {
    const Light* light = sources.light(i);
    // A light with Multiple Importance off has no L S+ D paths at all: Cycles' BSDF rays never meet it.
    return light && light->multiple_importance &&
           (light->kind == LightKind::point || light->kind == LightKind::spot || light->kind == LightKind::sun);
}

std::vector<Photon> trace_caustic_photons(const Scene& scene, const LightSources& sources, uint64_t count,
                                          int max_specular_bounces, uint64_t seed, uint64_t pass,
                                          const RenderControl& control, Stats& stats) {
    std::vector<Photon> out;
    // Sources by luminance of their flux, among those whose caustics are photon-mapped.
    std::vector<size_t> which;
    std::vector<double> cdf;
    double total = 0.0;
    for (size_t i = 0; i < sources.size(); ++i) {
        const double w = caustics_by_photons(sources, i) ? std::max(0.0f, luminance(sources.flux(i))) : 0.0;
        if (!(w > 0.0)) continue;
        which.push_back(i);
        cdf.push_back(total += w);
    }
    // Caustic paths go on through delta parts, which a surface may hold beside lobes (Principled glass with a
    // clearcoat, a mirror mixed with diffuse): any of them calls for photons. (Only purely specular surfaces counted
    // here once, and the path tracer still left these lights' caustics to photons: differential seed 138, a spot
    // behind clearcoated glass, lost its caustic and 45 % of the image.)
    bool any_delta = false;
    for (const Material& m : scene.materials()) any_delta = any_delta || m.has_delta;
    if (which.empty() || !any_delta || count == 0 || scene.triangle_count() == 0) return out;
    stats.counters["caustic_photons_emitted"] += static_cast<double>(count);

    const RayTracer& tracer = scene.ray_tracer();
    const uint64_t chunks = (count + kChunk - 1) / kChunk;
    std::vector<std::vector<Photon>> per_chunk(chunks);
    tbb::parallel_for(uint64_t{0}, chunks, [&](uint64_t chunk) {
        if (control.cancel_requested()) return;
        const uint64_t end = std::min(count, (chunk + 1) * kChunk);
        for (uint64_t index = chunk * kChunk; index < end; ++index) {
            Rng rng(seed, RngDomain::reference_photon, pass * count + index);
            const double u = rng.uniform() * total;
            const size_t k = std::min<size_t>(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin(), which.size() - 1);
            const double probability = (cdf[k] - (k ? cdf[k - 1] : 0.0)) / total;
            const float u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform(), u4 = rng.uniform(),
                        u5 = rng.uniform();
            const EmissionSample emitted = sources.sample_emission(which[k], u1, u2, u3, u4, u5);
            glm::vec3 power = emitted.power / static_cast<float>(probability);
            Ray ray{emitted.origin, emitted.direction};
            bool direct = true;
            int crossings = 0;  // surfaces no bounce sees, passed through
            for (int bounce = 0; bounce <= max_specular_bounces; ++bounce) {
                Hit hit;
                if (!tracer.intersect(ray, 0.0f, std::numeric_limits<float>::infinity(), hit, kPhotonReceivers))
                    break;
                const SurfacePoint s = surface_at(scene, ray, hit, ShaderRay::photon);
                // A surface no bounce sees (Ray Visibility): as Photon Splat's photons do (photons.cpp), stored
                // where the camera sees it, then passed through; straight from the light, a shadow stops it.
                const uint32_t visible_to = scene.instances()[hit.instance].visibility;
                if (!(visible_to & kIndirectRays)) {
                    if (direct && (visible_to & kShadowRays)) break;
                    if (!direct && (visible_to & kCameraRays) &&
                        bsdf_has(shade(scene, s, -ray.direction), LobeSet::all))
                        per_chunk[chunk].push_back(Photon{
                            s.position, -ray.direction, s.geometric_normal, power,
                            kCaustic | (inside_transmitter(s) ? kInsidePhoton : 0u), {}});
                    if (++crossings > kMaxPassedSurfaces) break;
                    const glm::vec3 beyond = -s.geometric_normal;  // geometric_normal faces the ray
                    ray.origin = offset_ray_origin(s.position, beyond, s.rounding_scale);
                    --bounce;  // not a bounce
                    continue;
                }
                if (bounce == 0) power *= first_hit_falloff(emitted, s.position, s.geometric_normal);  // a soft light's disc (lights.h)
                const Bsdf b = shade(scene, s, -ray.direction);
                // L D: direct light, the path tracer's. L S+ D: a caustic photon, ours, stored where the surface
                // has parts other than deltas (a path's vertex on either side gathers it: trace_reference_path);
                // it goes on only through delta parts (lobes are the path tracer's).
                if (!direct && bsdf_has(b, LobeSet::all))
                    per_chunk[chunk].push_back(Photon{
                        s.position, -ray.direction, s.geometric_normal, power,
                        kCaustic | (inside_transmitter(s) ? kInsidePhoton : 0u), {}});
                if (bounce == max_specular_bounces) break;
                const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
                const BsdfSample step = bsdf_sample(b, u0, u1, u2);
                if (step.kind == ScatterKind::none || step.kind == ScatterKind::lobes) break;
                // A mirror Cycles 3.x samples as Multiscatter GGX keeps what Cycles' MIS gives the light it
                // reflects (LightSources::mirror_weight).
                glm::vec3 step_weight = step.weight;
                if (direct && step.kind == ScatterKind::mirror && b.mirror_reported_alpha > 0.0f)
                    step_weight *= sources.mirror_weight(
                        which[k], s.position, offset_ray_origin(s.position, s.geometric_normal, s.rounding_scale),
                        s.geometric_normal, -ray.direction, mirror_reported_pdf(b));
                if (step.kind != ScatterKind::transparent) direct = false;  // L T D is the path tracer's (shadows)
                const float keep = std::min(1.0f, std::max({step_weight.x, step_weight.y, step_weight.z}));
                if (!(keep > 0.0f) || rng.uniform() >= keep) break;
                power *= step_weight * (photon_units_across(b, step) / keep);  // Cycles' units beyond glass
                if (step.kind != ScatterKind::transparent)
                    power *= shading_normal_ratios(s, -ray.direction, step.direction);
                const glm::vec3 side = step.transmitted ? -s.geometric_normal : s.geometric_normal;
                ray = Ray{offset_ray_origin(s.position, side, s.rounding_scale), step.direction};
            }
        }
    });
    control.check();
    for (auto& c : per_chunk) out.insert(out.end(), c.begin(), c.end());
    stats.counters["caustic_photons_stored"] += static_cast<double>(out.size());
    return out;
}

CausticPhotonMap::CausticPhotonMap(std::vector<Photon> photons, uint64_t emitted, float radius,
                                   const glm::vec3& origin)
    : origin_(origin) {
    params_.radius = radius;
    params_.cos_normal_tolerance = kCosNormalTolerance;
    params_.emitted = std::max<uint64_t>(emitted, 1);
    params_.kernel = Kernel::uniform;
    // Photons whose relative position is not finite can pass no test: left out.
    std::vector<Photon> kept;
    kept.reserve(photons.size());
    glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
    for (Photon& p : photons) {
        p.position -= origin;
        if (!(std::isfinite(p.position.x) && std::isfinite(p.position.y) && std::isfinite(p.position.z))) continue;
        lo = glm::min(lo, p.position);
        hi = glm::max(hi, p.position);
        kept.push_back(p);
    }
    if (kept.empty()) return;
    lo_ = lo;
    // Cell = radius, raised where an axis would need more cells than a key holds (only costs speed).
    cell_ = radius;
    for (int a = 0; a < 3; ++a) cell_ = std::max(cell_, (hi[a] - lo[a]) / static_cast<float>(kMaxCellsPerAxis - 1));
    for (int a = 0; a < 3; ++a) extent_[a] = cell_of(hi[a], a) + 1;
    std::vector<std::pair<uint64_t, uint32_t>> order(kept.size());
    for (uint32_t i = 0; i < kept.size(); ++i) {
        const glm::vec3& p = kept[i].position;
        order[i] = {key(cell_of(p.x, 0), cell_of(p.y, 1), cell_of(p.z, 2)), i};
    }
    std::sort(order.begin(), order.end());  // by cell, then by photon index: a fixed summation order
    photons_.reserve(kept.size());
    for (uint32_t i = 0; i < order.size(); ++i) {
        photons_.push_back(kept[order[i].second]);
        positions_.push_back(kept[order[i].second].position);
        auto& range = cells_.try_emplace(order[i].first, i, i).first->second;
        range.second = i + 1;
    }
}

int64_t CausticPhotonMap::cell_of(float v, int axis) const {
    const double c = std::floor((static_cast<double>(v) - lo_[axis]) / cell_);
    return static_cast<int64_t>(std::clamp(c, 0.0, static_cast<double>(kMaxCellsPerAxis - 1)));
}

template <class Flux>
glm::vec3 CausticPhotonMap::gather(const ViewSample& s, const Flux& flux) const {
    if (photons_.empty()) return glm::vec3(0.0f);
    const float r = params_.radius;
    int64_t from[3] = {0, 0, 0}, to[3] = {0, 0, 0};
    for (int a = 0; a < 3; ++a) {
        if (!(s.position[a] + r >= lo_[a])) return glm::vec3(0.0f);
        from[a] = cell_of(s.position[a] - r, a);
        to[a] = std::min(cell_of(s.position[a] + r, a), extent_[a] - 1);
        if (from[a] > to[a]) return glm::vec3(0.0f);
    }
    glm::dvec3 sum(0.0);
    for (int64_t z = from[2]; z <= to[2]; ++z)
        for (int64_t y = from[1]; y <= to[1]; ++y)
            for (int64_t x = from[0]; x <= to[0]; ++x) {
                const auto found = cells_.find(key(x, y, z));
                if (found == cells_.end()) continue;
                for (uint32_t i = found->second.first; i < found->second.second; ++i)
                    if (photon_reaches_sample(s, positions_[i], photons_[i], params_))
                        sum += flux(photons_[i], positions_[i]);
            }
    return finish_sample(s, sum, params_);
}

glm::vec3 CausticPhotonMap::radiance(const ViewSample& s, const Lobe* lobes) const {
    return gather(s, [&](const Photon& photon, const glm::vec3& p) {
        return photon_reflected_flux(s, lobes, p, photon, params_);
    });
}

glm::vec3 CausticPhotonMap::transmitted_radiance(const ViewSample& s, const Bsdf& b) const {
    return gather(s, [&](const Photon& photon, const glm::vec3& p) {
        const glm::dvec3 f = glm::dvec3(bsdf_eval(b, photon.wi, LobeSet::transmission)) * glm::dvec3(photon.power) *
                             photon_arrival_share(s, photon);  // s: the far side, its normals turned to the photons
        return params_.kernel == Kernel::uniform ? f : f * kernel_weight(s.position - p, params_);
    });
}

}  // namespace ps
