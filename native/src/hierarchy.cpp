// The view-sample cluster hierarchy (stage 3). How it is built, in order:
//   1. key every sample: 3D Morton code of (screen tile, depth slice), or of its quantised position for samples
//      seen through mirrors/glass (bit 63 set, so they sort after all others and form a subtree of their own);
//   2. sort (key, sample index): the index breaks ties, so the order never depends on the thread count;
//   3. leaves = runs of equal keys; each leaf's samples are one contiguous range of sample_order;
//   4. parents = key >> 3, level by level, bottom-up; a group of one is promoted instead of getting a parent;
//   5. lay the nodes out breadth-first, so that every node's children are contiguous;
//   6. with normal cones asked for: a cone and flags per leaf from its samples, then per parent from its children,
//      in reverse layout order (children come after their parent), all in double.
#include "photonsplat/hierarchy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "photonsplat/camera.h"
#include "photonsplat/errors.h"
#include "photonsplat/photon_shading_normals.h"
#include "photonsplat/validation.h"
#include "photonsplat/view_samples.h"

#include "building_blocks.h"

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

// --- normal cones -----------------------------------------------------------------------------------------
// Built in double; stored as float with the slack below, which covers the float rounding of the stored axis and
// of cos θ, sin θ (~1e-7 rad) many times over.
constexpr double kPi = 3.14159265358979323846;
constexpr double kLeafConeSlack = 1e-4;   // rad, added to a leaf's largest angle: float rounding of the normals
constexpr double kMergeConeSlack = 1e-6;  // rad, added by each merge (acos and float storage rounding)
// A normal is "regular" when finite and of length 1 within this: the cone tests rely on it.
constexpr double kUnitTolerance = cone_tests::kNormalLengthTolerance;

struct DCone {
    glm::dvec3 axis{0.0, 0.0, 1.0};
    double angle = kPi;  // >= π: full
    bool full() const { return !(angle < kPi); }
};

double angle_between(const glm::dvec3& a, const glm::dvec3& b) {  // both unit
    return std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0));
}

DCone full_cone() { return DCone{}; }

// Unit directions → the cone around their normalised sum. `unit` are already normalised.
DCone cone_of_unit_directions(const glm::dvec3* unit, size_t count) {
    if (count == 0) return full_cone();
    glm::dvec3 sum(0.0);
    for (size_t i = 0; i < count; ++i) sum += unit[i];
    const double length = glm::length(sum);
    if (!(length > 1e-9 * double(count))) return full_cone();  // the directions cancel: no useful axis
    DCone cone;
    cone.axis = sum / length;
    double min_cos = 1.0;
    for (size_t i = 0; i < count; ++i) min_cos = std::min(min_cos, glm::dot(cone.axis, unit[i]));
    cone.angle = std::acos(std::clamp(min_cos, -1.0, 1.0)) + kLeafConeSlack;
    if (cone.full()) return full_cone();
    return cone;
}

// The smallest cone containing both: around the great-circle arc between the axes.
DCone merge(const DCone& a, const DCone& b) {
    if (a.full() || b.full()) return full_cone();
    const double phi = angle_between(a.axis, b.axis);
    if (phi + b.angle <= a.angle) return a;
    if (phi + a.angle <= b.angle) return b;
    const double angle = 0.5 * (phi + a.angle + b.angle);
    if (!(angle + kMergeConeSlack < kPi)) return full_cone();
    DCone cone;
    const double t = angle - a.angle;  // rotate a's axis towards b's by t, along the arc between them
    if (phi < 1e-9) {
        cone.axis = a.axis;
    } else {
        const glm::dvec3 v = glm::normalize(a.axis * std::sin(phi - t) + b.axis * std::sin(t));
        cone.axis = v;
    }
    // The slerp puts the new axis at `angle − a.angle` from a and `angle − b.angle` from b in exact arithmetic;
    // measure the actual angles rather than trusting that, so rounding can only widen the cone.
    cone.angle = std::max(angle_between(cone.axis, a.axis) + a.angle, angle_between(cone.axis, b.axis) + b.angle) +
                 kMergeConeSlack;
    if (cone.full()) return full_cone();
    return cone;
}

