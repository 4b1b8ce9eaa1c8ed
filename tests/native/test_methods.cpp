// What every splatting method must do, one suite instantiated per method (test_support.h lists them):
// the exact methods equal the brute-force oracle (random scenes at radii from tiny to larger than the scene, both
// kernels, the plane-distance test, and whole renders of the Cornell box) and stop promptly when cancelled
// mid-way; every method gives the same bits for any thread count, handles zero photons and zero samples,
// refuses bad parameters and throws Cancelled when cancelled before it starts. What is particular to one method
// stays in its own file (test_splat.cpp, test_tiled.cpp, test_cones.cpp, test_gather.cpp, test_directional.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "photonsplat/errors.h"
#include "photonsplat/render.h"
#include "test_support.h"

namespace ps::test {
namespace {

// ---- the exact methods against brute ------------------------------------------------------------------------

class ExactMethod : public ::testing::TestWithParam<SplatMethod> {};

// Brute's result on one random scene, computed once for all the methods compared with it.
const std::vector<glm::vec3>& brute_on_random_scene(uint32_t seed, Kernel kernel, float radius) {
    static std::map<std::tuple<uint32_t, Kernel, float>, std::vector<glm::vec3>> cache;
    auto& out = cache[{seed, kernel, radius}];
    if (out.empty()) {
        std::mt19937 rng(seed);
        const ViewSamples vs = synthetic_view_samples(SyntheticOptions{}, rng);
        const PhotonMap map = synthetic_photons(vs, 3000, 0.5f, rng);
        RenderControl control;
        Stats stats;
        out = splat_brute(vs, map, splat_params(radius, map, kernel), control, stats);
    }
    return out;
}

// Half the samples hold reflection lobes beyond Lambert's: a GGX lobe and one more closure each, every kind in turn
// (Beckmann, anisotropic GGX, multiscatter GGX, clearcoat, sheen, velvet, Oren–Nayar, principled diffuse, principled
// Fresnel; test_support.h's add_random_lobes): the BRDF each photon meets is its own direction's in every method.
TEST_P(ExactMethod, MatchesBruteWithEveryReflectionClosure) {
    const SplatMethod method = GetParam();
    SyntheticOptions o;
    o.glossy_fraction = 0.5;
    for (uint32_t seed = 4; seed <= 5; ++seed) {
        const SyntheticSplat in = synthetic_splat(method, seed, 3000, 0.5f, o);
        size_t with_lobes = 0;
        for (const ViewSample& s : in.frame.samples.samples) with_lobes += (s.flags & kGlossy) ? 1 : 0;
        ASSERT_GT(with_lobes, in.frame.samples.samples.size() / 3);
        for (Kernel kernel : {Kernel::uniform, Kernel::epanechnikov})
            for (float radius : {0.05f, 0.3f, 1.5f}) {
                SCOPED_TRACE("seed " + std::to_string(seed) + " " + to_string(kernel) + " radius " + std::to_string(radius));
                const Comparison c = compare_with_brute(method, in.frame.input(), in.map, splat_params(radius, in.map, kernel));
                if (radius == 0.3f) EXPECT_GT(counter(c.brute, "contributing_pairs"), 1000.0);
            }
    }
}

TEST_P(ExactMethod, MatchesBruteOnRandomScenesAtEveryRadiusAndBothKernels) {
    const SplatMethod method = GetParam();
    size_t samples = 0, identical = 0;
    double accepts = 0.0, facing = 0.0, orientation = 0.0;
    for (uint32_t seed = 1; seed <= 3; ++seed) {
        const SyntheticSplat in = synthetic_splat(method, seed, 3000, 0.5f);
        const MethodFrame& frame = in.frame;
        const PhotonMap& map = in.map;
        for (Kernel kernel : {Kernel::uniform, Kernel::epanechnikov})
            for (float radius : {1e-3f, 0.05f, 0.3f, 1.5f, 1e3f}) {  // tiny … larger than the scene
                const std::string what = "seed " + std::to_string(seed) + " " + to_string(kernel) + " radius " +
                                         std::to_string(radius);
                SCOPED_TRACE(what);
                const Comparison c = compare_with_brute(method, frame.input(), map, splat_params(radius, map, kernel));
                EXPECT_TRUE(c.expected == brute_on_random_scene(seed, kernel, radius)) << "brute is deterministic";
                if (radius == 0.3f) EXPECT_GT(counter(c.brute, "contributing_pairs"), 1000.0);
                if (method == SplatMethod::gather && radius == 1e3f)
                    EXPECT_EQ(counter(c.method, "grid_cells"), 1.0);  // one cell: still exact
                if (seed == 1 && kernel == Kernel::uniform)
                    std::printf("%-12s %-28s %6zu samples, %6zu bit-identical, contributing pairs %.0f, sample "
                                "tests brute %.0f / %s %.0f\n",
                                to_string(method), what.c_str(), c.samples, c.identical,
                                counter(c.brute, "contributing_pairs"), counter(c.brute, "photon_sample_tests"),
                                to_string(method), counter(c.method, "photon_sample_tests"));
                samples += c.samples;
                identical += c.identical;
                accepts += counter(c.method, "node_accepts");
                facing += counter(c.method, "node_rejects_cone_facing");
                orientation += counter(c.method, "node_rejects_cone_orientation");
            }
    }
    RecordProperty("bit_identical_fraction", std::to_string(double(identical) / double(samples)));
    std::printf("%s bit-identical: %zu of %zu samples\n", to_string(method), identical, samples);
    // Gather and brute visit the same photons in the same order for each sample.
    if (method == SplatMethod::gather || method == SplatMethod::brute) EXPECT_EQ(identical, samples);
    if (method == SplatMethod::cluster_cone) {  // not vacuous: the cone tests fire often
        EXPECT_GT(accepts, 1000.0);
        EXPECT_GT(facing, 1000.0);
        EXPECT_GT(orientation, 1000.0);
    }
}

TEST_P(ExactMethod, MatchesBruteWithPlaneDistanceAndStrictNormals) {
    const SplatMethod method = GetParam();
    const SyntheticSplat in = synthetic_splat(method, 17, 2000, 0.4f);
    for (Kernel kernel : {Kernel::uniform, Kernel::epanechnikov}) {
        SplatParams params = splat_params(0.25f, in.map, kernel);
        params.plane_distance_factor = 0.2f;
        params.cos_normal_tolerance = 0.9f;
        const Comparison c = compare_with_brute(method, in.frame.input(), in.map, params, to_string(kernel));
        EXPECT_GT(counter(c.brute, "contributing_pairs"), 0.0);
    }
}

// The brute render of the Cornell box, made once for all the methods compared with it.
RenderResult render_cornell(SplatMethod method, Kernel kernel, int threads) {
    RenderSettings settings = method_settings(method, 5000, 7);
    settings.kernel = kernel;
    settings.threads = threads;
    return render_cornell_box(settings, 40, 36);
}

const RenderResult& brute_render(Kernel kernel) {
    static std::map<Kernel, RenderResult> cache;
    auto it = cache.find(kernel);
    if (it == cache.end()) it = cache.emplace(kernel, render_cornell(SplatMethod::brute, kernel, 0)).first;
    return it->second;
}

// The whole pipeline (render) with the method gives the oracle's image, whatever the thread count: the method
// setting reaches the splat, and the method reports its own counters, bytes and stage times.
TEST_P(ExactMethod, RenderOfTheCornellBoxEqualsBrute) {
    const SplatMethod method = GetParam();
    for (Kernel kernel : {Kernel::uniform, Kernel::epanechnikov}) {
        SCOPED_TRACE(to_string(kernel));
        const RenderResult& brute = brute_render(kernel);
        const RenderResult one = render_cornell(method, kernel, 1);
        ASSERT_EQ(brute.film[ps::FilmOutput::indirect].size(), one.film[ps::FilmOutput::indirect].size());
        double sum = 0.0;
        for (size_t i = 0; i < brute.film[ps::FilmOutput::indirect].size(); ++i) {
            EXPECT_LE(std::fabs(brute.film[ps::FilmOutput::indirect][i] - one.film[ps::FilmOutput::indirect][i]), 1e-4f * std::fabs(brute.film[ps::FilmOutput::indirect][i]))
                << "component " << i;
            sum += brute.film[ps::FilmOutput::indirect][i];
        }
        EXPECT_GT(sum, 0.0);
        EXPECT_EQ(one.stats.counters.at("contributing_pairs"), brute.stats.counters.at("contributing_pairs"));
        EXPECT_EQ(render_cornell(method, kernel, 2).rgba(), one.rgba()) << "1 and 2 threads";
        switch (method) {
            case SplatMethod::tiled:
                EXPECT_GT(one.stats.seconds.count("splat_binning"), 0u);
                EXPECT_GT(one.stats.bytes.count("tile_bounds"), 0u);
                break;
            case SplatMethod::cluster_cone:
                EXPECT_GT(one.stats.counters.at("node_accepts"), 0.0);
                EXPECT_GT(one.stats.bytes.at("cones"), 0.0);
                break;
            case SplatMethod::gather: EXPECT_GT(one.stats.counters.at("grid_cells"), 0.0); break;
            case SplatMethod::cluster: EXPECT_GT(one.stats.counters.at("leaf_photon_pairs"), 0.0); break;
            default: break;
        }
    }
}

// Every photon in reach of every sample, many photons (minutes of work): a cancel must still stop the splat
// within a fraction of a second. A small pair cap makes the batched methods cut the work in many batches.
TEST_P(ExactMethod, StopsPromptlyWhenCancelledMidway) {
    const SplatMethod method = GetParam();
    const SyntheticSplat in = synthetic_splat(method, 71, 200000, 0.5f, sized(160, 120));
    const MethodFrame& frame = in.frame;
    const PhotonMap& map = in.map;
    SplatParams params = splat_params(1e3f, map);
    params.max_pairs_in_memory = 4000;
    RenderControl control;
    Stats stats;
    const double seconds = seconds_until_cancelled(control, std::chrono::milliseconds(30), [&] {
        run_splat(method, frame.input(), map, params, control, stats);
    });
    EXPECT_LT(seconds, 0.5);
}

INSTANTIATE_TEST_SUITE_P(ExactMethods, ExactMethod, ::testing::ValuesIn(exact_methods()), method_name);

// ---- every method -------------------------------------------------------------------------------------------

class AnyMethod : public ::testing::TestWithParam<SplatMethod> {};

// Counters that depend on how the work fell to threads: lists a thread kept from its previous sample (gather),
// batches cut where ranges of photons in flight filled the pair cap (the hierarchy methods).
bool depends_on_threads(SplatMethod method, const std::string& name) {
    if (name == "gather_lists") return true;
    return name == "splat_batches" && (method == SplatMethod::cluster || method == SplatMethod::cluster_cone);
}

TEST_P(AnyMethod, SameOutputAndCountersWithOneTwoAndEightThreads) {
    // Let TBB run more threads than a 2-core machine has, so that 8 threads really interleave.
    tbb::global_control allow(tbb::global_control::max_allowed_parallelism, 8);
    const SplatMethod method = GetParam();
    const SyntheticSplat in = synthetic_splat(method, 59, 5000, 0.5f, sized(96, 80));
    const MethodFrame& frame = in.frame;
    const PhotonMap& map = in.map;
    // The default pair cap, and a small one: many batches with several ranges in flight.
    const uint64_t small_cap = 8 * std::max<uint64_t>(frame.hierarchy.leaves.size(), 64);
    for (Kernel kernel : {Kernel::uniform, Kernel::epanechnikov})
        for (uint64_t cap : {kDefaultMaxPairsInMemory, small_cap})
            for (int level : {0, 1}) {  // directional: the level of its cut (the others ignore it)
                if (level == 1 && method != SplatMethod::directional) continue;
                SplatParams params = splat_params(0.3f, map, kernel);
                params.max_pairs_in_memory = cap;
                params.directional_level = level;
                params.plane_distance_factor = level == 1 ? 0.2f : 0.0f;
                const std::string what = std::string(to_string(kernel)) + " cap " + std::to_string(cap) +
                                         " level " + std::to_string(level);
                auto run = [&](int threads, Stats& stats) {
                    std::vector<glm::vec3> out;
                    RenderControl control;
                    tbb::task_arena(threads).execute(
                        [&] { out = run_splat(method, frame.input(), map, params, control, stats); });
                    return out;
                };
                Stats one, two, eight;
                const std::vector<glm::vec3> expected = run(1, one);
                EXPECT_TRUE(run(2, two) == expected) << what;
                EXPECT_TRUE(run(8, eight) == expected) << what;
                EXPECT_GT(counter(one, "contributing_pairs"), 0.0) << what;
                for (const auto& [name, value] : one.counters) {
                    if (depends_on_threads(method, name)) continue;
                    EXPECT_EQ(counter(two, name.c_str()), value) << name << ", " << what;
                    EXPECT_EQ(counter(eight, name.c_str()), value) << name << ", " << what;
                }
                if (method == SplatMethod::directional) EXPECT_GT(counter(one, "node_deposits"), 0.0) << what;
            }
}

// Counters a method reports even when nothing reaches a sample: all 0 with no photons.
std::vector<const char*> counters_zero_without_photons(SplatMethod method) {
    switch (method) {
        case SplatMethod::gather: return {"contributing_pairs", "grid_cells"};
        case SplatMethod::cluster_cone: return {"contributing_pairs", "node_accepts"};
        case SplatMethod::directional: return {"contributing_pairs", "node_deposits"};
        case SplatMethod::tiled: return {"contributing_pairs", "tile_photon_pairs"};
        default: return {"contributing_pairs"};
    }
}

TEST_P(AnyMethod, ZeroPhotonsGiveZeroRadianceAndZeroSamplesNoOutput) {
    const SplatMethod method = GetParam();
    std::mt19937 rng(3);
    const SyntheticOptions options;
    const MethodFrame frame = synthetic_frame(method, options, rng);
    PhotonMap none;  // emitted 0 too: fine when nothing was stored
    RenderControl control;
    Stats stats;
    const std::vector<glm::vec3> out = run_splat(method, frame.input(), none, splat_params(0.3f, none), control, stats);
    ASSERT_EQ(out.size(), frame.samples.samples.size());
    for (const glm::vec3& v : out) EXPECT_EQ(v, glm::vec3(0.0f));
    for (const char* name : counters_zero_without_photons(method)) EXPECT_EQ(counter(stats, name), 0.0) << name;

    SyntheticOptions no_samples = options;
    no_samples.coverage = 0.0;
    const MethodFrame empty = synthetic_frame(method, no_samples, rng);
    ASSERT_TRUE(empty.samples.samples.empty());
    const PhotonMap map = synthetic_photons(frame.samples, 100, 0.1f, rng);
    EXPECT_TRUE(run_splat(method, empty.input(), map, splat_params(0.3f, map), control, stats).empty());
}

TEST_P(AnyMethod, RefusesBadParams) {
    const SplatMethod method = GetParam();
    const SyntheticSplat in = synthetic_splat(method, 73, 100, 0.5f);
    RenderControl control;
    Stats stats;
    const auto refused = [&](const SplatParams& params) {
        return run_splat(method, in.frame.input(), in.map, params, control, stats);
    };
    for (float radius : {0.0f, -1.0f, NAN, INFINITY})
        EXPECT_THROW(refused(splat_params(radius, in.map)), InvalidInput) << "radius " << radius;
    SplatParams no_emitted = splat_params(0.3f, in.map);
    no_emitted.emitted = 0;
    EXPECT_THROW(refused(no_emitted), InvalidInput);
    SplatParams no_pairs = splat_params(0.3f, in.map);
    no_pairs.max_pairs_in_memory = 0;
    EXPECT_THROW(refused(no_pairs), InvalidInput);
    EXPECT_EQ(splat_method_from_string(to_string(method)), method);
}

TEST_P(AnyMethod, CancelledBeforeStartThrows) {
    const SplatMethod method = GetParam();
    const SyntheticSplat in = synthetic_splat(method, 67, 1000, 0.5f);
    RenderControl control;
    control.request_cancel();
    Stats stats;
    for (int level : {0, -1}) {  // directional: a fixed level, and one chosen from r
        SplatParams params = splat_params(0.3f, in.map);
        params.directional_level = level;
        EXPECT_THROW(run_splat(method, in.frame.input(), in.map, params, control, stats), Cancelled)
            << "level " << level;
    }
}

INSTANTIATE_TEST_SUITE_P(AllMethods, AnyMethod, ::testing::ValuesIn(all_methods()), method_name);

}  // namespace
}  // namespace ps::test
