// Splatting: the cluster method must give what the brute-force oracle gives, sample for sample, on random
// scenes and on the cases where culling is easiest to get wrong (photons on box faces, at distance exactly r,
// grazing, coincident...). Also counters, cancellation, input checks and method names.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <thread>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/task_arena.h>

#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/render_control.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"

namespace ps {
namespace {

constexpr float kTanHalfFov = 0.57735027f;  // 60° vertical field of view

ClusterKeyParams key_params(int width, int height) {
    ClusterKeyParams params;
    params.width = width;
    params.height = height;
    params.near_clip = 0.1f;
    params.vertical_half_extent = kTanHalfFov;
    return params;
}

glm::vec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<float> g;
    for (;;) {
        const glm::vec3 v(g(rng), g(rng), g(rng));
        const float len = glm::length(v);
        if (len > 1e-3f) return v / len;
    }
}

struct SceneOptions {
    int width = 48, height = 40;
    double coverage = 0.95;           // fraction of pixels with a sample
    double specular_fraction = 0.1;   // fraction of samples flagged kViaSpecular
    int planes = 4;
    float min_depth = 1.0f, max_depth = 20.0f;
};

// A pinhole camera at `origin` looking down −z at a few randomly tilted planes: a sample per covered pixel on
// the nearest plane, with random albedo and throughput. Samples "seen through a mirror" are moved elsewhere.
ViewSamples random_view_samples(const SceneOptions& o, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    ViewSamples vs;
    vs.width = o.width;
    vs.height = o.height;
    vs.origin = glm::vec3(250.0f, -40.0f, 12.0f);
    std::vector<std::pair<glm::vec3, float>> planes;  // n·x = d
    for (int i = 0; i < o.planes; ++i) {
        const glm::vec3 n = glm::normalize(glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, 0.5f + u(rng)));
        planes.push_back({n, -(o.min_depth + (o.max_depth - o.min_depth) * u(rng)) * n.z});
    }
    const float aspect = float(o.width) / float(o.height);
    for (int y = 0; y < o.height; ++y)
        for (int x = 0; x < o.width; ++x) {
            if (u(rng) > o.coverage) continue;
            const glm::vec3 dir((2.0f * (x + 0.5f) / o.width - 1.0f) * kTanHalfFov * aspect,
                                (1.0f - 2.0f * (y + 0.5f) / o.height) * kTanHalfFov, -1.0f);
            float t_best = INFINITY;
            glm::vec3 n_best(0, 0, 1);
            for (const auto& [n, d] : planes) {
                const float t = d / glm::dot(n, dir);
                if (t > 0.0f && t < t_best) t_best = t, n_best = n;
            }
            if (!std::isfinite(t_best)) continue;
            ViewSample s{};
            s.position = dir * t_best;
            s.normal = s.shading_normal = glm::dot(n_best, dir) < 0.0f ? n_best : -n_best;
            s.wo = -glm::normalize(dir);
            s.albedo = glm::vec3(u(rng), u(rng), u(rng));
            s.throughput = glm::vec3(1.0f);
            s.pixel = uint32_t(y * o.width + x);
            s.depth = t_best;
            if (u(rng) < o.specular_fraction) {
                s.flags = kViaSpecular;
                s.position = glm::vec3(u(rng) * 8.0f - 4.0f, u(rng) * 8.0f - 4.0f, -2.0f - u(rng) * 10.0f);
                s.normal = s.shading_normal = random_unit(rng);
                s.throughput = glm::vec3(0.2f + u(rng), 0.2f + u(rng), 0.2f + u(rng));
            }
            vs.samples.push_back(s);
        }
    return vs;
}

