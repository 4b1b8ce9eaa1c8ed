// Splatting through the view-sample cluster hierarchy, in three steps:
//   1. traverse: each photon walks the hierarchy, skipping every node its sphere cannot reach, and records a
//      (leaf, photon) pair per leaf it may touch;
//   2. lists: a stable counting sort turns the pairs into one photon list per leaf, photon indices ascending;
//   3. shade: each leaf shades its own samples from its list (so no two threads write one output), adding to a
//      double sum per sample.
// Each sample thus sees the photons that can reach it in ascending index order, exactly as in `brute`, and
// the output is the same bit for bit unless the compiler orders the arithmetic differently.
//
// Bounded memory. The pairs grow as photons × leaves touched: with a radius as large as the scene that is
// photons × all leaves (~1.9e10 pairs at 1080p with 200k photons). So photons are splatted in batches of
// consecutive indices, each sorted and shaded before the next is added, and the per-sample sums carry over from
// batch to batch. Batches come in ascending photon order and each list is ascending, so every sample still adds
// its photons in ascending index order into one glm::dvec3: the output does not depend on where batches end.
//
// The pairs held at once stay under SplatParams::max_pairs_in_memory (the cap). The photons flow through an
// ordered pipeline:
//   - a serial stage cuts the photons into consecutive ranges, sized from the pairs per photon seen so far so
//     that a range is expected to hold half of `range_pairs` (1024 photons at most, a few at the start);
//   - ranges are traversed in parallel, `ranges_in_flight` at once; a range stops before a photon once it holds
//     `range_pairs` pairs (never before its first photon, so one photon that alone exceeds the cap still works);
//   - a serial stage takes ranges in photon order, traverses what is left of a range that stopped (in pieces,
//     in order), and adds the pieces to the batch, sorting and shading the batch first when a piece would take
//     it past `batch_pairs`. It also counts the pairs per leaf as they come, overlapping the lists' first pass
//     with the traversal.
// In flight are at most ranges_in_flight × range_pairs pairs (= cap − batch_pairs), plus the pairs of one
// photon per range; ranges_in_flight is lowered where the leaves are many for the cap so that this excess
// stays under cap / 2. When everything fits, which a typical radius does, there is one batch, shaded once
// traversal is over, as without batches; the pipeline then costs about what a parallel loop over chunks would.
//
// cluster_cone (Moreau et al. 2016, "cluster-trivial") is the same pipeline (ClusterSplat<true>) with the
// hierarchy's normal cones. A node is also rejected when every normal in its cone faces away from the photon
// (R2: n·ωi <= 0) or differs from the photon's normal by more than τ (R3: n·n_p <= cos τ); and it is ACCEPTED
// whole when its box lies inside the sphere, every normal faces the photon and is within τ of n_p (A2, A3), all
// its samples are diffuse-only and regular, and the plane-distance test is off or provably passed. Every test
// is conservative with margins (cone_tests in hierarchy.h): an accept never includes a sample the per-sample
// test would refuse, a reject never drops one it would take. An accept is a pair (node | kAcceptBit, photon)
// in the same segment buffers; the serial output stage, which sees photons in ascending order, adds the
// photon's power to the node's accumulator at once (so accepts never reach the lists): the sums are
// deterministic. At the end a top-down pass adds every node's accumulator to its children's, and each sample
// adds its leaf's total × its BRDF (diffuse: f = ρ/π whatever ωi) to what its list gave it.
// Kernels: uniform K is constant inside the sphere, so the accumulator is ΣΦ. Epanechnikov stays exact through
// per-node moments S0 = ΣΦ, S1 = ΣΦ·q, S2 = ΣΦ·|q|² with q = p − (node box centre):
//     ΣΦ·(1 − |x' − q|²/r²) = (1 − |x'|²/r²)·S0 + (2/r²)·x'·S1 − S2/r²,   x' = x − (box centre),
// shifted to each child's centre on the way down (S1 += δ·S0, S2 += 2δ·S1 + |δ|²·S0). Its accept also asks the
// box to lie within |x − p|² < 0.95·r², so that every accepted weight 2(1 − |x − p|²/r²) is >= 0.1, where the
// per-sample path's float rounding of |x − p|² moves a weight by < 1e-5 relative.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/render_control.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"
#include "splat_inputs.h"
#include "photonsplat/validation.h"
#include "photonsplat/splatter.h"

#include "../building_blocks.h"

