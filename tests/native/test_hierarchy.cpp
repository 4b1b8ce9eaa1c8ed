// The view-sample cluster hierarchy: structural invariants on random and degenerate sample sets, the depth
// slices of the cluster key, and determinism across thread counts.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <random>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/task_arena.h>

#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/view_samples.h"

namespace ps {
namespace {

ClusterKeyParams perspective_params(int width, int height) {
    ClusterKeyParams params;
    params.width = width;
    params.height = height;
    params.near_clip = 0.1f;
    params.vertical_half_extent = 0.57735027f;  // 60° vertical field of view
    return params;
}

ViewSample sample_at(const glm::vec3& position, uint32_t pixel, float depth, uint32_t flags = 0) {
    ViewSample s{};
    s.position = position;
    s.normal = s.shading_normal = glm::vec3(0, 0, 1);
    s.wo = glm::vec3(0, 0, 1);
    s.albedo = s.throughput = glm::vec3(1);
    s.pixel = pixel;
    s.flags = flags;
    s.depth = depth;
    return s;
}

// A pinhole camera at the origin looking down −z at a few random planes: every pixel sees the nearest one,
// so neighbouring pixels may sit at very different depths. A fraction of samples is "seen through a mirror"
// and placed anywhere in the scene; `coverage` < 1 leaves pixels empty (sky).
ViewSamples random_samples(int width, int height, uint32_t seed, double specular_fraction = 0.1,
                           double coverage = 0.9) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    ViewSamples vs;
    vs.width = width;
    vs.height = height;
    vs.origin = glm::vec3(1000.0f, -20.0f, 3.0f);
    const float tan_half = 0.57735027f;
    struct Plane {
        glm::vec3 n;
        float d;
    };
    std::vector<Plane> planes;
    for (int i = 0; i < 4; ++i) {
        glm::vec3 n = glm::normalize(glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, 1.0f + u(rng)));
        planes.push_back({n, -(1.0f + 20.0f * u(rng))});  // n·x = d crosses the view axis at depth 1..21
    }
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            if (u(rng) > coverage) continue;
            const float aspect = float(width) / float(height);
            glm::vec3 dir((2.0f * (x + 0.5f) / width - 1.0f) * tan_half * aspect,
                          (1.0f - 2.0f * (y + 0.5f) / height) * tan_half, -1.0f);
            float best = 1e30f;
            glm::vec3 normal(0, 0, 1);
            for (const Plane& p : planes) {
                const float t = p.d / glm::dot(p.n, dir);
                if (t > 0.0f && t < best) {
                    best = t;
                    normal = p.n;
                }
            }
            if (best == 1e30f) best = 50.0f;
            const uint32_t pixel = uint32_t(y * width + x);
            ViewSample s = sample_at(dir * best, pixel, best);
            s.normal = s.shading_normal = glm::dot(normal, dir) < 0.0f ? normal : -normal;
            if (u(rng) < specular_fraction) {
                s.flags = kViaSpecular;
                s.position = glm::vec3(u(rng) * 10.0f - 5.0f, u(rng) * 10.0f - 5.0f, -u(rng) * 20.0f);
            }
            vs.samples.push_back(s);
        }
    return vs;
}

// The cluster key of an ordinary sample, bit by bit: bit i of x, y, slice goes to bit 3i, 3i+1, 3i+2.
uint64_t slow_cluster_key(const ViewSample& s, const ClusterKeyParams& params) {
    const uint32_t w = uint32_t(params.width), t = ClusterHierarchy::kTileSize;
    const uint64_t coords[3] = {s.pixel % w / t, s.pixel / w / t, depth_slice(s.depth, params)};
    uint64_t key = 0;
    for (int bit = 0; bit < 21; ++bit)
        for (int axis = 0; axis < 3; ++axis) key |= ((coords[axis] >> bit) & 1u) << (3 * bit + axis);
    return key;
}

bool contains(const ClusterNode& outer, const glm::vec3& lo, const glm::vec3& hi) {
    return glm::all(glm::lessThanEqual(outer.box_min, lo)) && glm::all(glm::lessThanEqual(hi, outer.box_max));
}

