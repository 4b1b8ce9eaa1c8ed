// The gather method (photons in a hashed uniform grid, each view sample gathers from the cells its sphere
// overlaps) must give what the brute-force oracle gives, sample for sample: on random scenes at radii from tiny
// to larger than the scene, with both kernels, on photons exactly on cell boundaries and at distance exactly r,
// far from the origin, all at one point, none at all, and on the Cornell box through the real pipeline (samples
// behind glass included). Also determinism across thread counts, cancellation and the counters.
//
// GatherBenchmark.* are disabled (not timed tests): run with --gtest_also_run_disabled_tests to time gather
// against the cluster method at 1920×1080 with 200k photons in the same run.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/photons.h"
#include "photonsplat/render.h"
#include "photonsplat/render_control.h"
#include "photonsplat/scene.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"
#include "photonsplat/view_samples.h"
#include "test_support.h"

namespace ps {
namespace {

using namespace test;

// The synthetic scenes of these tests (test_support.h) are 40 × 32 pixels.
SyntheticOptions gather_scene() { return sized(40, 32); }

// Gather against brute: test::compare_with_brute.
Comparison check_against_brute(const ViewSamples& vs, const PhotonMap& map, const SplatParams& params) {
    return compare_with_brute(SplatMethod::gather, {vs}, map, params);
}

void print(const std::string& what, const Comparison& o) {
    std::printf("%-34s %5zu samples, %5zu bit-identical, pairs %8.0f, tests brute %9.0f / gather %8.0f, "
                "cells %6.0f, cell visits %7.0f\n",
                what.c_str(), o.samples, o.identical, counter(o.brute, "contributing_pairs"),
                counter(o.brute, "photon_sample_tests"), counter(o.method, "photon_sample_tests"),
                counter(o.method, "grid_cells"), counter(o.method, "cell_visits"));
}

// Photons exactly on cell faces, edges and corners, and at distance exactly r (and one ulp inside and
// outside) from samples, along the axes and along a 3-4-5 diagonal. With origin 0, r = 5/8 and a photon
// pinned at the grid's lower corner (−10, −10, −10), every cell boundary and every distance below is an exact binary fraction.
TEST(GatherSplat, PhotonsOnCellBoundariesAndAtDistanceExactlyR) {
    const float r = 0.625f;
    ViewSamples vs;
    vs.width = 24;
    vs.height = 24;
    vs.origin = glm::vec3(0.0f);  // world = relative: the distances below stay exact
    for (uint32_t pixel = 0; pixel < 24 * 24; ++pixel) {
        const uint32_t x = pixel % 24, y = pixel / 24;
        const float depth = (x / 4) % 2 ? 2.5f : 5.0f;
        // Every other sample on a cell boundary (−10 + k·r), the rest half-way.
        const glm::vec3 position(-5.0f + float(x) * 0.3125f, -5.0f + float(y) * 0.3125f, -depth);
        vs.samples.push_back(facing_sample(position, depth, pixel));
    }
    PhotonMap map;
    auto add = [&](const glm::vec3& position) {
        const glm::vec3 power(1.0f + 0.001f * float(map.photons.size() % 7));
        map.photons.push_back(photon_at(position, glm::normalize(glm::vec3(0.1f, 0.2f, 1.0f)), power));
    };
    add(glm::vec3(-10.0f, -10.0f, -10.0f));  // the grid's lower corner: cell boundaries at −10 + k·r
    for (int i = 0; i <= 16; ++i)
        for (int j = 0; j <= 16; ++j) {
            const float bx = -5.0f + float(i) * r, by = -5.0f + float(j) * r;
            add(glm::vec3(bx, by, -5.0f));                    // cell corner, on the far plane
            add(glm::vec3(bx, by + 0.5f * r, -2.5f));        // cell face, on the near plane
            add(glm::vec3(bx + 0.25f * r, by, -5.0f + r));   // an x–z cell edge, r above the far plane
        }
    const float below = std::nextafter(r, 0.0f), above = std::nextafter(r, 1.0f);
    for (size_t i = 0; i < vs.samples.size(); i += 13) {
        const glm::vec3 x = vs.samples[i].position;
        for (float d : {below, r, above}) {
            add(x + glm::vec3(d, 0, 0));
            add(x - glm::vec3(0, d, 0));
            add(x + glm::vec3(0, 0, d));
            add(x - glm::vec3(0, 0, d));
        }
        add(x + glm::vec3(0.375f, 0.5f, 0.0f));   // |(3/8, 4/8)| = 5/8 = r exactly: outside
        add(x + glm::vec3(0.0f, -0.375f, 0.5f));  // likewise
        add(x + glm::vec3(std::nextafter(0.375f, 0.0f), 0.5f, 0.0f));  // just inside
    }
    map.emitted = map.photons.size();
    for (Kernel kernel : {Kernel::uniform, Kernel::epanechnikov}) {
        const Comparison o = check_against_brute(vs, map, splat_params(r, map, kernel));
        print(std::string("cell boundaries, |x-p| = r, ") + to_string(kernel), o);
        EXPECT_GT(counter(o.brute, "contributing_pairs"), 0.0);
        EXPECT_EQ(o.identical, o.samples);
    }
}

// Camera 1e5 from the world origin, and samples 1e5 from the camera: float positions there have ulps of
// ~0.008, comparable to the radius.
TEST(GatherSplat, FarFromTheOrigin) {
    for (const glm::vec3& offset : {glm::vec3(0.0f), glm::vec3(1e5f, -1e5f, 3e4f)}) {
        std::mt19937 rng(29);
        SyntheticOptions options = gather_scene();
        options.origin = glm::vec3(1e5f, 1e5f, -1e5f);
        options.offset = offset;
        const ViewSamples vs = synthetic_view_samples(options, rng);
        const PhotonMap map = synthetic_photons(vs, 2000, 0.4f, rng);
        for (float radius : {0.02f, 0.3f}) {
            SCOPED_TRACE("offset " + std::to_string(offset.x) + " radius " + std::to_string(radius));
            const Comparison o = check_against_brute(vs, map, splat_params(radius, map));
            print("far, offset " + std::to_string(offset.x) + " r " + std::to_string(radius), o);
            EXPECT_GT(counter(o.brute, "contributing_pairs"), 0.0);
        }
    }
}

// A radius so small against the photons' extent that the grid would need more than 2^21 cells per axis: the
// cell size is raised there, nothing overflows, and photons coincident with samples are still found.
TEST(GatherSplat, TinyRadiusAgainstAHugeExtent) {
    std::mt19937 rng(31);
    SyntheticOptions options = gather_scene();
    options.max_depth = 500.0f;
    const ViewSamples vs = synthetic_view_samples(options, rng);
    PhotonMap map = synthetic_photons(vs, 1500, 50.0f, rng);
    for (size_t i = 0; i < vs.samples.size(); i += 5) {  // some exactly on samples
        Photon p = map.photons[i % map.photons.size()];
        p.position = vs.origin + vs.samples[i].position;
        p.normal = vs.samples[i].normal;
        p.wi = vs.samples[i].normal;
        map.photons.push_back(p);
    }
    map.photons.push_back(map.photons[0]);
    map.photons.back().position = glm::vec3(-1e6f, 2e6f, 1e6f);  // stretches the extent to ~3e6
    for (float radius : {1e-7f, 1e-18f}) {  // (r² must stay above float underflow, or nothing passes)
        SCOPED_TRACE("radius " + std::to_string(radius));
        const Comparison o = check_against_brute(vs, map, splat_params(radius, map));
        EXPECT_GT(counter(o.brute, "contributing_pairs"), 0.0);
        EXPECT_EQ(o.identical, o.samples);
    }
}

TEST(GatherSplat, ManyPhotonsAtOnePoint) {
    std::mt19937 rng(43);
    const ViewSamples vs = synthetic_view_samples(gather_scene(), rng);
    PhotonMap map = synthetic_photons(vs, 2000, 0.0f, rng);
    for (Photon& p : map.photons) p.position = map.photons[0].position;
    for (float radius : {1e-3f, 0.3f}) {
        const Comparison o = check_against_brute(vs, map, splat_params(radius, map));
        EXPECT_EQ(counter(o.method, "grid_cells"), 1.0);
        if (radius == 0.3f) EXPECT_GT(counter(o.brute, "contributing_pairs"), 0.0);
    }
    // And many at one point among others: a crowded cell next to sparse ones.
    PhotonMap mixed = synthetic_photons(vs, 2000, 0.5f, rng);
    for (size_t i = 0; i < mixed.photons.size(); i += 2) mixed.photons[i].position = mixed.photons[1].position;
    check_against_brute(vs, mixed, splat_params(0.3f, mixed));
}

// Photons and samples with NaN or infinite positions can pass no test; they must not break the grid.
TEST(GatherSplat, NonFinitePositions) {
    std::mt19937 rng(47);
    ViewSamples vs = synthetic_view_samples(gather_scene(), rng);
    PhotonMap map = synthetic_photons(vs, 2000, 0.5f, rng);
    map.photons[3].position = glm::vec3(NAN, 0.0f, 0.0f);
    map.photons[10].position = glm::vec3(0.0f, INFINITY, 0.0f);
    map.photons[11].position = glm::vec3(0.0f, 0.0f, -INFINITY);
    vs.samples[5].position = glm::vec3(NAN);
    vs.samples[6].position = glm::vec3(INFINITY, 0.0f, 0.0f);
    check_against_brute(vs, map, splat_params(0.3f, map));
}

// Candidate lists longer than a cancel-check block (64 Ki photons) and made of many cells: the blocks of one
// sample and the merge of many long runs must keep the ascending order.
TEST(GatherSplat, LongCandidateListsFromManyCells) {
    std::mt19937 rng(53);
    SyntheticOptions options = sized(16, 12);
    options.planes = 1;
    options.min_depth = options.max_depth = 2.0f;
    options.specular_fraction = 0.0;
    const ViewSamples vs = synthetic_view_samples(options, rng);
    const PhotonMap map = synthetic_photons(vs, 100000, 0.3f, rng);
    const Comparison o = check_against_brute(vs, map, splat_params(0.9f, map));
    EXPECT_GT(counter(o.method, "grid_cells"), 8.0);
    // The middle sample alone tests more photons than a block holds.
    ViewSamples middle = vs;
    const uint32_t centre = uint32_t(options.height / 2 * options.width + options.width / 2);
    const auto it = std::lower_bound(vs.samples.begin(), vs.samples.end(), centre,
                                     [](const ViewSample& s, uint32_t pixel) { return s.pixel < pixel; });
    ASSERT_NE(it, vs.samples.end());
    middle.samples.assign(1, *it);
    RenderControl control;
    Stats stats;
    splat_gather(middle, map, splat_params(0.9f, map), control, stats);
    EXPECT_GT(counter(stats, "photon_sample_tests"), 65536.0);
    EXPECT_EQ(o.identical, o.samples);
    print("long lists", o);
}

// Samples in a random order: the list a thread kept from its previous sample rarely fits the next one, and the
// result must not depend on which list a thread held before.
TEST(GatherSplat, SamplesInRandomOrder) {
    std::mt19937 rng(57);
    ViewSamples vs = synthetic_view_samples(gather_scene(), rng);
    std::shuffle(vs.samples.begin(), vs.samples.end(), rng);
    const PhotonMap map = synthetic_photons(vs, 3000, 0.5f, rng);
    const Comparison o = check_against_brute(vs, map, splat_params(0.2f, map));
    EXPECT_GT(counter(o.method, "gather_lists"), 0.5 * double(vs.samples.size()));
    EXPECT_EQ(o.identical, o.samples);
}

TEST(GatherSplat, ReportsCountersBytesAndStageTimes) {
    std::mt19937 rng(61);
    const ViewSamples vs = synthetic_view_samples(gather_scene(), rng);
    const PhotonMap map = synthetic_photons(vs, 3000, 0.5f, rng);
    const Comparison o = check_against_brute(vs, map, splat_params(0.1f, map));
    const Stats& s = o.method;
    EXPECT_GT(counter(s, "grid_cells"), 1.0);
    EXPECT_LE(counter(s, "grid_cells"), double(map.photons.size()));
    EXPECT_GT(counter(s, "cell_visits"), double(vs.samples.size()));
    EXPECT_GT(counter(s, "contributing_pairs"), 0.0);
    EXPECT_GE(s.bytes.at("photon_grid"), double(map.photons.size() * sizeof(Photon)));
    EXPECT_GE(counter(s, "gather_lists"), 1.0);
    EXPECT_LE(counter(s, "gather_lists"), double(vs.samples.size()));
    EXPECT_GT(s.bytes.at("gather_lists"), 0.0);
    EXPECT_EQ(s.seconds.count("splat_build_grid"), 1u);
    EXPECT_EQ(s.seconds.count("splat_shade"), 1u);
    // The point of the grid: far fewer tests than the oracle at a typical radius.
    EXPECT_LT(counter(s, "photon_sample_tests"), 0.05 * counter(o.brute, "photon_sample_tests"));
    print("counters, r 0.1", o);
}

// The view samples of the Cornell box (cornell_scene) at width × height, and `photons` photon paths traced
// with `seed`.
struct CornellStages {
    ViewSamples samples;
    PhotonMap map;
};

CornellStages cornell_stages(int width, int height, uint64_t photons, uint64_t seed) {
    RenderControl control;
    Stats stats;
    CornellStages stages;
    const Camera camera = cornell_camera(width, height);
    stages.samples = generate_view_samples(cornell_scene(), camera, ViewSampleSettings{}, control, stats);
    PhotonSettings settings;
    settings.count = photons;
    settings.seed = seed;
    stages.map = trace_photons(cornell_scene(), settings, control, stats);
    return stages;
}

// The Cornell box (with its glass and mirror spheres) through the real stages: view samples, photon tracing,
// then gather against brute on the same photons, some samples seen through glass or the mirror.
TEST(GatherSplat, CornellBoxStagesIncludingSamplesBehindGlass) {
    const Scene& scene = cornell_scene();
    const CornellStages stages = cornell_stages(56, 56, 15000, 11);
    const ViewSamples& vs = stages.samples;
    const PhotonMap& map = stages.map;
    size_t via_specular = 0;
    for (const ViewSample& s : vs.samples) via_specular += (s.flags & kViaSpecular) ? 1 : 0;
    ASSERT_GT(via_specular, 20u) << "the comparison must cover samples behind glass and in the mirror";
    const float radius = default_radius(scene, 15000);
    for (Kernel kernel : {Kernel::uniform, Kernel::epanechnikov}) {
        SplatParams params = splat_params(radius, map, kernel);
        params.emitted = map.emitted;
        params.cos_normal_tolerance = 0.5f;
        const Comparison o = check_against_brute(vs, map, params);
        print(std::string("Cornell box stages, ") + to_string(kernel), o);
        EXPECT_GT(counter(o.brute, "contributing_pairs"), 1000.0);
        EXPECT_EQ(o.identical, o.samples);
    }
}

// Not a test: gather against cluster at 1920×1080 on the Cornell box with 200k photons, same photons, same run.
//   photonsplat_tests --gtest_also_run_disabled_tests --gtest_filter='GatherBenchmark.*'
// PS_BENCH_PHOTONS, PS_BENCH_RADIUS_SCALE and PS_BENCH_REPEATS change the photon count, the radius (× the
// default radius) and the repeats (the median is printed); PS_BENCH_SKIP_CLUSTER times gather alone. Wall
// time and CPU time (all threads) are both printed: on a shared machine the CPU time is the steadier figure.
TEST(GatherBenchmark, DISABLED_GatherVersusClusterAt1080p) {
    auto env = [](const char* name, double fallback) {
        const char* v = std::getenv(name);
        return v ? std::atof(v) : fallback;
    };
    const uint64_t photon_count = uint64_t(env("PS_BENCH_PHOTONS", 200000));
    const int repeats = int(env("PS_BENCH_REPEATS", 3));
    const Scene& scene = cornell_scene();
    const CornellStages stages = cornell_stages(1920, 1080, photon_count, 1);
    const ViewSamples& vs = stages.samples;
    const PhotonMap& map = stages.map;
    RenderControl control;
    SplatParams params;
    params.radius = float(default_radius(scene, photon_count) * env("PS_BENCH_RADIUS_SCALE", 1.0));
    params.emitted = map.emitted;
    params.cos_normal_tolerance = std::cos(60.0f * 3.14159265f / 180.0f);
    std::printf("1080p Cornell box: %zu samples, %zu photons stored of %llu emitted, radius %g, %d threads\n",
                vs.samples.size(), map.photons.size(), (unsigned long long)map.emitted, params.radius,
                tbb::this_task_arena::max_concurrency());
    auto seconds_since = [](std::chrono::steady_clock::time_point t) {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    };
    auto median = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return v[v.size() / 2];
    };
    const bool skip_cluster = std::getenv("PS_BENCH_SKIP_CLUSTER") != nullptr;
    std::vector<double> cluster_times, gather_times, cluster_cpu, gather_cpu;
    std::vector<glm::vec3> cluster_out, gather_out;
    Stats cluster_stats, gather_stats;
    for (int k = 0; k < repeats; ++k) {
        if (!skip_cluster) {
            Stats stats;
            const auto t = std::chrono::steady_clock::now();
            const std::clock_t c = std::clock();
            const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, ClusterKeyParams::from_camera(cornell_camera(1920, 1080)));
            cluster_out = splat_cluster(hierarchy, vs, map, params, control, stats);
            cluster_times.push_back(seconds_since(t));
            cluster_cpu.push_back(double(std::clock() - c) / CLOCKS_PER_SEC);
            cluster_stats = stats;
        }
        {
            Stats stats;
            const auto t = std::chrono::steady_clock::now();
            const std::clock_t c = std::clock();
            gather_out = splat_gather(vs, map, params, control, stats);
            gather_times.push_back(seconds_since(t));
            gather_cpu.push_back(double(std::clock() - c) / CLOCKS_PER_SEC);
            gather_stats = stats;
        }
    }
    if (skip_cluster) {
        std::printf("gather (grid + shade): median %.3f s wall, %.3f s cpu\n", median(gather_times),
                    median(gather_cpu));
        return;
    }
    size_t identical = 0, within = 0;
    for (size_t i = 0; i < vs.samples.size(); ++i) {
        identical += cluster_out[i] == gather_out[i];
        bool ok = true;
        for (int ch = 0; ch < 3; ++ch)
            ok = ok && std::fabs(cluster_out[i][ch] - gather_out[i][ch]) <=
                           1e-4f * std::max(std::fabs(cluster_out[i][ch]), std::fabs(gather_out[i][ch]));
        within += ok;
    }
    const double tc = median(cluster_times), tg = median(gather_times);
    std::printf("cluster (hierarchy + splat): median %.3f s   gather (grid + shade): median %.3f s   ratio %.2f\n",
                tc, tg, tg / tc);
    std::printf("cpu time (all threads): cluster median %.3f s   gather median %.3f s   ratio %.2f\n",
                median(cluster_cpu), median(gather_cpu), median(gather_cpu) / median(cluster_cpu));
    for (const auto& [name, s] : gather_stats.seconds) std::printf("  gather  %-22s %.3f s\n", name.c_str(), s);
    for (const auto& [name, s] : cluster_stats.seconds) std::printf("  cluster %-22s %.3f s\n", name.c_str(), s);
    for (const char* name : {"photon_sample_tests", "contributing_pairs", "grid_cells", "cell_visits", "gather_lists"})
        std::printf("  gather  %-22s %.0f\n", name, counter(gather_stats, name));
    for (const char* name : {"photon_sample_tests", "contributing_pairs", "photon_node_tests"})
        std::printf("  cluster %-22s %.0f\n", name, counter(cluster_stats, name));
    std::printf("  gather bytes photon_grid %.1f MB, gather_lists %.2f MB; cluster leaf_photon_lists %.1f MB\n",
                gather_stats.bytes["photon_grid"] / 1e6, gather_stats.bytes["gather_lists"] / 1e6,
                cluster_stats.bytes["leaf_photon_lists"] / 1e6);
    std::printf("  gather vs cluster: %zu of %zu samples bit-identical, %zu within 1e-4\n", identical,
                vs.samples.size(), within);
    EXPECT_EQ(within, vs.samples.size());
}

}  // namespace
}  // namespace ps