// A cone containing all the children's: the best of pairwise merging in order and of the children's mean axis.
DCone merge_all(const DCone* cones, size_t count) {
    if (count == 0) return full_cone();
    DCone pairwise = cones[0];
    glm::dvec3 sum(0.0);
    for (size_t c = 0; c < count; ++c) {
        if (cones[c].full()) return full_cone();
        if (c > 0) pairwise = merge(pairwise, cones[c]);
        sum += cones[c].axis;
    }
    const double length = glm::length(sum);
    if (length > 1e-9) {
        DCone mean;
        mean.axis = sum / length;
        mean.angle = 0.0;
        for (size_t c = 0; c < count; ++c)
            mean.angle = std::max(mean.angle, angle_between(mean.axis, cones[c].axis) + cones[c].angle);
        mean.angle += kMergeConeSlack;
        if (mean.angle < pairwise.angle) return mean.full() ? full_cone() : mean;
    }
    return pairwise;
}

NormalCone to_float(const DCone& cone) {
    NormalCone out;  // full by default
    if (cone.full()) return out;
    out.axis = glm::vec3(cone.axis);
    out.cos_angle = float(std::cos(cone.angle));
    out.sin_angle = float(std::sin(cone.angle));
    if (out.cos_angle <= -1.0f) return NormalCone{};
    return out;
}

DCone to_double(const NormalCone& cone) {
    if (cone.full()) return full_cone();
    const glm::dvec3 axis(cone.axis);
    const double length = glm::length(axis);
    if (!(length > 0.0) || !std::isfinite(length)) return full_cone();
    DCone out;
    out.axis = axis / length;
    // The float axis is within ~1e-7 rad of the one the cone was built around: widen by that.
    out.angle = std::atan2(double(cone.sin_angle), double(cone.cos_angle)) + kMergeConeSlack;
    if (!(out.angle >= 0.0)) return full_cone();
    return out.full() ? full_cone() : out;
}

// Fills hierarchy.cones and node_flags: leaves from their samples, then parents from their children, level by
// level from the deepest; in parallel, with the same result for any thread count.
void build_cones(const ViewSamples& samples, ClusterHierarchy& h) {
    const size_t node_count = h.nodes.size();
    std::vector<DCone> cones(node_count);
    h.node_flags.assign(node_count, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, h.leaves.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<glm::dvec3> unit;
        for (size_t l = r.begin(); l != r.end(); ++l) {
            const uint32_t index = h.leaves[l];
            const ClusterNode& node = h.nodes[index];
            uint8_t flags = kNodeDiffuseOnly | kNodeRegular;
            bool cone_ok = true;
            unit.clear();
            for (uint32_t k = node.sample_begin; k != node.sample_end; ++k) {
                const ViewSample& s = samples.samples[h.sample_order[k]];
                // Trivial accepts skip the per-sample test: only for samples it could not refuse by side either,
                // and whose f is one number for every photon (no shading normal leaning off the triangle).
                if ((s.flags & (kGlossy | kInsideSample | kBumpShadowed)) ||
                    shading_normal_tilted(s.shading_normal, s.normal))
                    flags &= uint8_t(~kNodeDiffuseOnly);
                const glm::dvec3 n(s.normal);
                const double length = glm::length(n);
                const bool unit_normal = std::isfinite(length) && std::fabs(length - 1.0) <= kUnitTolerance;
                if (!unit_normal) cone_ok = false;  // the cone tests assume unit normals: say nothing here
                if (!unit_normal || !is_finite(s.position)) flags &= uint8_t(~kNodeRegular);
                if (unit_normal) unit.push_back(n / length);
            }
            cones[index] = cone_ok ? cone_of_unit_directions(unit.data(), unit.size()) : full_cone();
            h.node_flags[index] = flags;
        }
    });
    // The breadth-first layout puts each level in one contiguous range of nodes, deeper levels after: merge a
    // level at a time from the deepest up, each level in parallel (a node needs only its children).
    std::vector<uint32_t> level_begin{0};  // level d is nodes [level_begin[d], level_begin[d + 1])
    {
        std::vector<int> depth(node_count, 0);
        for (size_t i = 0; i < node_count; ++i) {
            const ClusterNode& node = h.nodes[i];
            if (i > 0 && depth[i] != depth[i - 1]) level_begin.push_back(uint32_t(i));
            for (uint32_t c = node.first_child; c != node.first_child + node.child_count; ++c) depth[c] = depth[i] + 1;
        }
        level_begin.push_back(uint32_t(node_count));
    }
    for (size_t level = level_begin.size() - 1; level-- > 0;) {
        tbb::parallel_for(
            tbb::blocked_range<size_t>(level_begin[level], level_begin[level + 1], 256),
            [&](const tbb::blocked_range<size_t>& r) {
                for (size_t i = r.begin(); i != r.end(); ++i) {
                    const ClusterNode& node = h.nodes[i];
                    if (node.child_count == 0) continue;
                    cones[i] = merge_all(&cones[node.first_child], node.child_count);
                    uint8_t flags = kNodeDiffuseOnly | kNodeRegular;
                    for (uint32_t c = 0; c < node.child_count; ++c) flags &= h.node_flags[node.first_child + c];
                    h.node_flags[i] = flags;
                }
            });
    }
    h.cones.resize(node_count);
    for (size_t i = 0; i < node_count; ++i) h.cones[i] = to_float(cones[i]);
}

