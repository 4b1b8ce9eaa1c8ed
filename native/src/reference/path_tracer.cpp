// Unidirectional path tracing with next-event estimation and multiple importance sampling (Veach 1997, power
// heuristic, one light sample per source per vertex and one BSDF sample per vertex).
//
// At a non-specular vertex x (diffuse, or glossy rough enough to be a lobe):
//   - every light source except the world is sampled once (LightSources::sample_incidence) and weighted by
//     w = p_light² / (p_light² + p_bsdf²) (where x holds a clearcoat or Multiscatter GGX glass, p_light times
//     Cycles' probability of picking that light: bsdf_weighs_by_cycles_pick; p_bsdf the density Cycles reports,
//     BsdfSample::mis_pdf); delta lights (p_light = 0 by convention) and lights with Multiple Importance off (which
//     no BSDF ray meets: Light::multiple_importance) get w = 1; a light with Cast Shadow off takes no shadow ray;
//   - this pass's caustic photons are gathered (the L S+ D paths of point and spot lights and suns, never
//     counted here), through the reflection parts from x's side and through the transmission parts from the
//     other;
//   - one BSDF direction is sampled; whatever light that ray meets next (an analytic light in front of the
//     first surface, an emissive triangle, a sun's cone when it escapes) is weighted w = p_bsdf² / (p_bsdf² +
//     p_light²). A constant world has no light sampling here, so it always gets w = 1; a programmed world
//     is sampled by its map (world.h) like the other sources.
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
#include "photonsplat/direct_light.h"
#include "photonsplat/glass_multiscatter.h"
#include "photonsplat/light_sources.h"
#include "photonsplat/lights.h"
#include "photonsplat/material_program.h"
#include "photonsplat/materials.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/rng.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/shading.h"
#include "photonsplat/splat.h"
#include "photonsplat/view_samples.h"

