// Splatting: the cluster method must give what the brute-force oracle gives, sample for sample, on the cases
// where culling is easiest to get wrong (photons on box faces, at distance exactly r, grazing, coincident...),
// and with its pair cap cutting photons in batches. Also counters, input checks and method names. What every
// method must do (random scenes, thread counts, cancels, zero input, bad parameters) is in test_methods.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/task_arena.h>

#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/render_control.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"
#include "test_support.h"

namespace ps {
namespace {

using namespace test;

// The cluster method against the oracle (test::compare_with_brute), over a hierarchy with the given keys.
Comparison compare_with_brute(const ViewSamples& vs, const PhotonMap& map, const SplatParams& params,
                              const ClusterKeyParams& key) {
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key);
    return test::compare_with_brute(SplatMethod::cluster, {vs, &hierarchy}, map, params);
}

void report(const char* what, const Comparison& c) {
    std::printf("%-28s %6zu samples, %6zu bit-identical, contributing pairs %.0f, sample tests brute %.0f / "
                "cluster %.0f, node tests %.0f\n",
                what, c.samples, c.identical, counter(c.brute, "contributing_pairs"),
                counter(c.brute, "photon_sample_tests"), counter(c.method, "photon_sample_tests"),
                counter(c.method, "photon_node_tests"));
}

// Photons on the faces and corners of node boxes, and at distance exactly r (and one ulp inside and outside)
// from samples and boxes. Positions are small binary fractions, so all these distances are exact in float.
TEST(SplatCluster, PhotonsOnBoxBoundariesAndAtDistanceExactlyR) {
    const ViewSamples vs = binary_grid_samples();  // origin 0: the distances below stay exact
    const float r = 0.5f;
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(32, 32));
    PhotonMap map;
    auto add = [&](const glm::vec3& position) {
        map.photons.push_back(photon_at(position, glm::normalize(glm::vec3(0.1f, 0.2f, 1.0f))));
    };
    const float below = std::nextafter(r, 0.0f), above = std::nextafter(r, 1.0f);
    for (const ClusterNode& node : hierarchy.nodes) {
        const glm::vec3 lo = node.box_min, hi = node.box_max, mid = 0.5f * (lo + hi);
        add(lo);
        add(hi);
        add(glm::vec3(lo.x, mid.y, mid.z));
        add(glm::vec3(mid.x, hi.y, mid.z));
        for (float d : {below, r, above}) {
            add(glm::vec3(hi.x + d, mid.y, mid.z));
            add(glm::vec3(mid.x, lo.y - d, mid.z));
            add(glm::vec3(mid.x, mid.y, hi.z + d));
            add(glm::vec3(lo.x, lo.y, lo.z - d));
        }
    }
    for (size_t i = 0; i < vs.samples.size(); i += 37)
        for (float d : {below, r, above}) {
            const glm::vec3 x = vs.samples[i].position;
            add(x + glm::vec3(d, 0, 0));
            add(x - glm::vec3(0, d, 0));
            add(x + glm::vec3(0, 0, d));
        }
    map.emitted = map.photons.size();
    const Comparison c = compare_with_brute(vs, map, splat_params(r, map), key_params(32, 32));
    report("box boundaries, |x-p| = r", c);
    EXPECT_GT(counter(c.brute, "contributing_pairs"), 0.0);
}

TEST(SplatCluster, GrazingPhotons) {
    std::mt19937 rng(23);
    const ViewSamples vs = synthetic_view_samples(SyntheticOptions{}, rng);
    PhotonMap map = synthetic_photons(vs, 2000, 0.3f, rng);
    for (size_t i = 0; i < map.photons.size(); ++i) {
        // ωi within a hair of the tangent plane of a random sample's normal, on either side.
        Photon& p = map.photons[i];
        const glm::vec3 n = vs.samples[(i * 7919) % vs.samples.size()].normal;
        const glm::vec3 tangent = glm::normalize(glm::cross(n, random_unit(rng)));
        p.wi = glm::normalize(tangent + (i % 2 ? 1e-6f : -1e-6f) * n);
        p.normal = n;
    }
    compare_with_brute(vs, map, splat_params(0.3f, map), key_params(48, 40));
}

