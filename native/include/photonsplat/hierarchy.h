// Stage 3 of the pipeline: the view-sample cluster hierarchy (Sintorn et al. 2014, as used by Moreau et al.
// 2016). Leaves are the distinct cluster keys: an 8×8 pixel tile and a logarithmic depth slice, interleaved as
// a Morton code. Parents are key prefixes (3 bits a level, so up to 8 children); single-child chains are
// collapsed. Samples reached through mirrors or glass are keyed by their real 3D position in a subtree of
// their own, because their pixel says nothing about where they are.
// Built with cones (ClusterBuildOptions::normal_cones), every node also gets a normal cone bounding its samples'
// geometric normals and flags saying whether all of them are diffuse-only and regular: what the cluster_cone
// splat needs for its trivial reject and accept (Moreau et al. 2016).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace ps {

struct ViewSamples;
class Camera;

struct ClusterNode {
    glm::vec3 box_min, box_max;   // bounds of the node's samples, relative to ViewSamples::origin
    uint32_t first_child;         // children are nodes[first_child, first_child + child_count)
    uint32_t child_count;         // 0 for a leaf
    uint32_t sample_begin;        // the node's samples are sample_order[sample_begin, sample_end)
    uint32_t sample_end;
};

// A cone of directions around a unit axis: every direction at an angle <= θ from `axis`, θ in [0, π], kept as
// cos θ and sin θ. θ = π (cos_angle = −1) is the full cone: it says nothing and never culls.
// Cones are computed in double and inflated (1e-4 rad at the leaves), so the stored float cone contains every
// normal of its subtree, normalised, with room to spare for float rounding in the tests that use it.
struct NormalCone {
    glm::vec3 axis{0.0f, 0.0f, 1.0f};
    float cos_angle = -1.0f;
    float sin_angle = 0.0f;
    bool full() const { return cos_angle <= -1.0f; }
};

// Per-node flags (ClusterHierarchy::node_flags).
enum ClusterNodeFlags : uint8_t {
    kNodeDiffuseOnly = 1u,  // no sample has kGlossy (or a nonzero specular tint) or a tilted shading normal
                            // (photon_shading_normals.h): what a sample takes of a photon ignores its direction
    kNodeRegular = 2u,      // every sample has a finite position and a finite unit (±1e-4) geometric normal
};

// What the directional method needs of a leaf's samples, gathered while the leaf's box is built (the samples are
// in cache then): with it, a cut node made of flat leaves is described without reading its samples again.
// Only samples with a finite position and a finite normal count ("regular" samples). A leaf whose normals spread
// to kNarrowLeafAngle or more (its tile holds two walls of a crease, or three of a corner) is summarised as
// parts, its samples split in two by orientation and each side again while it is that wide, up to
// kLeafSplitLevels times; each part is a LeafSummary of its own samples. The directional method splits nodes by
// whole parts narrower than kNarrowLeafAngle.
constexpr float kNarrowLeafAngle = 10.0f * 3.14159265f / 180.0f;  // rad
constexpr int kLeafSplitLevels = 2;                                // at most 4 parts per leaf

struct LeafSummary {
    glm::vec3 centroid{0.0f};    // mean position of its regular samples, relative to ViewSamples::origin
    float radius = 0.0f;         // largest distance from the centroid to one of them
    glm::vec3 normal_sum{0.0f};  // Σ of their normals, each normalised
    float cone_angle = 3.14159265f;  // rad: every normal within this of normalize(normal_sum); π = no bound
    float slab = 0.0f;           // largest |normalize(normal_sum)·(x − centroid)|: the leaf's thickness
    uint32_t count = 0;          // regular samples
};

struct ClusterBuildOptions {
    bool normal_cones = false;    // also build ClusterHierarchy::cones and node_flags (the cluster_cone method)
    bool leaf_summaries = false;  // also build ClusterHierarchy::leaf_summaries (the directional method)
};

// Parameters of the cluster key, taken from the camera.
struct ClusterKeyParams {
    int width = 0, height = 0;
    bool orthographic = false;
    float near_clip = 0.1f;           // perspective: depth of slice 0
    float vertical_half_extent = 1.0f; // perspective: tan(fovY/2); orthographic: half view height
    static ClusterKeyParams from_camera(const Camera& camera);
};

struct ClusterHierarchy {
    static constexpr int kTileSize = 8;

