// One frame, the whole pipeline: view samples → direct light → cluster hierarchy → photons → splat → image.
#pragma once
#include <cstdint>
#include <vector>

#include "photonsplat/camera.h"
#include "photonsplat/kernel_radius.h"
#include "photonsplat/render_control.h"
#include "photonsplat/settings.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"

namespace ps {

class Scene;


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
// own random streams (iteration_seed) and jitter each camera ray inside its pixel.
struct IterationParams {
    uint32_t index = 0;
    float radius = 0.0f;  // > 0: the kernel radius of this pass
};
uint64_t iteration_seed(uint64_t seed, uint32_t pass);  // = seed for pass 0

// The radius of pass 0: settings.radius, or when that is 0 default_radius, except for a progressive render
// that the boundary correction does not cover (switched off, or directional, whose approximate passes it
// skips): automatic_radius (kernel_radius.h, which depends on what the camera sees).
float first_radius(const Scene& scene, const Camera& camera, const RenderSettings& settings);

// One pass of the pipeline (the whole of a one-shot render). Throws InvalidInput, Cancelled.
RenderResult render_iteration(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                         const IterationParams& pass, RenderControl& control);

// The render settings ask for: one pass (settings.iterations == 1: render_iteration of pass 0), or a progressive
// render (progressive.h) stopped by settings.iterations, settings.time_limit or a cancel. A cancel before the first
// pass is done throws Cancelled; a cancel after it returns the mean of the passes done, with
// stats.values["cancelled"] = 1. Throws InvalidInput for bad settings.
RenderResult render(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                    RenderControl& control);

// (The memory check of a frame is memory_budget.h's check_frame_memory.)

}  // namespace ps
