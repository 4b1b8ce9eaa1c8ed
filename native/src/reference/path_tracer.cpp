// Unidirectional path tracing with next-event estimation and multiple importance sampling (Veach 1997, power
// heuristic, one light sample per source per vertex and one BSDF sample per vertex).
//
// At a non-specular vertex x (diffuse, or glossy rough enough to be a lobe):
//   - every light source except the world is sampled once (LightSources::sample_incidence) and weighted by
//     w = p_light² / (p_light² + p_bsdf²); delta lights (p_light = 0 by convention) get w = 1;
//   - this pass's caustic photons are gathered (the L S+ D paths of point lights and suns: never counted here);
//   - one BSDF direction is sampled; whatever light that ray meets next (an analytic light in front of the
//     first surface, an emissive triangle, a sun's cone when it escapes) is weighted w = p_bsdf² / (p_bsdf² +
//     p_light²). The world background has no light sampling here, so it always gets w = 1.
// After a specular vertex (mirror, glass, smooth glossy) no light sampling could have produced the same path,
// so lights met there get w = 1 — unless the light is a point light or sun and a non-specular vertex precedes
// the specular chain: that is an L S+ D path, the photons' (reference.h).
// Russian roulette on the throughput from the fourth vertex on keeps long paths cheap and unbiased.
#include "path_tracer.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "caustic_photons.h"
#include "photonsplat/brdf.h"
#include "photonsplat/light_sources.h"
#include "photonsplat/lights.h"
#include "photonsplat/materials.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/rng.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/splat.h"
#include "photonsplat/view_samples.h"

