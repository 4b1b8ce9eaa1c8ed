// Stage 5–6 of the pipeline: splat photons onto view samples and shade them.
// Every exact method uses the SAME per-sample test and contribution below, in the same order of photons
// (ascending photon index per sample), so an exact method equals `brute` up to float summation order.
#pragma once
#include <cmath>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "photonsplat/photons.h"
#include "photonsplat/view_samples.h"

namespace ps {

class RenderControl;
struct Stats;
struct ClusterHierarchy;

enum class SplatMethod {
    brute,    // every photon × every view sample: the oracle
    cluster,  // view-sample cluster hierarchy, sphere-vs-box culling, per-leaf photon lists
};
const char* to_string(SplatMethod method);
SplatMethod splat_method_from_string(const std::string& name);  // throws InvalidInput

struct SplatParams {
    float radius = 0.0f;                 // kernel radius r > 0, world units
    float cos_normal_tolerance = 0.5f;   // cos τ: reject when n_x·n_p <= cos τ
    float plane_distance_factor = 0.0f;  // κ: reject when |n_x·(x−p)| >= κ·r; 0 disables the test
    uint64_t emitted = 0;                // N_emitted of the photon map
};

// Photon positions relative to the view samples' origin: all methods splat in these coordinates.
std::vector<glm::vec3> relative_photon_positions(const PhotonMap& photons, const glm::vec3& origin);

// The per-sample test of the design (§3): distance, facing, normal agreement, optional plane distance.
// `p` is the photon position relative to the samples' origin.
inline bool photon_reaches_sample(const ViewSample& s, const glm::vec3& p, const Photon& photon,
                                  const SplatParams& params) {
    const glm::vec3 d = s.position - p;
    const float r = params.radius;
    if (!(glm::dot(d, d) < r * r)) return false;
    if (!(glm::dot(s.normal, photon.wi) > 0.0f)) return false;
    if (!(glm::dot(s.normal, photon.normal) > params.cos_normal_tolerance)) return false;
    if (params.plane_distance_factor > 0.0f &&
        !(std::fabs(glm::dot(s.normal, d)) < params.plane_distance_factor * r))
        return false;
    return true;
}

// f_r(x, ωi, ωo)·Φ for one accepted photon: what a sample accumulates (in double) before the kernel.
inline glm::dvec3 photon_reflected_flux(const ViewSample& s, const Photon& photon) {
    constexpr double inv_pi = 0.318309886183790671538;
    return glm::dvec3(s.albedo) * inv_pi * glm::dvec3(photon.power);
}

// Turns a sample's accumulated Σ f_r·Φ into radiance: × throughput × K / N_emitted, uniform K = 1/(π r²).
inline glm::vec3 finish_sample(const ViewSample& s, const glm::dvec3& reflected_flux, const SplatParams& params) {
    constexpr double pi = 3.14159265358979323846;
    const double r = params.radius;
    const double scale = 1.0 / (pi * r * r * static_cast<double>(params.emitted));
    return glm::vec3(reflected_flux * scale * glm::dvec3(s.throughput));
}

// Indirect radiance per view sample (index-aligned with samples.samples). Counters go to stats:
// "photon_node_tests", "photon_sample_tests", "contributing_pairs"; bytes of per-method structures too.
std::vector<glm::vec3> splat_brute(const ViewSamples& samples, const PhotonMap& photons, const SplatParams& params,
                                   const RenderControl& control, Stats& stats);
std::vector<glm::vec3> splat_cluster(const ClusterHierarchy& hierarchy, const ViewSamples& samples,
                                     const PhotonMap& photons, const SplatParams& params,
                                     const RenderControl& control, Stats& stats);

}  // namespace ps
