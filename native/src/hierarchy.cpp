// The view-sample cluster hierarchy (stage 3). How it is built, in order:
//   1. key every sample: 3D Morton code of (screen tile, depth slice), or of its quantised position for samples
//      seen through mirrors/glass (bit 63 set, so they sort after all others and form a subtree of their own);
//   2. sort (key, sample index): the index breaks ties, so the order never depends on the thread count;
//   3. leaves = runs of equal keys; each leaf's samples are one contiguous range of sample_order;
//   4. parents = key >> 3, level by level, bottom-up; a group of one is promoted instead of getting a parent;
//   5. lay the nodes out breadth-first, so that every node's children are contiguous.
#include "photonsplat/hierarchy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "photonsplat/camera.h"
#include "photonsplat/errors.h"
#include "photonsplat/view_samples.h"

namespace ps {
namespace {

constexpr uint32_t kMaxCoordinate = (1u << 21) - 1;  // 21 bits per Morton axis: 3 × 21 = 63 bits
constexpr uint64_t kViaSpecularKeyBit = uint64_t(1) << 63;

// Moves bit i of the low 21 bits of v to bit 3i.
uint64_t spread_bits_by_3(uint64_t v) {
    v &= kMaxCoordinate;
    v = (v | v << 32) & 0x001f00000000ffffULL;
    v = (v | v << 16) & 0x001f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
}

uint64_t morton3(uint32_t x, uint32_t y, uint32_t z) {
    return spread_bits_by_3(x) | spread_bits_by_3(y) << 1 | spread_bits_by_3(z) << 2;
}

uint32_t clamp_to_coordinate(double v) {
    if (!(v > 0.0)) return 0;  // also NaN
    if (v >= double(kMaxCoordinate)) return kMaxCoordinate;
    return static_cast<uint32_t>(v);  // truncation = floor for v > 0
}

int64_t tiles_y(const ClusterKeyParams& params) {
    const int64_t tile = ClusterHierarchy::kTileSize;
    return std::max<int64_t>(1, (int64_t(params.height) + tile - 1) / tile);
}

// The depth-slice formula with its per-camera constants computed once, so keying 2M samples costs one log each.
// Perspective: k = floor(ln(z/near) / ln(1 + 2·tan(fovY/2)/tilesY)); z <= near gives slice 0.
// Orthographic: a tile is 2·half_height/tilesY world units tall at every depth, so slices are that thick,
// counted from the near plane: k = floor((z − near) / (2·half_height/tilesY)).
// Both clamp to [0, 2^21 − 1]; a NaN depth gives slice 0.
class DepthSlicer {
public:
    explicit DepthSlicer(const ClusterKeyParams& params)
        : orthographic_(params.orthographic), near_(params.near_clip) {
        const double tiles = tiles_y(params);
        const double half = params.vertical_half_extent;
        // Perspective: ln of the ratio between consecutive slice depths (a slice is then as thick as a tile is
        // tall). Orthographic: the slice thickness in world units.
        step_ = orthographic_ ? 2.0 * half / tiles : std::log1p(2.0 * half / tiles);
    }