// Everything the rest of the renderer relies on.
void expect_valid_hierarchy(const ClusterHierarchy& h, const ViewSamples& vs, const ClusterKeyParams& params) {
    const size_t n = vs.samples.size();
    ASSERT_EQ(h.sample_order.size(), n);
    if (n == 0) {
        EXPECT_TRUE(h.empty());
        EXPECT_TRUE(h.leaves.empty());
        return;
    }
    ASSERT_FALSE(h.empty());
    ASSERT_LT(h.root, h.nodes.size());

    std::vector<int> seen(n, 0);
    for (uint32_t i : h.sample_order) {
        ASSERT_LT(i, n);
        ++seen[i];
    }
    EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int c) { return c == 1; })) << "not a permutation";

    // Walk from the root: every node reached once, children partition their parent's sample range in order.
    std::vector<int> visits(h.nodes.size(), 0);
    std::vector<uint32_t> leaves_in_walk;
    int max_depth = 0;
    std::function<void(uint32_t, int)> walk = [&](uint32_t index, int depth) {
        ASSERT_LT(index, h.nodes.size());
        ++visits[index];
        max_depth = std::max(max_depth, depth);
        const ClusterNode& node = h.nodes[index];
        ASSERT_LT(node.sample_begin, node.sample_end);
        ASSERT_LE(node.sample_end, n);
        for (uint32_t k = node.sample_begin; k < node.sample_end; ++k) {
            const glm::vec3& p = vs.samples[h.sample_order[k]].position;
            EXPECT_TRUE(contains(node, p, p)) << "node " << index << " misses sample " << h.sample_order[k];
        }
        if (node.child_count == 0) {
            leaves_in_walk.push_back(index);
            return;
        }
        EXPECT_GE(node.child_count, 2u) << "single-child chains must be collapsed";
        EXPECT_LE(node.child_count, 8u);
        uint32_t expected_begin = node.sample_begin;
        for (uint32_t c = node.first_child; c < node.first_child + node.child_count; ++c) {
            ASSERT_LT(c, h.nodes.size());
            const ClusterNode& child = h.nodes[c];
            EXPECT_EQ(child.sample_begin, expected_begin);
            expected_begin = child.sample_end;
            EXPECT_TRUE(contains(node, child.box_min, child.box_max));
            walk(c, depth + 1);
        }
        EXPECT_EQ(expected_begin, node.sample_end);
    };
    walk(h.root, 0);
    EXPECT_EQ(h.nodes[h.root].sample_begin, 0u);
    EXPECT_EQ(h.nodes[h.root].sample_end, n);
    EXPECT_TRUE(std::all_of(visits.begin(), visits.end(), [](int v) { return v == 1; })) << "unreachable node";
    EXPECT_EQ(h.depth, max_depth);

    // `leaves` lists every leaf once, in key (= sample_order) order, and together they cover every sample.
    EXPECT_EQ(h.leaves, leaves_in_walk);
    uint32_t next = 0;
    for (uint32_t leaf : h.leaves) {
        const ClusterNode& node = h.nodes[leaf];
        EXPECT_EQ(node.child_count, 0u);
        EXPECT_EQ(node.sample_begin, next);
        next = node.sample_end;
        // One key per leaf: same kind, and for ordinary samples the same tile and depth slice.
        const ViewSample& first = vs.samples[h.sample_order[node.sample_begin]];
        for (uint32_t k = node.sample_begin; k < node.sample_end; ++k) {
            const ViewSample& s = vs.samples[h.sample_order[k]];
            EXPECT_EQ(s.flags & kViaSpecular, first.flags & kViaSpecular);
            if (s.flags & kViaSpecular) continue;
            const uint32_t w = uint32_t(params.width), t = ClusterHierarchy::kTileSize;
            EXPECT_EQ(s.pixel % w / t, first.pixel % w / t);
            EXPECT_EQ(s.pixel / w / t, first.pixel / w / t);
            EXPECT_EQ(depth_slice(s.depth, params), depth_slice(first.depth, params));
        }
        // Ties between equal keys go by sample index.
        for (uint32_t k = node.sample_begin + 1; k < node.sample_end; ++k)
            EXPECT_LT(h.sample_order[k - 1], h.sample_order[k]);
    }
    EXPECT_EQ(next, n);

    // Leaves of ordinary samples come in increasing Morton order of (tile x, tile y, depth slice).
    uint64_t previous_key = 0;
    bool first_leaf = true;
    for (uint32_t leaf : h.leaves) {
        const ViewSample& s = vs.samples[h.sample_order[h.nodes[leaf].sample_begin]];
        if (s.flags & kViaSpecular) continue;
        const uint64_t key = slow_cluster_key(s, params);
        if (!first_leaf) {
            EXPECT_LT(previous_key, key);
        }
        previous_key = key;
        first_leaf = false;
    }

    // Samples seen through mirrors come last and, when both kinds exist, fill exactly one subtree.
    size_t specular = 0;
    for (const ViewSample& s : vs.samples) specular += (s.flags & kViaSpecular) ? 1 : 0;
    for (size_t k = 0; k < n; ++k)
        EXPECT_EQ(bool(vs.samples[h.sample_order[k]].flags & kViaSpecular), k >= n - specular);
    if (specular > 0 && specular < n) {
        const bool found = std::any_of(h.nodes.begin(), h.nodes.end(), [&](const ClusterNode& node) {
            return node.sample_begin == n - specular && node.sample_end == n;
        });
        EXPECT_TRUE(found) << "no subtree holds exactly the samples seen through mirrors";
    }
    EXPECT_GE(h.bytes(), h.nodes.size() * sizeof(ClusterNode) + 4 * (h.sample_order.size() + h.leaves.size()));
}