namespace ps {
namespace {

// Photon ranges: at most this many photons (enough to make a range's overhead negligible), and this many while
// nothing is known yet about the pairs per photon (small, so that a huge radius does not start with ranges that
// must stop early and be finished serially).
constexpr size_t kMaxPhotonsPerRange = 1024;
constexpr size_t kFirstPhotonsPerRange = 16;
// The share of the cap for ranges in flight: 1/16. The rest is for the batch.
constexpr uint64_t kInFlightShareDivisor = 16;

// Squared distance from p to the box, written with the same float operations as the per-sample test's
// dot(x − p, x − p). For x in the box, each gap component is a correctly rounded difference that is never
// larger in magnitude than the rounded x − p on that axis (rounding is monotone), and squaring and summing
// are monotone too: so this is never larger than the distance the per-sample test computes for any sample
// in the box. Rejecting when it is >= r² could therefore never lose a sample; the reject threshold adds a
// 1e-5 relative margin on top in case the compiler contracts one of the two expressions into FMAs.
inline float distance_sq_to_box(const glm::vec3& p, const glm::vec3& box_min, const glm::vec3& box_max) {
    const glm::vec3 gap = glm::max(glm::max(box_min - p, p - box_max), glm::vec3(0.0f));
    return glm::dot(gap, gap);
}
inline float distance_sq_to_box(const glm::vec3& p, const ClusterNode& node) {
    return distance_sq_to_box(p, node.box_min, node.box_max);
}

// cluster_cone's copy of a node: box, cone, children and flags in 48 bytes, so that a node test reads one
// place (the traversal is bound by fetching nodes: three arrays cost three misses, and a 64-byte node more
// bandwidth than it saves). `children` packs first_child (low 27 bits), child_count (4 bits) and whether the
// node may be accepted (all diffuse-only and regular, top bit).
constexpr uint32_t kConeNodeChildBits = 27;
constexpr uint32_t kConeNodeAcceptable = 0x80000000u;
struct alignas(16) ConeNode {
    glm::vec3 box_min;
    uint32_t children;
    glm::vec3 box_max;
    float cos_angle;
    glm::vec3 axis;
    float sin_angle;
    uint32_t first_child() const { return children & ((1u << kConeNodeChildBits) - 1); }
    uint32_t child_count() const { return (children >> kConeNodeChildBits) & 15u; }
    bool acceptable() const { return (children & kConeNodeAcceptable) != 0; }
    NormalCone cone() const { return NormalCone{axis, cos_angle, sin_angle}; }
};
static_assert(sizeof(ConeNode) == 48, "three nodes per three cache lines");

// An accept pair's node carries this bit in the segment buffers (node indices stay below it: checked).
constexpr uint32_t kAcceptBit = 0x80000000u;

// How the cap is shared out (see the top of the file).
struct PairBudget {
    size_t ranges_in_flight = 1;
    size_t range_pairs = 1;  // a range stops before a photon (not its first) once it holds this many pairs
    size_t batch_pairs = 0;  // a batch is shaded before a piece would take it past this (unless it is empty)
};

PairBudget pair_budget(uint64_t max_pairs, size_t leaf_count, size_t threads) {
    const uint64_t cap = std::max<uint64_t>(max_pairs, 1);
    PairBudget b;
    // Each range in flight may go past range_pairs by one photon's pairs, at most one per leaf.
    const uint64_t ranges = cap / (2 * std::max<uint64_t>(leaf_count, 1));
    b.ranges_in_flight = size_t(std::clamp<uint64_t>(ranges, 1, 2 * std::max<uint64_t>(threads, 1)));
    const uint64_t in_flight = std::max<uint64_t>(b.ranges_in_flight, cap / kInFlightShareDivisor);
    b.range_pairs = size_t(in_flight / b.ranges_in_flight);
    b.batch_pairs = size_t(cap - std::min(cap, in_flight));
    return b;
}

// The pairs of consecutive photons [begin, end), photon by photon (the photon of a pair is implied).
struct Segment {
    uint32_t begin = 0;
    uint32_t end = 0;              // one past the last photon traversed so far
    uint32_t range_end = 0;        // one past the last photon of the range this segment is (the start of)
    size_t expected_pairs = 0;     // a capacity hint
    std::vector<uint32_t> leaves;  // the leaf node of every pair, photons ascending
    std::vector<uint32_t> ends;    // ends[j − begin]: one past photon j's last pair in `leaves`
    uint64_t node_tests = 0;
    uint64_t rejects_distance = 0, rejects_facing = 0, rejects_orientation = 0;  // cluster_cone: also the cones'
    uint64_t accepts = 0;  // cluster_cone: accept pairs (node | kAcceptBit in `leaves`)
    size_t bytes() const { return (leaves.capacity() + ends.capacity()) * sizeof(uint32_t); }
};

// What cluster_cone accepted, per node: the sum of the accepted photons' power (uniform kernel), or their moments
// about the node's box centre (Epanechnikov). Filled in photon order by the serial output stage; push_down then
// turns every node's entry into the total of the node and its ancestors.
class AcceptedFlux {
public:
    void init(const ClusterHierarchy& hierarchy, bool moments) {
        moments_ = moments;
        nodes_.assign(hierarchy.nodes.size(), Node());
        if (moments_) {
            first_.assign(3 * hierarchy.nodes.size(), glm::dvec3(0.0));
            second_.assign(hierarchy.nodes.size(), glm::dvec3(0.0));
            centres_.resize(hierarchy.nodes.size());
            for (size_t i = 0; i < hierarchy.nodes.size(); ++i)
                centres_[i] = 0.5 * (glm::dvec3(hierarchy.nodes[i].box_min) + glm::dvec3(hierarchy.nodes[i].box_max));
        }
    }
    size_t bytes() const {
        return nodes_.capacity() * sizeof(Node) +
               (first_.capacity() + second_.capacity() + centres_.capacity()) * sizeof(glm::dvec3);
    }