// A node while the tree is built bottom-up; children index `child_ids`, not yet laid out.
struct BuildNode {
    Box box;
    uint32_t child_begin = 0, child_count = 0;
    uint32_t sample_begin = 0, sample_end = 0;
};

// A leaf's regular samples (finite position and normal, as the directional method counts them) as the parts
// its summary describes. Normals are summed as they are (unit for any real sample); a zero normal leaves the
// cone unbounded.
struct OrientedPoint {
    glm::dvec3 position, normal;
};

// One part: the points `members` (indices into `points`), around the normalised sum of their normals. Passes
// over a handful of points that are in cache.
LeafSummary summarise_part(const std::vector<OrientedPoint>& points, const std::vector<uint32_t>& members) {
    glm::dvec3 position_sum(0.0), normal_sum(0.0);
    for (const uint32_t i : members) {
        position_sum += points[i].position;
        normal_sum += points[i].normal;
    }
    LeafSummary summary;
    summary.count = uint32_t(members.size());
    if (members.empty()) return summary;
    const double count = double(members.size());
    const glm::dvec3 centroid = position_sum / count;
    const double sum_length = glm::length(normal_sum);
    const bool has_axis = sum_length > 1e-3 * count;  // as the directional method: else the normals cancel
    const glm::dvec3 axis = has_axis ? normal_sum / sum_length : glm::dvec3(0.0);
    double radius = 0.0, slab = 0.0, min_cos = 1.0;
    for (const uint32_t i : members) {
        const glm::dvec3 d = points[i].position - centroid;
        radius = std::max(radius, glm::length(d));
        slab = std::max(slab, std::fabs(glm::dot(axis, d)));
        const double length = glm::length(points[i].normal);
        min_cos = std::min(min_cos, length > 0.0 ? glm::dot(axis, points[i].normal) / length : -1.0);
    }
    // Margins for storing in float: the centroid moves by ~|centroid|·6e-8, the axis by ~1e-7 rad.
    summary.centroid = glm::vec3(centroid);
    const double storage = glm::length(centroid) * 1e-6;
    summary.radius = float(radius * (1.0 + 1e-6) + storage);
    summary.slab = float(slab * (1.0 + 1e-6) + storage + radius * 1e-6);
    summary.normal_sum = glm::vec3(normal_sum);
    const double angle = std::acos(std::clamp(min_cos, -1.0, 1.0)) + kLeafConeSlack;
    summary.cone_angle = has_axis && angle < kPi ? float(angle) : float(kPi);
    return summary;
}

// Splits `members` in two by orientation as the directional method splits a node (seeds: the normal farthest
// from their mean `mean`, then the one farthest from that; one k-means step). False when a side stays empty.
bool split_by_orientation(const std::vector<OrientedPoint>& points, const std::vector<uint32_t>& members,
                          const glm::dvec3& mean, std::vector<uint32_t>& first, std::vector<uint32_t>& second) {
    const auto farthest_from = [&](const glm::dvec3& d) {
        uint32_t best = members[0];
        for (const uint32_t i : members)
            if (glm::dot(d, points[i].normal) < glm::dot(d, points[best].normal)) best = i;
        return points[best].normal;
    };
    const glm::dvec3 seed0 = farthest_from(mean);
    const glm::dvec3 seed1 = farthest_from(seed0);
    glm::dvec3 sums[2] = {glm::dvec3(0.0), glm::dvec3(0.0)};
    for (const uint32_t i : members)
        sums[glm::dot(points[i].normal, seed1) > glm::dot(points[i].normal, seed0) ? 1 : 0] += points[i].normal;
    if (!(glm::length(sums[0]) > 0.0) || !(glm::length(sums[1]) > 0.0)) return false;
    const glm::dvec3 axis0 = glm::normalize(sums[0]), axis1 = glm::normalize(sums[1]);
    first.clear();
    second.clear();
    for (const uint32_t i : members)
        (glm::dot(points[i].normal, axis1) > glm::dot(points[i].normal, axis0) ? second : first).push_back(i);
    return !first.empty() && !second.empty();
}

