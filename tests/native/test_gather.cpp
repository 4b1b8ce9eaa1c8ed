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
#include "test_scenes.h"

namespace ps {
namespace {

constexpr float kTanHalfFov = 0.57735027f;  // 60° vertical field of view

glm::vec3 unit_vector(std::mt19937& rng) {
    std::normal_distribution<float> g;
    for (;;) {
        const glm::vec3 v(g(rng), g(rng), g(rng));
        const float len = glm::length(v);
        if (len > 1e-3f) return v / len;
    }
}

struct Synthetic {
    int width = 40, height = 32;
    double coverage = 0.95;          // fraction of pixels with a sample
    double specular_fraction = 0.1;  // samples "seen through a mirror": moved to random places
    int planes = 4;
    float min_depth = 1.0f, max_depth = 20.0f;
    glm::vec3 origin{250.0f, -40.0f, 12.0f};  // world position of the camera
    glm::vec3 offset{0.0f};                   // added to every sample's relative position
};

// A pinhole camera looking down −z at randomly tilted planes: one sample per covered pixel on the nearest plane.
ViewSamples make_samples(const Synthetic& o, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    ViewSamples vs;
    vs.width = o.width;
    vs.height = o.height;
    vs.origin = o.origin;
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
            s.position = dir * t_best + o.offset;
            s.normal = s.shading_normal = glm::dot(n_best, dir) < 0.0f ? n_best : -n_best;
            s.wo = -glm::normalize(dir);
            s.albedo = glm::vec3(u(rng), u(rng), u(rng));
            s.throughput = glm::vec3(1.0f);
            s.pixel = uint32_t(y * o.width + x);
            s.depth = t_best;
            if (u(rng) < o.specular_fraction) {
                s.flags = kViaSpecular;
                s.position = glm::vec3(u(rng) * 8.0f - 4.0f, u(rng) * 8.0f - 4.0f, -2.0f - u(rng) * 10.0f) + o.offset;
                s.normal = s.shading_normal = unit_vector(rng);
                s.throughput = glm::vec3(0.2f + u(rng), 0.2f + u(rng), 0.2f + u(rng));
            }
            vs.samples.push_back(s);
        }
    return vs;
}

// Photons around random samples (within `spread`), mostly on the sample's side and orientation, sometimes not.
PhotonMap make_photons(const ViewSamples& vs, size_t count, float spread, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    PhotonMap map;
    map.emitted = count * 3 + 1;
    for (size_t i = 0; i < count && !vs.samples.empty(); ++i) {
        const ViewSample& s = vs.samples[size_t(u(rng) * float(vs.samples.size())) % vs.samples.size()];
        Photon p{};
        p.position = vs.origin + s.position + unit_vector(rng) * (spread * u(rng));
        p.normal = u(rng) < 0.8f ? glm::normalize(s.normal + 0.3f * unit_vector(rng)) : unit_vector(rng);
        p.wi = unit_vector(rng);
        if (glm::dot(p.wi, p.normal) < 0.0f) p.wi = -p.wi;
        p.power = glm::vec3(0.5f + u(rng), 0.5f + u(rng), 0.5f + u(rng));
        p.flags = u(rng) < 0.1f ? kCaustic : 0u;
        map.photons.push_back(p);
    }
    return map;
}

SplatParams params_for(float radius, const PhotonMap& map, Kernel kernel = Kernel::uniform) {
    SplatParams params;
    params.radius = radius;
    params.emitted = std::max<uint64_t>(map.emitted, 1);
    params.kernel = kernel;
    return params;
}

double counter(const Stats& stats, const char* name) {
    const auto it = stats.counters.find(name);
    return it == stats.counters.end() ? -1.0 : it->second;
}

struct Outcome {
    size_t samples = 0, identical = 0;
    Stats brute, gather;
};

// Both methods on the same input; gather must equal brute to 1e-4 relative per sample and channel, with the
// same contributing pairs and never more per-sample tests.
Outcome check_against_brute(const ViewSamples& vs, const PhotonMap& map, const SplatParams& params) {
    Outcome o;
    RenderControl control;
    const std::vector<glm::vec3> expected = splat_brute(vs, map, params, control, o.brute);
    const std::vector<glm::vec3> actual = splat_gather(vs, map, params, control, o.gather);
    EXPECT_EQ(actual.size(), vs.samples.size());
    o.samples = std::min(expected.size(), actual.size());
    size_t failures = 0;
    for (size_t i = 0; i < o.samples; ++i) {
        bool same = true;
        for (int ch = 0; ch < 3; ++ch) {
            const float a = actual[i][ch], e = expected[i][ch];
            const bool ok = std::isfinite(a) && std::fabs(a - e) <= 1e-4f * std::max(std::fabs(a), std::fabs(e));
            if (!ok && ++failures <= 5)
                ADD_FAILURE() << "sample " << i << " channel " << ch << ": gather " << a << ", brute " << e;
            same = same && a == e;
        }
        o.identical += same ? 1 : 0;
    }
    EXPECT_EQ(failures, 0u);
    EXPECT_EQ(counter(o.gather, "contributing_pairs"), counter(o.brute, "contributing_pairs"));
    EXPECT_LE(counter(o.gather, "photon_sample_tests"), counter(o.brute, "photon_sample_tests"));
    return o;
}

void print(const std::string& what, const Outcome& o) {
    std::printf("%-34s %5zu samples, %5zu bit-identical, pairs %8.0f, tests brute %9.0f / gather %8.0f, "
                "cells %6.0f, cell visits %7.0f\n",
                what.c_str(), o.samples, o.identical, counter(o.brute, "contributing_pairs"),
                counter(o.brute, "photon_sample_tests"), counter(o.gather, "photon_sample_tests"),
                counter(o.gather, "grid_cells"), counter(o.gather, "cell_visits"));
}

TEST(GatherSplat, MatchesBruteOnRandomScenesAtEveryRadiusAndBothKernels) {
    size_t samples = 0, identical = 0;
    for (uint32_t seed = 1; seed <= 3; ++seed) {
        std::mt19937 rng(seed);
        const ViewSamples vs = make_samples(Synthetic{}, rng);
        const PhotonMap map = make_photons(vs, 2500, 0.5f, rng);
        for (Kernel kernel : {Kernel::uniform, Kernel::epanechnikov})
            for (float radius : {1e-3f, 0.05f, 0.3f, 1e3f}) {  // tiny … larger than the scene
                const std::string what = std::string(to_string(kernel)) + " radius " + std::to_string(radius);
                SCOPED_TRACE("seed " + std::to_string(seed) + " " + what);
                const Outcome o = check_against_brute(vs, map, params_for(radius, map, kernel));
                if (radius == 0.3f) EXPECT_GT(counter(o.brute, "contributing_pairs"), 1000.0);
                if (radius == 1e3f) EXPECT_EQ(counter(o.gather, "grid_cells"), 1.0);  // one cell: still exact
                if (seed == 1) print(what, o);
                samples += o.samples;
                identical += o.identical;
            }
    }
    std::printf("bit-identical: %zu of %zu samples\n", identical, samples);
    EXPECT_EQ(identical, samples) << "same photons in the same order as brute: bit-identical expected";
}

TEST(GatherSplat, MatchesBruteWithPlaneDistanceAndStrictNormals) {
    std::mt19937 rng(17);
    const ViewSamples vs = make_samples(Synthetic{}, rng);
    const PhotonMap map = make_photons(vs, 2000, 0.4f, rng);
    for (Kernel kernel : {Kernel::uniform, Kernel::epanechnikov}) {
        SplatParams params = params_for(0.25f, map, kernel);
        params.plane_distance_factor = 0.2f;
        params.cos_normal_tolerance = 0.9f;
        check_against_brute(vs, map, params);
    }
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
        ViewSample s{};
        s.depth = (x / 4) % 2 ? 2.5f : 5.0f;
        // Every other sample on a cell boundary (−10 + k·r), the rest half-way.
        s.position = glm::vec3(-5.0f + float(x) * 0.3125f, -5.0f + float(y) * 0.3125f, -s.depth);
        s.normal = s.shading_normal = s.wo = glm::vec3(0, 0, 1);
        s.albedo = glm::vec3(0.8f, 0.5f, 0.25f);
        s.throughput = glm::vec3(1.0f);
        s.pixel = pixel;
        vs.samples.push_back(s);
    }
    PhotonMap map;
    auto add = [&](const glm::vec3& position) {
        Photon p{};
        p.position = position;
        p.wi = glm::normalize(glm::vec3(0.1f, 0.2f, 1.0f));
        p.normal = glm::vec3(0, 0, 1);
        p.power = glm::vec3(1.0f + 0.001f * float(map.photons.size() % 7));
        map.photons.push_back(p);
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
        const Outcome o = check_against_brute(vs, map, params_for(r, map, kernel));
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
        Synthetic options;
        options.origin = glm::vec3(1e5f, 1e5f, -1e5f);
        options.offset = offset;
        const ViewSamples vs = make_samples(options, rng);
        const PhotonMap map = make_photons(vs, 2000, 0.4f, rng);
        for (float radius : {0.02f, 0.3f}) {
            SCOPED_TRACE("offset " + std::to_string(offset.x) + " radius " + std::to_string(radius));
            const Outcome o = check_against_brute(vs, map, params_for(radius, map));
            print("far, offset " + std::to_string(offset.x) + " r " + std::to_string(radius), o);
            EXPECT_GT(counter(o.brute, "contributing_pairs"), 0.0);
        }
    }
}

