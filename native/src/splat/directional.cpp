// The approximate "directional" splat of Moreau et al. 2016: "photon traversal is stopped at a fixed level of
// our hierarchy, and the incoming radiance is accumulated per node and direction, rather than per view sample."
//
// 1. Cut. Levels are counted from the leaves by HEIGHT (a leaf has height 0, a node 1 + its children's largest).
//    The nodes of level L are the cut: every node of height <= L whose parent has height > L (or the root). Along
//    any leaf-to-root path heights strictly increase, so each leaf, hence each sample, lies under exactly one cut
//    node; a leaf whose parent is already above L (single-child chains are collapsed) is its own cut node.
//    L = params.directional_level (clamped to the root's height), or, for -1, the highest level whose median
//    node diagonal (the node holding the median sample) is still <= r: nodes about as large as the kernel, so
//    that a node's samples lie within about r/2 of its centroid. When even the leaves are more than 2r across,
//    that resolution is gone (a radius shrinking iteration after iteration would converge to blocks),
//    and the automatic level falls back to the exact cluster splat.
// 2. Facets. A cut node whose normals spread by more than kSplitAngle (a tile across a corner, a silhouette) is
//    split by orientation into two facets (two seeds, then one k-means step on the normals); any other node is
//    one facet. A facet has its sample centroid, its normal cone, and its own bins: without the split, a corner
//    node's centroid floats off both walls and its bins mix the photons of both, which the exact method keeps
//    apart with its n_x·n_p test.
//    Nodes are described from the summaries of their leaves' parts (built with the hierarchy,
//    ClusterBuildOptions::leaf_summaries; a leaf across a crease is summarised as parts split by orientation)
//    and split by whole parts: a sample belongs to the facet its part went to, so a facet's bounds are exactly
//    its parts' bounds. Only nodes to split that hold a part still wider than kNarrowLeafAngle (more orientations
//    in one tile than it has parts), or whose normals the summaries cannot bound, read their samples again; a
//    sample of theirs belongs to the facet whose axis is closest to its normal. That pass, through
//    sample_order to samples scattered over the frame, cost as much as shading all of them; before leaves were
//    split into parts it still took a fifth of the splat on the atrium.
// 3. Traverse. Each photon walks down to the cut only, rejecting nodes above it by sphere-vs-box as `cluster`
//    does. At a cut node it is deposited into each facet whose centroid is within r, with weight
//    w = kernel_weight(centroid − p), unless the facet's normal cone shows that none of its samples could accept
//    it: all facing away from ωi, all turned from the photon's normal by more than τ, or (κ > 0) all too far from
//    the photon's plane.
// 4. Bins. 8 bins on the hemisphere of the facet's axis: 4 azimuth quadrants × 2 elevation bands split at 60°
//    (equal solid angles); ωi below the horizon, which only a wide cone lets through, go to the outer band. A
//    planar facet thereby uses all 8 bins, where world octants would leave half of them empty (4 quadrants of one
//    hemisphere): twice the angular resolution for glossy receivers. A bin holds Σ w·Φ (RGB) and
//    Σ w·mean(Φ)·ωi, whose direction is the bin's flux-weighted mean direction ω̄.
// 5. Shade. A sample x of facet f, in cut node n with parent P, is shaded from f's bins blended with P's:
//      L(x) = finish_sample( (1 − β)·Σ_b [n_x·ω̄_b > 0]·f_r(x, ω̄_b)·F_b + β·(the same over P's bins) ),
//    f_r = sample_brdf(x, ω̄_b) times, on a smooth-shaded or bump-mapped sample, its shading normal's arrival
//    ratio for ω̄_b against its own triangle (photon_shading_normals.h; the exact methods take each photon's
//    triangle), so glossy and smooth-shaded receivers see each bin from its mean direction. P's bins are the
//    sample-weighted mean of the bins of the facets under P that face like f (axes within τ):
//    Σ m_g·F_g / Σ m_g, re-binned by the world octant of each ω̄. That is P's estimate over its larger region
//    on the scale of a single node (P's raw sum would count every child's disc), without the other wall of a
//    corner. β grows linearly from 0 at f's centroid to kMaxParentBlend at its farthest sample, so that on both
//    sides of an edge between siblings the estimate leans towards the same parent value, which halves the jump
//    there. A parent much larger than its child (a collapsed chain) is no neighbourhood: then β = 0.
//    Normalisation: none is needed. A facet's centroid is a convex combination of its samples, so for a planar
//    facet it lies on the plane, and Σ w·Φ over a photon density ρ there is ρ·Φ·∫_disc w = ρ·Φ·π r² for both
//    kernels (kernel_weight is relative to the uniform kernel), which finish_sample's 1/(π r² N) turns into what
//    brute gives on average. A curved facet has its centroid a little off the surface and reads a little low:
//    that is part of the approximation, measured against brute in the tests.
//    Cost: the per-facet bins (own and parent's) are prepared once per facet, then the samples are shaded in
//    pixel order (sequential reads of the large view samples); a diffuse sample whose facet's normal cone shows
//    that every bin faces it takes the bins' precomputed sum instead of the per-bin loop (equal up to rounding).
//
// Determinism: deposits are summed as 64-bit fixed-point integers, first per task, then into the shared bins
// with atomic adds. Each contribution is rounded on its own and integer addition is exact, so the sums, and the
// image, are the same bit for bit whatever the thread count and the order photons are taken in. The unit makes
// 2^61 steps = N_photons × the largest contribution, so no sum can overflow; a step is about 4e-19·N of a
// photon's contribution, far below float precision. Photons are traversed in the photon map's order, which the
// render makes the Morton order of their position (photons.h; any order gives the same sums): neighbouring
// photons meet the same nodes, which keeps both in cache and makes a task's deposits gather on few nodes, hence
// few atomic adds.
//
// Counters: "photon_node_tests" (box tests above the cut and facet tests at it), "node_deposits" (photon
// deposits into a facet's bin), "photon_sample_tests" = 0 (no photon is ever tested against a sample),
// "bin_evaluations" (bins shaded, own and parent's, summed over samples), "contributing_pairs" = Σ over deposits
// of the facet's sample count (the photon–sample pairs the deposits hand flux to, whether or not a sample's
// facing test then takes that bin), "directional_cut_nodes", "directional_summarised_cut_nodes" (described from leaf
// summaries), "directional_facets". Values: "directional_level"
// (the level used; -1 when the exact splat was used), "directional_exact_fallback" (1 then).
// Bytes: "direction_bins" (8 bins × 6 int64 per facet), "directional_nodes" (facets, cut and tree bookkeeping).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/render_control.h"
#include "photonsplat/scattering.h"
#include "photonsplat/settings.h"
#include "photonsplat/splatter.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"
#include "splat_inputs.h"
#include "photonsplat/validation.h"