// Appends the parts of `members`: one part when their normals lie within kNarrowLeafAngle of their mean (or
// after kLeafSplitLevels splits), else the parts of each side of a split by orientation. Sets part_of_point[i]
// of each member to its part's number within the leaf, whose parts start at out[leaf_start].
void add_leaf_parts(const std::vector<OrientedPoint>& points, const std::vector<uint32_t>& members, int level,
                    size_t leaf_start, std::vector<uint8_t>& part_of_point, std::vector<LeafSummary>& out) {
    const LeafSummary whole = summarise_part(points, members);
    std::vector<uint32_t> first, second;
    if (level < kLeafSplitLevels && whole.count >= 2 && !(whole.cone_angle < kNarrowLeafAngle)) {
        const glm::dvec3 sum(whole.normal_sum);
        const glm::dvec3 mean = glm::length(sum) > 0.0 ? glm::normalize(sum) : points[members[0]].normal;
        if (split_by_orientation(points, members, mean, first, second)) {
            add_leaf_parts(points, first, level + 1, leaf_start, part_of_point, out);
            add_leaf_parts(points, second, level + 1, leaf_start, part_of_point, out);
            return;
        }
    }
    for (const uint32_t i : members) part_of_point[i] = uint8_t(out.size() - leaf_start);
    out.push_back(whole);
}

// A leaf's summary, appended to `out`: one part, or up to 2^kLeafSplitLevels split by orientation when its
// normals spread to kNarrowLeafAngle or more (a leaf across a crease: its tile and depth slice hold two walls;
// a corner, three). Done on the leaf's few samples while they are in cache, so that the directional method can
// split a node across the crease by whole parts instead of reading the node's samples again. Writes each
// sample's part number to sample_part[begin, end) (0 for a sample that is not regular). `points`, `members`
// and `part_of_point` are scratch space. Returns the number of parts appended (at least 1).
uint32_t summarise_leaf(const ViewSamples& samples, const std::vector<uint32_t>& order, uint32_t begin,
                        uint32_t end, std::vector<OrientedPoint>& points, std::vector<uint32_t>& members,
                        std::vector<uint8_t>& part_of_point, std::vector<uint8_t>& sample_part,
                        std::vector<LeafSummary>& out) {
    points.clear();
    members.clear();
    for (uint32_t k = begin; k != end; ++k) {
        const ViewSample& s = samples.samples[order[k]];
        if (!is_finite(s.position) || !is_finite(s.normal)) continue;
        members.push_back(uint32_t(points.size()));
        points.push_back({glm::dvec3(s.position), glm::dvec3(s.normal)});
    }
    part_of_point.assign(points.size(), 0);
    const size_t before = out.size();
    add_leaf_parts(points, members, 0, before, part_of_point, out);
    size_t point = 0;
    for (uint32_t k = begin; k != end; ++k) {
        const ViewSample& s = samples.samples[order[k]];
        sample_part[k] = is_finite(s.position) && is_finite(s.normal) ? part_of_point[point++] : 0;
    }
    return uint32_t(out.size() - before);
}

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

size_t ClusterHierarchy::cone_bytes() const {
    return cones.capacity() * sizeof(NormalCone) + node_flags.capacity() * sizeof(uint8_t);
}

NormalCone cone_of_directions(const std::vector<glm::vec3>& directions) {
    std::vector<glm::dvec3> unit;
    for (const glm::vec3& d : directions) {
        const glm::dvec3 v(d);
        const double length = glm::length(v);
        if (!(length > 0.0) || !std::isfinite(length)) return NormalCone{};
        unit.push_back(v / length);
    }
    return to_float(cone_of_unit_directions(unit.data(), unit.size()));
}

NormalCone merge_cones(const NormalCone& a, const NormalCone& b) { return to_float(merge(to_double(a), to_double(b))); }