// A radius so small against the photons' extent that the grid would need more than 2^21 cells per axis: the
// cell size is raised there, nothing overflows, and photons coincident with samples are still found.
TEST(GatherSplat, TinyRadiusAgainstAHugeExtent) {
    std::mt19937 rng(31);
    Synthetic options;
    options.max_depth = 500.0f;
    const ViewSamples vs = make_samples(options, rng);
    PhotonMap map = make_photons(vs, 1500, 50.0f, rng);
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
        const Outcome o = check_against_brute(vs, map, params_for(radius, map));
        EXPECT_GT(counter(o.brute, "contributing_pairs"), 0.0);
        EXPECT_EQ(o.identical, o.samples);
    }
}

TEST(GatherSplat, ManyPhotonsAtOnePoint) {
    std::mt19937 rng(43);
    const ViewSamples vs = make_samples(Synthetic{}, rng);
    PhotonMap map = make_photons(vs, 2000, 0.0f, rng);
    for (Photon& p : map.photons) p.position = map.photons[0].position;
    for (float radius : {1e-3f, 0.3f}) {
        const Outcome o = check_against_brute(vs, map, params_for(radius, map));
        EXPECT_EQ(counter(o.gather, "grid_cells"), 1.0);
        if (radius == 0.3f) EXPECT_GT(counter(o.brute, "contributing_pairs"), 0.0);
    }
    // And many at one point among others: a crowded cell next to sparse ones.
    PhotonMap mixed = make_photons(vs, 2000, 0.5f, rng);
    for (size_t i = 0; i < mixed.photons.size(); i += 2) mixed.photons[i].position = mixed.photons[1].position;
    check_against_brute(vs, mixed, params_for(0.3f, mixed));
}

