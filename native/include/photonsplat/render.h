// One frame, the whole pipeline: view samples → direct light → cluster hierarchy → photons → splat → image.
#pragma once
#include <cstdint>
#include <vector>

#include "photonsplat/camera.h"
#include "photonsplat/kernel_radius.h"
#include "photonsplat/render_control.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"

namespace ps {

class Scene;

struct RenderSettings {
    uint64_t photons = 200000;        // photon paths emitted
    float radius = 0.0f;              // kernel radius in world units; 0 = derived from the scene's size
    SplatMethod method = SplatMethod::cluster_cone;
    int max_bounces = 8;              // photon path length bound, and camera-path specular depth bound
    uint64_t seed = 0;
    int threads = 0;                  // 0 = all cores
    int direct_samples = 4;           // shadow rays per light per view sample (soft shadows)
    float normal_tolerance = 60.0f;   // τ in degrees: photons on surfaces turned further away are ignored
    float plane_distance = 0.0f;      // κ of the plane-distance test (stacked surfaces); 0 = off
    Kernel kernel = Kernel::uniform;  // density-estimation kernel
    // Divide each view sample's splatted light by the part of its kernel disc that lies on a like-facing surface
    // (kernel_coverage.h): removes the darkening of corners, edges and thin parts (boundary bias). Every method
    // but directional, whose blocks are not kernel discs (it is corrected where it falls back to exact).
    bool boundary_correction = true;
    int directional_level = -1;       // directional method: hierarchy level from the leaves; -1 = from the radius
    uint64_t memory_budget = 0;       // bytes the render may hold; 0 = 3/4 of available memory (memory_budget.h)
    bool guide_photons = true;        // emit sun photons where pilot paths found them stored (emission_guide.h)
    // Extra photons per pass aimed at mirror and glass objects from point, spot and area lights, as a fraction
    // of `photons`; they only add caustic photons (caustic_aim.h). 0 = off; nothing is added without mirrors
    // or glass.
    float aimed_photons = 0.1f;
    bool caustics_pass = false;       // also splat the caustic photons (L S+ D) alone into RenderResult::caustics
    bool transparent = false;         // film transparency: alpha 0 and no background where camera rays escape
    // Progressive rendering (progressive.h): passes of new photons, jittered camera rays and a shrinking radius,
    // averaged. 1 = the paper's one-shot method, exactly the image of a single pass.
    uint32_t passes = 1;              // 0 = no pass limit (then time_limit must be > 0)
    double time_limit = 0.0;          // seconds of rendering; 0 = none. A pass predicted to end past it is not started
    float alpha = 2.0f / 3.0f;        // Knaus & Zwicker: r_i² = r_{i−1}²·(i−1+α)/i; in (0, 1], 1 = fixed radius
};

void validate(const RenderSettings& settings);  // throws InvalidInput naming the field

struct RenderResult {
    int width = 0, height = 0;
    std::vector<float> rgba;   // height × width × 4, linear radiance, row 0 = TOP of the image
    // Per-pixel components, height × width × 3 each; rgba = emission + direct + indirect.
    std::vector<float> emission, direct, indirect;
    // The part of `indirect` carried by caustic photons (height × width × 3); empty unless settings.caustics_pass.
    std::vector<float> caustics;
    // First camera hit, as Cycles' passes: world-space normal (height × width × 3, 0 where nothing was hit) and
    // depth along the camera axis (height × width, kNoDepth where nothing was hit).
    std::vector<float> normal, depth;
    static constexpr float kNoDepth = 1e10f;  // Cycles' depth of the background
    Stats stats;
};

// Which pass of a progressive render is being rendered, and with what radius. Pass 0 keeps settings.seed and
// pixel-centred camera rays, so a one-pass render is the paper's one-shot image; later passes draw from their
// own random streams (pass_seed) and jitter each camera ray inside its pixel.
struct PassParams {
    uint32_t index = 0;
    float radius = 0.0f;  // > 0: the kernel radius of this pass
};
uint64_t pass_seed(uint64_t seed, uint32_t pass);  // = seed for pass 0

// The radius of pass 0: settings.radius, or when that is 0 default_radius, except for a progressive render
// that the boundary correction does not cover (switched off, or directional, whose approximate passes it
// skips): automatic_radius (kernel_radius.h, which depends on what the camera sees).
float first_radius(const Scene& scene, const Camera& camera, const RenderSettings& settings);

// One pass of the pipeline (the whole of a one-shot render). Throws InvalidInput, Cancelled.
RenderResult render_pass(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                         const PassParams& pass, RenderControl& control);

// The render settings ask for: one pass (settings.passes == 1: render_pass of pass 0), or a progressive
// render (progressive.h) stopped by settings.passes, settings.time_limit or a cancel. A cancel before the first
// pass is done throws Cancelled; a cancel after it returns the mean of the passes done, with
// stats.values["cancelled"] = 1. Throws InvalidInput for bad settings.
RenderResult render(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                    RenderControl& control);

// (The memory check of a frame is memory_budget.h's check_frame_memory.)

}  // namespace ps