namespace ps {
namespace {

constexpr int kBins = 8;
constexpr int kSlots = 6;  // per bin: Σ w·Φ (R, G, B), then Σ w·mean(Φ)·ωi (x, y, z)
constexpr int kBinValues = kBins * kSlots;
constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
constexpr size_t kPhotonsPerTask = 2048;         // in the map's spatial order: a task's deposits share nodes
constexpr size_t kCutNodesPerTask = 16;
constexpr size_t kSamplesPerTask = 8192;
constexpr uint32_t kPrefetch = 16;               // samples fetched ahead when gathering a node's samples
constexpr double kMaxParentBlend = 0.5;          // β at a facet's farthest sample
constexpr double kParentSpan = 4.0;              // blend with P only if diag(P) <= this × max(diag(n), r)
constexpr size_t kMaxParentFacets = 256;         // and only if P holds at most this many facets
constexpr double kFallbackLeafDiagonal = 2.0;    // auto level: exact splat when median leaf diagonal > this × r
constexpr double kFixedPointRange = 2305843009213693952.0;  // 2^61
constexpr float kPi = 3.14159265358979f;
// Split a cut node whose normals spread wider than this (20°); split it by whole leaf parts (hierarchy.h) when
// every part is narrower than half of it.
constexpr float kSplitAngle = 2.0f * kNarrowLeafAngle;
constexpr float kConeInflation = 1e-4f;          // rad, as the hierarchy inflates its cones
constexpr float kNever = -2.0f;                  // a cosine threshold no dot product of unit vectors reaches

// ---- the cut ------------------------------------------------------------------------------------------------

// Parent links and heights, derived from the children ranges in O(nodes).
struct TreeShape {
    std::vector<uint32_t> parent;  // kNone for the root
    std::vector<int> height;       // 0 for leaves
    std::vector<uint32_t> order;   // the nodes reachable from the root, every parent before its children
};

TreeShape tree_shape(const ClusterHierarchy& hierarchy) {
    TreeShape t;
    t.parent.assign(hierarchy.nodes.size(), kNone);
    t.height.assign(hierarchy.nodes.size(), 0);
    t.order.reserve(hierarchy.nodes.size());
    t.order.push_back(hierarchy.root);
    for (size_t i = 0; i < t.order.size(); ++i) {
        const ClusterNode& node = hierarchy.nodes[t.order[i]];
        for (uint32_t c = 0; c < node.child_count; ++c) {
            t.parent[node.first_child + c] = t.order[i];
            t.order.push_back(node.first_child + c);
        }
    }
    for (size_t i = t.order.size(); i-- > 1;) {
        const uint32_t child = t.order[i];
        int& h = t.height[t.parent[child]];
        h = std::max(h, t.height[child] + 1);
    }
    return t;
}

bool in_cut(const TreeShape& t, uint32_t node, int level) {
    return t.height[node] <= level && (t.parent[node] == kNone || t.height[t.parent[node]] > level);
}

double diagonal(const ClusterNode& node) {
    const double d = glm::length(glm::dvec3(node.box_max) - glm::dvec3(node.box_min));
    return std::isfinite(d) ? d : 0.0;
}

// For every level L (0 to the root's height): whether the cut node holding the median sample of the cut of L,
// the nodes sorted by diagonal, has a diagonal <= limit[L]. That holds exactly when the cut nodes no larger
// than limit[L] hold at least half the samples, so no sort is needed, and one pass over the nodes serves every
// level: a node is in the cuts of the levels from its height to its parent's height − 1 (the root: to the top).
std::vector<bool> median_at_most(const ClusterHierarchy& hierarchy, const TreeShape& t,
                                 const std::vector<double>& limit) {
    const int top = t.height[hierarchy.root];
    // Per level: the cut's samples and nodes as differences (added at a node's first level, removed after its
    // last), and the samples and nodes within that level's limit summed directly.
    std::vector<int64_t> total_delta(size_t(top) + 2, 0), count_delta(size_t(top) + 2, 0);
    std::vector<uint64_t> below(size_t(top) + 1, 0), nodes_below(size_t(top) + 1, 0);
    for (const uint32_t n : t.order) {
        const int lo = t.height[n];
        const int hi = t.parent[n] == kNone ? top : t.height[t.parent[n]] - 1;
        if (hi < lo) continue;
        const ClusterNode& node = hierarchy.nodes[n];
        const uint64_t m = node.sample_end - node.sample_begin;
        total_delta[size_t(lo)] += int64_t(m);
        total_delta[size_t(hi) + 1] -= int64_t(m);
        ++count_delta[size_t(lo)];
        --count_delta[size_t(hi) + 1];
        const double d = diagonal(node);
        for (int level = lo; level <= hi; ++level)
            if (d <= limit[size_t(level)]) below[size_t(level)] += m, ++nodes_below[size_t(level)];
    }
    std::vector<bool> result(size_t(top) + 1);
    int64_t total = 0, count = 0;
    for (int level = 0; level <= top; ++level) {
        total += total_delta[size_t(level)];
        count += count_delta[size_t(level)];
        // With no samples at all, the "median" is the smallest node (within the limit if any node is), and 0 for
        // an empty cut.
        result[size_t(level)] = total == 0 ? count == 0 || nodes_below[size_t(level)] > 0
                                           : 2 * below[size_t(level)] >= uint64_t(total);
    }
    return result;
}

// The level to use, and whether the automatic level gives up for the exact splat.
std::pair<int, bool> choose_level(const ClusterHierarchy& hierarchy, const TreeShape& t, const SplatParams& params) {
    const int top = t.height[hierarchy.root];
    if (params.directional_level >= 0) return {std::min(params.directional_level, top), false};
    const double r = params.radius;
    std::vector<double> limit(size_t(top) + 1, r);
    limit[0] = kFallbackLeafDiagonal * r;
    const std::vector<bool> leaf_small = median_at_most(hierarchy, t, limit);
    if (!leaf_small[0]) return {0, true};
    if (top == 0) return {0, false};
    limit[0] = r;  // level 0 again, at r: only levels >= 1 are read below
    const std::vector<bool> small = median_at_most(hierarchy, t, limit);
    int level = 0;
    while (level < top && small[size_t(level) + 1]) ++level;
    return {level, false};
}

}  // namespace

bool directional_leaves_exceed_radius(const ClusterHierarchy& hierarchy, float radius) {
    if (hierarchy.empty()) return false;
    const TreeShape shape = tree_shape(hierarchy);
    std::vector<double> limit(size_t(shape.height[hierarchy.root]) + 1, double(radius));
    limit[0] = kFallbackLeafDiagonal * double(radius);
    return !median_at_most(hierarchy, shape, limit)[0];
}

namespace {

// ---- facets -------------------------------------------------------------------------------------------------

// The samples of one orientation in a cut node: what the traversal tests and what shading needs.
struct Facet {
    glm::vec3 centroid{std::numeric_limits<float>::quiet_NaN()};  // of its samples' positions
    glm::vec3 axis{0.0f, 0.0f, 1.0f};  // its samples' mean geometric normal: the bins' pole
    glm::vec3 tangent{1.0f, 0.0f, 0.0f}, bitangent{0.0f, 1.0f, 0.0f};
    float facing_reject = kNever;  // every sample faces away from ωi when dot(axis, ωi) <= this
    float normal_reject = kNever;  // every sample's normal is > τ from n_p when dot(axis, n_p) <= this
    float plane_reject = std::numeric_limits<float>::infinity();  // |axis·(c − p)| >= this: all beyond κ·r
    float reach = 0.0f;            // distance from the centroid to its farthest sample (for β)
    float cone = kPi;              // half-angle of its samples' normal cone around the axis (rad)
    uint32_t samples = 0;          // m: its samples with a finite position and normal
};

struct Cut {
    uint32_t node = 0;
    uint32_t first_facet = 0;
    uint32_t facet_count = 0;  // 0 (no finite sample), 1 or 2
    uint32_t parent = kNone;   // the parent node to blend with, or kNone
};

bool regular(const ViewSample& s) { return is_finite(s.position) && is_finite(s.normal); }

// Which of a cut node's facets a sample belongs to: the one whose axis is closest to its normal.
uint32_t facet_of(const glm::vec3& normal, const Facet* facets, uint32_t count) {
    return count == 2 && glm::dot(normal, facets[1].axis) > glm::dot(normal, facets[0].axis) ? 1 : 0;
}

// A cut node's regular samples (finite position and normal), gathered once: every pass below then reads this
// small array, which stays in cache, instead of the large view samples through sample_order again.
struct Oriented {
    glm::vec3 position, normal;
};

// A facet's rejection tests from its normal cone (half-angle theta around its axis) and its thickness `slab`
// (largest |axis·(x − centroid)| of its samples).
void set_rejects(Facet& f, float theta, double slab, const SplatParams& params) {
    const float tau = std::acos(std::clamp(params.cos_normal_tolerance, -1.0f, 1.0f));
    f.cone = theta;
    if (theta < 0.5f * kPi) f.facing_reject = -std::sin(theta);
    if (theta + tau < kPi) f.normal_reject = std::cos(theta + tau);
    if (params.plane_distance_factor > 0.0f && theta < kPi)
        f.plane_reject = params.plane_distance_factor * params.radius + float(slab) +
                         2.0f * std::sin(0.5f * theta) * params.radius;
}

// Fills in a facet from its samples (those of `points` for which `member` holds), around a given axis.
template <typename Member>
void describe_facet(Facet& f, const std::vector<Oriented>& points, const SplatParams& params, Member member) {
    glm::dvec3 position_sum(0.0);
    for (const Oriented& s : points) {
        if (!member(s)) continue;
        position_sum += glm::dvec3(s.position);
        ++f.samples;
    }
    if (f.samples == 0) return;
    const glm::dvec3 centroid = position_sum / double(f.samples);
    const glm::dvec3 axis(f.axis);
    f.centroid = glm::vec3(centroid);
    orthonormal_basis(f.axis, f.tangent, f.bitangent);
    double min_cos = 1.0, slab = 0.0, reach = 0.0;
    for (const Oriented& s : points) {
        if (!member(s)) continue;
        const glm::dvec3 d = glm::dvec3(s.position) - centroid;
        const glm::dvec3 n(s.normal);
        const double len = glm::length(n);
        min_cos = std::min(min_cos, len > 0.0 ? glm::dot(axis, n) / len : -1.0);
        slab = std::max(slab, std::fabs(glm::dot(axis, d)));
        reach = std::max(reach, glm::length(d));
    }
    f.reach = float(reach);
    set_rejects(f, std::acos(float(std::clamp(min_cos, -1.0, 1.0))) + kConeInflation, slab, params);
}

// A cut node's facets: one, or two when its normals spread wider than kSplitAngle. Returns how many.
// `points` is scratch space (reused across calls to avoid allocating per node).
uint32_t describe_cut_node(const ClusterHierarchy& hierarchy, const std::vector<ViewSample>& views,
                           const ClusterNode& node, const SplatParams& params, std::vector<Oriented>& points,
                           Facet* out) {
    points.clear();
    glm::dvec3 normal_sum(0.0);
    for (uint32_t k = node.sample_begin; k != node.sample_end; ++k) {
        // The samples of a node are scattered over the frame's rows: fetch ahead, or each one is a cache miss.
        if (k + kPrefetch < node.sample_end) __builtin_prefetch(&views[hierarchy.sample_order[k + kPrefetch]]);
        const ViewSample& s = views[hierarchy.sample_order[k]];
        if (regular(s)) normal_sum += glm::dvec3(s.normal), points.push_back({s.position, s.normal});
    }
    const size_t count = points.size();
    if (count == 0) return 0;
    const double length = glm::length(normal_sum);
    const glm::vec3 mean = length > 1e-3 * count ? glm::vec3(normal_sum / length) : glm::vec3(0.0f, 0.0f, 1.0f);
    // Seeds: the normal farthest from the mean, then the normal farthest from that one.
    glm::vec3 seed0 = mean, seed1 = mean;
    float lowest = 2.0f;
    for (const Oriented& s : points)
        if (glm::dot(mean, s.normal) < lowest) lowest = glm::dot(mean, s.normal), seed0 = s.normal;
    const bool split = length <= 1e-3 * count || lowest < std::cos(kSplitAngle);
    const auto all = [](const Oriented&) { return true; };
    if (split) {
        lowest = 2.0f;
        for (const Oriented& s : points)
            if (glm::dot(seed0, s.normal) < lowest) lowest = glm::dot(seed0, s.normal), seed1 = s.normal;
        // One k-means step: the axes are the mean normals of the samples closer to each seed.
        glm::dvec3 sums[2] = {glm::dvec3(0.0), glm::dvec3(0.0)};
        for (const Oriented& s : points)
            sums[glm::dot(s.normal, seed1) > glm::dot(s.normal, seed0) ? 1 : 0] += glm::dvec3(s.normal);
        const double l0 = glm::length(sums[0]), l1 = glm::length(sums[1]);
        if (l0 > 0.0 && l1 > 0.0) {
            out[0] = Facet();
            out[1] = Facet();
            out[0].axis = glm::vec3(sums[0] / l0);
            out[1].axis = glm::vec3(sums[1] / l1);
            for (uint32_t i = 0; i < 2; ++i)
                describe_facet(out[i], points, params,
                               [&](const Oriented& s) { return facet_of(s.normal, out, 2) == i; });
            if (out[0].samples > 0 && out[1].samples > 0) return 2;
        }
    }
    out[0] = Facet();
    out[0].axis = mean;
    describe_facet(out[0], points, params, all);
    if (length <= 1e-3 * count) {  // the normals cancel: a full cone, which never rejects
        out[0].facing_reject = out[0].normal_reject = kNever;
        out[0].plane_reject = std::numeric_limits<float>::infinity();
        out[0].cone = kPi;
    }
    return 1;
}

// One facet from the parts of a node's leaves (hierarchy.leaf_summaries[first, last)) that `owned` gives, around
// `axis`: its count and centroid, and its bounds (cone, slab, reach) widened by each part's own bounds, so the
// rejection tests stay conservative. Returns false when no owned part has a sample.
template <typename Owned>
bool facet_from_parts(const ClusterHierarchy& hierarchy, size_t first, size_t last, const glm::dvec3& axis,
                      const SplatParams& params, Owned owned, Facet& out) {
    glm::dvec3 position_sum(0.0);
    double count = 0.0;
    for (size_t l = first; l != last; ++l) {
        const LeafSummary& part = hierarchy.leaf_summaries[l];
        if (part.count == 0 || !owned(l)) continue;
        position_sum += glm::dvec3(part.centroid) * double(part.count);
        count += part.count;
    }
    if (count == 0.0) return false;
    const glm::dvec3 centroid = position_sum / count;
    double spread = 0.0, slab = 0.0, reach = 0.0;
    for (size_t l = first; l != last; ++l) {
        const LeafSummary& part = hierarchy.leaf_summaries[l];
        if (part.count == 0 || !owned(l)) continue;
        const glm::dvec3 part_axis = glm::normalize(glm::dvec3(part.normal_sum));
        spread = std::max(spread, std::acos(std::clamp(glm::dot(axis, part_axis), -1.0, 1.0)) + part.cone_angle);
        // |a·(x − c)| <= |a·(c_l − c)| + |a_l·(x − c_l)| + |a − a_l|·|x − c_l|
        const glm::dvec3 offset = glm::dvec3(part.centroid) - centroid;
        slab = std::max(slab, std::fabs(glm::dot(axis, offset)) + double(part.slab) +
                                  glm::length(axis - part_axis) * double(part.radius));
        reach = std::max(reach, glm::length(offset) + double(part.radius));
    }
    out = Facet();
    out.axis = glm::vec3(axis);
    out.centroid = glm::vec3(centroid);
    out.samples = uint32_t(count);
    out.reach = float(reach);
    orthonormal_basis(out.axis, out.tangent, out.bitangent);
    set_rejects(out, float(std::min(spread, double(kPi))) + kConeInflation, slab, params);
    return true;
}

// A cut node's facets from the summaries of its leaves instead of its samples. `first`, `last` index
// hierarchy.leaf_summaries: the parts of the node's leaves (a leaf across a crease comes as parts split by
// orientation, hierarchy.h). One facet when the parts bound the normals within kSplitAngle; else two, split as
// describe_cut_node splits samples (seeds, one k-means step) but with whole parts: each part goes to the facet
// whose axis is closest to its own, and so do its samples when they are shaded (part_facet[l − first] says
// which), so each facet's bounds are exactly those of its parts. Returns the facet count, or 0 when the node must
// be described from its samples (unbounded or cancelling normals, a part wider than kNarrowLeafAngle in a node
// to split, a failed split).
uint32_t describe_node_from_parts(const ClusterHierarchy& hierarchy, size_t first, size_t last,
                                  const SplatParams& params, Facet* out, uint8_t* part_facet) {
    glm::dvec3 normal_sum(0.0);
    double count = 0.0;
    bool narrow = true;
    for (size_t l = first; l != last; ++l) {
        const LeafSummary& part = hierarchy.leaf_summaries[l];
        part_facet[l - first] = 0;
        if (part.count == 0) continue;
        if (!(part.cone_angle < kPi)) return 0;
        narrow = narrow && part.cone_angle < kNarrowLeafAngle;
        normal_sum += glm::dvec3(part.normal_sum);
        count += part.count;
    }
    const double length = glm::length(normal_sum);
    if (count == 0.0 || !(length > 1e-3 * count)) return 0;
    const glm::dvec3 mean = normal_sum / length;
    const auto axis_of = [&](size_t l) { return glm::normalize(glm::dvec3(hierarchy.leaf_summaries[l].normal_sum)); };
    double spread = 0.0;
    glm::dvec3 seed0 = mean;
    double lowest = 2.0;
    for (size_t l = first; l != last; ++l) {
        if (hierarchy.leaf_summaries[l].count == 0) continue;
        const glm::dvec3 a = axis_of(l);
        spread = std::max(spread, std::acos(std::clamp(glm::dot(mean, a), -1.0, 1.0)) +
                                      hierarchy.leaf_summaries[l].cone_angle);
        if (glm::dot(mean, a) < lowest) lowest = glm::dot(mean, a), seed0 = a;
    }
    const auto all = [](size_t) { return true; };
    if (spread < kSplitAngle) return facet_from_parts(hierarchy, first, last, mean, params, all, out[0]) ? 1 : 0;
    if (!narrow) return 0;  // a part holding several orientations would blur the split: the samples do better
    glm::dvec3 seed1 = seed0;
    lowest = 2.0;
    for (size_t l = first; l != last; ++l) {
        if (hierarchy.leaf_summaries[l].count == 0) continue;
        const glm::dvec3 a = axis_of(l);
        if (glm::dot(seed0, a) < lowest) lowest = glm::dot(seed0, a), seed1 = a;
    }
    glm::dvec3 sums[2] = {glm::dvec3(0.0), glm::dvec3(0.0)};
    for (size_t l = first; l != last; ++l) {
        if (hierarchy.leaf_summaries[l].count == 0) continue;
        const glm::dvec3 a = axis_of(l);
        sums[glm::dot(a, seed1) > glm::dot(a, seed0) ? 1 : 0] += glm::dvec3(hierarchy.leaf_summaries[l].normal_sum);
    }
    const double l0 = glm::length(sums[0]), l1 = glm::length(sums[1]);
    if (!(l0 > 0.0) || !(l1 > 0.0)) return 0;
    const glm::dvec3 axes[2] = {sums[0] / l0, sums[1] / l1};
    for (size_t l = first; l != last; ++l)
        if (hierarchy.leaf_summaries[l].count > 0)
            part_facet[l - first] = glm::dot(axis_of(l), axes[1]) > glm::dot(axis_of(l), axes[0]) ? 1 : 0;
    for (uint8_t f = 0; f < 2; ++f)
        if (!facet_from_parts(hierarchy, first, last, axes[f], params,
                              [&](size_t l) { return part_facet[l - first] == f; }, out[f]))
            return 0;
    return 2;
}

int bin_of(const Facet& f, const glm::vec3& wi) {
    const float x = glm::dot(f.tangent, wi), y = glm::dot(f.bitangent, wi), z = glm::dot(f.axis, wi);
    return int(x > 0.0f) | int(y > 0.0f) << 1 | int(!(z >= 0.5f)) << 2;
}

int world_octant(const glm::dvec3& w) { return int(w.x > 0.0) | int(w.y > 0.0) << 1 | int(w.z > 0.0) << 2; }

// A bin ready to shade with: its flux (in the units finish_sample expects) and its mean direction.
struct ShadeBin {
    glm::dvec3 flux;
    glm::vec3 direction;
};

// The non-empty bins of `values` (kBinValues doubles), flux × scale.
int shade_bins(const double* values, double scale, ShadeBin* out) {
    int count = 0;
    for (int b = 0; b < kBins; ++b, values += kSlots) {
        const glm::dvec3 flux(values[0], values[1], values[2]);
        const glm::dvec3 d(values[3], values[4], values[5]);
        const double len = glm::length(d);
        if (flux == glm::dvec3(0.0) || !(len > 0.0)) continue;  // no flux, or no direction to shade it from
        out[count++] = {flux * scale, glm::vec3(d / len)};
    }
    return count;
}

glm::dvec3 reflect_bins(const ViewSample& s, const Lobe* lobes, const ShadeBin* bins, int count, LabelShare share) {
    glm::dvec3 sum(0.0);
    for (int b = 0; b < count; ++b)
        if (glm::dot(s.normal, bins[b].direction) > 0.0f)
            sum += sample_brdf(s, lobes, bins[b].direction, share) * bins[b].flux *
                   double(photon_arrival_ratio(s.shading_normal, s.normal, bins[b].direction));
    return sum;
}

// Whether every one of `count` bins faces every sample of facet f (n_x·ω̄ > 0 for all n_x in its normal cone:
// ω̄ within π/2 − cone of the axis, with a margin for rounding); if so, `sum` = Σ_b F_b.
bool faces_all(const Facet& f, const ShadeBin* bins, int count, glm::dvec3& sum) {
    constexpr float kMargin = 1e-3f;  // rad
    sum = glm::dvec3(0.0);
    if (!(f.cone + kMargin < 0.5f * kPi)) return false;
    const float min_dot = std::sin(f.cone + kMargin);
    for (int b = 0; b < count; ++b) {
        if (!(glm::dot(f.axis, bins[b].direction) > min_dot)) return false;
        sum += bins[b].flux;
    }
    return true;
}

// ---- the splat ----------------------------------------------------------------------------------------------

class DirectionalSplat : private SplatInputs {
public:
    DirectionalSplat(const ClusterHierarchy& hierarchy, const ViewSamples& samples, const PhotonMap& photons,
                     const SplatParams& params, const RenderControl& control, Stats& stats, TreeShape shape,
                     int level)
        : SplatInputs(samples, photons, params, control, stats),
          hierarchy_(hierarchy),
          shape_(std::move(shape)),
          level_(level),
          radiance_(views_.size(), glm::vec3(0.0f)) {}