// Photons and samples with NaN or infinite positions can pass no test; they must not break the grid.
TEST(GatherSplat, NonFinitePositions) {
    std::mt19937 rng(47);
    ViewSamples vs = make_samples(Synthetic{}, rng);
    PhotonMap map = make_photons(vs, 2000, 0.5f, rng);
    map.photons[3].position = glm::vec3(NAN, 0.0f, 0.0f);
    map.photons[10].position = glm::vec3(0.0f, INFINITY, 0.0f);
    map.photons[11].position = glm::vec3(0.0f, 0.0f, -INFINITY);
    vs.samples[5].position = glm::vec3(NAN);
    vs.samples[6].position = glm::vec3(INFINITY, 0.0f, 0.0f);
    check_against_brute(vs, map, params_for(0.3f, map));
}

// Candidate lists longer than a cancel-check block (64 Ki photons) and made of many cells: the blocks of one
// sample and the merge of many long runs must keep the ascending order.
TEST(GatherSplat, LongCandidateListsFromManyCells) {
    std::mt19937 rng(53);
    Synthetic options;
    options.width = 16;
    options.height = 12;
    options.planes = 1;
    options.min_depth = options.max_depth = 2.0f;
    options.specular_fraction = 0.0;
    const ViewSamples vs = make_samples(options, rng);
    const PhotonMap map = make_photons(vs, 100000, 0.3f, rng);
    const Outcome o = check_against_brute(vs, map, params_for(0.9f, map));
    EXPECT_GT(counter(o.gather, "grid_cells"), 8.0);
    // The middle sample alone tests more photons than a block holds.
    ViewSamples middle = vs;
    const uint32_t centre = uint32_t(options.height / 2 * options.width + options.width / 2);
    const auto it = std::lower_bound(vs.samples.begin(), vs.samples.end(), centre,
                                     [](const ViewSample& s, uint32_t pixel) { return s.pixel < pixel; });
    ASSERT_NE(it, vs.samples.end());
    middle.samples.assign(1, *it);
    RenderControl control;
    Stats stats;
    splat_gather(middle, map, params_for(0.9f, map), control, stats);
    EXPECT_GT(counter(stats, "photon_sample_tests"), 65536.0);
    EXPECT_EQ(o.identical, o.samples);
    print("long lists", o);
}