// Photons scattered around random samples (within `spread`), mostly on the sample's side and orientation,
// sometimes not, so that every branch of the per-sample test is exercised.
PhotonMap random_photons(const ViewSamples& vs, size_t count, float spread, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    PhotonMap map;
    map.emitted = count * 3 + 1;
    for (size_t i = 0; i < count && !vs.samples.empty(); ++i) {
        const ViewSample& s = vs.samples[size_t(u(rng) * float(vs.samples.size())) % vs.samples.size()];
        Photon p{};
        p.position = vs.origin + s.position + random_unit(rng) * (spread * u(rng));
        p.normal = u(rng) < 0.8f ? glm::normalize(s.normal + 0.3f * random_unit(rng)) : random_unit(rng);
        p.wi = random_unit(rng);
        if (glm::dot(p.wi, p.normal) < 0.0f) p.wi = -p.wi;
        p.power = glm::vec3(0.5f + u(rng), 0.5f + u(rng), 0.5f + u(rng));
        p.flags = u(rng) < 0.1f ? kCaustic : 0u;
        map.photons.push_back(p);
    }
    return map;
}

SplatParams splat_params(float radius, const PhotonMap& map) {
    SplatParams params;
    params.radius = radius;
    params.emitted = map.emitted;
    return params;
}

double counter(const Stats& stats, const char* name) {
    const auto it = stats.counters.find(name);
    return it == stats.counters.end() ? 0.0 : it->second;
}

struct Comparison {
    size_t samples = 0, identical = 0;
    Stats brute, cluster;
};

// Runs both methods and checks the cluster result against the oracle: relative 1e-4 per sample and channel.
Comparison compare_with_brute(const ViewSamples& vs, const PhotonMap& map, const SplatParams& params,
                              const ClusterKeyParams& key) {
    Comparison c;
    RenderControl control;
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key);
    const std::vector<glm::vec3> expected = splat_brute(vs, map, params, control, c.brute);
    const std::vector<glm::vec3> actual = splat_cluster(hierarchy, vs, map, params, control, c.cluster);
    EXPECT_EQ(expected.size(), vs.samples.size());
    EXPECT_EQ(actual.size(), vs.samples.size());
    c.samples = std::min(expected.size(), actual.size());
    for (size_t i = 0; i < c.samples; ++i) {
        bool same = true;
        for (int ch = 0; ch < 3; ++ch) {
            const float a = actual[i][ch], e = expected[i][ch];
            EXPECT_TRUE(std::isfinite(a)) << "sample " << i;
            EXPECT_LE(std::fabs(a - e), 1e-4f * std::max(std::fabs(a), std::fabs(e)))
                << "sample " << i << " channel " << ch << ": cluster " << a << ", brute " << e;
            same = same && a == e;
        }
        c.identical += same ? 1 : 0;
    }
    // Same photons reach the same samples; culling only ever removes tests.
    EXPECT_EQ(counter(c.cluster, "contributing_pairs"), counter(c.brute, "contributing_pairs"));
    EXPECT_LE(counter(c.cluster, "photon_sample_tests"), counter(c.brute, "photon_sample_tests"));
    return c;
}

void report(const char* what, const Comparison& c) {
    std::printf("%-28s %6zu samples, %6zu bit-identical, contributing pairs %.0f, sample tests brute %.0f / "
                "cluster %.0f, node tests %.0f\n",
                what, c.samples, c.identical, counter(c.brute, "contributing_pairs"),
                counter(c.brute, "photon_sample_tests"), counter(c.cluster, "photon_sample_tests"),
                counter(c.cluster, "photon_node_tests"));
}

TEST(SplatCluster, MatchesBruteOnRandomScenes) {
    size_t samples = 0, identical = 0;
    for (uint32_t seed = 1; seed <= 3; ++seed) {
        std::mt19937 rng(seed);
        SceneOptions options;
        const ViewSamples vs = random_view_samples(options, rng);
        const PhotonMap map = random_photons(vs, 3000, 0.5f, rng);
        for (float radius : {1e-3f, 0.05f, 0.3f, 1e3f}) {
            SCOPED_TRACE("seed " + std::to_string(seed) + " radius " + std::to_string(radius));
            const Comparison c = compare_with_brute(vs, map, splat_params(radius, map), key_params(48, 40));
            if (radius == 0.3f) {
                EXPECT_GT(counter(c.brute, "contributing_pairs"), 1000.0);
            }
            if (seed == 1) report(("radius " + std::to_string(radius)).c_str(), c);
            samples += c.samples;
            identical += c.identical;
        }
    }
    RecordProperty("bit_identical_fraction", std::to_string(double(identical) / double(samples)));
    std::printf("bit-identical: %zu of %zu samples\n", identical, samples);
}

