// The path-tracing half of the reference renderer (see reference.h for the partition of path space).
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "photonsplat/camera.h"

namespace ps {

class CausticPhotonMap;
class LightSources;
class Rng;
class Scene;

struct PathTracerContext {
    const Scene& scene;
    const LightSources& sources;
    const CausticPhotonMap* caustics;        // this pass's photons; nullptr = no photon mapping
    std::vector<uint8_t> photon_caustics;    // per source: its L S+ D paths belong to the photons
    int max_bounces;
    bool transparency = false;               // scene_has_transparency: shadow rays look through transparent closures
    bool terminator_offsets = false;         // Scene::any_terminator_offset: shadow rays may start lifted
};

// Per-thread tallies, added into the render's counters once per pass.
struct PathCounters {
    uint64_t rays = 0;         // closest-hit rays
    uint64_t shadow_rays = 0;
    uint64_t non_finite = 0;   // path samples dropped because they came out NaN or infinite
};

// Radiance arriving at the camera along `ray` (one sample of one camera path).
glm::vec3 trace_reference_path(const PathTracerContext& context, Ray ray, Rng& rng, PathCounters& counters);

}  // namespace ps