TEST(SplatCluster, SparseSamplesGiveSingleSampleLeaves) {
    std::mt19937 rng(5);
    SyntheticOptions options = sized(96, 64);
    options.coverage = 0.02;
    options.specular_fraction = 0.0;
    const ViewSamples vs = synthetic_view_samples(options, rng);
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(96, 64));
    size_t single = 0;
    for (uint32_t leaf : hierarchy.leaves)
        single += hierarchy.nodes[leaf].sample_end - hierarchy.nodes[leaf].sample_begin == 1 ? 1 : 0;
    EXPECT_GT(single, hierarchy.leaves.size() / 2);
    const PhotonMap map = synthetic_photons(vs, 1000, 1.0f, rng);
    compare_with_brute(vs, map, splat_params(0.5f, map), key_params(96, 64));
}

TEST(SplatCluster, DepthDiscontinuitiesWithinTiles) {
    std::mt19937 rng(31);
    SyntheticOptions options;
    options.planes = 8;
    options.min_depth = 0.5f;
    options.max_depth = 500.0f;
    const ViewSamples vs = synthetic_view_samples(options, rng);
    const PhotonMap map = synthetic_photons(vs, 3000, 2.0f, rng);
    for (float radius : {0.5f, 5.0f}) compare_with_brute(vs, map, splat_params(radius, map), key_params(48, 40));
}

TEST(SplatCluster, SamplesSeenThroughMirrors) {
    std::mt19937 rng(41);
    SyntheticOptions options;
    options.specular_fraction = 0.6;
    const ViewSamples vs = synthetic_view_samples(options, rng);
    const PhotonMap map = synthetic_photons(vs, 3000, 0.5f, rng);
    const Comparison c = compare_with_brute(vs, map, splat_params(0.4f, map), key_params(48, 40));
    report("mostly via specular", c);
}

TEST(SplatCluster, AllPhotonsAtOnePoint) {
    std::mt19937 rng(43);
    const ViewSamples vs = synthetic_view_samples(SyntheticOptions{}, rng);
    PhotonMap map = synthetic_photons(vs, 2000, 0.0f, rng);
    for (Photon& p : map.photons) p.position = map.photons[0].position;
    const Comparison c = compare_with_brute(vs, map, splat_params(0.3f, map), key_params(48, 40));
    EXPECT_GT(counter(c.brute, "contributing_pairs"), 0.0);
}

TEST(SplatCluster, ReportsCountersAndBytes) {
    std::mt19937 rng(61);
    const ViewSamples vs = synthetic_view_samples(SyntheticOptions{}, rng);
    const PhotonMap map = synthetic_photons(vs, 1000, 0.5f, rng);
    const Comparison c = compare_with_brute(vs, map, splat_params(0.3f, map), key_params(48, 40));
    EXPECT_EQ(c.brute.counters.at("photon_sample_tests"), double(vs.samples.size() * map.photons.size()));
    EXPECT_GT(c.method.counters.at("photon_node_tests"), double(map.photons.size()));
    EXPECT_GT(c.method.counters.at("leaf_photon_pairs"), 0.0);
    EXPECT_GT(c.method.bytes.at("hierarchy"), 0.0);
    EXPECT_GT(c.method.bytes.at("leaf_photon_lists"), 0.0);
    // Far fewer tests than the oracle at a typical radius: the point of the hierarchy.
    EXPECT_LT(c.method.counters.at("photon_sample_tests"), 0.2 * c.brute.counters.at("photon_sample_tests"));
}

// Bounded memory: photons are splatted in batches whose pairs stay under SplatParams::max_pairs_in_memory, and
// the output must not depend on where the batches end.
struct BatchCase {
    SplatParams params;
    ClusterHierarchy hierarchy;
};