    // Σ over accepts of the accepted node's samples: the (sample, photon) pairs reached through accepts.
    uint64_t accepted_samples(const ClusterHierarchy& hierarchy) const {
        uint64_t total = 0;
        for (size_t i = 0; i < nodes_.size(); ++i)
            total += uint64_t(nodes_[i].count) * (hierarchy.nodes[i].sample_end - hierarchy.nodes[i].sample_begin);
        return total;
    }

    void add(uint32_t node, const glm::vec3& position, const Photon& photon) {
        const glm::dvec3 power(photon.power);
        Node& n = nodes_[node];
        n.flux += power;
        n.any = 1;
        ++n.count;
        if (moments_) {
            const glm::dvec3 q = glm::dvec3(position) - centres_[node];
            for (int c = 0; c < 3; ++c) first_[node * 3 + c] += power[c] * q;
            second_[node] += power * glm::dot(q, q);
        }
    }

    // Top-down over the breadth-first layout (parents before children): child += parent, moments shifted to the
    // child's centre. Nodes under no accept keep nothing (and their centre, perhaps of an empty box, is unused).
    void push_down(const ClusterHierarchy& hierarchy) {
        for (size_t i = 0; i < hierarchy.nodes.size(); ++i) {
            const ClusterNode& node = hierarchy.nodes[i];
            if (!nodes_[i].any || node.child_count == 0) continue;
            const glm::dvec3 flux = nodes_[i].flux;
            for (uint32_t c = node.first_child; c != node.first_child + node.child_count; ++c) {
                nodes_[c].any = 1;
                nodes_[c].flux += flux;
                if (!moments_) continue;
                const glm::dvec3 delta = centres_[i] - centres_[c];  // q_child = q_parent + delta
                double s2[3];
                for (int k = 0; k < 3; ++k) {
                    const glm::dvec3 s1 = first_[i * 3 + k] + delta * flux[k];
                    s2[k] = second_[i][k] + 2.0 * glm::dot(delta, first_[i * 3 + k]) + glm::dot(delta, delta) * flux[k];
                    first_[c * 3 + k] += s1;
                }
                second_[c] += glm::dvec3(s2[0], s2[1], s2[2]);
            }
        }
    }

    bool any(uint32_t node) const { return nodes_[node].any != 0; }

    // Σ Φ·w over the photons accepted by `node` and its ancestors, w the kernel relative to uniform (as in
    // kernel_weight) at the sample position x; per colour channel.
    glm::dvec3 weighted_power(uint32_t node, const glm::vec3& x, double radius) const {
        const glm::dvec3& flux = nodes_[node].flux;
        if (!moments_) return flux;
        const glm::dvec3 q = glm::dvec3(x) - centres_[node];
        const double inv_r2 = 1.0 / (radius * radius);
        const double outer = 1.0 - glm::dot(q, q) * inv_r2;
        glm::dvec3 out;
        for (int k = 0; k < 3; ++k)
            out[k] = 2.0 * (outer * flux[k] + 2.0 * inv_r2 * glm::dot(q, first_[node * 3 + k]) -
                            second_[node][k] * inv_r2);
        return out;
    }

private:
    struct Node {                      // one 32-byte line per node: an accept touches one place
        glm::dvec3 flux{0.0};          // S0 = ΣΦ
        uint32_t count = 0;            // photons accepted here
        uint32_t any = 0;              // something was accepted here or above
    };
    bool moments_ = false;
    std::vector<Node> nodes_;
    std::vector<glm::dvec3> first_;    // Epanechnikov: S1, three per node (one per colour channel): ΣΦ_c·q
    std::vector<glm::dvec3> second_;   // Epanechnikov: S2 = ΣΦ·|q|²
    std::vector<glm::dvec3> centres_;  // Epanechnikov: box centres, in double
};

template <bool kCones>
class ClusterSplat : private SplatInputs {
public:
    ClusterSplat(const ClusterHierarchy& hierarchy, const ViewSamples& samples, const PhotonMap& photons,
                 const SplatParams& params, const RenderControl& control, Stats& stats)
        : SplatInputs(samples, photons, params, control, stats),
          hierarchy_(hierarchy),
          radiance_(views_.size(), glm::vec3(0.0f)) {
        const float r = params.radius;
        reject_distance_sq_ = (r * r) * (1.0f + 1e-5f);
        budget_ = pair_budget(params.max_pairs_in_memory, hierarchy.leaves.size(),
                              size_t(tbb::this_task_arena::max_concurrency()));
        if constexpr (kCones) {
            // Accept margins on |x − p|² (see the top of the file): uniform 1e-5 against rounding; Epanechnikov
            // keeps every accepted weight >= 0.1. A kernel added later gets no accept until it is made exact.
            if (params.kernel == Kernel::uniform) {
                accept_distance_sq_ = (r * r) * (1.0f - 1e-5f);
            } else if (params.kernel == Kernel::epanechnikov) {
                accept_distance_sq_ = (r * r) * 0.95f;
            } else {
                accept_distance_sq_ = -1.0f;
            }
            accepted_.init(hierarchy, params.kernel != Kernel::uniform);
            cone_nodes_.resize(hierarchy.nodes.size());
            tbb::parallel_for(tbb::blocked_range<size_t>(0, cone_nodes_.size(), 4096),
                              [&](const tbb::blocked_range<size_t>& range) {
                                  for (size_t i = range.begin(); i != range.end(); ++i) {
                                      const ClusterNode& n = hierarchy.nodes[i];
                                      const NormalCone& cone = hierarchy.cones[i];
                                      ConeNode& c = cone_nodes_[i];
                                      c.box_min = n.box_min;
                                      c.box_max = n.box_max;
                                      c.children = n.first_child | n.child_count << kConeNodeChildBits |
                                                   (hierarchy.node_flags[i] == (kNodeDiffuseOnly | kNodeRegular)
                                                        ? kConeNodeAcceptable
                                                        : 0u);
                                      c.axis = cone.axis;
                                      c.cos_angle = cone.cos_angle;
                                      c.sin_angle = cone.sin_angle;
                                  }
                              });
        }
    }