    std::vector<ClusterNode> nodes;       // root is nodes[root]
    uint32_t root = 0;
    std::vector<uint32_t> sample_order;   // indices into ViewSamples::samples, grouped by leaf
    std::vector<uint32_t> leaves;         // node indices of the leaves, in key order
    int depth = 0;                        // levels from root to the deepest leaf
    // Only when built with ClusterBuildOptions::normal_cones (else empty), index-aligned with `nodes`:
    std::vector<NormalCone> cones;        // the node's samples' geometric normals lie in its cone
    std::vector<uint8_t> node_flags;      // ClusterNodeFlags true of every sample of the node
    // Only with ClusterBuildOptions::leaf_summaries (else empty): leaf l (index into `leaves`) is summarised by
    // the parts leaf_summaries[leaf_summary_begin[l], leaf_summary_begin[l + 1]), at least one.
    std::vector<LeafSummary> leaf_summaries;
    std::vector<uint32_t> leaf_summary_begin;  // leaves.size() + 1 entries
    std::vector<uint8_t> sample_part;          // per sample_order entry: its part's number within its leaf

    bool empty() const { return nodes.empty(); }
    bool has_cones() const {
        return !nodes.empty() && cones.size() == nodes.size() && node_flags.size() == nodes.size();
    }
    size_t bytes() const;       // nodes, sample order, leaves: not the cones
    size_t cone_bytes() const;  // cones and node flags
    size_t summary_bytes() const {
        return leaf_summaries.capacity() * sizeof(LeafSummary) + leaf_summary_begin.capacity() * sizeof(uint32_t) +
               sample_part.capacity();
    }
};

// Depth slice of the cluster key (Olsson et al. 2012): k = floor(ln(z/near) / ln(1 + 2 tan(fovY/2) / tilesY)),
// clamped to [0, 2^21 − 1]; orthographic cameras use linear slices one tile high.
uint32_t depth_slice(float depth, const ClusterKeyParams& params);

ClusterHierarchy build_cluster_hierarchy(const ViewSamples& samples, const ClusterKeyParams& params,
                                         const ClusterBuildOptions& options = {});

// The cone of a set of unit directions as the hierarchy builds it for a leaf: axis = their normalised sum,
// θ = the largest angle to it + 1e-4 rad; full when the sum (nearly) vanishes. Directions are normalised first;
// an empty set gives the full cone. Exposed for tests.
NormalCone cone_of_directions(const std::vector<glm::vec3>& directions);
// A cone containing both, as the hierarchy merges children. Exposed for tests.
NormalCone merge_cones(const NormalCone& a, const NormalCone& b);

