// Splatting through the view-sample cluster hierarchy, in three steps:
//   1. traverse: each photon walks the hierarchy, skipping every node its sphere cannot reach, and emits a
//      (leaf, photon) pair per leaf it may touch;
//   2. lists: a stable counting sort turns the pairs into one photon list per leaf, photon indices ascending;
//   3. shade: each leaf shades its own samples from its list (so no two threads write one output).
// Each sample thus sees the photons that can reach it in ascending index order, exactly as in `brute`, and
// the output is the same bit for bit unless the compiler orders the arithmetic differently.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/render_control.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"

namespace ps {
namespace {

// Photons are traversed in fixed chunks so that the pairs, and hence everything after, do not depend on how
// TBB splits the work.
constexpr size_t kPhotonsPerChunk = 1024;

struct LeafPhotonPair {
    uint32_t node;
    uint32_t photon;
};

void check_inputs(const SplatParams& params, const PhotonMap& photons) {
    if (!(params.radius > 0.0f) || !std::isfinite(params.radius))
        throw InvalidInput("radius", std::to_string(params.radius) + " is not a positive finite number");
    if (!photons.photons.empty() && params.emitted == 0)
        throw InvalidInput("emitted", "0 emitted photons, but " + std::to_string(photons.photons.size()) +
                                          " stored: the estimate would divide by zero");
}

// Squared distance from p to the box, written with the same float operations as the per-sample test's
// dot(x − p, x − p). For x in the box, each gap component is a correctly rounded difference that is never
// larger in magnitude than the rounded x − p on that axis (rounding is monotone), and squaring and summing
// are monotone too: so this is never larger than the distance the per-sample test computes for any sample
// in the box. Rejecting when it is >= r² could therefore never lose a sample; the reject threshold adds a
// 1e-5 relative margin on top in case the compiler contracts one of the two expressions into FMAs.
float distance_sq_to_box(const glm::vec3& p, const ClusterNode& node) {
    const glm::vec3 gap = glm::max(glm::max(node.box_min - p, p - node.box_max), glm::vec3(0.0f));
    return glm::dot(gap, gap);
}

bool is_finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

struct ChunkPairs {
    std::vector<LeafPhotonPair> pairs;  // in photon order
    uint64_t node_tests = 0;
};

ChunkPairs traverse_chunk(const ClusterHierarchy& hierarchy, const std::vector<glm::vec3>& positions,
                          size_t photon_begin, size_t photon_end, float reject_distance_sq,
                          const RenderControl& control) {
    ChunkPairs out;
    std::vector<uint32_t> stack;
    stack.reserve(7 * size_t(hierarchy.depth) + 1);  // depth-first: at most 7 siblings waiting per level
    for (size_t j = photon_begin; j != photon_end; ++j) {
        control.check();
        const glm::vec3& p = positions[j];
        if (!is_finite(p)) continue;  // it can pass no per-sample test, and would visit every node
        stack.push_back(hierarchy.root);
        while (!stack.empty()) {
            const uint32_t index = stack.back();
            stack.pop_back();
            const ClusterNode& node = hierarchy.nodes[index];
            ++out.node_tests;
            if (distance_sq_to_box(p, node) > reject_distance_sq) continue;
            if (node.child_count == 0) {
                out.pairs.push_back({index, uint32_t(j)});
            } else {
                for (uint32_t c = node.child_count; c-- > 0;) stack.push_back(node.first_child + c);
            }
        }
    }
    return out;
}

// Per-leaf photon lists in CSR form: the photons of node n are photons[offsets[n], offsets[n + 1]).
// Indexed by node (internal nodes have empty lists), which saves a node → leaf map.
struct PhotonLists {
    std::vector<size_t> offsets;    // size_t: the pairs of a large radius can outnumber 2^32
    std::vector<uint32_t> photons;
    size_t bytes() const { return offsets.capacity() * sizeof(size_t) + photons.capacity() * sizeof(uint32_t); }
};

// A stable counting sort by node: chunks are visited in photon order, so every list is ascending.
PhotonLists sort_pairs_by_leaf(std::vector<ChunkPairs>& chunks, size_t node_count) {
    PhotonLists lists;
    lists.offsets.assign(node_count + 1, 0);
    for (const ChunkPairs& chunk : chunks)
        for (const LeafPhotonPair& pair : chunk.pairs) ++lists.offsets[pair.node + 1];
    for (size_t n = 0; n < node_count; ++n) lists.offsets[n + 1] += lists.offsets[n];
    lists.photons.resize(lists.offsets[node_count]);
    std::vector<size_t> cursor(lists.offsets.begin(), lists.offsets.end() - 1);
    for (ChunkPairs& chunk : chunks) {
        for (const LeafPhotonPair& pair : chunk.pairs) lists.photons[cursor[pair.node]++] = pair.photon;
        chunk.pairs = {};  // release as we go: the pairs and the lists are the two largest buffers
    }
    return lists;
}

}  // namespace

std::vector<glm::vec3> splat_cluster(const ClusterHierarchy& hierarchy, const ViewSamples& samples,
                                     const PhotonMap& photons, const SplatParams& params,
                                     const RenderControl& control, Stats& stats) {
    check_inputs(params, photons);
    const std::vector<ViewSample>& views = samples.samples;
    if (hierarchy.sample_order.size() != views.size())
        throw InvalidInput("cluster hierarchy", "built over " + std::to_string(hierarchy.sample_order.size()) +
                                                    " view samples, but " + std::to_string(views.size()) +
                                                    " were given");
    if (photons.photons.size() >= std::numeric_limits<uint32_t>::max())
        throw InvalidInput("photons", "too many photons for 32-bit photon indices");
    control.check();
    stats.bytes["hierarchy"] = double(hierarchy.bytes());
    double& node_tests_counter = stats.counters["photon_node_tests"];
    double& sample_tests_counter = stats.counters["photon_sample_tests"];
    double& contributing_counter = stats.counters["contributing_pairs"];
    double& pairs_counter = stats.counters["leaf_photon_pairs"];
    std::vector<glm::vec3> radiance(views.size(), glm::vec3(0.0f));
    if (hierarchy.empty() || photons.photons.empty()) {
        stats.bytes["leaf_photon_lists"] = 0.0;
        return radiance;  // (emitted may be 0: nothing to finish)
    }

    const std::vector<glm::vec3> positions = relative_photon_positions(photons, samples.origin);
    const float r = params.radius;
    const float reject_distance_sq = (r * r) * (1.0f + 1e-5f);

    std::vector<ChunkPairs> chunks((positions.size() + kPhotonsPerChunk - 1) / kPhotonsPerChunk);
    {
        StageTimer timer(stats, "splat_traverse");
        tbb::parallel_for(size_t(0), chunks.size(), [&](size_t c) {
            const size_t begin = c * kPhotonsPerChunk;
            const size_t end = std::min(positions.size(), begin + kPhotonsPerChunk);
            chunks[c] = traverse_chunk(hierarchy, positions, begin, end, reject_distance_sq, control);
        });
    }
    uint64_t node_tests = 0;
    for (const ChunkPairs& chunk : chunks) node_tests += chunk.node_tests;
    control.check();

    PhotonLists lists;
    {
        StageTimer timer(stats, "splat_lists");
        lists = sort_pairs_by_leaf(chunks, hierarchy.nodes.size());
    }
    stats.bytes["leaf_photon_lists"] = double(lists.bytes());
    control.check();

    std::atomic<uint64_t> sample_tests{0}, contributing{0};
    {
        StageTimer timer(stats, "splat_shade");
        const std::vector<uint32_t>& leaves = hierarchy.leaves;
        const tbb::blocked_range<size_t> all_leaves(0, leaves.size(), 16);
        tbb::parallel_for(all_leaves, [&](const tbb::blocked_range<size_t>& range) {
            uint64_t local_tests = 0, local_contributing = 0;
            for (size_t l = range.begin(); l != range.end(); ++l) {
                control.check();
                const uint32_t leaf = leaves[l];
                const ClusterNode& node = hierarchy.nodes[leaf];
                const uint32_t* list = lists.photons.data() + lists.offsets[leaf];
                const size_t list_size = lists.offsets[leaf + 1] - lists.offsets[leaf];
                for (uint32_t k = node.sample_begin; k != node.sample_end; ++k) {
                    const uint32_t i = hierarchy.sample_order[k];
                    const ViewSample& s = views[i];
                    glm::dvec3 reflected_flux(0.0);
                    for (size_t m = 0; m != list_size; ++m) {
                        const uint32_t j = list[m];
                        if (!photon_reaches_sample(s, positions[j], photons.photons[j], params)) continue;
                        reflected_flux += photon_reflected_flux(s, photons.photons[j]);
                        ++local_contributing;
                    }
                    radiance[i] = finish_sample(s, reflected_flux, params);
                }
                local_tests += uint64_t(list_size) * (node.sample_end - node.sample_begin);
            }
            sample_tests += local_tests;
            contributing += local_contributing;
        });
    }

    node_tests_counter += double(node_tests);
    sample_tests_counter += double(sample_tests.load());
    contributing_counter += double(contributing.load());
    pairs_counter += double(lists.photons.size());
    return radiance;
}

}  // namespace ps
