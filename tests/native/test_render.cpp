// The whole pipeline on the Cornell box: the cluster splat equals the brute-force oracle per pixel, the image
// is bit-identical for any thread count, caustics appear where they should, and bad cases end cleanly.
#include <cmath>
#include <thread>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "photonsplat/errors.h"
#include "photonsplat/render.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/view_samples.h"
#include "test_support.h"

namespace {

using namespace ps;

RenderResult render_cornell(SplatMethod method, int threads, uint64_t photons = 20000, int size = 64) {
    RenderSettings settings = test::method_settings(method, photons, 7);
    settings.threads = threads;
    return test::render_cornell_box(settings, size, size);
}

TEST(Render, ClusterEqualsBruteOnTheCornellBox) {
    const RenderResult brute = render_cornell(SplatMethod::brute, 0);
    const RenderResult cluster = render_cornell(SplatMethod::cluster, 0);
    test::expect_same_indirect(brute, cluster, "the box has indirect light, so the comparison is not vacuous");
    EXPECT_EQ(brute.stats.counters.at("contributing_pairs"), cluster.stats.counters.at("contributing_pairs"));
    EXPECT_LT(cluster.stats.counters.at("photon_sample_tests"), brute.stats.counters.at("photon_sample_tests") / 10);
}

TEST(Render, ImageIsBitIdenticalForAnyThreadCount) {
    // Let TBB run more threads than this (2-core) machine has, so 8 threads really interleave.
    tbb::global_control allow(tbb::global_control::max_allowed_parallelism, 8);
    for (SplatMethod method : {SplatMethod::cluster, SplatMethod::brute}) {
        const RenderResult one = render_cornell(method, 1, 5000, 32);
        for (int threads : {2, 8}) {
            const RenderResult many = render_cornell(method, threads, 5000, 32);
            ASSERT_EQ(one.rgba(), many.rgba()) << to_string(method) << " with " << threads << " threads";
        }
    }
}

TEST(Render, CausticUnderAFloatingGlassSphereIsBrighterThanTheFloorAround) {
    // A glass ball floating right under the lamp focuses its light into a spot on the floor below it.
    Scene scene;
    test::build_cornell_box(scene, false);
    const uint32_t glass = scene.add_material({"glass", MaterialKind::glass, glm::vec3(1.0f), 1.5f, glm::vec3(0.0f)});
    test::add_sphere(scene, "ball", {0.0f, 0.0f, 1.0f}, 0.35f, glass);
    const Camera camera = test::cornell_camera(96, 96);
    RenderSettings settings;
    settings.photons = 200000;
    settings.radius = 0.04f;
    RenderControl control;
    const RenderResult r = render(scene, camera, settings, control);
    Stats stats;
    const ViewSamples samples = generate_view_samples(scene, camera, ViewSampleSettings{}, control, stats);
    double spot = 0, ring = 0;
    int n_spot = 0, n_ring = 0;
    for (const ViewSample& s : samples.samples) {
        const glm::vec3 x = s.position + samples.origin;
        if (std::fabs(x.z) > 1e-3f) continue;  // floor only
        const float d = std::hypot(x.x, x.y);
        const float v = luminance(glm::vec3(r.film[ps::FilmOutput::indirect][3 * s.pixel], r.film[ps::FilmOutput::indirect][3 * s.pixel + 1], r.film[ps::FilmOutput::indirect][3 * s.pixel + 2]));
        if (d < 0.08f) spot += v, ++n_spot;
        if (d > 0.45f && d < 0.7f) ring += v, ++n_ring;
    }
    ASSERT_GT(n_spot, 5);
    ASSERT_GT(n_ring, 20);
    EXPECT_GT(spot / n_spot, 3.0 * ring / n_ring) << "caustic spot vs floor around it (indirect light)";
    EXPECT_GT(r.stats.counters.at("caustic_photons_stored"), 0.0);
}

TEST(Render, CancelStopsTheRenderWithCancelled) {
    Scene scene;
    test::build_cornell_box(scene, true);
    RenderSettings settings;
    settings.photons = 50'000'000;  // far more than the test waits for
    // The whole trace would need ~30 GiB by the budget's prediction; cancelled at 200 ms it allocates a fraction.
    settings.memory_budget = uint64_t(64) << 30;
    settings.method = SplatMethod::brute;
    RenderControl control;
    std::thread canceller([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
        control.request_cancel();
    });
    const auto start = std::chrono::steady_clock::now();
    EXPECT_THROW(render(scene, test::cornell_camera(256, 256), settings, control), Cancelled);
    canceller.join();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_LT(seconds, 2.0) << "cancel must take effect within a second of the request";
}

TEST(Render, EmptySceneAndNoLightsGiveFiniteImagesOfTheBackground) {
    Scene empty;
    empty.set_background({0.1f, 0.2f, 0.3f});
    RenderControl control;
    const RenderResult r = render(empty, test::cornell_camera(8, 8), RenderSettings{}, control);
    for (size_t p = 0; p < 64; ++p) {
        EXPECT_FLOAT_EQ(r.rgba()[4 * p + 0], 0.1f);
        EXPECT_FLOAT_EQ(r.rgba()[4 * p + 2], 0.3f);
    }
    Scene unlit;
    unlit.add_material({"white", MaterialKind::diffuse, glm::vec3(0.8f), 1.45f, glm::vec3(0.0f)});
    test::add_quad(unlit, "floor", {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, 0);
    const RenderResult u = render(unlit, test::cornell_camera(8, 8), RenderSettings{}, control);
    for (float v : u.rgba()) EXPECT_TRUE(std::isfinite(v));
}

TEST(Render, SettingsAreValidatedNamingTheField) {
    Scene scene;
    RenderControl control;
    RenderSettings bad;
    bad.radius = -1.0f;
    try {
        render(scene, test::cornell_camera(4, 4), bad, control);
        FAIL() << "negative radius accepted";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(e.field(), "radius");
    }
    bad = RenderSettings{};
    bad.radius = std::nanf("");
    EXPECT_THROW(render(scene, test::cornell_camera(4, 4), bad, control), InvalidInput);
}

}  // namespace

namespace {

using namespace ps;

// Inside a closed box whose walls all emit Le and reflect with albedo a, radiance is Le/(1 − a) everywhere:
// emission, direct light from the emissive walls and splatted photons must add up to exactly that.
TEST(Render, ClosedEmissiveBoxReachesLeOverOneMinusAlbedo) {
    Scene scene;
    const float albedo = 0.5f, le = 1.0f;
    scene.add_material({"wall", MaterialKind::diffuse, glm::vec3(albedo), 1.45f, glm::vec3(le)});
    const glm::vec3 c[8] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                            {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
    test::add_quad(scene, "bottom", c[0], c[1], c[2], c[3], 0);
    test::add_quad(scene, "top", c[4], c[7], c[6], c[5], 0);
    test::add_quad(scene, "front", c[0], c[4], c[5], c[1], 0);
    test::add_quad(scene, "back", c[3], c[2], c[6], c[7], 0);
    test::add_quad(scene, "left", c[0], c[3], c[7], c[4], 0);
    test::add_quad(scene, "right", c[1], c[5], c[6], c[2], 0);
    RenderControl control;
    const RenderResult r = render(scene, test::look_at({0, 0, 0}, {0, 1, 0}, 16, 16, 30.0f),
                                  test::emissive_box_settings(400000, 0.1f, 64, 16), control);
    double mean = 0.0;
    for (size_t p = 0; p < 16 * 16; ++p) mean += r.rgba()[4 * p + 1];
    mean /= 16 * 16;
    EXPECT_NEAR(mean, le / (1.0f - albedo), 0.03 * le / (1.0f - albedo));
}

}  // namespace