ClusterHierarchy build_with_threads(int threads, const ViewSamples& vs, const ClusterKeyParams& params,
                                    const ClusterBuildOptions& options = {}) {
    tbb::task_arena arena(threads);
    ClusterHierarchy h;
    arena.execute([&] { h = build_cluster_hierarchy(vs, params, options); });
    return h;
}

// Runs `body` on the random sample sets of seeds 1 … seeds, w0 + dw·seed × h0 + dh·seed pixels each, with their
// key parameters and size (the seed traced).
void for_random_sample_sets(uint32_t seeds, int w0, int dw, int h0, int dh,
                            const std::function<void(const ViewSamples&, const ClusterKeyParams&, int, int)>& body) {
    for (uint32_t seed = 1; seed <= seeds; ++seed) {
        const int w = w0 + dw * int(seed), h = h0 + dh * int(seed);
        SCOPED_TRACE(seed);
        body(random_samples(w, h, seed), perspective_params(w, h), w, h);
    }
}

TEST(ClusterHierarchy, RandomSampleSetsAreValid) {
    for_random_sample_sets(4, 40, 13, 30, 7, [](const ViewSamples& vs, const ClusterKeyParams& params, int w, int h) {
        const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, params);
        expect_valid_hierarchy(hierarchy, vs, params);
        EXPECT_GT(hierarchy.leaves.size(), size_t(w / 8) * size_t(h / 8) / 2);
    });
}

// Cones are an option of the build: the tree is the same with them, and every node's cone holds its samples'
// normals (tests/native/test_cones.cpp checks the cones in depth).
TEST(ClusterHierarchy, BuiltWithNormalConesIsTheSameValidTree) {
    for_random_sample_sets(3, 45, 11, 33, 5, [](const ViewSamples& vs, const ClusterKeyParams& params, int, int) {
        ClusterBuildOptions options;
        options.normal_cones = true;
        const ClusterHierarchy with = build_cluster_hierarchy(vs, params, options);
        const ClusterHierarchy without = build_cluster_hierarchy(vs, params);
        expect_valid_hierarchy(with, vs, params);
        ASSERT_TRUE(with.has_cones());
        EXPECT_FALSE(without.has_cones());
        ASSERT_EQ(with.nodes.size(), without.nodes.size());
        EXPECT_EQ(0, std::memcmp(with.nodes.data(), without.nodes.data(), with.nodes.size() * sizeof(ClusterNode)));
        EXPECT_EQ(with.sample_order, without.sample_order);
        EXPECT_EQ(with.bytes(), without.bytes());  // cones are counted apart
        EXPECT_EQ(with.cone_bytes(), with.nodes.size() * (sizeof(NormalCone) + 1));
        for (size_t i = 0; i < with.nodes.size(); ++i) {
            const NormalCone& cone = with.cones[i];
            for (uint32_t k = with.nodes[i].sample_begin; k < with.nodes[i].sample_end; ++k) {
                const glm::vec3 n = glm::normalize(vs.samples[with.sample_order[k]].normal);
                if (!cone.full()) EXPECT_GE(double(glm::dot(glm::normalize(cone.axis), n)), double(cone.cos_angle));
            }
            EXPECT_EQ(with.node_flags[i], kNodeDiffuseOnly | kNodeRegular);  // all diffuse, unit normals
        }
    });
}