    std::vector<glm::vec3> run() {
        {
            StageTimer timer(stats_, "splat_setup");
            build_cut();
            choose_fixed_point_unit();
        }
        control_.check();
        {
            StageTimer timer(stats_, "splat_traverse");
            if (unit_ > 0.0) traverse();
        }
        control_.check();
        {
            StageTimer timer(stats_, "splat_shade");
            shade();
        }
        stats_.counters["photon_node_tests"] += double(node_tests_.load());
        stats_.counters["node_deposits"] += double(deposits_.load());
        stats_.counters["contributing_pairs"] += double(pairs_.load());
        stats_.counters["bin_evaluations"] += double(bin_evaluations_.load());
        stats_.counters["directional_cut_nodes"] += double(cuts_.size());
        stats_.counters["directional_facets"] += double(facets_.size());
        stats_.bytes["direction_bins"] = double(bins_.capacity() * sizeof(std::atomic<int64_t>));
        stats_.bytes["directional_nodes"] =
            double(facets_.capacity() * sizeof(Facet) + cuts_.capacity() * sizeof(Cut) +
                   views_.size() * sizeof(uint32_t) +
                   walk_.capacity() * sizeof(WalkNode) + facet_tests_.capacity() * sizeof(FacetTest) +
                   shape_.parent.capacity() * sizeof(uint32_t) +
                   shape_.height.capacity() * sizeof(int) + shape_.order.capacity() * sizeof(uint32_t));
        return std::move(radiance_);
    }

private:
    void build_cut() {
        for (const uint32_t n : shape_.order)
            if (in_cut(shape_, n, level_)) cuts_.emplace_back().node = n;
        // In sample order: the cut nodes under any node are then one run of cuts_ (see parent_facets).
        std::sort(cuts_.begin(), cuts_.end(), [&](const Cut& a, const Cut& b) {
            return hierarchy_.nodes[a.node].sample_begin < hierarchy_.nodes[b.node].sample_begin;
        });
        if (cuts_.size() >= kFacetBit) throw InvalidInput("cluster hierarchy", "too many nodes for the directional cut");
        std::vector<Facet> pairs(2 * cuts_.size());
        // Every sample lies under exactly one cut node, which writes it below: no need to fill it first.
        cut_of_sample_.reset(new uint32_t[views_.size()]);
        // The parts under a node: leaves are in sample order, so those whose first sample lies in its range.
        const bool summaries = hierarchy_.leaf_summary_begin.size() == hierarchy_.leaves.size() + 1 &&
                               hierarchy_.sample_part.size() == hierarchy_.sample_order.size();
        std::vector<uint32_t> leaf_begin(summaries ? hierarchy_.leaves.size() : 0);
        for (size_t l = 0; l < leaf_begin.size(); ++l) leaf_begin[l] = hierarchy_.nodes[hierarchy_.leaves[l]].sample_begin;
        struct Scratch {
            std::vector<Oriented> points;
            std::vector<uint8_t> part_facet;
        };
        tbb::enumerable_thread_specific<Scratch> scratch;
        std::atomic<uint64_t> from_summaries{0};
        tbb::parallel_for(tbb::blocked_range<size_t>(0, cuts_.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
            Scratch& local = scratch.local();
            uint64_t described = 0;
            for (size_t c = r.begin(); c != r.end(); ++c) {
                const ClusterNode& node = hierarchy_.nodes[cuts_[c].node];
                Facet* facets = &pairs[2 * c];
                // Flat nodes (most of a frame) from their leaves' parts: reading the samples again, scattered over
                // the frame, cost as much as shading them. Each sample then takes its part's facet.
                if (summaries) {
                    const size_t first = size_t(std::lower_bound(leaf_begin.begin(), leaf_begin.end(), node.sample_begin) - leaf_begin.begin());
                    const size_t last = size_t(std::lower_bound(leaf_begin.begin(), leaf_begin.end(), node.sample_end) - leaf_begin.begin());
                    const size_t first_part = hierarchy_.leaf_summary_begin[first];
                    local.part_facet.resize(hierarchy_.leaf_summary_begin[last] - first_part);
                    const uint32_t count = describe_node_from_parts(hierarchy_, first_part, hierarchy_.leaf_summary_begin[last],
                                                                    params_, facets, local.part_facet.data());
                    if (count > 0) {
                        cuts_[c].facet_count = count;
                        ++described;
                        for (size_t l = first; l != last; ++l) {
                            const ClusterNode& leaf = hierarchy_.nodes[hierarchy_.leaves[l]];
                            const uint8_t* facet_of_part = &local.part_facet[hierarchy_.leaf_summary_begin[l] - first_part];
                            for (uint32_t k = leaf.sample_begin; k != leaf.sample_end; ++k)
                                cut_of_sample_[hierarchy_.sample_order[k]] =
                                    uint32_t(c) | (count == 2 && facet_of_part[hierarchy_.sample_part[k]] ? kFacetBit : 0u);
                        }
                        continue;
                    }
                }
                // From the samples: each takes the facet whose axis is closest to its normal.
                const uint32_t count = describe_cut_node(hierarchy_, views_, node, params_, local.points, facets);
                cuts_[c].facet_count = count;
                for (uint32_t k = node.sample_begin; k != node.sample_end; ++k) {
                    const uint32_t i = hierarchy_.sample_order[k];
                    cut_of_sample_[i] = uint32_t(c) | (count == 2 && facet_of(views_[i].normal, facets, 2) ? kFacetBit : 0u);
                }
            }
            from_summaries += described;
        });
        stats_.counters["directional_summarised_cut_nodes"] += double(from_summaries.load());
        facets_.reserve(cuts_.size() + cuts_.size() / 8);
        for (size_t c = 0; c < cuts_.size(); ++c) {
            Cut& cut = cuts_[c];
            cut.first_facet = uint32_t(facets_.size());
            for (uint32_t f = 0; f < cut.facet_count; ++f) facets_.push_back(pairs[2 * c + f]);
            // The parent to blend with: a neighbourhood, not a large part of the image.
            const uint32_t p = shape_.parent[cut.node];
            if (p == kNone) continue;
            const double own = std::max(diagonal(hierarchy_.nodes[cut.node]), double(params_.radius));
            if (diagonal(hierarchy_.nodes[p]) <= kParentSpan * own) cut.parent = p;
        }
        // What the traversal reads, packed: a node's box and children, or for a cut node its facets; and the
        // facets' rejection tests without the rest of Facet (facet_tests_, indexed like facets_).
        // Only the nodes a photon can reach: those above the cut and the cut itself, breadth-first from the root
        // (walk_[0]), each node's children kept together.
        const auto cut_at = [&](uint32_t n) {  // cut nodes have disjoint sample ranges, and cuts_ is sorted by them
            return std::lower_bound(cuts_.begin(), cuts_.end(), hierarchy_.nodes[n].sample_begin,
                                    [&](const Cut& cut, uint32_t begin) { return hierarchy_.nodes[cut.node].sample_begin < begin; });
        };
        std::vector<uint32_t> walk_nodes{hierarchy_.root};
        walk_.clear();
        for (size_t w = 0; w < walk_nodes.size(); ++w) {
            const ClusterNode& node = hierarchy_.nodes[walk_nodes[w]];
            if (in_cut(shape_, walk_nodes[w], level_)) {
                const Cut& cut = *cut_at(walk_nodes[w]);
                walk_.push_back({node.box_min, cut.first_facet, node.box_max, cut.facet_count | kCutBit});
                continue;
            }
            walk_.push_back({node.box_min, uint32_t(walk_nodes.size()), node.box_max, node.child_count});
            for (uint32_t k = 0; k < node.child_count; ++k) walk_nodes.push_back(node.first_child + k);
        }
        facet_tests_.resize(facets_.size());
        for (size_t f = 0; f < facets_.size(); ++f) {
            const Facet& facet = facets_[f];
            facet_tests_[f] = {facet.centroid, facet.facing_reject, facet.axis, facet.normal_reject, facet.plane_reject};
        }
        bins_ = std::vector<std::atomic<int64_t>>(facets_.size() * kBinValues);
        for (std::atomic<int64_t>& b : bins_) b.store(0, std::memory_order_relaxed);
    }

