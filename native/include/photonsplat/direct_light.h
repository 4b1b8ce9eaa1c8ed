// Stage 2 of the pipeline: direct light at every view sample by shadow rays (next-event estimation), with
// multiple importance sampling against the BSDF's own directions where the BSDF is more than Lambert's.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "photonsplat/camera.h"
#include "photonsplat/shading.h"
#include "photonsplat/shadow_terminator.h"

namespace ps {

class Scene;
class RenderControl;
class LightSources;
class Rng;
class SampleSequence;
struct LightIncidence;
struct Stats;
struct ViewSamples;

struct DirectLightSettings {
    uint64_t seed = 0;
    int samples_per_light = 4;  // shadow rays per light with a size (a point of radius 0 or a 0° sun needs 1)
    // A programmed world's samples come from each view sample's low-discrepancy sequence (sample_sequence.h),
    // scrambled by sequence_seed (the render's seed), iteration `iteration` taking its samples_per_light points.
    uint64_t sequence_seed = 0;
    uint32_t iteration = 0;
};

// Reflected direct radiance per view sample (index-aligned with samples.samples), throughput included.
std::vector<glm::vec3> compute_direct_light(const Scene& scene, const ViewSamples& samples,
                                            const DirectLightSettings& settings, const RenderControl& control,
                                            Stats& stats);

// For the Caustics output: the direct light of the samples reached right after translucency (kAfterDiffuseScatter,
// view_samples.h) through the parts Cycles' Caustics toggles drop there (all but the diffuse-labelled ones), with
// shadow rays of its own, throughput included; 0 at every other sample. Empty when no sample has such parts.
std::vector<glm::vec3> compute_dropped_direct_light(const Scene& scene, const ViewSamples& samples,
                                                    const DirectLightSettings& settings, const RenderControl& control,
                                                    Stats& stats);

// Direct light scattered by one set of a BSDF's parts at x (towards b.wo), throughput not included:
//   - every source sampled `samples_per_light` times (once if it is a delta light), stratified, from the side
//     of the surface the set scatters from (reflection: wo's side; transmission: the other);
//   - where the set is directional (any lobe beyond Lambert's, or transmission), as many BSDF-sampled rays,
//     each adding the emitter it meets first (a light with a size, an emissive triangle, the world), the two
//     strategies weighted by the power heuristic. A Lambert-only set uses light sampling alone.
// Shadow rays pass through transparent closures, attenuated (Cycles' transparent shadows). `rays` counts them.
struct DirectLightContext {
    const Scene& scene;
    const LightSources& sources;
    int samples_per_light;
    bool transparency;  // scene_has_transparency(scene)
};
// `sequences` (optional): the view sample's two sequences (light samples, BSDF samples) and the iteration, whose
// k samples of each kind take points iteration·k … iteration·k + k − 1 (consecutive points: a stride would
// leave part of the square unvisited); a programmed world then draws from them instead of rng.
struct DirectLightSequences {
    const SampleSequence* light = nullptr;
    const SampleSequence* bsdf = nullptr;
    uint32_t iteration = 0;
};
// `terminator`: the lift of x's shadow rays towards the set's side (shadow_terminator.h), or null for none.
glm::vec3 direct_light_at(const DirectLightContext& c, const Bsdf& b, const glm::vec3& x, float rounding_scale,
                          LobeSet set, Rng& rng, uint64_t& rays, const DirectLightSequences& sequences = {},
                          const TerminatorLift* terminator = nullptr);

// What Cycles 3.x's light samples find at a near-mirror Multiscatter GGX (Bsdf::mirror_reported_alpha): its lamps
// seen through the lobe's clamped D (cycles3_multiscatter_mirror_eval), a dim glow around their reflection, each
// weighted against the directions the lobe reports by Cycles' own densities (the rest, mirror_emitter_weight,
// is the BSDF rays'). Times b.mirror (the mirror's colour). Emissive surfaces and a programmed world are left out:
// their share of that glow is the smallest (a world lights it from everywhere at once, at a density far below a
// lamp's). 0 where b has no such mirror.
glm::vec3 near_mirror_light(const DirectLightContext& c, const Bsdf& b, const glm::vec3& x, float rounding_scale,
                            Rng& rng, uint64_t& rays);

// The shadow ray towards the point a light sample `in` (drawn from x) lies on, leaving from `origin` (x stepped
// off its surface): aimed from origin at that point, so that it ends on the light and not beside it. Stepping off
// moves the origin along the surface's normal; along in.wi from there, the ray's end would be moved as much and,
// where it meets an emissive surface at a grazing angle, lie behind that surface, which then hides its own light
// (floors lit by an emissive mesh resting on them lost up to 40 % of it wherever coordinates are large enough
// for the step to be ~1e-3). Its end stops a relative 1e-4 short of the point, so that the light's surroundings
// still shadow it. A light at infinity (sun, world) keeps in.wi.
struct ShadowSegment {
    Ray ray;
    float t_max = 0.0f;
};
ShadowSegment shadow_segment(const glm::vec3& x, const glm::vec3& origin, const LightIncidence& in);

// What reaches `ray.origin` from ray.origin + t_max·direction: 1, 0 behind an opaque surface, the product of
// the transparent weights of the surfaces crossed where the scene has transparency (`transparency`).
glm::vec3 shadow_transmittance(const Scene& scene, const Ray& ray, float t_max, bool transparency);

// Whether any material of the scene has a transparent closure (shadow rays must then look through them).
bool scene_has_transparency(const Scene& scene);

// The power heuristic of multiple importance sampling (β = 2) for the strategy of density `chosen` against `other`.
float power_heuristic(float chosen, float other);

// The weight of an emitter a ray meets right after a mirror whose direction reports density `mirror_pdf`
// (mirror_reported_pdf, shading.h): Cycles 3.x weighs it against sampling that emitter, of density `light_pdf`
// (Cycles' pick of it included), by the power heuristic; the light samples it weighs it against see next to
// nothing (shading.h), so the rest of that light is lost, as in Cycles 3.4. 1 after a true mirror (mirror_pdf 0).
float mirror_emitter_weight(float mirror_pdf, float light_pdf);

}  // namespace ps
