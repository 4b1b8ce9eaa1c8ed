// The reference renderer: a converged image that every fast method is measured against (docs/reference.md).
//
// Two estimators, each owning a disjoint part of path space, so their sum counts every light path once:
//
//   Path tracing (reference/path_tracer.cpp): camera paths with next-event estimation to every light source
//   and BSDF sampling, combined by multiple importance sampling (power heuristic) wherever both can produce a
//   path: lights with a size (point lights with a radius, suns with an angle, area lights), emissive
//   triangles; the world background is reached by BSDF sampling only. Every material: diffuse, glossy GGX
//   (brdf.h), mirror and glass (scattering.h). Unbiased for the paths it owns.
//
//   Progressive photon mapping (reference/caustic_photons.cpp): photons from point lights and suns, stored
//   at the first non-specular surface after one or more specular bounces: the L S+ D prefixes. Every
//   non-specular vertex of every camera path gathers them, with a radius that shrinks from pass to pass as
//   r_i² = r_{i−1}² (i − 1 + α)/i, α = 2/3 (Knaus & Zwicker 2011): consistent (bias → 0 as passes grow).
//
// The partition: classify a light path by its light end. Let L be the light vertex and D the first
// non-specular vertex after it. If L is a point light or a sun AND at least one specular vertex lies between
// L and D (L S+ D ...), the path belongs to photon mapping; every other path belongs to path tracing. The path
// tracer therefore ignores a point light or sun met by a ray that left a non-specular vertex and then passed
// one or more specular vertices, and the photon tracer emits only from point lights and suns and stores
// only photons that passed a specular vertex. For delta lights (radius 0, angle 0) those paths cannot be
// sampled by a path tracer at all; for point lights with a radius and suns with an angle they could be, but
// only with a probability proportional to the light's (tiny) apparent size: photons converge far faster.
// Area lights, emissive surfaces and the world are large; their caustics stay with the path tracer.
// Lights reached from the camera through specular vertices only (a lamp seen in a mirror: L S* E) are path
// traced; lights (not emissive surfaces) are invisible to camera rays, as in render().
//
// Units are those of render(): the same scene gives the same image once both converge (render() counts a
// pixel's centre only; the reference jitters camera rays over the pixel: a box filter, as Cycles' BOX filter).
// Deterministic per seed whatever the thread count: camera paths draw from Rng(seed, reference_path,
// pass × pixels + pixel), photons from Rng(seed, reference_photon, pass × photons + index), each pixel is
// accumulated in double by one thread in pass order.
#pragma once
#include <cstdint>
#include <vector>

#include "photonsplat/camera.h"
#include "photonsplat/render_control.h"
#include "photonsplat/stats.h"

namespace ps {

class Scene;

struct ReferenceSettings {
    int samples = 64;                  // camera paths per pixel; one per pass
    uint64_t seed = 0;
    int threads = 0;                   // 0 = all cores
    int max_bounces = 16;              // as Cycles' Max Bounces: camera-path vertices 0..N scatter (0: direct
                                       // light); specular bounces of a photon
    uint64_t caustic_photons = 100000; // photon paths emitted per pass (0 = no photon mapping: pure path tracing,
                                       // which then misses L S+ D paths of point lights and suns)
    float caustic_radius = 0.0f;       // photon radius of the first pass, world units; 0 = automatic
    double time_limit = 0.0;           // seconds; stops after the pass that reaches it (>= 1 pass); 0 = none
};

void validate(const ReferenceSettings& settings);  // throws InvalidInput naming the field

// The automatic first-pass radius: half of render()'s default radius for that many photons (caustics are
// sharp; the radius then shrinks pass after pass, and the passes average the noise out).
float default_caustic_radius(const Scene& scene, uint64_t photons_per_pass);

struct ReferenceResult {
    int width = 0, height = 0;
    std::vector<float> rgba;  // height × width × 4, linear radiance, alpha 1, row 0 = TOP
    Stats stats;              // seconds, counters, values (values["samples"] = passes actually done)
};

// Throws InvalidInput for bad settings, Cancelled when control asks it to stop.
ReferenceResult render_reference(const Scene& scene, const Camera& camera, const ReferenceSettings& settings,
                                 RenderControl& control);

}  // namespace ps