    std::vector<glm::vec3> run() {
        // offsets_[n + 2] counts leaf n's pairs of the batch so far (see shade_batch).
        offsets_.assign(hierarchy_.nodes.size() + 2, 0);
        meter_.add(int64_t(offsets_.capacity() * sizeof(size_t)));
        const auto start = std::chrono::steady_clock::now();
        const auto cut = tbb::make_filter<void, Segment*>(
            tbb::filter_mode::serial_in_order, [this](tbb::flow_control& fc) { return next_range(fc); });
        const auto walk = tbb::make_filter<Segment*, Segment*>(tbb::filter_mode::parallel, [this](Segment* segment) {
            traverse(*segment);
            return segment;
        });
        const auto take = tbb::make_filter<Segment*, void>(tbb::filter_mode::serial_in_order, [this](Segment* segment) {
            take_range(*segment);
            release(segment);
        });
        tbb::parallel_pipeline(budget_.ranges_in_flight, cut & walk & take);
        const std::chrono::duration<double> pipeline = std::chrono::steady_clock::now() - start;
        // The pipeline's time, less the batches it shaded on the way: traversal (overlapped with counting).
        stats_.seconds["splat_traverse"] += pipeline.count() - seconds_in_batches_;
        if constexpr (kCones) {
            StageTimer timer(stats_, "splat_shade");
            accepted_samples_ = accepted_.accepted_samples(hierarchy_);
            accepted_.push_down(hierarchy_);
        }
        shade_batch(true);

        stats_.counters["photon_node_tests"] += double(node_tests_);
        stats_.counters["node_rejects_distance"] += double(rejects_distance_);
        stats_.counters["photon_sample_tests"] += double(sample_tests_.load());
        stats_.counters["contributing_pairs"] += double(contributing_.load() + accepted_samples_);
        if constexpr (kCones) {
            stats_.counters["node_rejects_cone_facing"] += double(rejects_facing_);
            stats_.counters["node_rejects_cone_orientation"] += double(rejects_orientation_);
            stats_.counters["node_accepts"] += double(accepts_);
            stats_.counters["accepted_samples"] += double(accepted_samples_);
            stats_.bytes["accepted_flux"] = double(accepted_.bytes());
            stats_.bytes["cone_traversal_nodes"] = double(cone_nodes_.capacity() * sizeof(ConeNode));
        }
        report_batches("leaf", total_pairs_, batches_, double(meter_.peak()),
                       double(sums_.capacity() * sizeof(glm::dvec3)));
        return std::move(radiance_);
    }

private:
    // Input stage (serial): the next range of photons.
    Segment* next_range(tbb::flow_control& fc) {
        if (next_photon_ == positions_.size()) {
            fc.stop();
            return nullptr;
        }
        const double estimate = pairs_per_photon_.load(std::memory_order_relaxed);
        size_t count = kFirstPhotonsPerRange;
        if (estimate >= 0.0) {
            const double fit = double(budget_.range_pairs) / (2.0 * std::max(estimate, 1e-3));
            count = size_t(std::clamp(fit, 1.0, double(kMaxPhotonsPerRange)));
        }
        Segment* segment = acquire();
        segment->begin = segment->end = uint32_t(next_photon_);
        next_photon_ = std::min(positions_.size(), next_photon_ + count);
        segment->range_end = uint32_t(next_photon_);
        if (estimate >= 0.0)
            segment->expected_pairs = size_t(std::min(double(budget_.range_pairs), 1.25 * estimate * double(count)));
        return segment;
    }

    // Traverses photons from segment.end on, until the range ends or the segment holds range_pairs pairs.
    void traverse(Segment& segment) {
        const size_t before = segment.bytes();
        segment.leaves.reserve(segment.expected_pairs);
        segment.ends.reserve(segment.range_end - segment.end);
        std::vector<uint32_t> stack;
        stack.reserve(7 * size_t(hierarchy_.depth) + 1);  // depth-first: at most 7 siblings waiting per level
        for (uint32_t j = segment.end; j != segment.range_end; ++j) {
            if (j != segment.begin && segment.leaves.size() >= budget_.range_pairs) break;
            control_.check();
            const glm::vec3& p = positions_[j];
            if (is_finite(p)) {  // else it can pass no per-sample test, and would visit every node
                if constexpr (kCones) {
                    walk_with_cones(p, photons_[j], segment, stack);
                } else {
                    stack.push_back(hierarchy_.root);
                    while (!stack.empty()) {
                        const uint32_t index = stack.back();
                        stack.pop_back();
                        const ClusterNode& node = hierarchy_.nodes[index];
                        ++segment.node_tests;
                        if (distance_sq_to_box(p, node) > reject_distance_sq_) {
                            ++segment.rejects_distance;
                            continue;
                        }
                        if (node.child_count == 0) {
                            segment.leaves.push_back(index);
                        } else {
                            for (uint32_t c = node.child_count; c-- > 0;) stack.push_back(node.first_child + c);
                        }
                    }
                }
            }
            segment.ends.push_back(uint32_t(segment.leaves.size()));
            segment.end = j + 1;
        }
        meter_.add(int64_t(segment.bytes()) - int64_t(before));
    }