    static bool usable(const Photon& photon, const glm::vec3& p) {
        return is_finite(p) && is_finite(photon.power) && is_finite(photon.wi) && is_finite(photon.normal);
    }

    // unit_ = the value of one fixed-point step: N × the largest |contribution| = 2^61 steps.
    void choose_fixed_point_unit() {
        double largest = 0.0;
        for (size_t j = 0; j < photons_.size(); ++j) {
            if (!usable(photons_[j], positions_[j])) continue;
            const glm::vec3 a = glm::abs(photons_[j].power);
            largest = std::max(largest, double(std::max(a.x, std::max(a.y, a.z))));
        }
        const double max_weight = params_.kernel == Kernel::uniform ? 1.0 : 2.0;
        unit_ = largest * max_weight * double(std::max<size_t>(photons_.size(), 1)) / kFixedPointRange;
        inv_unit_ = unit_ > 0.0 ? 1.0 / unit_ : 0.0;
    }

    // A task's deposits, summed locally (as integers, so exactly), then added to the shared bins once per facet.
    struct LocalBins {
        std::vector<uint32_t> slot_of;  // per facet: its slot in `sums`, or kNone
        std::vector<uint32_t> touched;  // facets in slot order
        std::vector<int64_t> sums;      // slot × bin × value
    };