// The node tests of the cluster_cone traversal (Moreau et al. 2016), all conservative
// against the per-sample test of splat.h AS IT IS COMPUTED IN FLOAT: a reject never drops a sample that test
// would take, an accept never includes one it would refuse.
//
// Cone tests, for a cone (a, θ) containing every normal of a node. With c = a·ω for unit ω, the angle ψ between
// a and ω exceeds α exactly when c < cos α, so each test compares c with the cosine of a sum of angles written
// with cos θ, sin θ (no acos):
//   R2  every n faces away (n·ωi <= 0):   θ < π/2 and ψ_w > π/2 + θ      ⇐  c_w < −sin θ − ε
//   A2  every n faces ωi (n·ωi > 0):      θ < π/2 and ψ_w < π/2 − θ − ε  ⇐  c_w > sin θ + ε
//   R3  every n fails n·n_p > cos τ:      ψ_n > θ + τ_r                  ⇐  c_n < cos(θ + τ_r) − ε
//   A3  every n passes n·n_p > cos τ:     ψ_n < τ_a − θ                  ⇐  c_n > cos(τ_a − θ) + ε
// τ_r and τ_a are τ made conservative for the float dot product of a sample normal of length 1 ± 1e-4 (a node
// with other normals has a full cone and is not regular) with n_p of any length L, whose rounding error is below
// 1e-5·L. ε = 1e-5 covers the rounding of c and of the cosines (~1e-6); the cones carry >= 1e-4 rad of slack.
namespace cone_tests {

constexpr float kEpsilon = 1e-5f;
constexpr double kNormalLengthTolerance = 1e-4;  // what kNodeRegular allows
constexpr double kDotErrorPerLength = 1e-5;

// What the tests need of one photon, computed once per photon by photon_cone.
struct PhotonCone {
    glm::vec3 wi{0.0f};           // unit ωi
    glm::vec3 n{0.0f};            // unit n_p
    bool facing = false;          // ωi is usable: R2 and A2 apply
    bool orientation = false;     // n_p (and cos τ) are usable: R3 and A3 apply
    bool fails_all = false;       // no regular normal can pass n·n_p > cos τ
    bool passes_all = false;      // every regular normal passes it
    bool reject_angle = false;    // τ_r in (0, π): reject_cos/sin hold cos τ_r, sin τ_r
    bool accept_angle = false;    // τ_a in (0, π): accept_cos/sin hold cos τ_a, sin τ_a
    float reject_cos = 0.0f, reject_sin = 0.0f;
    float accept_cos = 0.0f, accept_sin = 0.0f;
};
PhotonCone photon_cone(const glm::vec3& wi, const glm::vec3& photon_normal, float cos_tolerance);

// The four tests below are written with bitwise & and | rather than && and ||: the traversal calls them for
// every node, and evaluating all of a few comparisons costs less than mispredicting a branch.

// R2: every normal of the cone faces away from the photon.
inline bool faces_away(const NormalCone& cone, const PhotonCone& pc) {
    return pc.facing & (cone.cos_angle > 0.0f) & (glm::dot(cone.axis, pc.wi) < -cone.sin_angle - kEpsilon);
}

// A2: every normal of the cone faces the photon.
inline bool faces_photon(const NormalCone& cone, const PhotonCone& pc) {
    return pc.facing & (cone.cos_angle > 0.0f) & (glm::dot(cone.axis, pc.wi) > cone.sin_angle + kEpsilon);
}

// R3: every normal of the cone differs from the photon's by more than τ. A full cone may hold normals that are
// not unit (see kNodeRegular), so it never rejects. θ + τ_r < π is cos θ > −cos τ_r.
inline bool misoriented(const NormalCone& cone, const PhotonCone& pc) {
    const float cs = cone.cos_angle, sn = cone.sin_angle;
    return pc.orientation & !(cs <= -1.0f) &  // not full(), as a comparison: the whole test stays branch-free
           (pc.fails_all | (pc.reject_angle & (cs > -pc.reject_cos) &
                            (glm::dot(cone.axis, pc.n) < cs * pc.reject_cos - sn * pc.reject_sin - kEpsilon)));
}

// A3: every normal of the cone is within τ of the photon's (meaningful for regular nodes only). θ < τ_a is
// cos θ > cos τ_a.
inline bool oriented(const NormalCone& cone, const PhotonCone& pc) {
    const float cs = cone.cos_angle, sn = cone.sin_angle;
    return pc.orientation &
           (pc.passes_all | (pc.accept_angle & (cs > pc.accept_cos) &
                             (glm::dot(cone.axis, pc.n) > cs * pc.accept_cos + sn * pc.accept_sin + kEpsilon)));
}

// Squared distance from p to the farthest point of the box [lo, hi]. Never smaller than what the per-sample test
// computes, dot(x − p, x − p) in float, for an x in the box: rounding is monotone, so per axis
// |fl(x − p)| <= max(|fl(lo − p)|, |fl(hi − p)|), and squaring and summing in the same order are monotone too.
// (Accepting below r²·(1 − 1e-5) also covers a compiler contracting one of them into FMAs.)
inline float max_distance_sq(const glm::vec3& p, const glm::vec3& lo, const glm::vec3& hi) {
    const glm::vec3 far = glm::max(glm::abs(p - lo), glm::abs(hi - p));
    return glm::dot(far, far);
}

// Whether every sample in the box [lo, hi] with a regular normal in the cone passes the plane-distance test
// |n·(x − p)| < κ·r, given that the box lies within sqrt(max_d2) <= r of p. For a unit n within θ <= π/2 of the
// axis a, |n·d| <= |a·d| + sin θ·|d|, and a·d over the box lies between the sums of the per-axis minima and
// maxima of a_i·(lo_i − p_i), a_i·(hi_i − p_i); always |n·d| <= |d|. Margins: normal length, rounding.
inline bool plane_test_passes(const glm::vec3& p, const glm::vec3& lo, const glm::vec3& hi, const NormalCone& cone,
                              float max_d2, float radius, float kappa) {
    const float far = std::sqrt(max_d2);
    float bound = far;
    if (cone.cos_angle > 0.0f) {
        const glm::vec3 a = cone.axis * (lo - p), b = cone.axis * (hi - p);
        const glm::vec3 top = glm::max(a, b), bottom = glm::min(a, b);
        const float along = std::max(top.x + top.y + top.z, -(bottom.x + bottom.y + bottom.z));
        bound = std::min(far, along + cone.sin_angle * far);
    }
    const float margin = float(1.0 + kNormalLengthTolerance) * 1.0001f;
    return bound * margin + 1e-5f * radius < kappa * radius;
}

}  // namespace cone_tests

}  // namespace ps