namespace ps {

namespace {

constexpr float kInvPi = 0.318309886183790671538f;
constexpr int kRouletteFromDepth = 3;
constexpr float kMinGlossyCosine = 1e-3f;  // as view_samples.cpp: below it a glossy lobe uses the geometric normal

float power_heuristic(float chosen, float other) {
    if (!(other > 0.0f)) return 1.0f;
    const float a = chosen * chosen, b = other * other;
    return std::isfinite(a + b) ? a / (a + b) : (chosen >= other ? 1.0f : 0.0f);
}

// The vertex as the shared BRDF and photon-gathering code (splat.h) sees a view sample.
ViewSample vertex_at(const SurfacePoint& s, const glm::vec3& wo, const glm::vec3& origin, const glm::vec3& throughput) {
    ViewSample v{};
    v.position = s.position - origin;
    v.normal = s.geometric_normal;
    v.shading_normal = s.shading_normal;
    v.rounding_scale = s.rounding_scale;
    v.wo = wo;
    v.throughput = throughput;
    if (s.material->is_glossy()) {
        v.albedo = glm::vec3(0.0f);
        v.specular = s.material->color;
        v.roughness = s.material->glossy_alpha();
        v.flags = kGlossy;
        if (!(glm::dot(v.shading_normal, wo) > kMinGlossyCosine)) v.shading_normal = v.normal;
    } else {
        v.albedo = s.material->color;
        v.specular = glm::vec3(0.0f);
        v.roughness = 0.0f;
        v.flags = 0;
    }
    return v;
}

// Density of the BSDF sampling below choosing wi at v.
float bsdf_pdf(const ViewSample& v, const glm::vec3& wi) {
    if (!(glm::dot(wi, v.normal) > 0.0f)) return 0.0f;
    if (v.flags & kGlossy) return ggx_reflection_pdf(v.roughness, v.shading_normal, wi, v.wo);
    return std::max(0.0f, glm::dot(wi, v.shading_normal)) * kInvPi;
}

struct BsdfSample {
    glm::vec3 direction;
    glm::vec3 weight;  // f cos / pdf
    float pdf;         // 0: the path ends
};

BsdfSample sample_bsdf(const ViewSample& v, float u1, float u2) {
    if (v.flags & kGlossy) {
        const GgxSample g = sample_ggx_reflection(v.specular, v.roughness, v.shading_normal, v.wo, u1, u2);
        if (!(g.pdf > 0.0f) || !(glm::dot(g.direction, v.normal) > 0.0f)) return {g.direction, glm::vec3(0.0f), 0.0f};
        return {g.direction, g.weight, g.pdf};
    }
    const glm::vec3 d = sample_cosine_hemisphere(v.shading_normal, u1, u2);
    const float pdf = glm::dot(d, v.shading_normal) * kInvPi;
    if (!(glm::dot(d, v.normal) > 0.0f) || !(pdf > 0.0f)) return {d, glm::vec3(0.0f), 0.0f};
    return {d, v.albedo, pdf};
}

// Next-event estimation at v (world position x) over every source but the world.
glm::vec3 sample_lights(const PathTracerContext& c, const ViewSample& v, const glm::vec3& x, Rng& rng,
                        PathCounters& counters) {
    glm::vec3 sum(0.0f);
    const RayTracer& tracer = c.scene.ray_tracer();
    for (size_t l = 0; l < c.sources.size(); ++l) {
        if (c.sources.is_world(l)) continue;
        const float u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
        const LightIncidence in = c.sources.sample_incidence(l, x, v.normal, u1, u2, u3);
        if (!(glm::dot(in.wi, v.normal) > 0.0f)) continue;  // light from behind the surface the path sees
        const float cos_shading = glm::dot(in.wi, v.shading_normal);
        if (!(cos_shading > 0.0f) || in.value == glm::vec3(0.0f)) continue;
        const glm::vec3 f(sample_brdf(v, in.wi));
        if (f == glm::vec3(0.0f)) continue;
        ++counters.shadow_rays;
        if (tracer.occluded(Ray{offset_ray_origin(x, v.normal, v.rounding_scale), in.wi}, 0.0f, in.distance * (1.0f - 1e-4f))) continue;
        const float w = c.sources.is_delta(l) ? 1.0f : power_heuristic(in.pdf, bsdf_pdf(v, in.wi));
        sum += f * in.value * (cos_shading * w);
    }
    return sum;
}

// Where the last BSDF sample left from, for the MIS weight of a light it meets.
struct LastScatter {
    bool nonspecular = false;      // a non-specular vertex lies behind on the path
    bool specular_since = false;   // and one or more specular vertices since it
    glm::vec3 x{0.0f};             // that vertex
    float pdf = 0.0f;              // its BSDF sample's density
};

// Weight of a light met by the current ray, or < 0 when that path belongs to the photons.
float light_weight(const LastScatter& last, bool photon_caustics, float light_pdf) {
    if (!last.nonspecular) return 1.0f;                                  // L S* E
    if (last.specular_since) return photon_caustics ? -1.0f : 1.0f;     // L S+ D ...
    return power_heuristic(last.pdf, light_pdf);                         // L D ...
}

}  // namespace

glm::vec3 trace_reference_path(const PathTracerContext& c, Ray ray, Rng& rng, PathCounters& counters) {
    const Scene& scene = c.scene;
    const RayTracer& tracer = scene.ray_tracer();
    const glm::vec3 origin = c.caustics ? c.caustics->origin() : glm::vec3(0.0f);
    glm::vec3 radiance(0.0f), throughput(1.0f);
    LastScatter last;
    for (int depth = 0;; ++depth) {
        Hit hit;
        ++counters.rays;
        const bool found = tracer.intersect(ray, 0.0f, std::numeric_limits<float>::infinity(), hit);
        // Scene lights are not in the BVH: test them against the ray. Camera rays do not see them (render()).
        if (depth > 0) {
            for (size_t l = 0; l < c.sources.size(); ++l) {
                const Light* light = c.sources.light(l);
                if (!light) continue;
                const LightHit h = intersect_light(*light, last.nonspecular && !last.specular_since ? last.x : ray.origin,
                                                   ray.direction);
                if (!h.hit || (found && !(h.distance < hit.t))) continue;
                const float w = light_weight(last, c.photon_caustics[l] != 0, h.pdf);
                if (w > 0.0f) radiance += throughput * h.radiance * w;
            }
        }
        if (!found) {
            radiance += throughput * scene.background();  // the world: BSDF sampling only, weight 1
            break;
        }
        const SurfacePoint s = surface_at(scene, ray, hit);
        const Material& m = *s.material;
        if (m.emission != glm::vec3(0.0f)) {
            // Emissive triangles are one source of the path tracer (never photon-mapped).
            const float light_pdf =
                last.nonspecular && !last.specular_since ? c.sources.emissive_pdf(hit.instance, hit.triangle, last.x, s.position) : 0.0f;
            radiance += throughput * m.emission * light_weight(last, false, light_pdf);
        }
        if (m.is_specular()) {
            if (depth >= c.max_bounces) break;
            const SpecularStep step = scatter_specular(m, s, ray.direction, rng.uniform());
            throughput *= step.weight;
            const glm::vec3 side = step.transmitted ? -s.geometric_normal : s.geometric_normal;
            ray = Ray{offset_ray_origin(s.position, side, s.rounding_scale), step.direction};
            last.specular_since = true;
        } else {
            const ViewSample v = vertex_at(s, -ray.direction, origin, throughput);
            radiance += throughput * sample_lights(c, v, s.position, rng, counters);
            if (c.caustics) radiance += c.caustics->radiance(v);  // throughput included
            if (depth >= c.max_bounces) break;
            const float u1 = rng.uniform(), u2 = rng.uniform();
            const BsdfSample b = sample_bsdf(v, u1, u2);
            if (!(b.pdf > 0.0f)) break;
            throughput *= b.weight;
            ray = Ray{offset_ray_origin(s.position, s.geometric_normal, s.rounding_scale), b.direction};
            last = LastScatter{true, false, s.position, b.pdf};
        }
        const float keep = std::max({throughput.x, throughput.y, throughput.z});
        if (!(keep > 0.0f)) break;
        if (depth >= kRouletteFromDepth && keep < 1.0f) {
            if (rng.uniform() >= keep) break;
            throughput /= keep;
        }
    }
    return radiance;
}

}  // namespace ps