    uint32_t operator()(float depth) const {
        // Degenerate cameras (step or near not positive, NaN) put everything into slice 0 rather than crash.
        if (!(step_ > 0.0) || !std::isfinite(step_)) return 0;
        if (orthographic_) return clamp_to_coordinate((double(depth) - double(near_)) / step_);
        if (!(near_ > 0.0f) || !(depth > near_)) return 0;
        return clamp_to_coordinate(std::log(double(depth) / double(near_)) / step_);
    }

private:
    bool orthographic_;
    float near_;
    double step_;
};

void check_inputs(const ViewSamples& samples, const ClusterKeyParams& params) {
    if (params.width <= 0 || params.height <= 0)
        throw InvalidInput("cluster key size",
                           std::to_string(params.width) + "x" + std::to_string(params.height) + " is not positive");
    if (uint64_t(params.width) * uint64_t(params.height) > std::numeric_limits<uint32_t>::max())
        throw InvalidInput("cluster key size", "too many pixels for 32-bit pixel indices");
    if (samples.width != params.width || samples.height != params.height)
        throw InvalidInput("view samples size",
                           std::to_string(samples.width) + "x" + std::to_string(samples.height) +
                               " differs from the camera's " + std::to_string(params.width) + "x" +
                               std::to_string(params.height));
    if (!(params.vertical_half_extent > 0.0f) || !std::isfinite(params.vertical_half_extent))
        throw InvalidInput("cluster key vertical_half_extent",
                           std::to_string(params.vertical_half_extent) + " is not a positive finite number");
    if (!std::isfinite(params.near_clip) || (!params.orthographic && !(params.near_clip > 0.0f)))
        throw InvalidInput("cluster key near_clip", std::to_string(params.near_clip) +
                                                        (params.orthographic ? " is not finite"
                                                                             : " is not a positive finite number"));
    if (samples.samples.size() >= std::numeric_limits<uint32_t>::max())
        throw InvalidInput("view samples", "too many samples for 32-bit indices");
}

struct Box {
    glm::vec3 lo{std::numeric_limits<float>::infinity()};
    glm::vec3 hi{-std::numeric_limits<float>::infinity()};
    // Argument order matters: glm::min(a, b) returns a when b is NaN, so NaN positions never poison a box
    // (they also never pass the per-sample distance test, so no box needs to contain them).
    void add(const glm::vec3& p) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    void add(const Box& b) {
        lo = glm::min(lo, b.lo);
        hi = glm::max(hi, b.hi);
    }
};

struct KeyedSample {
    uint64_t key;
    uint32_t index;
    bool operator<(const KeyedSample& o) const { return key < o.key || (key == o.key && index < o.index); }
};

std::vector<KeyedSample> key_samples(const ViewSamples& samples, const ClusterKeyParams& params) {
    const size_t n = samples.samples.size();
    const uint32_t pixels = uint32_t(params.width) * uint32_t(params.height);
    // One serial pass (so that a message names the FIRST bad sample) also finds the box on which the samples
    // seen through mirrors/glass are quantised: the box of their finite positions.
    Box specular;
    for (size_t i = 0; i < n; ++i) {
        const ViewSample& s = samples.samples[i];
        if (s.flags & kViaSpecular) {
            if (std::isfinite(s.position.x) && std::isfinite(s.position.y) && std::isfinite(s.position.z))
                specular.add(s.position);
        } else if (s.pixel >= pixels) {
            throw InvalidInput("view sample " + std::to_string(i) + " pixel",
                               std::to_string(s.pixel) + " is outside the " + std::to_string(params.width) + "x" +
                                   std::to_string(params.height) + " image");
        }
    }
    glm::dvec3 specular_scale(0.0);  // grid cells per unit length; 0 on an axis of zero extent
    for (int a = 0; a < 3; ++a) {
        const double extent = double(specular.hi[a]) - double(specular.lo[a]);
        if (extent > 0.0 && std::isfinite(extent)) specular_scale[a] = double(kMaxCoordinate) / extent;
    }

    const DepthSlicer slice(params);
    const uint32_t width = uint32_t(params.width);
    const uint32_t tile = ClusterHierarchy::kTileSize;
    std::vector<KeyedSample> keyed(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t i = range.begin(); i != range.end(); ++i) {
            const ViewSample& s = samples.samples[i];
            uint64_t key;
            if (s.flags & kViaSpecular) {
                const glm::dvec3 q = (glm::dvec3(s.position) - glm::dvec3(specular.lo)) * specular_scale;
                key = kViaSpecularKeyBit |
                      morton3(clamp_to_coordinate(q.x), clamp_to_coordinate(q.y), clamp_to_coordinate(q.z));
            } else {
                const uint32_t x = s.pixel % width, y = s.pixel / width;
                key = morton3(x / tile, y / tile, slice(s.depth));
            }
            keyed[i] = {key, uint32_t(i)};
        }
    });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    return keyed;
}

// A node while the tree is built bottom-up; children index `child_ids`, not yet laid out.
struct BuildNode {
    Box box;
    uint32_t child_begin = 0, child_count = 0;
    uint32_t sample_begin = 0, sample_end = 0;
};

}  // namespace

ClusterKeyParams ClusterKeyParams::from_camera(const Camera& camera) {
    ClusterKeyParams params;
    params.width = camera.width();
    params.height = camera.height();
    params.orthographic = camera.orthographic();
    params.near_clip = camera.near_clip();
    params.vertical_half_extent = camera.vertical_half_extent();
    return params;
}

size_t ClusterHierarchy::bytes() const {
    return nodes.capacity() * sizeof(ClusterNode) + sample_order.capacity() * sizeof(uint32_t) +
           leaves.capacity() * sizeof(uint32_t);
}