    // One photon's walk with the cone tests (cone_tests in hierarchy.h). Children are tested together when their
    // parent is opened: they lie side by side (ConeNode), and their lines are prefetched as the parent is pushed.
    // The walk is bound by fetching nodes and by mispredicted branches, so the tests are combined into one
    // branch per outcome, and the counters are kept in registers. The stack holds nodes tested, to be opened.
    void walk_with_cones(const glm::vec3& p, const Photon& photon, Segment& segment, std::vector<uint32_t>& stack) {
        using namespace cone_tests;
        const float reject_d2 = reject_distance_sq_, accept_d2 = accept_distance_sq_;
        const float kappa = params_.plane_distance_factor;
        const ConeNode* nodes = cone_nodes_.data();
        // Many photons land nowhere near the visible samples (behind the camera, in other rooms): the root's
        // distance test alone rejects them, before photon_cone's square roots and divisions in double.
        if (distance_sq_to_box(p, nodes[hierarchy_.root].box_min, nodes[hierarchy_.root].box_max) > reject_d2) {
            ++segment.node_tests;
            ++segment.rejects_distance;
            return;
        }
        const PhotonCone pc = photon_cone(photon.wi, photon.normal, params_.cos_normal_tolerance);
        // An inside photon (photons.h) reaches only inside samples, which accepted nodes never hold.
        const bool inside = (photon.flags & kInsidePhoton) != 0;
        std::vector<uint32_t>& out = segment.leaves;
        uint64_t tests = 0, far = 0, facing_away = 0, misoriented_count = 0, accepts = 0;
        stack.clear();
        // A node whose cone passed A2 and A3 passes them for every sample below it: its children skip the cone
        // tests (no R2 or R3 can hold there either). Stack entries carry that in kConesPassed.
        constexpr uint32_t kConesPassed = 0x80000000u;
        uint32_t first = hierarchy_.root, end = hierarchy_.root + 1;
        bool passed = false;  // the cones of [first, end) are known to pass
        for (;;) {
            tests += end - first;
            for (uint32_t index = first; index != end; ++index) {
                const ConeNode& node = nodes[index];
                if (distance_sq_to_box(p, node.box_min, node.box_max) > reject_d2) {
                    ++far;
                    continue;
                }
                const NormalCone cone = node.cone();
                bool cones_pass = passed;
                if (!passed) {
                    const bool r2 = faces_away(cone, pc), r3 = misoriented(cone, pc);
                    if (r2 | r3) {
                        facing_away += r2;
                        misoriented_count += !r2;
                        continue;
                    }
                    const bool faces = faces_photon(cone, pc), within = oriented(cone, pc);
                    cones_pass = faces & within;
                }
                const float max_d2 = max_distance_sq(p, node.box_min, node.box_max);
                bool accept = (max_d2 < accept_d2) & node.acceptable() & cones_pass & !inside;
                if (kappa > 0.0f && accept)
                    accept = plane_test_passes(p, node.box_min, node.box_max, cone, max_d2, params_.radius, kappa);
                if (accept) {
                    out.push_back(index | kAcceptBit);
                    ++accepts;
                } else if (node.child_count() == 0) {
                    out.push_back(index);
                } else {
                    // Opened soon (the stack is LIFO): start fetching its children now.
                    const uintptr_t from = reinterpret_cast<uintptr_t>(nodes + node.first_child());
                    const uintptr_t to = reinterpret_cast<uintptr_t>(nodes + node.first_child() + node.child_count());
                    for (uintptr_t line = from & ~uintptr_t(63); line < to; line += 64)
                        __builtin_prefetch(reinterpret_cast<const void*>(line));
                    stack.push_back(index | (cones_pass ? kConesPassed : 0u));
                }
            }
            if (stack.empty()) break;
            const uint32_t entry = stack.back();
            stack.pop_back();
            const ConeNode& open = nodes[entry & ~kConesPassed];
            passed = (entry & kConesPassed) != 0;
            first = open.first_child();
            end = first + open.child_count();
        }
        segment.node_tests += tests;
        segment.rejects_distance += far;
        segment.rejects_facing += facing_away;
        segment.rejects_orientation += misoriented_count;
        segment.accepts += accepts;
    }

    // The pipeline's tokens are Segment pointers into segments_, which owns them: TBB does not destroy the tokens
    // of a pipeline that an exception (a cancel) stopped. At most ranges_in_flight are in use at once.
    Segment* acquire() {
        std::lock_guard<std::mutex> lock(segments_mutex_);
        if (free_segments_.empty()) {
            segments_.push_back(std::make_unique<Segment>());
            return segments_.back().get();
        }
        Segment* segment = free_segments_.back();
        free_segments_.pop_back();
        return segment;
    }

