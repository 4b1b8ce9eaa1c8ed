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
    uint64_t memory_budget = 0;       // bytes the render may hold; 0 = 3/4 of available memory (memory_budget.h)
};

void validate(const RenderSettings& settings);  // throws InvalidInput naming the field

// The radius used when settings.radius is 0: a fraction of the scene's size, shrinking with photon count.
float default_radius(const Scene& scene, uint64_t photons);

struct RenderResult {
    int width = 0, height = 0;
    std::vector<float> rgba;   // height × width × 4, linear radiance, row 0 = TOP of the image
    // Per-pixel components, height × width × 3 each; rgba = emission + direct + indirect.
    std::vector<float> emission, direct, indirect;
    Stats stats;
};

// Throws InvalidInput for bad settings, Cancelled when control asks it to stop.
RenderResult render(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                    RenderControl& control);

}  // namespace ps