TEST(SplatCluster, MatchesBruteWithPlaneDistanceAndStrictNormals) {
    std::mt19937 rng(17);
    const ViewSamples vs = random_view_samples(SceneOptions{}, rng);
    const PhotonMap map = random_photons(vs, 2000, 0.4f, rng);
    SplatParams params = splat_params(0.25f, map);
    params.plane_distance_factor = 0.2f;
    params.cos_normal_tolerance = 0.9f;
    compare_with_brute(vs, map, params, key_params(48, 40));
}

// Photons on the faces and corners of node boxes, and at distance exactly r (and one ulp inside and outside)
// from samples and boxes. Positions are small binary fractions, so all these distances are exact in float.
TEST(SplatCluster, PhotonsOnBoxBoundariesAndAtDistanceExactlyR) {
    ViewSamples vs;
    vs.width = 32;
    vs.height = 32;
    vs.origin = glm::vec3(0.0f);  // world = relative: the distances below stay exact
    for (uint32_t pixel = 0; pixel < 32 * 32; ++pixel) {
        const uint32_t x = pixel % 32, y = pixel / 32;
        ViewSample s{};
        s.depth = (x / 4) % 2 ? 2.0f : 8.0f;  // depth discontinuities inside tiles
        s.position = glm::vec3(float(x) * 0.25f, float(y) * 0.25f, -s.depth);
        s.normal = s.shading_normal = s.wo = glm::vec3(0, 0, 1);
        s.albedo = glm::vec3(0.8f, 0.5f, 0.25f);
        s.throughput = glm::vec3(1.0f);
        s.pixel = pixel;
        vs.samples.push_back(s);
    }
    const float r = 0.5f;
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(32, 32));
    PhotonMap map;
    auto add = [&](const glm::vec3& position) {
        Photon p{};
        p.position = position;
        p.wi = glm::normalize(glm::vec3(0.1f, 0.2f, 1.0f));
        p.normal = glm::vec3(0, 0, 1);
        p.power = glm::vec3(1.0f);
        map.photons.push_back(p);
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
    const ViewSamples vs = random_view_samples(SceneOptions{}, rng);
    PhotonMap map = random_photons(vs, 2000, 0.3f, rng);
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
    SceneOptions options;
    options.width = 96;
    options.height = 64;
    options.coverage = 0.02;
    options.specular_fraction = 0.0;
    const ViewSamples vs = random_view_samples(options, rng);
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(96, 64));
    size_t single = 0;
    for (uint32_t leaf : hierarchy.leaves)
        single += hierarchy.nodes[leaf].sample_end - hierarchy.nodes[leaf].sample_begin == 1 ? 1 : 0;
    EXPECT_GT(single, hierarchy.leaves.size() / 2);
    const PhotonMap map = random_photons(vs, 1000, 1.0f, rng);
    compare_with_brute(vs, map, splat_params(0.5f, map), key_params(96, 64));
}

TEST(SplatCluster, DepthDiscontinuitiesWithinTiles) {
    std::mt19937 rng(31);
    SceneOptions options;
    options.planes = 8;
    options.min_depth = 0.5f;
    options.max_depth = 500.0f;
    const ViewSamples vs = random_view_samples(options, rng);
    const PhotonMap map = random_photons(vs, 3000, 2.0f, rng);
    for (float radius : {0.5f, 5.0f}) compare_with_brute(vs, map, splat_params(radius, map), key_params(48, 40));
}