namespace ps {

namespace {

constexpr int kRouletteFromDepth = 3;

// The vertex as the shared photon-gathering code (splat.h) sees a view sample: its reflection parts, the lobes
// copied into `lobes` (the sample's lobe_begin is 0 there).
ViewSample vertex_at(const SurfacePoint& s, const Bsdf& b, const glm::vec3& origin, const glm::vec3& throughput,
                     Lobe (&lobes)[kMaxLobes]) {
    ViewSample v{};
    v.position = s.position - origin;
    v.normal = b.ng;
    v.shading_normal = b.n;
    v.smooth_normal = b.smooth_n;
    v.rounding_scale = s.rounding_scale;
    v.wo = b.wo;
    v.throughput = throughput;
    v.albedo = b.lambert;
    v.lobe_begin = 0;
    v.lobe_count = 0;
    for (int k = 0; k < b.lobe_count; ++k)
        if (!is_transmission(b.lobes[k])) lobes[v.lobe_count++] = b.lobes[k];
    v.flags = (v.lobe_count > 0 ? kGlossy : 0u) |
              (inside_transmitter(s) ? static_cast<uint32_t>(kInsideSample) : 0u) |
              (b.bump_shadowed ? static_cast<uint32_t>(kBumpShadowed) | bump_form_flags(b.bump_form) : 0u);
    return v;
}

// The vertex as photons on the other side of its surface see it: for light that its transmission parts pass on.
ViewSample far_side_vertex(const SurfacePoint& s, const Bsdf& b, const glm::vec3& origin, const glm::vec3& throughput) {
    ViewSample v{};
    v.position = s.position - origin;
    v.normal = -b.ng;
    v.shading_normal = -b.n;
    v.rounding_scale = s.rounding_scale;
    v.wo = b.wo;
    v.throughput = throughput;
    v.flags = inside_transmitter(s) ? 0u : static_cast<uint32_t>(kInsideSample);
    return v;
}

// A vertex on a lone Multiscatter GGX Glass (lone_multi_ggx_glass), in its local frame (n = +z), with Cycles'
// random numbers for its walks there: Cycles runs the walks of one path's vertices on numbers shifted from one
// another by constants (CyclesLcg), and what it converges to through such glass depends on that.
struct CyclesGlassVertex {
    glm::vec3 t{0.0f}, bt{0.0f}, n{0.0f};
    CyclesLcg lcg;
    glm::vec3 local(const glm::vec3& w) const { return {glm::dot(w, t), glm::dot(w, bt), glm::dot(w, n)}; }
    glm::vec3 world(const glm::vec3& w) const { return w.x * t + w.y * bt + w.z * n; }
};

// The density Cycles reports for wi from the glass: mf_glass_pdf, both sides in one.
float glass_reported_pdf(const Bsdf& b, const CyclesGlassVertex& g, const glm::vec3& wi) {
    const glm::vec3 i = g.local(wi), o = g.local(b.wo);
    const Lobe* lobe = lone_multi_ggx_glass(b, i.z);
    return lobe != nullptr ? cycles3_multi_glass_pdf(lobe->eta, lobe->alpha_x, i, o) : 0.0f;
}

// Cycles' value of the glass towards a light sample at wi: its evaluation walk, on the vertex's numbers where this
// is the one light sample Cycles takes there (`consumes`: it runs before the vertex's sampling walk, on the same
// numbers), else on numbers of its own.
glm::vec3 glass_light_value(const Bsdf& b, CyclesGlassVertex& g, const glm::vec3& wi, bool consumes) {
    if (!consumes) return bsdf_eval(b, wi, LobeSet::all, MultiScatterEstimate::light_sample);
    const glm::vec3 i = g.local(wi), o = g.local(b.wo);
    const Lobe* lobe = lone_multi_ggx_glass(b, i.z);
    if (lobe == nullptr) return glm::vec3(0.0f);
    return lobe->weight * cycles3_multi_glass_light_value(lobe->eta, lobe->alpha_x, lobe->specular_color, i, o, g.lcg);
}

// The BSDF direction at a lone Multiscatter Glass, drawn by Cycles' sampling walk on the vertex's numbers (after its
// light sample's), with the density Cycles reports for it.
BsdfSample glass_walk_sample(const Bsdf& b, CyclesGlassVertex& g) {
    BsdfSample out;
    const glm::vec3 o = g.local(b.wo);
    const Lobe* either = lone_multi_ggx_glass(b, 1.0f);
    glm::vec3 i(0.0f);
    const glm::vec3 weight =
        cycles3_multi_glass_walk_sample(either->eta, either->alpha_x, either->specular_color, o, g.lcg, i);
    const Lobe* lobe = lone_multi_ggx_glass(b, i.z);
    if (weight == glm::vec3(0.0f) || lobe == nullptr) return out;
    out.kind = ScatterKind::lobes;
    out.direction = glm::normalize(g.world(i));
    out.weight = lobe->weight * weight;
    out.mis_pdf = out.pdf = cycles3_multi_glass_pdf(lobe->eta, lobe->alpha_x, i, o);
    out.transmitted = i.z < 0.0f;
    out.glossy = true;
    return out;
}

// Next-event estimation at x over every source but a constant world, both sides of the surface (transmission lobes
// see light from behind), weighted against the BSDF sampling of bsdf_sample. `glass`: the vertex is a lone
// Multiscatter Glass (CyclesGlassVertex), sampled by Cycles' walk, whose density Cycles reports as mf_glass_pdf.
glm::vec3 sample_lights(const PathTracerContext& c, const Bsdf& b, const SurfacePoint& s, Rng& rng,
                        PathCounters& counters, CyclesGlassVertex* glass) {
    glm::vec3 sum(0.0f);
    const bool transmits = bsdf_has(b, LobeSet::transmission);
    const bool cycles_weights = bsdf_weighs_by_cycles_pick(b);  // weights take Cycles' light densities (shading.h)
    // Cycles samples one light per vertex, picked by its distribution; its glass walk runs on the vertex's numbers
    // for that one. We sample every light, and let the one Cycles would have picked take those numbers.
    size_t picked = c.sources.size();
    if (glass != nullptr) {
        float u = rng.uniform();
        for (size_t l = 0; l < c.sources.size() && picked == c.sources.size(); ++l) {
            u -= c.sources.cycles_pick_probability(l);
            if (u < 0.0f) picked = l;
        }
    }
    for (size_t l = 0; l < c.sources.size(); ++l) {
        if (c.sources.is_world(l) && c.sources.world().constant()) continue;  // BSDF sampling alone (below)
        const float u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
        const LightIncidence in = c.sources.sample_incidence(l, s.position, b.ng, u1, u2, u3);
        const bool front = glm::dot(in.wi, b.ng) > 0.0f;
        // Under the triangle's horizon but above the shading normal's: traced from the smooth surface where the
        // object has a terminator offset (shadow_terminator.h), and evaluated by the shading normal, as Cycles.
        const TerminatorLift lift = c.terminator_offsets ? terminator_lift(c.scene, s, b.ng) : TerminatorLift{};
        const bool below = !front && terminator_reaches_below(lift, b.n, b.ng, in.wi);
        if (!front && !transmits && !below) continue;  // light from behind a surface that does not pass it on
        if (!front && glm::dot(in.wi, b.ng) == 0.0f) continue;
        if (in.value == glm::vec3(0.0f)) continue;
        const glm::vec3 f = glass != nullptr && !below
                                ? glass_light_value(b, *glass, in.wi, l == picked)
                            : below ? bsdf_eval_shading_side(b, in.wi, LobeSet::all, c.scene.multiscatter_light_estimate())
                                    : bsdf_eval(b, in.wi, LobeSet::all, c.scene.multiscatter_light_estimate());
        if (f == glm::vec3(0.0f)) continue;
        ++counters.shadow_rays;
        const glm::vec3 side = front || below ? b.ng : -b.ng;
        const glm::vec3 start =
            !c.terminator_offsets ? s.position
            : side == b.ng        ? terminator_origin(s.position, lift, b.n, side, in.wi)
                                  : terminator_origin(s.position, terminator_lift(c.scene, s, side), b.n, side, in.wi);
        const ShadowSegment segment = shadow_segment(s.position, offset_ray_origin(start, side, s.rounding_scale), in);
        // Cast Shadow off: no shadow ray, nothing occludes the sample (Cycles' shadow_ray_setup).
        const glm::vec3 t = c.sources.casts_shadow(l)
                                ? shadow_transmittance(c.scene, segment.ray, segment.t_max, c.transparency)
                                : glm::vec3(1.0f);
        if (t == glm::vec3(0.0f)) continue;
        // Multiple Importance off: no BSDF ray meets the light (below), so its samples keep their full value.
        float w = 1.0f;
        if (c.sources.mis_with_bsdf_rays(l)) {
            const float p_light = cycles_weights ? c.sources.cycles_mis_density(l, s.position, in.wi, in.pdf) : in.pdf;
            const float p_bsdf = glass != nullptr ? glass_reported_pdf(b, *glass, in.wi) : bsdf_sample_pdf(b, in.wi);
            w = power_heuristic(p_light, p_bsdf);
        }
        sum += f * in.value * t * (std::fabs(glm::dot(in.wi, b.n)) * w);
    }
    return sum;
}

// Where the last BSDF sample left from, for the MIS weight of a light it meets.
struct LastScatter {
    bool nonspecular = false;      // a non-specular vertex lies behind on the path
    bool specular_since = false;   // and one or more specular vertices since it
    glm::vec3 x{0.0f};             // that vertex
    float pdf = 0.0f;              // its BSDF sample's density, as Cycles reports it (BsdfSample::mis_pdf)
    bool cycles_weights = false;   // lights' densities are Cycles' there (bsdf_weighs_by_cycles_pick)
    float pick(float cycles_pick) const { return cycles_weights ? cycles_pick : 1.0f; }
    // The last scatter was a mirror reporting this density (mirror_reported_pdf), from mirror_x: what the ray
    // meets takes mirror_emitter_weight. 0: another scatter, or a true mirror.
    float mirror_pdf = 0.0f;
    glm::vec3 mirror_x{0.0f};
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
    bool camera_ray = true;  // only transparency crossed so far: still the camera's ray, which sees no lights
    const uint32_t cycles_numbers = rng.next_u32();  // the path's Cycles rng_hash + sample * scramble (CyclesLcg)
    for (int depth = 0;; ++depth) {
        Hit hit;
        ++counters.rays;
        // Object ray visibility as Cycles keeps it: the camera's ray (transparency crossed keeps it one) meets what
        // is visible to the camera, every later ray what is visible to diffuse, glossy or transmission rays.
        const bool found = tracer.intersect(ray, 0.0f, std::numeric_limits<float>::infinity(), hit,
                                            camera_ray ? kCameraRays : kIndirectRays);
        // Scene lights are not in the BVH: test them against the ray. Camera rays do not see them (render()).
        // A light counts where it lies on this ray's own segment, from ray.origin to the hit. Its density for the
        // MIS weight is the one next-event estimation drew it with, from the last scatter: after transparency
        // the ray goes on along the same line from beyond that point, and testing from there had a light met
        // before the crossing counted again at every crossing (differential seed 134: an area light reflected
        // by a Principled Suzanne through a transparent sphere, the reference 1.11 of Cycles).
        if (!camera_ray) {
            const bool weighed_from_last = last.nonspecular && !last.specular_since;
            for (size_t l = 0; l < c.sources.size(); ++l) {
                const Light* light = c.sources.light(l);
                if (!light || !c.sources.found_by_bsdf_rays(l)) continue;  // Multiple Importance off: only camera rays
                const LightHit h = intersect_light(*light, ray.origin, ray.direction);
                if (!h.hit || (found && !(h.distance < hit.t))) continue;
                const LightHit drawn = weighed_from_last ? intersect_light(*light, last.x, ray.direction) : h;
                const float own = drawn.hit ? drawn.pdf : h.pdf;
                const float pdf =
                    last.cycles_weights ? c.sources.cycles_mis_density(l, last.x, ray.direction, own) : own;
                float w = light_weight(last, c.photon_caustics[l] != 0, pdf);
                if (w > 0.0f && last.mirror_pdf > 0.0f)
                    w *= mirror_emitter_weight(last.mirror_pdf, c.sources.cycles_lamp_pdf(l, last.mirror_x, ray.direction));
                if (w > 0.0f) radiance += throughput * h.radiance * w;
            }
        }
        if (!found) {
            // A constant world: BSDF sampling only, weight 1. A programmed one is also light-sampled.
            const WorldLight& world = c.sources.world();
            const glm::vec3 L = world_radiance(scene, ray.direction, depth > 0 ? ShaderRay::reflected : ShaderRay::camera);
            const bool sampled = !world.constant() && !world.black();
            const float world_pdf = last.nonspecular && !last.specular_since
                                        ? world.pdf(last.x, glm::vec3(0.0f, 0.0f, 1.0f), ray.direction) *
                                              last.pick(c.sources.cycles_lamp_pick_probability())
                                        : 0.0f;
            float w = sampled ? light_weight(last, false, world_pdf) : 1.0f;
            if (sampled && last.mirror_pdf > 0.0f)
                w *= mirror_emitter_weight(last.mirror_pdf, world.pdf(last.mirror_x, glm::vec3(0.0f, 0.0f, 1.0f),
                                                                      ray.direction) *
                                                                c.sources.cycles_lamp_pick_probability());
            radiance += throughput * L * w;
            break;
        }
        const SurfacePoint s = surface_at(scene, ray, hit, depth > 0 ? ShaderRay::reflected : ShaderRay::camera);
        const Material& m = *s.material;
        if (m.emission != glm::vec3(0.0f) || m.program_emission) {
            // Emissive triangles are one source of the path tracer (never photon-mapped).
            const float light_pdf =
                last.nonspecular && !last.specular_since
                    ? c.sources.emissive_pdf(hit.instance, hit.triangle, last.x, s.position) *
                          last.pick(c.sources.cycles_emissive_pick_probability())
                    : 0.0f;
            float w = light_weight(last, false, light_pdf);
            if (last.mirror_pdf > 0.0f)
                w *= mirror_emitter_weight(last.mirror_pdf,
                                           c.sources.cycles_emissive_pdf(hit.instance, hit.triangle, last.mirror_x, s.position));
            radiance += throughput * emission_at(scene, s, -ray.direction) * w;
        }
        // Cycles' Max Bounces N: vertices 0..N scatter (light samples and a BSDF ray; N = 0 is direct light, the
        // camera's hit sampling both ways), and the vertex after them only emits. Stopping before vertex N's BSDF
        // ray kept only the light-sample half of its MIS pair (a large light in a rough glass cube's faces at
        // N = 0: 0.76 of Cycles, tests/blender/test_reference_light_paths.py).
        if (depth > c.max_bounces) break;
        Bsdf b = shade(scene, s, -ray.direction);
        if (depth == 0) choose_defensively(b);  // the camera's first hit (shading.h)
        if (b.mirror_reported_alpha > 0.0f) {  // a near-mirror's light samples (near_mirror_light)
            uint64_t rays = 0;
            radiance += throughput * near_mirror_light(DirectLightContext{scene, c.sources, 1, c.transparency}, b,
                                                       s.position, s.rounding_scale, rng, rays);
            counters.shadow_rays += rays;
        }
        // Cycles 3.x's lone Multiscatter Glass: its walks on Cycles' numbers (CyclesLcg), light sample then bounce.
        CyclesGlassVertex glass_vertex;
        CyclesGlassVertex* glass = nullptr;
        const Lobe* lone_glass = lone_multi_ggx_glass(b, 1.0f);
        if (lone_glass != nullptr && lone_glass->alpha_x * lone_glass->alpha_x >= 1e-7f &&
            c.scene.multiscatter_light_estimate() == MultiScatterEstimate::light_sample) {
            glass_vertex.n = b.n;
            orthonormal_basis(b.n, glass_vertex.t, glass_vertex.bt);
            glass_vertex.lcg = CyclesLcg::at_vertex(cycles_numbers, depth);
            glass = &glass_vertex;
        }
        if (bsdf_has(b, LobeSet::all)) {
            radiance += throughput * sample_lights(c, b, s, rng, counters, glass);
            if (c.caustics && bsdf_has(b, LobeSet::reflection)) {
                Lobe lobes[kMaxLobes];
                const ViewSample v = vertex_at(s, b, origin, throughput, lobes);
                radiance += c.caustics->radiance(v, lobes);  // throughput included
            }
            if (c.caustics && bsdf_has(b, LobeSet::transmission))
                radiance += c.caustics->transmitted_radiance(far_side_vertex(s, b, origin, throughput), b);
        }
        const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        const BsdfSample bs = glass != nullptr ? glass_walk_sample(b, *glass) : bsdf_sample(b, u0, u1, u2);
        if (bs.kind == ScatterKind::none) break;
        throughput *= bs.weight;
        const glm::vec3 side = bs.transmitted ? -s.geometric_normal : s.geometric_normal;
        if (bs.kind == ScatterKind::lobes && !(glm::dot(bs.direction, side) > 0.0f)) break;
        ray = Ray{offset_ray_origin(s.position, side, s.rounding_scale), bs.direction};
        // Transparency lets the ray go on as it was: its MIS state stays that of the last real scatter.
        if (bs.kind == ScatterKind::lobes) {
            last = LastScatter{true, false, s.position, bs.mis_pdf, bsdf_weighs_by_cycles_pick(b)};
        } else if (bs.kind != ScatterKind::transparent) {
            last.specular_since = true;
            last.mirror_pdf = bs.kind == ScatterKind::mirror ? mirror_reported_pdf(b) : 0.0f;
            last.mirror_x = s.position;
        }
        if (bs.kind != ScatterKind::transparent) camera_ray = false;
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