    void release(Segment* segment) {
        *segment = Segment();  // its buffers were moved to the batch; this resets the rest
        std::lock_guard<std::mutex> lock(segments_mutex_);
        free_segments_.push_back(segment);
    }

    // Output stage (serial, in photon order): adds a traversed range to the batch, finishing it here if it
    // stopped early, and updates the estimate of pairs per photon.
    void take_range(Segment& first) {
        const uint32_t range_begin = first.begin, range_end = first.range_end;
        size_t pairs = first.leaves.size();
        uint32_t done = first.end;
        add_to_batch(first);
        while (done != range_end) {
            Segment rest;
            rest.begin = rest.end = done;
            rest.range_end = range_end;
            traverse(rest);
            pairs += rest.leaves.size();
            done = rest.end;
            add_to_batch(rest);
        }
        // Follows a rise at once and a fall slowly: ranges sized for too few pairs stop early, and their rest
        // is traversed serially here.
        // Progress: photons traversed, then (in the last batch) leaves shaded.
        control_.advance(range_end, positions_.size() + hierarchy_.leaves.size());
        const double sample = double(pairs) / double(range_end - range_begin);
        const double previous = pairs_per_photon_.load(std::memory_order_relaxed);
        pairs_per_photon_.store(previous < 0.0 ? sample : std::max(sample, 0.75 * previous + 0.25 * sample),
                                std::memory_order_relaxed);
    }

    void add_to_batch(Segment& segment) {
        // The budget counts every entry the segment's buffers hold (accepts too, until the batch releases them).
        const size_t entries = segment.leaves.size();
        if (batch_entries_ > 0 && batch_entries_ + entries > budget_.batch_pairs) {
            const auto start = std::chrono::steady_clock::now();
            shade_batch(false);
            const std::chrono::duration<double> d = std::chrono::steady_clock::now() - start;
            seconds_in_batches_ += d.count();
        }
        if constexpr (kCones) {
            // Photon order: accepts go to their node's accumulator now, leaf pairs are kept, compacted in place.
            size_t kept = 0, k = 0;
            for (uint32_t j = segment.begin; j != segment.end; ++j) {
                uint32_t& end = segment.ends[j - segment.begin];
                for (; k != end; ++k) {
                    const uint32_t entry = segment.leaves[k];
                    if (entry & kAcceptBit) {
                        accepted_.add(entry & ~kAcceptBit, positions_[j], photons_[j]);
                    } else {
                        segment.leaves[kept++] = entry;
                        ++offsets_[entry + 2];
                    }
                }
                end = uint32_t(kept);
            }
            segment.leaves.resize(kept);  // keeps the capacity, which the meter still counts
            rejects_facing_ += segment.rejects_facing;
            rejects_orientation_ += segment.rejects_orientation;
            accepts_ += segment.accepts;
        } else {
            for (const uint32_t leaf : segment.leaves) ++offsets_[leaf + 2];
        }
        const size_t pairs = segment.leaves.size();
        node_tests_ += segment.node_tests;
        rejects_distance_ += segment.rejects_distance;
        batch_entries_ += entries;
        batch_pairs_ += pairs;
        total_pairs_ += pairs;
        batch_.push_back(std::move(segment));  // moves the buffers out of the pipeline's token
    }

    // Sorts the batch's pairs into per-leaf lists and shades the leaves. With `last`, every sample is finished;
    // otherwise the leaves with photons add them to their samples' sums.
    void shade_batch(bool last) {
        {
            StageTimer timer(stats_, "splat_lists");
            // offsets_[n + 2] holds leaf n's count; the prefix sum makes offsets_[n + 1] the start of leaf n's
            // list, and filling advances it to the list's end, which is the start of leaf n + 1's: then
            // leaf n's photons are list_[offsets_[n], offsets_[n + 1]), with no cursor array.
            for (size_t n = 0; n + 2 < offsets_.size(); ++n) offsets_[n + 2] += offsets_[n + 1];
            const size_t before = list_.capacity() * sizeof(uint32_t);
            if (batch_pairs_ > list_.capacity()) {  // exactly: resize alone would double the capacity
                list_ = std::vector<uint32_t>();
                list_.reserve(last ? batch_pairs_ : std::max(batch_pairs_, budget_.batch_pairs));
            }
            list_.resize(batch_pairs_);
            meter_.add(int64_t(list_.capacity() * sizeof(uint32_t)) - int64_t(before));
            for (Segment& segment : batch_) {  // photon order: every list comes out ascending
                size_t k = 0;
                for (uint32_t j = segment.begin; j != segment.end; ++j)
                    for (const size_t end = segment.ends[j - segment.begin]; k != end; ++k)
                        list_[offsets_[segment.leaves[k] + 1]++] = j;
                meter_.add(-int64_t(segment.bytes()));
                segment = Segment();  // release as we go: the pairs and the lists are the two largest buffers
            }
            batch_.clear();
        }
        control_.check();
        if (!last && sums_.empty()) sums_.assign(views_.size(), glm::dvec3(0.0));
        {
            StageTimer timer(stats_, "splat_shade");
            const std::vector<uint32_t>& leaves = hierarchy_.leaves;
            tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.size(), 16),
                              [&](const tbb::blocked_range<size_t>& range) { shade_leaves(range, last); });
        }
        std::fill(offsets_.begin(), offsets_.end(), size_t(0));
        batch_pairs_ = 0;
        batch_entries_ = 0;
        ++batches_;
    }