TEST(SplatCluster, SamplesSeenThroughMirrors) {
    std::mt19937 rng(41);
    SceneOptions options;
    options.specular_fraction = 0.6;
    const ViewSamples vs = random_view_samples(options, rng);
    const PhotonMap map = random_photons(vs, 3000, 0.5f, rng);
    const Comparison c = compare_with_brute(vs, map, splat_params(0.4f, map), key_params(48, 40));
    report("mostly via specular", c);
}

TEST(SplatCluster, AllPhotonsAtOnePoint) {
    std::mt19937 rng(43);
    const ViewSamples vs = random_view_samples(SceneOptions{}, rng);
    PhotonMap map = random_photons(vs, 2000, 0.0f, rng);
    for (Photon& p : map.photons) p.position = map.photons[0].position;
    const Comparison c = compare_with_brute(vs, map, splat_params(0.3f, map), key_params(48, 40));
    EXPECT_GT(counter(c.brute, "contributing_pairs"), 0.0);
}

TEST(SplatCluster, ZeroPhotonsGiveZeroRadiance) {
    std::mt19937 rng(3);
    const ViewSamples vs = random_view_samples(SceneOptions{}, rng);
    PhotonMap map;  // emitted 0 too: fine when nothing was stored
    const SplatParams params = splat_params(0.3f, map);
    RenderControl control;
    Stats stats;
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(48, 40));
    for (const std::vector<glm::vec3>& out : {splat_brute(vs, map, params, control, stats),
                                               splat_cluster(hierarchy, vs, map, params, control, stats)}) {
        ASSERT_EQ(out.size(), vs.samples.size());
        for (const glm::vec3& v : out) EXPECT_EQ(v, glm::vec3(0.0f));
    }
    EXPECT_EQ(stats.counters["contributing_pairs"], 0.0);
}

TEST(SplatCluster, ZeroSamples) {
    ViewSamples vs;
    vs.width = 4;
    vs.height = 4;
    std::mt19937 rng(3);
    const ViewSamples other = random_view_samples(SceneOptions{}, rng);
    const PhotonMap map = random_photons(other, 100, 0.1f, rng);
    RenderControl control;
    Stats stats;
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(4, 4));
    EXPECT_TRUE(splat_brute(vs, map, splat_params(0.3f, map), control, stats).empty());
    EXPECT_TRUE(splat_cluster(hierarchy, vs, map, splat_params(0.3f, map), control, stats).empty());
}

TEST(SplatCluster, SameOutputWithOneAndTwoThreads) {
    std::mt19937 rng(59);
    SceneOptions options;
    options.width = 96;
    options.height = 80;
    const ViewSamples vs = random_view_samples(options, rng);
    const PhotonMap map = random_photons(vs, 5000, 0.5f, rng);
    const SplatParams params = splat_params(0.3f, map);
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(96, 80));
    auto run = [&](int threads) {
        std::vector<glm::vec3> out;
        RenderControl control;
        Stats stats;
        tbb::task_arena(threads).execute([&] { out = splat_cluster(hierarchy, vs, map, params, control, stats); });
        return out;
    };
    EXPECT_EQ(run(1), run(2));
}