// Samples in a random order: the list a thread kept from its previous sample rarely fits the next one, and the
// result must not depend on which list a thread held before.
TEST(GatherSplat, SamplesInRandomOrder) {
    std::mt19937 rng(57);
    ViewSamples vs = make_samples(Synthetic{}, rng);
    std::shuffle(vs.samples.begin(), vs.samples.end(), rng);
    const PhotonMap map = make_photons(vs, 3000, 0.5f, rng);
    const Outcome o = check_against_brute(vs, map, params_for(0.2f, map));
    EXPECT_GT(counter(o.gather, "gather_lists"), 0.5 * double(vs.samples.size()));
    EXPECT_EQ(o.identical, o.samples);
}

TEST(GatherSplat, ZeroPhotonsAndZeroSamples) {
    std::mt19937 rng(3);
    const ViewSamples vs = make_samples(Synthetic{}, rng);
    PhotonMap none;  // emitted 0 too: fine when nothing was stored
    RenderControl control;
    Stats stats;
    const std::vector<glm::vec3> out = splat_gather(vs, none, params_for(0.3f, none), control, stats);
    ASSERT_EQ(out.size(), vs.samples.size());
    for (const glm::vec3& v : out) EXPECT_EQ(v, glm::vec3(0.0f));
    EXPECT_EQ(counter(stats, "contributing_pairs"), 0.0);
    EXPECT_EQ(counter(stats, "grid_cells"), 0.0);

    ViewSamples empty;
    empty.width = empty.height = 4;
    const PhotonMap map = make_photons(vs, 100, 0.1f, rng);
    EXPECT_TRUE(splat_gather(empty, map, params_for(0.3f, map), control, stats).empty());
}

TEST(GatherSplat, SameOutputAndCountersWithOneTwoAndEightThreads) {
    tbb::global_control allow(tbb::global_control::max_allowed_parallelism, 8);
    std::mt19937 rng(59);
    Synthetic options;
    options.width = 96;
    options.height = 80;
    const ViewSamples vs = make_samples(options, rng);
    const PhotonMap map = make_photons(vs, 5000, 0.5f, rng);
    for (Kernel kernel : {Kernel::uniform, Kernel::epanechnikov}) {
        const SplatParams params = params_for(0.3f, map, kernel);
        auto run = [&](int threads, Stats& stats) {
            std::vector<glm::vec3> out;
            RenderControl control;
            tbb::task_arena(threads).execute([&] { out = splat_gather(vs, map, params, control, stats); });
            return out;
        };
        Stats one, two, eight;
        const std::vector<glm::vec3> expected = run(1, one);
        EXPECT_TRUE(run(2, two) == expected);
        EXPECT_TRUE(run(8, eight) == expected);
        for (const char* name : {"photon_sample_tests", "contributing_pairs", "grid_cells", "cell_visits"}) {
            EXPECT_EQ(counter(two, name), counter(one, name)) << name;
            EXPECT_EQ(counter(eight, name), counter(one, name)) << name;
        }
    }
}