    // The lists are short (a few photons per leaf on a typical frame: most of the flux arrives through accepts),
    // so the per-sample test runs directly on them; the last pass is bound by reading the samples themselves.
    void shade_leaves(const tbb::blocked_range<size_t>& range, bool last) {
        const bool carried = !sums_.empty();
        [[maybe_unused]] const double r = params_.radius;
        uint64_t tests = 0, contributing = 0;
        if (last) {
            // Progress once per chunk of leaves: a shared counter bumped per leaf would bounce between cores.
            const uint64_t shaded = leaves_shaded_.fetch_add(range.size(), std::memory_order_relaxed) + range.size();
            control_.advance(positions_.size() + shaded, positions_.size() + hierarchy_.leaves.size());
        }
        for (size_t l = range.begin(); l != range.end(); ++l) {
            const uint32_t leaf = hierarchy_.leaves[l];
            const uint32_t* list = list_.data() + offsets_[leaf];
            const size_t list_size = offsets_[leaf + 1] - offsets_[leaf];
            if (list_size == 0 && !last) continue;
            [[maybe_unused]] const bool accepted_here = kCones && last && accepted_.any(leaf);
            // A leaf that nothing reached (no photon in any batch, no accept above it) would only write
            // finish_sample(s, 0) = 0 × throughput = 0, which radiance_ already holds: skipping it spares reading
            // its samples, much of the last pass's time where photons are sparse. (This assumes a finite
            // throughput, a product of BSDF weights, where 0 × throughput could not be NaN.)
            if (last && list_size == 0 && !carried && !accepted_here) continue;
            control_.check();
            const ClusterNode& node = hierarchy_.nodes[leaf];
            for (uint32_t k = node.sample_begin; k != node.sample_end; ++k) {
                const uint32_t i = hierarchy_.sample_order[k];
                // The samples of a leaf are scattered through views_ (pixel order): fetch a few ahead, since
                // the loop is bound by these misses rather than by arithmetic.
                if (k + 4 < node.sample_end) {
                    const char* ahead = reinterpret_cast<const char*>(&views_[hierarchy_.sample_order[k + 4]]);
                    __builtin_prefetch(ahead);
                    __builtin_prefetch(ahead + sizeof(ViewSample) - 1);
                }
                const ViewSample& s = views_[i];
                glm::dvec3 reflected_flux = carried ? sums_[k] : glm::dvec3(0.0);
                for (size_t m = 0; m != list_size; ++m) {
                    const uint32_t j = list[m];
                    if (!photon_reaches_sample(s, positions_[j], photons_[j], params_)) continue;
                    reflected_flux += photon_reflected_flux(s, lobes_, positions_[j], photons_[j], params_);
                    ++contributing;
                }
                if constexpr (kCones) {
                    // The photons accepted by the leaf or its ancestors: all diffuse-only here, f = ρ/π for any ωi.
                    if (last && accepted_here)
                        reflected_flux += sample_brdf(s, lobes_, s.normal, params_.label_share) *
                                          accepted_.weighted_power(leaf, s.position, r);
                }
                if (last)
                    radiance_[i] = finish_sample(s, reflected_flux, params_);
                else
                    sums_[k] = reflected_flux;
            }
            tests += uint64_t(list_size) * (node.sample_end - node.sample_begin);
        }
        sample_tests_ += tests;
        contributing_ += contributing;
    }

    const ClusterHierarchy& hierarchy_;
    float reject_distance_sq_ = 0.0f;
    float accept_distance_sq_ = -1.0f;  // cluster_cone: accept a node only when its farthest point is nearer
    PairBudget budget_;

    size_t next_photon_ = 0;                      // input stage
    std::atomic<double> pairs_per_photon_{-1.0};  // output stage → input stage; < 0 until known
    std::atomic<uint64_t> leaves_shaded_{0};       // in the last batch, for progress
    std::mutex segments_mutex_;                   // input and output stages
    std::vector<std::unique_ptr<Segment>> segments_;
    std::vector<Segment*> free_segments_;

    std::vector<Segment> batch_;    // output stage: the pairs of the batch, photons ascending
    size_t batch_pairs_ = 0;        // leaf pairs: what the lists will hold
    size_t batch_entries_ = 0;      // every entry the batch's segment buffers held, accepts included
    std::vector<size_t> offsets_;   // pair counts per leaf while filling, then the lists' CSR offsets
    std::vector<uint32_t> list_;    // the batch's per-leaf photon lists
    std::vector<glm::dvec3> sums_;  // per position in sample_order: Σ f_r·Φ so far; empty while one batch
    std::vector<glm::vec3> radiance_;

    AcceptedFlux accepted_;             // cluster_cone only
    std::vector<ConeNode> cone_nodes_;  // cluster_cone only

    ByteMeter meter_;
    uint64_t node_tests_ = 0, total_pairs_ = 0, batches_ = 0, rejects_distance_ = 0;
    uint64_t rejects_facing_ = 0, rejects_orientation_ = 0, accepts_ = 0, accepted_samples_ = 0;
    std::atomic<uint64_t> sample_tests_{0}, contributing_{0};
    double seconds_in_batches_ = 0.0;
};

