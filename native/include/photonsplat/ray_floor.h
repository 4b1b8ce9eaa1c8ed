// Embree's floor for a frame: the frame's primary rays (one through each pixel's centre) traced as coherent
// packets of 4 × 2 pixels, closest hits only, nothing shaded. The benchmark prints every ray-traced stage's rays
// per second beside it (docs/benchmarks.md): a stage near it spends its time in Embree, one far from it in our
// own code or in rays that are costlier than a camera's.
#pragma once
#include <cstdint>

namespace ps {

class Scene;
class Camera;

struct RayFloor {
    uint64_t rays = 0;
    double seconds = 0.0;
    uint64_t hits = 0;  // rays that hit something (a floor over sky is cheaper than one over geometry)
};

RayFloor measure_ray_floor(const Scene& scene, const Camera& world_camera);

}  // namespace ps