    void flush(LocalBins& local) {
        for (size_t t = 0; t < local.touched.size(); ++t) {
            const int64_t* from = &local.sums[t * kBinValues];
            std::atomic<int64_t>* to = &bins_[size_t(local.touched[t]) * kBinValues];
            for (int v = 0; v < kBinValues; ++v)
                if (from[v] != 0) to[v].fetch_add(from[v], std::memory_order_relaxed);
            local.slot_of[local.touched[t]] = kNone;
        }
        local.touched.clear();
        local.sums.clear();
    }

    void traverse() {
        const float r2 = params_.radius * params_.radius;
        const float reject_box = r2 * (1.0f + 1e-5f);  // a margin, as in `cluster`: never drops a reachable node
        const bool plane_test = params_.plane_distance_factor > 0.0f;
        const uint64_t total = total_progress();
        std::atomic<uint64_t> done{0};
        tbb::enumerable_thread_specific<LocalBins> locals([&] {
            LocalBins local;
            local.slot_of.assign(facets_.size(), kNone);
            return local;
        });
        tbb::parallel_for(tbb::blocked_range<size_t>(0, photons_.size(), kPhotonsPerTask), [&](const tbb::blocked_range<size_t>& range) {
            control_.check();
            LocalBins& local = locals.local();
            std::vector<uint32_t> stack;
            stack.reserve(8 * size_t(hierarchy_.depth + 1));
            uint64_t tests = 0, deposits = 0, pairs = 0;
            // A photon at a cut node: each facet's tests, then the deposit.
            const auto visit_facets = [&](const glm::vec3& p, const Photon& photon, const WalkNode& node) {
                const uint32_t first_facet = node.first, facet_count = node.count & ~kCutBit;
                for (uint32_t f = first_facet; f != first_facet + facet_count; ++f) {
                    ++tests;
                    const FacetTest& facet = facet_tests_[f];
                    const glm::vec3 d = facet.centroid - p;
                    if (!(glm::dot(d, d) < r2)) continue;
                    if (glm::dot(facet.axis, photon.wi) <= facet.facing_reject) continue;
                    if (glm::dot(facet.axis, photon.normal) <= facet.normal_reject) continue;
                    if (plane_test && !(std::fabs(glm::dot(facet.axis, d)) < facet.plane_reject)) continue;
                    uint32_t& slot = local.slot_of[f];
                    if (slot == kNone) {
                        slot = uint32_t(local.touched.size());
                        local.touched.push_back(f);
                        local.sums.resize(local.sums.size() + kBinValues, 0);
                    }
                    int64_t* bin = &local.sums[size_t(slot) * kBinValues + bin_of(facets_[f], photon.wi) * kSlots];
                    // Each contribution is rounded on its own (towards zero), so no sum depends on grouping.
                    const double mean_power = (double(photon.power.x) + photon.power.y + photon.power.z) / 3.0;
                    const double w = kernel_weight(d, params_) * inv_unit_;
                    const double wm = w * mean_power;
                    bin[0] += int64_t(w * photon.power.x);
                    bin[1] += int64_t(w * photon.power.y);
                    bin[2] += int64_t(w * photon.power.z);
                    bin[3] += int64_t(wm * photon.wi.x);
                    bin[4] += int64_t(wm * photon.wi.y);
                    bin[5] += int64_t(wm * photon.wi.z);
                    ++deposits;
                    pairs += facets_[f].samples;
                }
            };
            for (size_t o = range.begin(); o != range.end(); ++o) {
                const glm::vec3& p = positions_[o];
                if (!usable(photons_[o], p)) continue;
                stack.push_back(0);  // walk_[0] is the root
                while (!stack.empty()) {
                    const uint32_t index = stack.back();
                    stack.pop_back();
                    const WalkNode& node = walk_[index];
                    if (!(node.count & kCutBit)) {  // above the cut: sphere vs box, then the children
                        ++tests;
                        const glm::vec3 gap = glm::max(glm::max(node.box_min - p, p - node.box_max), glm::vec3(0.0f));
                        if (glm::dot(gap, gap) > reject_box) continue;
                        for (uint32_t k = node.count; k-- > 0;) stack.push_back(node.first + k);
                        continue;
                    }
                    visit_facets(p, photons_[o], node);
                }
            }
            flush(local);
            node_tests_ += tests;
            deposits_ += deposits;
            pairs_ += pairs;
            control_.advance(done += range.size(), total);
        });
    }