TEST(ClusterHierarchy, ConesAreTheSameWithOneAndTwoThreads) {
    const ViewSamples vs = random_samples(160, 120, 6);
    const ClusterKeyParams params = perspective_params(160, 120);
    ClusterBuildOptions options;
    options.normal_cones = true;
    ClusterHierarchy a, b;
    tbb::task_arena(1).execute([&] { a = build_cluster_hierarchy(vs, params, options); });
    tbb::task_arena(2).execute([&] { b = build_cluster_hierarchy(vs, params, options); });
    ASSERT_EQ(a.cones.size(), b.cones.size());
    EXPECT_EQ(0, std::memcmp(a.cones.data(), b.cones.data(), a.cones.size() * sizeof(NormalCone)));
    EXPECT_EQ(a.node_flags, b.node_flags);
}

TEST(ClusterHierarchy, OnlySamplesSeenThroughMirrors) {
    const ViewSamples vs = random_samples(37, 29, 7, /*specular_fraction=*/1.0);
    const ClusterKeyParams params = perspective_params(37, 29);
    expect_valid_hierarchy(build_cluster_hierarchy(vs, params), vs, params);
}

TEST(ClusterHierarchy, SamplesAtIdenticalPositions) {
    ViewSamples vs;
    vs.width = 16;
    vs.height = 16;
    for (uint32_t pixel = 0; pixel < 256; ++pixel) {
        const uint32_t flags = pixel % 3 == 0 ? uint32_t(kViaSpecular) : 0u;
        vs.samples.push_back(sample_at(glm::vec3(1, 2, -3), pixel, 3.0f, flags));
    }
    const ClusterKeyParams params = perspective_params(16, 16);
    const ClusterHierarchy h = build_cluster_hierarchy(vs, params);
    expect_valid_hierarchy(h, vs, params);
    // 4 tiles of ordinary samples, and one leaf for all the mirrored ones: they share one quantised position.
    EXPECT_EQ(h.leaves.size(), 5u);
    for (const ClusterNode& node : h.nodes) {
        EXPECT_EQ(node.box_min, glm::vec3(1, 2, -3));
        EXPECT_EQ(node.box_max, glm::vec3(1, 2, -3));
    }
}

TEST(ClusterHierarchy, SingleSampleIsARootLeaf) {
    for (uint32_t flags : {0u, uint32_t(kViaSpecular)}) {
        ViewSamples vs;
        vs.width = 3;
        vs.height = 5;
        vs.samples.push_back(sample_at(glm::vec3(0.5f, -0.25f, -2.0f), 7, 2.0f, flags));
        const ClusterKeyParams params = perspective_params(3, 5);
        const ClusterHierarchy h = build_cluster_hierarchy(vs, params);
        expect_valid_hierarchy(h, vs, params);
        ASSERT_EQ(h.nodes.size(), 1u);
        EXPECT_EQ(h.depth, 0);
        EXPECT_EQ(h.leaves, std::vector<uint32_t>{h.root});
        EXPECT_EQ(h.nodes[h.root].box_min, vs.samples[0].position);
    }
}

TEST(ClusterHierarchy, ZeroSamplesGiveAnEmptyHierarchy) {
    ViewSamples vs;
    vs.width = 64;
    vs.height = 64;
    const ClusterHierarchy h = build_cluster_hierarchy(vs, perspective_params(64, 64));
    EXPECT_TRUE(h.empty());
    EXPECT_TRUE(h.sample_order.empty());
    EXPECT_TRUE(h.leaves.empty());
}

