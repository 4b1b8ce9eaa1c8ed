// One frame, the whole pipeline: view samples → direct light → cluster hierarchy → photons → splat → image.
#pragma once
#include <cstdint>
#include <vector>

#include "photonsplat/camera.h"
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
    int directional_level = -1;       // directional method: hierarchy level from the leaves; -1 = from the radius
    bool caustics_pass = false;       // also splat the caustic photons (L S+ D) alone into RenderResult::caustics
    bool transparent = false;         // film transparency: alpha 0 and no background where camera rays escape
};

void validate(const RenderSettings& settings);  // throws InvalidInput naming the field

// The radius used when settings.radius is 0: a fraction of the scene's size, shrinking with photon count.
float default_radius(const Scene& scene, uint64_t photons);

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

// Throws InvalidInput for bad settings, Cancelled when control asks it to stop.
RenderResult render(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                    RenderControl& control);

}  // namespace ps
