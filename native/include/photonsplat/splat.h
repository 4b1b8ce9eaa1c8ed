// Stage 5–6 of the pipeline: splat photons onto view samples and shade them.
// Every exact method uses the SAME per-sample test and contribution below, in the same order of photons
// (ascending photon index per sample), so an exact method equals `brute` up to float summation order.
#pragma once
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "photonsplat/bump_shadowing.h"
#include "photonsplat/photon_shading_normals.h"
#include "photonsplat/shading.h"
#include "photonsplat/photons.h"
#include "photonsplat/view_samples.h"

namespace ps {

class Camera;
class RenderControl;
struct Stats;
struct ClusterHierarchy;

// The splatting methods (splatter.h registers them). All but `directional` are exact: the same photons give the
// same image as `brute`, up to float summation order.
enum class SplatMethod {
    brute,         // every photon × every view sample: the oracle
    tiled,         // Mara et al. 2013: 32×32 screen tiles with per-tile depth bounds
    cluster,       // view-sample cluster hierarchy, sphere-vs-box culling, per-leaf photon lists
    cluster_cone,  // the paper's cluster-trivial: the hierarchy plus normal-cone trivial reject and accept
    directional,   // the paper's approximation: flux per node of a fixed level in 8 direction bins
    gather,        // the classic alternative: each view sample gathers photons from a hashed uniform grid
};
const char* to_string(SplatMethod method);
SplatMethod splat_method_from_string(const std::string& name);  // throws InvalidInput
std::vector<std::string> splat_method_names();                   // in the order above

// The density-estimation kernel; both integrate to 1 over the disc of radius r.
enum class Kernel {
    uniform,       // K = 1/(π r²): makes the cluster_cone trivial accept exact
    epanechnikov,  // K = 2/(π r²)·(1 − d²/r²): smoother
};
const char* to_string(Kernel kernel);
Kernel kernel_from_string(const std::string& name);  // throws InvalidInput

// Default of SplatParams::max_pairs_in_memory: 32 Mi (leaf, photon) pairs, about 300 MB of pair buffers and
// per-leaf lists at the peak. A 1080p frame with 200k photons at a typical radius fits in one batch.
constexpr uint64_t kDefaultMaxPairsInMemory = uint64_t(1) << 25;

struct SplatParams {
    float radius = 0.0f;                 // kernel radius r > 0, world units
    float cos_normal_tolerance = 0.5f;   // cos τ: reject when n_x·n_p <= cos τ
    float plane_distance_factor = 0.0f;  // κ: reject when |n_x·(x−p)| >= κ·r; 0 disables the test
    uint64_t emitted = 0;                // N_emitted of the photon map
    Kernel kernel = Kernel::uniform;
    int directional_level = -1;          // directional only: hierarchy level counted from the leaves; -1 = from r
    // Cluster method only: how many (leaf, photon) pairs may be held at once, each about 9 bytes at the peak
    // (4 in the traversal buffers, 4 in the per-leaf lists, plus the buffers' growth slack). The pairs grow as
    // photons × leaves touched, which a radius as large as the scene makes photons × all leaves: photons are then
    // splatted in consecutive batches that stay under this cap, with the same result. (Ranges of photons being
    // traversed can each go past their share by the pairs of one photon; that is kept under half the cap, unless
    // one photon alone has more.) Must be >= 1; small values are for tests (they make many batches).
    uint64_t max_pairs_in_memory = kDefaultMaxPairsInMemory;
    // The share of each sample's BRDF the photons are splatted with: the whole, except for the Caustics output's
    // splats (render.cpp), which weigh its photons by how Cycles would label the sample's own scatter (sample_brdf).
    LabelShare label_share = LabelShare::whole;
};

// Checks what every method relies on: a positive finite radius, N_emitted > 0 when photons are stored, a
// pair cap >= 1. Throws InvalidInput naming the field.
void validate(const SplatParams& params, const PhotonMap& photons);

// For the hierarchy methods: the hierarchy was built over these samples, and photon indices fit 32 bits.
void validate(const ClusterHierarchy& hierarchy, const ViewSamples& samples, const PhotonMap& photons);

// Photon positions relative to the view samples' origin: all methods splat in these coordinates.
std::vector<glm::vec3> relative_photon_positions(const PhotonMap& photons, const glm::vec3& origin);

// The per-sample test: distance, facing, normal agreement, optional plane distance.
// `p` is the photon position relative to the samples' origin.
inline bool photon_reaches_sample(const ViewSample& s, const glm::vec3& p, const Photon& photon,
                                  const SplatParams& params) {
    const glm::vec3 d = s.position - p;
    const float r = params.radius;
    if (!(glm::dot(d, d) < r * r)) return false;
    // Inside a transmitting surface and outside it are different places, however close (view_samples.h).
    if (((photon.flags & kInsidePhoton) != 0) != ((s.flags & kInsideSample) != 0)) return false;
    if (!(glm::dot(s.normal, photon.wi) > 0.0f)) return false;
    if (!(glm::dot(s.normal, photon.normal) > params.cos_normal_tolerance)) return false;
    if (params.plane_distance_factor > 0.0f &&
        !(std::fabs(glm::dot(s.normal, d)) < params.plane_distance_factor * r))
        return false;
    return true;
}

// Whether a Lambert-only sample takes its albedo under `share`: it is labelled diffuse whole.
inline bool lambert_takes(LabelShare share) { return share != LabelShare::other && share != LabelShare::other_parts; }

// f_r(x, ωi, ωo): the view sample's BRDF for light arriving from ωi (towards the light), seen along s.wo.
// albedo/π, plus for kGlossy samples their reflection lobes (shading.h); `lobes` is ViewSamples::lobes.data().
// `share`: all of it, or what the Caustics output takes (render.cpp: splat_caustics) of the photons' shares:
//   - diffuse / other: the share of f Cycles' camera paths label diffuse or not (LabelShare; a Lambert-only sample
//     is labelled diffuse whole);
//   - at a kAfterDiffuseScatter sample, whose other parts Cycles' toggles drop: diffuse is its diffuse parts' f and
//     other nothing, and other_parts (which every other sample takes nothing of) the f of those dropped parts.
// A kBumpShadowed sample's diffuse parts take Cycles' bump shadowing term of ωi (bump_shadowing.h).
inline glm::dvec3 sample_brdf(const ViewSample& s, const Lobe* lobes, const glm::vec3& wi, LabelShare share) {
    constexpr double inv_pi = 0.318309886183790671538;
    if (s.flags & kAfterDiffuseScatter) {
        if (share == LabelShare::other) return glm::dvec3(0.0);
        if (share == LabelShare::diffuse) share = LabelShare::diffuse_parts;
    } else if (share == LabelShare::other_parts) {
        return glm::dvec3(0.0);
    }
    const float diffuse_term =
        s.flags & kBumpShadowed ? bump_shadowing_term(bump_form_of(s.flags), s.smooth_normal, s.shading_normal, wi)
                                : 1.0f;
    if (!(s.flags & kGlossy))
        return lambert_takes(share) ? glm::dvec3(s.albedo) * (inv_pi * diffuse_term) : glm::dvec3(0.0);
    return glm::dvec3(bsdf_eval_reflection(s.albedo, lobes + s.lobe_begin, static_cast<int>(s.lobe_count),
                                           s.shading_normal, wi, s.wo, share, s.selection_floor, diffuse_term));
}

// The kernel relative to the uniform one, so that finish_sample's 1/(π r²) applies to both:
// 1 for uniform; 2·(1 − d²/r²) for Epanechnikov. `d` is x − p.
inline double kernel_weight(const glm::vec3& d, const SplatParams& params) {
    if (params.kernel == Kernel::uniform) return 1.0;
    const double r2 = static_cast<double>(params.radius) * params.radius;
    return 2.0 * (1.0 - static_cast<double>(glm::dot(d, d)) / r2);
}

// Whether the sample's f alone (sample_brdf) is what it takes from every photon: its shading normal is its
// triangle's (photon_shading_normals.h). Else each photon also counts its arrival ratio, and the methods' shortcuts
// for diffuse samples (one f for all ω_i: cone accepts, directional sums) do not apply to it; nor do they to a
// bump-shadowed sample, whose diffuse f depends on ω_i.
inline bool sample_shading_tilted(const ViewSample& s) {
    return shading_normal_tilted(s.shading_normal, s.normal) || (s.flags & kBumpShadowed);
}

// The share of a photon's flux that the sample responds to, beyond f: 1 unless the sample's shading normal is
// tilted, else (n_s·ω_i) over the photon's own (n_g·ω_i), since its flux is per unit of its own triangle's area
// (which may be a neighbour of the sample's, with another normal, on a low-poly mesh).
inline double photon_arrival_share(const ViewSample& s, const Photon& photon) {
    return shading_normal_tilted(s.shading_normal, s.normal)
               ? double(photon_arrival_ratio(s.shading_normal, photon.normal, photon.wi))
               : 1.0;
}

// f_r·Φ·w for one photon that passed photon_reaches_sample (f_r with its shading normal's arrival ratio): what a
// sample accumulates (in double) before finish_sample. `p` is the photon position relative to the samples' origin.
inline glm::dvec3 photon_reflected_flux(const ViewSample& s, const Lobe* lobes, const glm::vec3& p,
                                        const Photon& photon, const SplatParams& params) {
    const glm::dvec3 f = sample_brdf(s, lobes, photon.wi, params.label_share) * glm::dvec3(photon.power) *
                         photon_arrival_share(s, photon);
    return params.kernel == Kernel::uniform ? f : f * kernel_weight(s.position - p, params);
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
// The cluster method also reports counters "leaf_photon_pairs" and "splat_batches" (photons are splatted in
// consecutive batches under SplatParams::max_pairs_in_memory), bytes "leaf_photon_lists" (the peak held by the
// pair buffers and per-leaf lists together) and "splat_sample_sums" (the per-sample sums kept between batches,
// 0 when there is one).
std::vector<glm::vec3> splat_cluster(const ClusterHierarchy& hierarchy, const ViewSamples& samples,
                                     const PhotonMap& photons, const SplatParams& params,
                                     const RenderControl& control, Stats& stats);
// The cluster method with normal-cone trivial reject and accept (needs a hierarchy built with cones).
std::vector<glm::vec3> splat_cluster_cone(const ClusterHierarchy& hierarchy, const ViewSamples& samples,
                                          const PhotonMap& photons, const SplatParams& params,
                                          const RenderControl& control, Stats& stats);
// Mara et al. 2013: per-tile frusta with depth bounds, photons binned by their sphere's screen bounds.
std::vector<glm::vec3> splat_tiled(const ViewSamples& samples, const Camera& camera, const PhotonMap& photons,
                                   const SplatParams& params, const RenderControl& control, Stats& stats);
// Used by tiled: the screen rectangle (x_min, y_min, x_max, y_max), in pixel units (y = 0 at the top), holding
// every image point whose camera ray passes within `radius` of `center` (relative to camera.position());
// infinite when the sphere reaches the eye plane of a perspective camera.
glm::dvec4 tiled_sphere_screen_bounds(const Camera& camera, const glm::vec3& center, float radius);
// The approximate variant: traversal stops at level params.directional_level (or one chosen from r).
std::vector<glm::vec3> splat_directional(const ClusterHierarchy& hierarchy, const ViewSamples& samples,
                                         const PhotonMap& photons, const SplatParams& params,
                                         const RenderControl& control, Stats& stats);
// The directional method's test for giving up its bins: the median leaf (by the samples it holds) is more than
// 2r across. With directional_level -1 it then splats exactly (splat_cluster); progressive passes apply the same
// test to an explicit level, so that the running mean converges to the exact methods' answer.
bool directional_leaves_exceed_radius(const ClusterHierarchy& hierarchy, float radius);
// Gathering from a hashed uniform grid of photons.
std::vector<glm::vec3> splat_gather(const ViewSamples& samples, const PhotonMap& photons, const SplatParams& params,
                                    const RenderControl& control, Stats& stats);

}  // namespace ps
