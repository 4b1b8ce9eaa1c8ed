// The photon-mapping half of the reference renderer (see reference.h for the partition of path space):
// caustic photons from point and spot lights and suns, and their density estimate at a camera-path vertex.
#pragma once
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "photonsplat/photons.h"
#include "photonsplat/splat.h"

namespace ps {

class LightSources;
class RenderControl;
class Scene;

// Whether the L S+ D paths of source i belong to photon mapping: point and spot lights and suns, of any size
// (area lights and emitters are path traced: their caustics are found by BSDF rays, as Cycles finds them).
// Spots joined on 26 Nov: path tracing a small spot's caustic through sharp glass left fireflies that a pair of
// seeds agreeing within 1 % did not see (differential seeds 4 and 33, 1.033 and 1.022 of Cycles).
bool caustics_by_photons(const LightSources& sources, size_t i);

// One pass's caustic photons in a hashed uniform grid (cell = radius), positions relative to `origin`.
class CausticPhotonMap {
public:
    CausticPhotonMap(std::vector<Photon> photons, uint64_t emitted, float radius, const glm::vec3& origin);

    // Radiance reflected towards s.wo by the photons around s (s.position relative to origin()), times
    // s.throughput: the per-sample test, BRDF and uniform kernel of render() (splat.h), τ = 60°.
    glm::vec3 radiance(const ViewSample& s, const Lobe* lobes) const;
    // Radiance that the photons around a vertex arriving from the other side of its surface send through its
    // transmission parts (b's) towards b.wo, times s.throughput: a rough glass surface lit through a mirror or
    // glass from the side the path is not on. `s` is the vertex as seen from that other side (its normal and
    // inside flag turned over), so that the photons stored there pass the same test.
    glm::vec3 transmitted_radiance(const ViewSample& s, const Bsdf& b) const;
    const glm::vec3& origin() const { return origin_; }
    size_t size() const { return photons_.size(); }

private:
    std::vector<Photon> photons_;         // sorted by cell; positions relative to origin_
    std::vector<glm::vec3> positions_;    // the same, for the splat.h test
    std::unordered_map<uint64_t, std::pair<uint32_t, uint32_t>> cells_;  // key → [begin, end)
    glm::vec3 origin_;
    glm::vec3 lo_{0.0f};
    float cell_ = 1.0f;
    int64_t extent_[3] = {1, 1, 1};
    SplatParams params_;

    uint64_t key(int64_t x, int64_t y, int64_t z) const { return (uint64_t(z) << 42) | (uint64_t(y) << 21) | uint64_t(x); }
    int64_t cell_of(float v, int axis) const;
    // Σ flux(photon, its position) over the photons that reach s, finished as a radiance (splat.h).
    template <class Flux>
    glm::vec3 gather(const ViewSample& s, const Flux& flux) const;
};

// Traces `count` photon paths of pass `pass` from the point and spot lights and suns (chosen by power), through
// mirrors and glass (Russian roulette on the tint, as photons.cpp), and keeps those that reach a non-specular surface
// after at least one specular bounce (and at most max_specular_bounces), stored there. Deterministic for any
// thread count. Counters: "caustic_photons_emitted", "caustic_photons_stored".
std::vector<Photon> trace_caustic_photons(const Scene& scene, const LightSources& sources, uint64_t count,
                                          int max_specular_bounces, uint64_t seed, uint64_t pass,
                                          const RenderControl& control, Stats& stats);

}  // namespace ps