TEST(ClusterHierarchy, OneFullTileAtOneDepthIsOneLeaf) {
    ViewSamples vs;
    vs.width = 8;
    vs.height = 8;
    for (uint32_t pixel = 0; pixel < 64; ++pixel)
        vs.samples.push_back(sample_at(glm::vec3(float(pixel % 8), float(pixel / 8), -5.0f), pixel, 5.0f));
    const ClusterKeyParams params = perspective_params(8, 8);
    const ClusterHierarchy h = build_cluster_hierarchy(vs, params);
    expect_valid_hierarchy(h, vs, params);
    ASSERT_EQ(h.nodes.size(), 1u);
    EXPECT_EQ(h.nodes[0].box_min, glm::vec3(0, 0, -5));
    EXPECT_EQ(h.nodes[0].box_max, glm::vec3(7, 7, -5));
}

TEST(ClusterHierarchy, DepthDiscontinuityInOneTileSplitsIt) {
    ViewSamples vs;
    vs.width = 8;
    vs.height = 8;
    for (uint32_t pixel = 0; pixel < 64; ++pixel) {
        const float depth = pixel % 8 < 4 ? 1.0f : 100.0f;
        vs.samples.push_back(sample_at(glm::vec3(0, 0, -depth), pixel, depth));
    }
    const ClusterKeyParams params = perspective_params(8, 8);
    const ClusterHierarchy h = build_cluster_hierarchy(vs, params);
    expect_valid_hierarchy(h, vs, params);
    EXPECT_EQ(h.leaves.size(), 2u);
}

TEST(ClusterHierarchy, TinyImages) {
    for (auto [w, h] : {std::pair{1, 1}, std::pair{3, 5}, std::pair{9, 1}, std::pair{1, 17}}) {
        SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
        const ViewSamples vs = random_samples(w, h, uint32_t(w * 100 + h), 0.2, 1.0);
        const ClusterKeyParams params = perspective_params(w, h);
        expect_valid_hierarchy(build_cluster_hierarchy(vs, params), vs, params);
    }
}

TEST(ClusterHierarchy, OrthographicCamera) {
    const ViewSamples vs = random_samples(50, 40, 11);
    ClusterKeyParams params = perspective_params(50, 40);
    params.orthographic = true;
    params.near_clip = 0.0f;
    params.vertical_half_extent = 5.0f;
    expect_valid_hierarchy(build_cluster_hierarchy(vs, params), vs, params);
}

TEST(ClusterHierarchy, SameResultWithOneAndTwoThreads) {
    const ViewSamples vs = random_samples(160, 120, 5);
    const ClusterKeyParams params = perspective_params(160, 120);
    const ClusterHierarchy a = build_with_threads(1, vs, params);
    const ClusterHierarchy b = build_with_threads(2, vs, params);
    ASSERT_EQ(a.nodes.size(), b.nodes.size());
    EXPECT_EQ(0, std::memcmp(a.nodes.data(), b.nodes.data(), a.nodes.size() * sizeof(ClusterNode)));
    EXPECT_EQ(a.sample_order, b.sample_order);
    EXPECT_EQ(a.leaves, b.leaves);
    EXPECT_EQ(a.root, b.root);
    EXPECT_EQ(a.depth, b.depth);
}

