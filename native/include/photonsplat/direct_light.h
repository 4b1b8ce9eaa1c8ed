// Stage 2 of the pipeline: direct light at every view sample by shadow rays (next-event estimation).
#pragma once
#include <vector>

#include <glm/vec3.hpp>

namespace ps {

class Scene;
class RenderControl;
struct Stats;
struct ViewSamples;

struct DirectLightSettings {
    uint64_t seed = 0;
    int samples_per_light = 4;  // shadow rays per light with a size (a point of radius 0 or a 0° sun needs 1)
};

// Reflected direct radiance per view sample (index-aligned with samples.samples), throughput included.
std::vector<glm::vec3> compute_direct_light(const Scene& scene, const ViewSamples& samples,
                                            const DirectLightSettings& settings, const RenderControl& control,
                                            Stats& stats);

}  // namespace ps