// What both entry points check and report before splatting; false when there is nothing to splat.
bool prepare(const char* method, const ClusterHierarchy& hierarchy, const ViewSamples& samples,
             const PhotonMap& photons, const SplatParams& params, const RenderControl& control, Stats& stats,
             bool cones) {
    validate(params, photons);
    validate(hierarchy, samples, photons);
    if (cones && !hierarchy.empty() && !hierarchy.has_cones())
        throw InvalidInput("cluster hierarchy", std::string("built without normal cones, which the ") + method +
                                                    " method needs (ClusterBuildOptions::normal_cones)");
    if (cones && hierarchy.nodes.size() > (size_t(1) << kConeNodeChildBits))
        throw InvalidInput("cluster hierarchy", "too many nodes for the " + std::string(method) + " method");
    control.check();
    stats.bytes["hierarchy"] = double(hierarchy.bytes());
    for (const char* name : {"photon_node_tests", "node_rejects_distance", "photon_sample_tests",
                             "contributing_pairs", "leaf_photon_pairs", "splat_batches"})
        stats.counters[name] += 0.0;  // present even when there is nothing to splat
    if (cones) {
        stats.bytes["cones"] = double(hierarchy.cone_bytes());
        for (const char* name : {"node_rejects_cone_facing", "node_rejects_cone_orientation", "node_accepts",
                                 "accepted_samples"})
            stats.counters[name] += 0.0;
    }
    if (hierarchy.empty() || photons.photons.empty()) {
        stats.bytes["leaf_photon_lists"] = 0.0;
        if (cones) stats.bytes["accepted_flux"] = 0.0;
        return false;
    }
    return true;
}

// Both entry points: the checks, then the splat with or without cones.
template <bool kCones>
std::vector<glm::vec3> cluster_splat(const char* method, const ClusterHierarchy& hierarchy, const ViewSamples& samples,
                                     const PhotonMap& photons, const SplatParams& params,
                                     const RenderControl& control, Stats& stats) {
    if (!prepare(method, hierarchy, samples, photons, params, control, stats, kCones))
        return std::vector<glm::vec3>(samples.samples.size(), glm::vec3(0.0f));  // (emitted may be 0)
    return ClusterSplat<kCones>(hierarchy, samples, photons, params, control, stats).run();
}

}  // namespace

std::vector<glm::vec3> splat_cluster(const ClusterHierarchy& hierarchy, const ViewSamples& samples,
                                     const PhotonMap& photons, const SplatParams& params,
                                     const RenderControl& control, Stats& stats) {
    return cluster_splat<false>("cluster", hierarchy, samples, photons, params, control, stats);
}

std::vector<glm::vec3> splat_cluster_cone(const ClusterHierarchy& hierarchy, const ViewSamples& samples,
                                          const PhotonMap& photons, const SplatParams& params,
                                          const RenderControl& control, Stats& stats) {
    return cluster_splat<true>("cluster_cone", hierarchy, samples, photons, params, control, stats);
}

namespace {

// cluster and cluster_cone: the same splat, with or without the normal cones' trivial reject and accept.
template <bool kCones>
class ClusterSplatter final : public Splatter {
public:
    std::optional<ClusterBuildOptions> hierarchy_options() const override {
        ClusterBuildOptions options;
        options.normal_cones = kCones;
        return options;
    }
    SplatMemory predict_memory(const SplatFrame& frame, size_t photons, const SplatParams& params) const override {
        SplatMemory m = cluster_splat_memory(frame, photons);
        if (kCones) {
            const double nodes = double(frame.hierarchy ? frame.hierarchy->nodes.size() : 0);
            m.fixed["cone_traversal_nodes"] = nodes * 48.0;
            m.fixed["accepted_flux"] = nodes * (32.0 + (params.kernel == Kernel::uniform ? 0.0 : 5.0 * 24.0));
        }
        return m;
    }
    SplatEstimate splat(const SplatFrame& frame, const PhotonMap& photons, const SplatParams& params,
                        const RenderControl& control, Stats& stats) const override {
        if (kCones) return {splat_cluster_cone(*frame.hierarchy, frame.samples, photons, params, control, stats)};
        return {splat_cluster(*frame.hierarchy, frame.samples, photons, params, control, stats)};
    }
};

}  // namespace

SplatMemory cluster_splat_memory(const SplatFrame& frame, size_t photons) {
    const double nodes = double(frame.hierarchy ? frame.hierarchy->nodes.size() : 0);
    SplatMemory m;
    m.fixed["photon_positions"] = photon_position_bytes(photons);
    m.fixed["splat_sample_sums"] = sample_sum_bytes(frame.samples.samples.size());
    m.pair_key = "leaf_photon_lists";
    m.pair_fixed = (nodes + 2.0) * double(sizeof(size_t));  // per-node offsets of a batch
    m.per_pair = kPairBytesAtPeak;
    return m;
}

std::unique_ptr<Splatter> make_cluster_splatter(const RenderSettings&) {
    return std::make_unique<ClusterSplatter<false>>();
}

std::unique_ptr<Splatter> make_cluster_cone_splatter(const RenderSettings&) {
    return std::make_unique<ClusterSplatter<true>>();
}

}  // namespace ps