// Leaf summaries (for the directional method): a leaf whose tile holds several planes is summarised as parts
// split by orientation; every regular sample lies within the bounds of the part it is numbered with, the parts'
// counts add up to the leaf's regular samples, and the summaries do not depend on the thread count.
TEST(ClusterHierarchy, LeafSummaryPartsBoundTheirSamples) {
    ClusterBuildOptions options;
    options.leaf_summaries = true;
    size_t split = 0;
    for (uint32_t seed = 1; seed <= 3; ++seed) {
        SCOPED_TRACE(seed);
        const int w = 96 + 8 * int(seed), h = 64;
        const ViewSamples vs = random_samples(w, h, seed);
        const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, perspective_params(w, h), options);
        const size_t leaves = hierarchy.leaves.size();
        ASSERT_EQ(hierarchy.leaf_summary_begin.size(), leaves + 1);
        ASSERT_EQ(hierarchy.leaf_summaries.size(), hierarchy.leaf_summary_begin.back());
        ASSERT_EQ(hierarchy.sample_part.size(), hierarchy.sample_order.size());
        for (size_t l = 0; l < leaves; ++l) {
            const uint32_t first = hierarchy.leaf_summary_begin[l], parts = hierarchy.leaf_summary_begin[l + 1] - first;
            ASSERT_GE(parts, 1u);
            ASSERT_LE(parts, 1u << kLeafSplitLevels);
            split += parts > 1;
            const ClusterNode& leaf = hierarchy.nodes[hierarchy.leaves[l]];
            std::vector<uint32_t> counted(parts, 0);
            for (uint32_t k = leaf.sample_begin; k != leaf.sample_end; ++k) {
                const ViewSample& s = vs.samples[hierarchy.sample_order[k]];
                if (!std::isfinite(s.position.x) || !std::isfinite(s.normal.x)) continue;
                ASSERT_LT(hierarchy.sample_part[k], parts);
                ++counted[hierarchy.sample_part[k]];
                const LeafSummary& part = hierarchy.leaf_summaries[first + hierarchy.sample_part[k]];
                const glm::dvec3 axis = glm::normalize(glm::dvec3(part.normal_sum));
                const glm::dvec3 d = glm::dvec3(s.position) - glm::dvec3(part.centroid);
                const double angle = std::acos(std::clamp(glm::dot(axis, glm::normalize(glm::dvec3(s.normal))), -1.0, 1.0));
                EXPECT_LE(angle, double(part.cone_angle));
                EXPECT_LE(glm::length(d), double(part.radius));
                EXPECT_LE(std::fabs(glm::dot(axis, d)), double(part.slab));
            }
            for (uint32_t p = 0; p < parts; ++p) {
                EXPECT_EQ(hierarchy.leaf_summaries[first + p].count, counted[p]);
                if (parts > 1) EXPECT_GT(counted[p], 0u);  // a split leaves no part empty
            }
        }
        const ClusterHierarchy two = build_with_threads(2, vs, perspective_params(w, h), options);
        EXPECT_EQ(two.leaf_summary_begin, hierarchy.leaf_summary_begin);
        EXPECT_EQ(two.sample_part, hierarchy.sample_part);
        ASSERT_EQ(two.leaf_summaries.size(), hierarchy.leaf_summaries.size());
        EXPECT_EQ(0, std::memcmp(two.leaf_summaries.data(), hierarchy.leaf_summaries.data(),
                                 hierarchy.leaf_summaries.size() * sizeof(LeafSummary)));
    }
    EXPECT_GT(split, 0u);  // tiles across the planes' intersections
}

TEST(ClusterHierarchy, RefusesInconsistentInput) {
    ViewSamples vs = random_samples(16, 16, 3, 0.0);
    EXPECT_THROW(build_cluster_hierarchy(vs, perspective_params(16, 15)), InvalidInput);  // size differs
    ClusterKeyParams params = perspective_params(16, 16);
    params.near_clip = 0.0f;
    EXPECT_THROW(build_cluster_hierarchy(vs, params), InvalidInput);
    vs.samples.back().pixel = 16 * 16;
    EXPECT_THROW(build_cluster_hierarchy(vs, perspective_params(16, 16)), InvalidInput);
}

// Not a benchmark (see tools/), but a guard against an accidentally quadratic build: a full 1080p frame.
TEST(ClusterHierarchy, FullHdFrameBuildsQuickly) {
    const ViewSamples vs = random_samples(1920, 1080, 9, 0.02, 1.0);
    const ClusterKeyParams params = perspective_params(1920, 1080);
    const auto start = std::chrono::steady_clock::now();
    const ClusterHierarchy h = build_cluster_hierarchy(vs, params);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    RecordProperty("build_seconds_1080p", std::to_string(seconds));
    std::printf("1080p hierarchy: %zu samples, %zu leaves, %zu nodes, depth %d, %.1f MiB, %.3f s\n",
                vs.samples.size(), h.leaves.size(), h.nodes.size(), h.depth, h.bytes() / 1048576.0, seconds);
    EXPECT_LT(seconds, 2.0);  // generous: debug builds and busy machines; expect ~0.1 s in Release
}