    // A facet's bins as doubles in flux units.
    void facet_values(uint32_t f, double* values) const {
        const std::atomic<int64_t>* from = &bins_[size_t(f) * kBinValues];
        for (int v = 0; v < kBinValues; ++v) values[v] = double(from[v].load(std::memory_order_relaxed)) * unit_;
    }

    // P's estimate for facet `own`: Σ m_g·(bins of g) / Σ m_g over the facets g under P whose axis is within τ of
    // own's, each bin re-binned by the world octant of its mean direction (facets' bins have different poles).
    // Returns how many bins it wrote, 0 when P has no such facet or too many facets to be worth it.
    // Siblings usually share the parent's estimate (the same facets pass the τ test for both), and cuts are in
    // sample order, so a task remembers the last one it computed and reuses it for the same facets of the same P.
    struct ParentCache {
        uint32_t parent = kNone;
        std::vector<uint32_t> accepted, candidate;  // facets of the remembered estimate; of the one asked for
        ShadeBin bins[kBins];
        int count = 0;
    };

    int parent_bins(uint32_t parent, const Facet& own, ShadeBin* out, ParentCache& cache) const {
        const ClusterNode& p = hierarchy_.nodes[parent];
        const auto by_sample = [&](const Cut& cut, uint32_t sample) {
            return hierarchy_.nodes[cut.node].sample_begin < sample;
        };
        const auto first = std::lower_bound(cuts_.begin(), cuts_.end(), p.sample_begin, by_sample);
        const auto last = std::lower_bound(first, cuts_.end(), p.sample_end, by_sample);
        if (first == last || size_t(last - first) > kMaxParentFacets) return 0;
        const float cos_tau = std::clamp(params_.cos_normal_tolerance, -1.0f, 1.0f);
        cache.candidate.clear();
        for (auto cut = first; cut != last; ++cut)
            for (uint32_t g = cut->first_facet; g != cut->first_facet + cut->facet_count; ++g)
                if (glm::dot(facets_[g].axis, own.axis) > cos_tau) cache.candidate.push_back(g);
        if (parent != cache.parent || cache.candidate != cache.accepted) {
            double sums[kBinValues] = {};
            double weight = 0.0;
            for (const uint32_t g : cache.candidate) {
                double values[kBinValues];
                facet_values(g, values);
                const double m = facets_[g].samples;
                for (int b = 0; b < kBins; ++b) {
                    const double* v = values + b * kSlots;
                    if (v[0] == 0.0 && v[1] == 0.0 && v[2] == 0.0) continue;
                    double* to = sums + world_octant(glm::dvec3(v[3], v[4], v[5])) * kSlots;
                    for (int s = 0; s < kSlots; ++s) to[s] += m * v[s];
                }
                weight += m;
            }
            cache.parent = parent;
            std::swap(cache.accepted, cache.candidate);
            cache.count = weight > 0.0 ? shade_bins(sums, 1.0 / weight, cache.bins) : 0;
        }
        std::copy(cache.bins, cache.bins + cache.count, out);
        return cache.count;
    }