double peak_pair_bytes(const Stats& stats) { return stats.bytes.at("leaf_photon_lists"); }

// What the pair buffers may hold under a cap: each pair twice (traversal buffer, then the lists) with growth
// slack, so 16 bytes per pair of the cap, plus the per-node offsets of the lists, which do not depend on it.
double pair_bytes_bound(uint64_t cap, const ClusterHierarchy& hierarchy) {
    return 16.0 * double(cap) + double(sizeof(size_t) * (hierarchy.nodes.size() + 2));
}

TEST(SplatCluster, TinyPairCapWithRadiusLargerThanTheSceneMatchesBruteBitForBit) {
    constexpr uint64_t kCap = 1000;
    for (uint32_t seed = 1; seed <= 3; ++seed) {
        SCOPED_TRACE("seed " + std::to_string(seed));
        std::mt19937 rng(seed);
        const ViewSamples vs = synthetic_view_samples(SyntheticOptions{}, rng);
        const PhotonMap map = synthetic_photons(vs, 1500, 0.5f, rng);
        const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(48, 40));
        SplatParams params = splat_params(1e3f, map);
        params.max_pairs_in_memory = kCap;
        const Comparison c = compare_with_brute(vs, map, params, key_params(48, 40));
        EXPECT_EQ(c.identical, c.samples);
        const double pairs = counter(c.method, "leaf_photon_pairs");
        EXPECT_EQ(pairs, double(map.photons.size() * hierarchy.leaves.size()));  // every photon, every leaf
        EXPECT_GT(counter(c.method, "splat_batches"), pairs / double(kCap));
        EXPECT_LE(peak_pair_bytes(c.method), pair_bytes_bound(kCap, hierarchy));
        EXPECT_LT(peak_pair_bytes(c.method), 0.02 * pairs * 8.0);  // what holding them all would take
        if (seed == 1) {
            report("radius 1e3, cap 1000 pairs", c);
            std::printf("%.0f pairs in %.0f batches, peak %.0f bytes\n", pairs, counter(c.method, "splat_batches"),
                        peak_pair_bytes(c.method));
        }
    }
}

TEST(SplatCluster, OnePhotonAloneBeyondThePairCap) {
    std::mt19937 rng(83);
    const ViewSamples vs = synthetic_view_samples(SyntheticOptions{}, rng);
    const PhotonMap map = synthetic_photons(vs, 40, 0.5f, rng);
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(48, 40));
    ASSERT_GT(hierarchy.leaves.size(), 10u);
    for (uint64_t cap : {uint64_t(1), uint64_t(10)}) {
        SplatParams params = splat_params(1e3f, map);
        params.max_pairs_in_memory = cap;
        const Comparison c = compare_with_brute(vs, map, params, key_params(48, 40));
        EXPECT_EQ(c.identical, c.samples);
        EXPECT_EQ(counter(c.method, "splat_batches"), double(map.photons.size()));  // one photon a batch
        EXPECT_LE(peak_pair_bytes(c.method), pair_bytes_bound(4 * hierarchy.leaves.size(), hierarchy));
    }
}