// --- depth slices -----------------------------------------------------------------------------------------

TEST(DepthSlice, ZeroAtAndBeforeTheNearPlane) {
    const ClusterKeyParams params = perspective_params(1920, 1080);
    EXPECT_EQ(depth_slice(params.near_clip, params), 0u);
    EXPECT_EQ(depth_slice(0.05f, params), 0u);
    EXPECT_EQ(depth_slice(0.0f, params), 0u);
    EXPECT_EQ(depth_slice(-3.0f, params), 0u);
    EXPECT_EQ(depth_slice(std::nanf(""), params), 0u);
}

TEST(DepthSlice, MonotoneInDepth) {
    for (bool orthographic : {false, true}) {
        ClusterKeyParams params = perspective_params(640, 480);
        params.orthographic = orthographic;
        uint32_t previous = 0;
        for (double z = 1e-3; z < 1e7; z *= 1.0007) {
            const uint32_t k = depth_slice(float(z), params);
            ASSERT_GE(k, previous) << "z = " << z;
            previous = k;
        }
        EXPECT_GT(previous, 900u);  // ln(1e7 / 0.1) / ln(1 + 2·tan 30° / 60) = 966
    }
}

TEST(DepthSlice, MatchesTheFormulaByHand) {
    // One tile row, tan(fovY/2) = 1, near 1: slices grow by 1 + 2·1/1 = 3, so k = floor(log3 z).
    ClusterKeyParams params = perspective_params(8, 8);
    params.near_clip = 1.0f;
    params.vertical_half_extent = 1.0f;
    EXPECT_EQ(depth_slice(2.9f, params), 0u);   // log3 2.9 = 0.969
    EXPECT_EQ(depth_slice(3.1f, params), 1u);   // 1.030
    EXPECT_EQ(depth_slice(10.0f, params), 2u);  // 2.096
    EXPECT_EQ(depth_slice(27.5f, params), 3u);  // 3.017
    // 1080p, 60° vertical field of view, near 0.1: 135 tile rows, ratio 1 + 2·tan 30°/135 = 1.0085534.
    const ClusterKeyParams hd = perspective_params(1920, 1080);
    EXPECT_EQ(depth_slice(1.0f, hd), 270u);     // 270.35
    EXPECT_EQ(depth_slice(10.0f, hd), 540u);    // 540.71
    EXPECT_EQ(depth_slice(1000.0f, hd), 1081u); // 1081.41: ln(1e4)/ln(1.0085534), 1081 slices from near to far
    // Height 1081 needs 136 tile rows, not 135: the last, partial row counts.
    EXPECT_EQ(depth_slice(1000.0f, perspective_params(1920, 1081)), 1089u);  // ln(1e4)/ln(1+2·tan30°/136)
}

TEST(DepthSlice, ClampsTo21Bits) {
    ClusterKeyParams params = perspective_params(8, 1 << 20);
    params.vertical_half_extent = 1e-3f;
    EXPECT_EQ(depth_slice(1e30f, params), (1u << 21) - 1);
    EXPECT_EQ(depth_slice(INFINITY, params), (1u << 21) - 1);
}

TEST(DepthSlice, OrthographicSlicesAreOneTileHigh) {
    // Half height 2 over 2 tile rows: slices 2 units thick, counted from the near plane at 0.5.
    ClusterKeyParams params = perspective_params(16, 16);
    params.orthographic = true;
    params.near_clip = 0.5f;
    params.vertical_half_extent = 2.0f;
    EXPECT_EQ(depth_slice(0.5f, params), 0u);
    EXPECT_EQ(depth_slice(-1.0f, params), 0u);
    EXPECT_EQ(depth_slice(2.4f, params), 0u);
    EXPECT_EQ(depth_slice(2.6f, params), 1u);
    EXPECT_EQ(depth_slice(10.6f, params), 5u);
}

}  // namespace
}  // namespace ps