TEST(SplatCluster, ReportsCountersAndBytes) {
    std::mt19937 rng(61);
    const ViewSamples vs = random_view_samples(SceneOptions{}, rng);
    const PhotonMap map = random_photons(vs, 1000, 0.5f, rng);
    const Comparison c = compare_with_brute(vs, map, splat_params(0.3f, map), key_params(48, 40));
    EXPECT_EQ(c.brute.counters.at("photon_sample_tests"), double(vs.samples.size() * map.photons.size()));
    EXPECT_GT(c.cluster.counters.at("photon_node_tests"), double(map.photons.size()));
    EXPECT_GT(c.cluster.counters.at("leaf_photon_pairs"), 0.0);
    EXPECT_GT(c.cluster.bytes.at("hierarchy"), 0.0);
    EXPECT_GT(c.cluster.bytes.at("leaf_photon_lists"), 0.0);
    // Far fewer tests than the oracle at a typical radius: the point of the hierarchy.
    EXPECT_LT(c.cluster.counters.at("photon_sample_tests"), 0.2 * c.brute.counters.at("photon_sample_tests"));
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
        const ViewSamples vs = random_view_samples(SceneOptions{}, rng);
        const PhotonMap map = random_photons(vs, 1500, 0.5f, rng);
        const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(48, 40));
        SplatParams params = splat_params(1e3f, map);
        params.max_pairs_in_memory = kCap;
        const Comparison c = compare_with_brute(vs, map, params, key_params(48, 40));
        EXPECT_EQ(c.identical, c.samples);
        const double pairs = counter(c.cluster, "leaf_photon_pairs");
        EXPECT_EQ(pairs, double(map.photons.size() * hierarchy.leaves.size()));  // every photon, every leaf
        EXPECT_GT(counter(c.cluster, "splat_batches"), pairs / double(kCap));
        EXPECT_LE(peak_pair_bytes(c.cluster), pair_bytes_bound(kCap, hierarchy));
        EXPECT_LT(peak_pair_bytes(c.cluster), 0.02 * pairs * 8.0);  // what holding them all would take
        if (seed == 1) {
            report("radius 1e3, cap 1000 pairs", c);
            std::printf("%.0f pairs in %.0f batches, peak %.0f bytes\n", pairs, counter(c.cluster, "splat_batches"),
                        peak_pair_bytes(c.cluster));
        }
    }
}

TEST(SplatCluster, OnePhotonAloneBeyondThePairCap) {
    std::mt19937 rng(83);
    const ViewSamples vs = random_view_samples(SceneOptions{}, rng);
    const PhotonMap map = random_photons(vs, 40, 0.5f, rng);
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(48, 40));
    ASSERT_GT(hierarchy.leaves.size(), 10u);
    for (uint64_t cap : {uint64_t(1), uint64_t(10)}) {
        SplatParams params = splat_params(1e3f, map);
        params.max_pairs_in_memory = cap;
        const Comparison c = compare_with_brute(vs, map, params, key_params(48, 40));
        EXPECT_EQ(c.identical, c.samples);
        EXPECT_EQ(counter(c.cluster, "splat_batches"), double(map.photons.size()));  // one photon a batch
        EXPECT_LE(peak_pair_bytes(c.cluster), pair_bytes_bound(4 * hierarchy.leaves.size(), hierarchy));
    }
}

// Many batches with several ranges in flight: the same output with one thread, two threads, and the oracle.
TEST(SplatCluster, SmallPairCapSameOutputWithOneAndTwoThreads) {
    std::mt19937 rng(89);
    SceneOptions options;
    options.width = 96;
    options.height = 80;
    const ViewSamples vs = random_view_samples(options, rng);
    const PhotonMap map = random_photons(vs, 4000, 0.5f, rng);
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
    const ViewSamples vs = random_view_samples(SceneOptions{}, rng);
    const PhotonMap map = random_photons(vs, 3000, 0.5f, rng);
    const SplatParams params = splat_params(0.3f, map);
    EXPECT_EQ(params.max_pairs_in_memory, kDefaultMaxPairsInMemory);
    const Comparison c = compare_with_brute(vs, map, params, key_params(48, 40));
    EXPECT_EQ(c.identical, c.samples);
    EXPECT_EQ(counter(c.cluster, "splat_batches"), 1.0);
    EXPECT_EQ(c.cluster.bytes.count("splat_sample_sums") ? c.cluster.bytes.at("splat_sample_sums") : 0.0, 0.0);
}