    // What shading needs of one facet: its bins and its parent's estimate, and their sums when they face all of
    // its samples (see faces_all).
    // Trivially constructible on purpose: the table is allocated uninitialised and every field is written by the
    // parallel first pass, which then also takes the page faults of the fresh memory.
    struct FacetShade {
        ShadeBin own[kBins], parent[kBins];  // the first own_count, parent_count are set
        glm::dvec3 own_sum, parent_sum;
        int own_count, parent_count;
        bool own_faces, parent_faces;
    };
    static_assert(std::is_trivially_default_constructible_v<FacetShade>, "allocated uninitialised");

    // What every sample reads of its facet, in one cache line (FacetShade's bins are 0.7 KB): where it is, for
    // β, and for a diffuse sample that every bin faces the whole answer up to its albedo and
    // throughput: radiance = albedo·throughput·((1 − β)·own + β·parent), own and parent being the bins' sums
    // × 1/π (the diffuse f_r) × K/N (finish_sample), in float like the radiance it makes.
    struct FacetHot {
        glm::vec3 centroid;
        float inv_reach;  // 1 / reach, or 0 when reach is 0 (then β = 0 as t = 0)
        glm::vec3 own, parent;
        uint32_t mode;    // kSumsFaceAll: own and parent are the answer for diffuse samples; kHasParent; kHasBins
        uint32_t bins;    // own + parent bins (the bin_evaluations counter)
    };
    static_assert(std::is_trivially_default_constructible_v<FacetHot>, "allocated uninitialised");
    static constexpr uint32_t kSumsFaceAll = 1u, kHasParent = 2u, kHasBins = 4u;

    // Two passes: the facets' shading data, cut by cut; then the samples in pixel order, which reads the large
    // view samples and writes the radiance sequentially (walking them cut by cut, through sample_order, is a
    // cache miss per sample and cost as much as the rest of the splat).
    void shade() {
        const std::unique_ptr<FacetShade[]> shades(new FacetShade[facets_.size()]);
        const std::unique_ptr<FacetHot[]> hot(new FacetHot[facets_.size()]);
        constexpr double kInvPi = 0.318309886183790671538;
        const double r = params_.radius;
        const double to_radiance = kInvPi / (3.14159265358979323846 * r * r * double(params_.emitted));
        tbb::parallel_for(tbb::blocked_range<size_t>(0, cuts_.size(), kCutNodesPerTask), [&](const tbb::blocked_range<size_t>& range) {
            control_.check();
            ParentCache cache;
            for (size_t c = range.begin(); c != range.end(); ++c) {
                const Cut& cut = cuts_[c];
                for (uint32_t f = cut.first_facet; f != cut.first_facet + cut.facet_count; ++f) {
                    FacetShade& sh = shades[f];
                    double values[kBinValues];
                    facet_values(f, values);
                    sh.own_count = shade_bins(values, 1.0, sh.own);
                    sh.parent_count = cut.parent != kNone ? parent_bins(cut.parent, facets_[f], sh.parent, cache) : 0;
                    sh.own_faces = faces_all(facets_[f], sh.own, sh.own_count, sh.own_sum);
                    sh.parent_faces = faces_all(facets_[f], sh.parent, sh.parent_count, sh.parent_sum);
                    const Facet& facet = facets_[f];
                    FacetHot& h = hot[f];
                    h.inv_reach = facet.reach > 0.0f ? 1.0f / facet.reach : 0.0f;
                    h.centroid = facet.centroid;
                    h.mode = (sh.own_faces && (sh.parent_count == 0 || sh.parent_faces) ? kSumsFaceAll : 0u) |
                             (sh.parent_count > 0 ? kHasParent : 0u) |
                             (sh.own_count > 0 || sh.parent_count > 0 ? kHasBins : 0u);
                    h.bins = uint32_t(sh.own_count + sh.parent_count);
                    h.own = glm::vec3(sh.own_sum * to_radiance);
                    h.parent = glm::vec3(sh.parent_sum * to_radiance);
                }
            }
            control_.advance(positions_.size() + (progress_ += range.size()), total_progress());
        });
        control_.check();
        tbb::parallel_for(tbb::blocked_range<size_t>(0, views_.size(), kSamplesPerTask), [&](const tbb::blocked_range<size_t>& range) {
            control_.check();
            uint64_t evaluations = 0;
            for (size_t i = range.begin(); i != range.end(); ++i) {
                const uint32_t word = cut_of_sample_[i];
                const Cut& cut = cuts_[word & ~kFacetBit];
                const ViewSample& s = views_[i];
                if (cut.facet_count == 0 || !is_finite(s.position)) continue;  // stays 0, as in brute
                const uint32_t f = cut.first_facet + (word & kFacetBit ? 1 : 0);
                const FacetHot& h = hot[f];
                if (!(h.mode & kHasBins)) continue;
                const float t = glm::length(s.position - h.centroid) * h.inv_reach;
                const float beta = h.mode & kHasParent ? float(kMaxParentBlend) * std::min(1.0f, t) : 0.0f;
                // (A tilted shading normal weighs each bin by its direction: photon_shading_normals.h.)
                const bool diffuse = !(s.flags & kGlossy) && !sample_shading_tilted(s);
                evaluations += h.bins;
                // A diffuse sample's f_r does not depend on ω̄: with every bin facing it, one product.
                if (diffuse && (h.mode & kSumsFaceAll)) {
                    // (sample_brdf's: a Lambert-only sample is labelled diffuse whole.)
                    const glm::vec3 albedo = lambert_takes(params_.label_share) ? s.albedo : glm::vec3(0.0f);
                    radiance_[i] = albedo * s.throughput * ((1.0f - beta) * h.own + beta * h.parent);
                    continue;
                }
                const FacetShade& sh = shades[f];
                const LabelShare share = params_.label_share;
                glm::dvec3 flux = diffuse && sh.own_faces ? sample_brdf(s, lobes_, s.normal, share) * sh.own_sum
                                                          : reflect_bins(s, lobes_, sh.own, sh.own_count, share);
                if (sh.parent_count > 0) {
                    const glm::dvec3 from_parent = diffuse && sh.parent_faces
                                                       ? sample_brdf(s, lobes_, s.normal, share) * sh.parent_sum
                                                       : reflect_bins(s, lobes_, sh.parent, sh.parent_count, share);
                    flux = (1.0 - double(beta)) * flux + double(beta) * from_parent;
                }
                radiance_[i] = finish_sample(s, flux, params_);
            }
            bin_evaluations_ += evaluations;
            control_.advance(positions_.size() + (progress_ += range.size()), total_progress());
        });
    }