// Many batches with several ranges in flight: the same output with one thread, two threads, and the oracle.
TEST(SplatCluster, SmallPairCapSameOutputWithOneAndTwoThreads) {
    std::mt19937 rng(89);
    const SyntheticOptions options = sized(96, 80);
    const ViewSamples vs = synthetic_view_samples(options, rng);
    const PhotonMap map = synthetic_photons(vs, 4000, 0.5f, rng);
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(96, 80));
    SplatParams params = splat_params(0.6f, map);
    params.max_pairs_in_memory = 8 * hierarchy.leaves.size();  // up to 4 ranges in flight
    auto run = [&](int threads, Stats& stats) {
        std::vector<glm::vec3> out;
        RenderControl control;
        tbb::task_arena(threads).execute([&] { out = splat_cluster(hierarchy, vs, map, params, control, stats); });
        return out;
    };
    Stats one, two, brute;
    const std::vector<glm::vec3> expected = splat_brute(vs, map, params, RenderControl(), brute);
    EXPECT_TRUE(run(1, one) == expected);
    EXPECT_TRUE(run(2, two) == expected);
    for (const Stats* stats : {&one, &two}) {
        EXPECT_GE(counter(*stats, "splat_batches"), 4.0);
        EXPECT_LE(peak_pair_bytes(*stats), pair_bytes_bound(params.max_pairs_in_memory, hierarchy));
        EXPECT_EQ(counter(*stats, "contributing_pairs"), counter(brute, "contributing_pairs"));
        EXPECT_EQ(counter(*stats, "leaf_photon_pairs"), counter(one, "leaf_photon_pairs"));
        EXPECT_EQ(counter(*stats, "photon_node_tests"), counter(one, "photon_node_tests"));
    }
    std::printf("cap %llu pairs: %.0f pairs in %.0f batches, peak %.0f bytes\n",
                (unsigned long long)params.max_pairs_in_memory, counter(two, "leaf_photon_pairs"),
                counter(two, "splat_batches"), peak_pair_bytes(two));
}

TEST(SplatCluster, OneBatchWithTheDefaultPairCap) {
    std::mt19937 rng(97);
    const ViewSamples vs = synthetic_view_samples(SyntheticOptions{}, rng);
    const PhotonMap map = synthetic_photons(vs, 3000, 0.5f, rng);
    const SplatParams params = splat_params(0.3f, map);
    EXPECT_EQ(params.max_pairs_in_memory, kDefaultMaxPairsInMemory);
    const Comparison c = compare_with_brute(vs, map, params, key_params(48, 40));
    EXPECT_EQ(c.identical, c.samples);
    EXPECT_EQ(counter(c.method, "splat_batches"), 1.0);
    EXPECT_EQ(c.method.bytes.count("splat_sample_sums") ? c.method.bytes.at("splat_sample_sums") : 0.0, 0.0);
}

// (Bad parameters, for every method: AnyMethod.RefusesBadParams.)
TEST(Splat, RefusesBadInput) {
    std::mt19937 rng(73);
    const ViewSamples vs = synthetic_view_samples(SyntheticOptions{}, rng);
    const PhotonMap map = synthetic_photons(vs, 100, 0.5f, rng);
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(48, 40));
    RenderControl control;
    Stats stats;
    ViewSamples fewer = vs;
    fewer.samples.pop_back();
    EXPECT_THROW(splat_cluster(hierarchy, fewer, map, splat_params(0.3f, map), control, stats), InvalidInput);
}

TEST(Splat, MethodNamesRoundTrip) {
    for (SplatMethod m : all_methods()) EXPECT_EQ(splat_method_from_string(to_string(m)), m);
    EXPECT_STREQ(to_string(SplatMethod::cluster), "cluster");
    EXPECT_THROW(splat_method_from_string("Cluster"), InvalidInput);
    EXPECT_THROW(splat_method_from_string(""), InvalidInput);
}

TEST(Splat, RelativePhotonPositions) {
    PhotonMap map;
    map.photons.resize(2);
    map.photons[0].position = glm::vec3(1.5f, 2.0f, -3.0f);
    map.photons[1].position = glm::vec3(100000.0f, 0.0f, 0.25f);
    const std::vector<glm::vec3> rel = relative_photon_positions(map, glm::vec3(100000.0f, 1.0f, 0.0f));
    ASSERT_EQ(rel.size(), 2u);
    EXPECT_EQ(rel[0], glm::vec3(1.5f - 100000.0f, 1.0f, -3.0f));
    EXPECT_EQ(rel[1], glm::vec3(0.0f, -1.0f, 0.25f));
}

}  // namespace
}  // namespace ps