// A cancel reaches the pipeline's stages and the batches shaded on the way.
TEST(SplatCluster, StopsPromptlyWhenCancelledBetweenBatches) {
    std::mt19937 rng(101);
    const ViewSamples vs = random_view_samples(SceneOptions{}, rng);
    const PhotonMap map = random_photons(vs, 100000, 0.5f, rng);
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(48, 40));
    SplatParams params = splat_params(1e3f, map);
    params.max_pairs_in_memory = 4000;
    RenderControl control;
    Stats stats;
    std::atomic<bool> started{false};
    std::thread canceller([&] {
        while (!started) std::this_thread::yield();
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        control.request_cancel();
    });
    const auto start = std::chrono::steady_clock::now();
    started = true;
    EXPECT_THROW(splat_cluster(hierarchy, vs, map, params, control, stats), Cancelled);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    canceller.join();
    EXPECT_LT(seconds, 0.5);
}

TEST(Splat, CancelledBeforeStartThrows) {
    std::mt19937 rng(67);
    const ViewSamples vs = random_view_samples(SceneOptions{}, rng);
    const PhotonMap map = random_photons(vs, 500, 0.5f, rng);
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(48, 40));
    RenderControl control;
    control.request_cancel();
    Stats stats;
    EXPECT_THROW(splat_brute(vs, map, splat_params(0.3f, map), control, stats), Cancelled);
    EXPECT_THROW(splat_cluster(hierarchy, vs, map, splat_params(0.3f, map), control, stats), Cancelled);
}

// A brute splat of minutes must stop within a fraction of a second of the cancel.
TEST(Splat, BruteStopsPromptlyWhenCancelledMidway) {
    std::mt19937 rng(71);
    SceneOptions options;
    options.width = 160;
    options.height = 120;
    const ViewSamples vs = random_view_samples(options, rng);
    const PhotonMap map = random_photons(vs, 200000, 0.5f, rng);
    RenderControl control;
    Stats stats;
    std::atomic<bool> started{false};
    std::thread canceller([&] {
        while (!started) std::this_thread::yield();
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
        control.request_cancel();
    });
    const auto start = std::chrono::steady_clock::now();
    started = true;
    EXPECT_THROW(splat_brute(vs, map, splat_params(0.3f, map), control, stats), Cancelled);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    canceller.join();
    EXPECT_LT(seconds, 0.5);
}

TEST(Splat, RefusesBadInput) {
    std::mt19937 rng(73);
    const ViewSamples vs = random_view_samples(SceneOptions{}, rng);
    const PhotonMap map = random_photons(vs, 100, 0.5f, rng);
    const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, key_params(48, 40));
    RenderControl control;
    Stats stats;
    for (float radius : {0.0f, -1.0f, NAN, INFINITY}) {
        EXPECT_THROW(splat_brute(vs, map, splat_params(radius, map), control, stats), InvalidInput);
        EXPECT_THROW(splat_cluster(hierarchy, vs, map, splat_params(radius, map), control, stats), InvalidInput);
    }
    SplatParams no_emitted = splat_params(0.3f, map);
    no_emitted.emitted = 0;
    EXPECT_THROW(splat_brute(vs, map, no_emitted, control, stats), InvalidInput);
    EXPECT_THROW(splat_cluster(hierarchy, vs, map, no_emitted, control, stats), InvalidInput);
    SplatParams no_pairs = splat_params(0.3f, map);
    no_pairs.max_pairs_in_memory = 0;
    EXPECT_THROW(splat_brute(vs, map, no_pairs, control, stats), InvalidInput);
    EXPECT_THROW(splat_cluster(hierarchy, vs, map, no_pairs, control, stats), InvalidInput);
    ViewSamples fewer = vs;
    fewer.samples.pop_back();
    EXPECT_THROW(splat_cluster(hierarchy, fewer, map, splat_params(0.3f, map), control, stats), InvalidInput);
}

TEST(Splat, MethodNamesRoundTrip) {
    for (SplatMethod m : {SplatMethod::brute, SplatMethod::cluster})
        EXPECT_EQ(splat_method_from_string(to_string(m)), m);
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