    // Progress units: photons traversed, cut nodes prepared for shading, samples shaded.
    uint64_t total_progress() const { return positions_.size() + cuts_.size() + views_.size(); }

    const ClusterHierarchy& hierarchy_;
    const TreeShape shape_;
    const int level_;
    std::vector<glm::vec3> radiance_;

    std::vector<Cut> cuts_;                   // in sample order
    std::vector<Facet> facets_;               // cut by cut
    std::vector<std::atomic<int64_t>> bins_;  // facet × bin × value, fixed point
    double unit_ = 0.0, inv_unit_ = 0.0;

    struct WalkNode {
        glm::vec3 box_min;
        uint32_t first;  // first child, or for a cut node (count & kCutBit) its first facet
        glm::vec3 box_max;
        uint32_t count;  // children, or kCutBit | facets
    };
    struct FacetTest {
        glm::vec3 centroid;
        float facing_reject;
        glm::vec3 axis;
        float normal_reject;
        float plane_reject;
    };
    static constexpr uint32_t kCutBit = 0x80000000u;
    std::vector<WalkNode> walk_;              // the nodes above the cut and the cut nodes, root first
    std::vector<FacetTest> facet_tests_;      // per facet
    // Per view sample: the index of the cut node it lies under, with kFacetBit set when the second of the node's
    // facets shades it.
    std::unique_ptr<uint32_t[]> cut_of_sample_;
    static constexpr uint32_t kFacetBit = 0x80000000u;
    std::atomic<uint64_t> progress_{0};
    std::atomic<uint64_t> node_tests_{0}, deposits_{0}, pairs_{0}, bin_evaluations_{0};
};

}  // namespace

namespace {

// splat_directional, saying whether the automatic level gave up its bins for the exact cluster splat.
SplatEstimate directional_estimate(const ClusterHierarchy& hierarchy, const ViewSamples& samples,
                                   const PhotonMap& photons, const SplatParams& params, const RenderControl& control,
                                   Stats& stats) {
    validate(params, photons);
    const std::vector<ViewSample>& views = samples.samples;
    validate(hierarchy, samples, photons);
    control.check();
    for (const char* name : {"photon_node_tests", "node_deposits", "photon_sample_tests", "contributing_pairs",
                             "bin_evaluations", "directional_cut_nodes", "directional_summarised_cut_nodes", "directional_facets"})
        stats.counters[name] += 0.0;  // present even when there is nothing to splat
    stats.bytes["direction_bins"] = 0.0;
    stats.values["directional_exact_fallback"] = 0.0;
    if (hierarchy.empty() || photons.photons.empty()) {
        stats.values["directional_level"] = std::max(params.directional_level, 0);
        // (emitted may be 0: nothing to finish)
        return {std::vector<glm::vec3>(views.size(), glm::vec3(0.0f)), false};
    }
    TreeShape shape = tree_shape(hierarchy);
    const auto [level, fallback] = choose_level(hierarchy, shape, params);
    stats.values["directional_level"] = fallback ? -1.0 : double(level);
    if (fallback) {
        stats.values["directional_exact_fallback"] = 1.0;
        return {splat_cluster(hierarchy, samples, photons, params, control, stats), true};
    }
    return {DirectionalSplat(hierarchy, samples, photons, params, control, stats, std::move(shape), level).run(),
            false};
}

class DirectionalSplatter final : public Splatter {
public:
    explicit DirectionalSplatter(int level) : level_(level) {}

    std::optional<ClusterBuildOptions> hierarchy_options() const override {
        ClusterBuildOptions options;
        options.leaf_summaries = true;
        return options;
    }

    SplatMemory predict_memory(const SplatFrame& frame, size_t photons, const SplatParams&) const override {
        // When the radius is below a leaf's size it falls back to the exact cluster splat and its pair lists.
        SplatMemory m = cluster_splat_memory(frame, photons);
        const double nodes = double(frame.hierarchy ? frame.hierarchy->nodes.size() : 0);
        // 8 direction bins × 6 slots of 8 bytes per node at most (the cut level has fewer), and the cut's
        // bookkeeping (facets, cuts, walk, parent/height/order) per node, the cut of every sample.
        m.fixed["direction_bins"] = nodes * 8.0 * 6.0 * 8.0;
        m.fixed["directional_nodes"] = nodes * 256.0 + double(frame.samples.samples.size()) * 8.0;
        return m;
    }

    SplatEstimate splat(const SplatFrame& frame, const PhotonMap& photons, const SplatParams& params,
                        const RenderControl& control, Stats& stats) const override {
        SplatParams own = params;
        own.directional_level = level_;
        // In a progressive render an explicit level would keep its blocks however small r gets, and the mean would
        // converge to the blocky image: once the leaves outgrow the radius the automatic rule takes over, which
        // splats exactly.
        if (frame.iteration > 0 && level_ >= 0 && directional_leaves_exceed_radius(*frame.hierarchy, params.radius))
            own.directional_level = -1;
        return directional_estimate(*frame.hierarchy, frame.samples, photons, own, control, stats);
    }

private:
    int level_;  // RenderSettings::directional_level: from the leaves; -1 = chosen from the radius
};

}  // namespace

std::vector<glm::vec3> splat_directional(const ClusterHierarchy& hierarchy, const ViewSamples& samples,
                                         const PhotonMap& photons, const SplatParams& params,
                                         const RenderControl& control, Stats& stats) {
    return directional_estimate(hierarchy, samples, photons, params, control, stats).radiance;
}

std::unique_ptr<Splatter> make_directional_splatter(const RenderSettings& settings) {
    return std::make_unique<DirectionalSplatter>(settings.directional_level);
}

}  // namespace ps