namespace cone_tests {

PhotonCone photon_cone(const glm::vec3& wi_in, const glm::vec3& normal_in, float cos_tolerance) {
    PhotonCone pc;
    const glm::dvec3 wi(wi_in), np(normal_in);
    const double w = glm::length(wi), length = glm::length(np);
    if (std::isfinite(w) && w > 1e-30) {
        pc.wi = glm::vec3(wi / w);
        pc.facing = true;
    }
    const double t = cos_tolerance;
    if (!(std::isfinite(length) && length > 1e-30 && std::isfinite(t))) return pc;
    pc.n = glm::vec3(np / length);
    pc.orientation = true;
    const double error = kDotErrorPerLength * length, d = kNormalLengthTolerance;
    // A sample surely fails when |n|·L·cos φ + error <= t for every |n| in [1 − d, 1 + d]: cos φ <= `reject`.
    const double q = (t - error) / length;
    const double reject = q >= 0.0 ? q / (1.0 + d) : q / (1.0 - d);
    if (reject >= 1.0) {
        pc.fails_all = true;
    } else if (reject > -1.0) {
        pc.reject_angle = true;
        pc.reject_cos = float(reject);
        pc.reject_sin = float(std::sqrt(1.0 - reject * reject));
    }
    // A sample surely passes when |n|·L·cos φ − error > t for every |n|: cos φ > `accept`.
    const double q2 = (t + error) / length;
    const double accept = q2 >= 0.0 ? q2 / (1.0 - d) : q2 / (1.0 + d);
    if (accept < -1.0) {
        pc.passes_all = true;
    } else if (accept < 1.0) {
        pc.accept_angle = true;
        pc.accept_cos = float(accept);
        pc.accept_sin = float(std::sqrt(1.0 - accept * accept));
    }
    return pc;
}

}  // namespace cone_tests

uint32_t depth_slice(float depth, const ClusterKeyParams& params) { return DepthSlicer(params)(depth); }

ClusterHierarchy build_cluster_hierarchy(const ViewSamples& samples, const ClusterKeyParams& params,
                                         const ClusterBuildOptions& options) {
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
    // Leaves are boxed (and summarised) in fixed chunks, each appending its leaves' parts to its own list, so
    // that the lists joined in chunk order are in leaf order whatever the thread count.
    constexpr size_t kLeavesPerChunk = 256;
    const size_t chunks = (leaf_count + kLeavesPerChunk - 1) / kLeavesPerChunk;
    std::vector<std::vector<LeafSummary>> chunk_parts(options.leaf_summaries ? chunks : 0);
    std::vector<uint32_t> part_count(options.leaf_summaries ? leaf_count : 0);
    struct Scratch {
        std::vector<OrientedPoint> points;
        std::vector<uint32_t> members;
        std::vector<uint8_t> part_of_point;
    };
    if (options.leaf_summaries) hierarchy.sample_part.resize(n);
    tbb::enumerable_thread_specific<Scratch> scratch;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks), [&](const tbb::blocked_range<size_t>& range) {
        Scratch& local = scratch.local();
        for (size_t chunk = range.begin(); chunk != range.end(); ++chunk) {
            for (size_t l = chunk * kLeavesPerChunk; l != std::min(leaf_count, (chunk + 1) * kLeavesPerChunk); ++l) {
                for (uint32_t k = build[l].sample_begin; k != build[l].sample_end; ++k)
                    build[l].box.add(samples.samples[hierarchy.sample_order[k]].position);
                if (options.leaf_summaries)  // the leaf's samples were just read: summarising them now is cheap
                    part_count[l] = summarise_leaf(samples, hierarchy.sample_order, build[l].sample_begin,
                                                   build[l].sample_end, local.points, local.members,
                                                   local.part_of_point, hierarchy.sample_part, chunk_parts[chunk]);
            }
        }
    });
    if (options.leaf_summaries) {
        hierarchy.leaf_summary_begin.resize(leaf_count + 1);
        uint32_t parts = 0;
        for (size_t l = 0; l < leaf_count; ++l) hierarchy.leaf_summary_begin[l] = parts, parts += part_count[l];
        hierarchy.leaf_summary_begin[leaf_count] = parts;
        hierarchy.leaf_summaries.reserve(parts);
        for (std::vector<LeafSummary>& list : chunk_parts) {
            hierarchy.leaf_summaries.insert(hierarchy.leaf_summaries.end(), list.begin(), list.end());
            std::vector<LeafSummary>().swap(list);
        }
    }

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
    if (options.normal_cones) build_cones(samples, hierarchy);
    return hierarchy;
}

}  // namespace ps