uint32_t depth_slice(float depth, const ClusterKeyParams& params) { return DepthSlicer(params)(depth); }

ClusterHierarchy build_cluster_hierarchy(const ViewSamples& samples, const ClusterKeyParams& params) {
    check_inputs(samples, params);
    ClusterHierarchy hierarchy;
    if (samples.samples.empty()) return hierarchy;

    const std::vector<KeyedSample> keyed = key_samples(samples, params);
    const size_t n = keyed.size();
    hierarchy.sample_order.resize(n);
    for (size_t i = 0; i < n; ++i) hierarchy.sample_order[i] = keyed[i].index;

    // Leaves: one per run of equal keys. Build nodes 0..leaf_count-1 are the leaves, in key order.
    std::vector<BuildNode> build;
    std::vector<uint64_t> level_keys;
    for (size_t i = 0; i < n;) {
        size_t j = i + 1;
        while (j < n && keyed[j].key == keyed[i].key) ++j;
        BuildNode leaf;
        leaf.sample_begin = uint32_t(i);
        leaf.sample_end = uint32_t(j);
        build.push_back(leaf);
        level_keys.push_back(keyed[i].key);
        i = j;
    }
    const size_t leaf_count = build.size();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaf_count, 256), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t l = range.begin(); l != range.end(); ++l)
            for (uint32_t k = build[l].sample_begin; k != build[l].sample_end; ++k)
                build[l].box.add(samples.samples[hierarchy.sample_order[k]].position);
    });

    // Parents, one level (3 key bits) at a time, until one node is left. Every key reaches 0 after 22 shifts.
    std::vector<uint32_t> level(leaf_count);
    for (size_t l = 0; l < leaf_count; ++l) level[l] = uint32_t(l);
    std::vector<uint32_t> child_ids;
    std::vector<uint32_t> next_level;
    std::vector<uint64_t> next_keys;
    while (level.size() > 1) {
        for (uint64_t& key : level_keys) key >>= 3;
        next_level.clear();
        next_keys.clear();
        for (size_t i = 0; i < level.size();) {
            size_t j = i + 1;
            while (j < level.size() && level_keys[j] == level_keys[i]) ++j;
            if (j - i == 1) {
                next_level.push_back(level[i]);  // a lone child is promoted: no single-child chains
            } else {
                BuildNode parent;
                parent.child_begin = uint32_t(child_ids.size());
                parent.child_count = uint32_t(j - i);
                // Keys sort the samples, so siblings' sample ranges are adjacent and their union is one range.
                parent.sample_begin = build[level[i]].sample_begin;
                parent.sample_end = build[level[j - 1]].sample_end;
                for (size_t c = i; c < j; ++c) {
                    child_ids.push_back(level[c]);
                    parent.box.add(build[level[c]].box);
                }
                next_level.push_back(uint32_t(build.size()));
                build.push_back(parent);
            }
            next_keys.push_back(level_keys[i]);
            i = j;
        }
        level.swap(next_level);
        level_keys.swap(next_keys);
    }

    // Breadth-first layout: a node's children are appended together, so they are contiguous.
    std::vector<uint32_t> order{level[0]};  // build ids in layout order
    std::vector<int> node_depth{0};
    std::vector<uint32_t> layout_index(build.size());
    order.reserve(build.size());
    hierarchy.nodes.reserve(build.size());
    for (size_t i = 0; i < order.size(); ++i) {
        const BuildNode& b = build[order[i]];
        layout_index[order[i]] = uint32_t(i);
        ClusterNode node;
        node.box_min = b.box.lo;
        node.box_max = b.box.hi;
        node.first_child = b.child_count ? uint32_t(order.size()) : 0;
        node.child_count = b.child_count;
        node.sample_begin = b.sample_begin;
        node.sample_end = b.sample_end;
        hierarchy.nodes.push_back(node);
        for (uint32_t c = 0; c < b.child_count; ++c) {
            order.push_back(child_ids[b.child_begin + c]);
            node_depth.push_back(node_depth[i] + 1);
        }
    }
    hierarchy.root = 0;
    hierarchy.depth = *std::max_element(node_depth.begin(), node_depth.end());
    hierarchy.leaves.resize(leaf_count);
    for (size_t l = 0; l < leaf_count; ++l) hierarchy.leaves[l] = layout_index[l];
    return hierarchy;
}

}  // namespace ps