TEST(GatherSplat, ReportsCountersBytesAndStageTimes) {
    std::mt19937 rng(61);
    const ViewSamples vs = make_samples(Synthetic{}, rng);
    const PhotonMap map = make_photons(vs, 3000, 0.5f, rng);
    const Outcome o = check_against_brute(vs, map, params_for(0.1f, map));
    const Stats& s = o.gather;
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

TEST(GatherSplat, CancelledBeforeStartThrows) {
    std::mt19937 rng(67);
    const ViewSamples vs = make_samples(Synthetic{}, rng);
    const PhotonMap map = make_photons(vs, 500, 0.5f, rng);
    RenderControl control;
    control.request_cancel();
    Stats stats;
    EXPECT_THROW(splat_gather(vs, map, params_for(0.3f, map), control, stats), Cancelled);
}

// A radius larger than the scene makes every sample scan every photon (minutes at this size): a cancel must
// still stop it within a fraction of a second.
TEST(GatherSplat, StopsPromptlyWhenCancelledMidway) {
    std::mt19937 rng(71);
    Synthetic options;
    options.width = 160;
    options.height = 120;
    const ViewSamples vs = make_samples(options, rng);
    const PhotonMap map = make_photons(vs, 200000, 0.5f, rng);
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
    EXPECT_THROW(splat_gather(vs, map, params_for(1e3f, map), control, stats), Cancelled);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    canceller.join();
    EXPECT_LT(seconds, 0.5);
}

TEST(GatherSplat, RefusesBadInput) {
    std::mt19937 rng(73);
    const ViewSamples vs = make_samples(Synthetic{}, rng);
    const PhotonMap map = make_photons(vs, 100, 0.5f, rng);
    RenderControl control;
    Stats stats;
    for (float radius : {0.0f, -1.0f, NAN, INFINITY})
        EXPECT_THROW(splat_gather(vs, map, params_for(radius, map), control, stats), InvalidInput);
    SplatParams no_emitted = params_for(0.3f, map);
    no_emitted.emitted = 0;
    EXPECT_THROW(splat_gather(vs, map, no_emitted, control, stats), InvalidInput);
    EXPECT_EQ(splat_method_from_string("gather"), SplatMethod::gather);
}

// The Cornell box (with its glass and mirror spheres) through the real stages: view samples, photon tracing,
// then gather against brute on the same photons, some samples seen through glass or the mirror.
TEST(GatherSplat, CornellBoxStagesIncludingSamplesBehindGlass) {
    Scene scene;
    test::build_cornell_box(scene, true);
    const Camera camera = test::cornell_camera(56, 56);
    RenderControl control;
    Stats stats;
    const ViewSamples vs = generate_view_samples(scene, camera, ViewSampleSettings{}, control, stats);
    PhotonSettings photon_settings;
    photon_settings.count = 15000;
    photon_settings.seed = 11;
    const PhotonMap map = trace_photons(scene, photon_settings, control, stats);
    size_t via_specular = 0;
    for (const ViewSample& s : vs.samples) via_specular += (s.flags & kViaSpecular) ? 1 : 0;
    ASSERT_GT(via_specular, 20u) << "the comparison must cover samples behind glass and in the mirror";
    const float radius = default_radius(scene, photon_settings.count);
    for (Kernel kernel : {Kernel::uniform, Kernel::epanechnikov}) {
        SplatParams params = params_for(radius, map, kernel);
        params.emitted = map.emitted;
        params.cos_normal_tolerance = 0.5f;
        const Outcome o = check_against_brute(vs, map, params);
        print(std::string("Cornell box stages, ") + to_string(kernel), o);
        EXPECT_GT(counter(o.brute, "contributing_pairs"), 1000.0);
        EXPECT_EQ(o.identical, o.samples);
    }
}

// And through render(): the method setting reaches the gather splat, and the image equals brute's.
TEST(GatherSplat, CornellBoxRenderEqualsBrute) {
    static Scene* scene = [] {
        auto* s = new Scene;
        test::build_cornell_box(*s, true);
        return s;
    }();
    auto render_with = [&](SplatMethod method) {
        RenderSettings settings;
        settings.photons = 8000;
        settings.method = method;
        settings.seed = 7;
        settings.kernel = Kernel::epanechnikov;
        RenderControl control;
        return render(*scene, test::cornell_camera(40, 40), settings, control);
    };
    const RenderResult brute = render_with(SplatMethod::brute);
    const RenderResult gather = render_with(SplatMethod::gather);
    ASSERT_EQ(brute.film[ps::FilmOutput::indirect].size(), gather.film[ps::FilmOutput::indirect].size());
    double sum = 0.0;
    for (size_t i = 0; i < brute.film[ps::FilmOutput::indirect].size(); ++i) {
        const float b = brute.film[ps::FilmOutput::indirect][i], g = gather.film[ps::FilmOutput::indirect][i];
        EXPECT_LE(std::fabs(b - g), 1e-4f * std::max(std::fabs(b), 1e-6f)) << "component " << i;
        sum += b;
    }
    EXPECT_GT(sum, 0.0);
    EXPECT_EQ(gather.stats.counters.at("contributing_pairs"), brute.stats.counters.at("contributing_pairs"));
    EXPECT_GT(gather.stats.counters.at("grid_cells"), 0.0);
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
    Scene scene;
    test::build_cornell_box(scene, true);
    const Camera camera = test::cornell_camera(1920, 1080);
    RenderControl control;
    Stats setup;
    const ViewSamples vs = generate_view_samples(scene, camera, ViewSampleSettings{}, control, setup);
    PhotonSettings photon_settings;
    photon_settings.count = photon_count;
    photon_settings.seed = 1;
    const PhotonMap map = trace_photons(scene, photon_settings, control, setup);
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
            const ClusterHierarchy hierarchy = build_cluster_hierarchy(vs, ClusterKeyParams::from_camera(camera));
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
