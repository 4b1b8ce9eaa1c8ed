// Radius levels (photon_density.h): photons that a glossy or sharp part focused, where they gather far more densely
// than usual, splat with a half or a quarter of the radius.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "photonsplat/materials.h"
#include "photonsplat/photon_density.h"
#include "photonsplat/photons.h"
#include "photonsplat/progressive.h"
#include "photonsplat/reference.h"
#include "photonsplat/render.h"
#include "photonsplat/render_control.h"
#include "photonsplat/stats.h"
#include "test_support.h"

namespace {

using namespace ps;

Photon photon_at(glm::vec3 position, uint32_t flags) {
    return Photon{position, {0, 0, 1}, {0, 0, 1}, glm::vec3(1.0f), flags, {}};
}

// `count` photons spread evenly (at random) over the square [-half, half]² of the plane z = 0.
void add_even(std::vector<Photon>& out, size_t count, float half, uint32_t flags, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-half, half);
    for (size_t i = 0; i < count; ++i) out.push_back(photon_at({u(rng), u(rng), 0.0f}, flags));
}

// 200 000 photons over a 2 m square (a disc of radius 0.05 holds about 390 of them), then a spot of `spot`
// photons within `spot_radius` of (0.5, 0.5).
PhotonMap lit_square(size_t spot, float spot_radius, uint32_t spot_flags) {
    std::mt19937 rng(7);
    PhotonMap map;
    map.emitted = 1000;
    add_even(map.photons, 200000, 1.0f, kAfterGlossy, rng);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (size_t i = 0; i < spot;) {
        const glm::vec2 d(u(rng), u(rng));
        if (glm::dot(d, d) > 1.0f) continue;
        map.photons.push_back(photon_at({0.5f + spot_radius * d.x, 0.5f + spot_radius * d.y, 0.0f}, spot_flags));
        ++i;
    }
    return map;
}

TEST(RadiusLevels, EvenLightKeepsOneRadius) {
    Stats stats;
    const PhotonMap map = lit_square(0, 0.0f, 0);
    const RadiusLevels levels = photon_radius_levels(map, 0.05f, stats);
    EXPECT_EQ(levels.count[0], map.photons.size());
    // A box of 2 × 2 cells of 0.05 m on the plane: 0.01 m² of the 4 m², 500 photons.
    EXPECT_NEAR(levels.typical, 500.0, 60.0);
}

TEST(RadiusLevels, AFocusedSpotTakesAQuarterOfTheRadius) {
    Stats stats;
    // 40 000 photons within 0.02 m: some 80 times the even light's density.
    const PhotonMap map = lit_square(40000, 0.02f, kAfterGlossy | kCaustic);
    const RadiusLevels levels = photon_radius_levels(map, 0.05f, stats);
    size_t spot_at_quarter = 0;
    for (size_t i = 200000; i < map.photons.size(); ++i) spot_at_quarter += levels.level[i] == 2 ? 1 : 0;
    EXPECT_EQ(spot_at_quarter, 40000u);
    // The even photons around the spot share its boxes; a few of those within a box's width take its level too.
    size_t even_moved = 0;
    for (size_t i = 0; i < 200000; ++i) even_moved += levels.level[i] > 0 ? 1 : 0;
    EXPECT_LT(even_moved, 2000u);
    EXPECT_EQ(levels.count[0] + levels.count[1] + levels.count[2], map.photons.size());
    EXPECT_NEAR(levels.typical, 500.0, 60.0);  // the spot does not make the typical count
    EXPECT_GT(stats.bytes.at("radius_levels"), 0.0);
    EXPECT_LE(stats.bytes.at("radius_levels"), predict_radius_level_bytes(map.photons.size()));
}

TEST(RadiusLevels, AModeratelyDenseSpotTakesAHalf) {
    Stats stats;
    // 3 000 photons within 0.03 m: about 8 times the even density, over a box's area.
    const PhotonMap map = lit_square(3000, 0.03f, kAfterGlossy);
    const RadiusLevels levels = photon_radius_levels(map, 0.05f, stats);
    size_t half = 0;
    for (size_t i = 200000; i < map.photons.size(); ++i) half += levels.level[i] == 1 ? 1 : 0;
    EXPECT_GT(half, 2500u);
}

// Light no glossy or sharp part passed on cannot be focused: a dense spot of it keeps the radius.
TEST(RadiusLevels, OnlyLightAfterGlossyPartsIsLeveled) {
    Stats stats;
    const PhotonMap map = lit_square(40000, 0.02f, 0);
    const RadiusLevels levels = photon_radius_levels(map, 0.05f, stats);
    for (size_t i = 200000; i < map.photons.size(); ++i) ASSERT_EQ(levels.level[i], 0) << i;
}

TEST(RadiusLevels, DegenerateInputsKeepOneRadius) {
    Stats stats;
    PhotonMap empty;
    EXPECT_TRUE(photon_radius_levels(empty, 0.05f, stats).level.empty());
    PhotonMap map = lit_square(40000, 0.02f, kAfterGlossy);
    map.photons[3].position.x = std::nanf("");
    map.photons[4].position.y = std::numeric_limits<float>::infinity();
    for (float radius : {0.0f, -1.0f, std::nanf(""), std::numeric_limits<float>::infinity()}) {
        const RadiusLevels levels = photon_radius_levels(map, radius, stats);
        EXPECT_EQ(levels.count[0], map.photons.size()) << radius;
    }
    const RadiusLevels levels = photon_radius_levels(map, 0.05f, stats);
    EXPECT_EQ(levels.level[3], 0);
    EXPECT_EQ(levels.level[4], 0);
    EXPECT_EQ(levels.level[map.photons.size() - 1], 2);
    // A radius far below the photons' spacing: every box holds a photon or two, nothing is dense.
    EXPECT_EQ(photon_radius_levels(map, 1e-6f, stats).count[0], map.photons.size());
}

// A glass ball focusing a small lamp onto a white floor, seen from the side under the ball: a caustic a few
// pixels wide, far narrower than the radius chosen for the floor's light.
struct FocusedCaustic {
    Scene scene;
    Camera camera = test::look_at({0.0f, -1.5f, 0.5f}, {0.0f, 0.0f, 0.0f}, 32, 32, 30.0f);

    FocusedCaustic() {
        const uint32_t floor = scene.add_material(Material{});
        test::add_ground(scene, 2.0f, floor);
        const uint32_t glass =
            scene.add_material({"glass", MaterialKind::glass, glm::vec3(1.0f), 1.5f, glm::vec3(0.0f)});
        test::add_sphere(scene, "ball", {0.0f, 0.0f, 0.6f}, 0.3f, glass);
        scene.add_light(test::point_light("lamp", {0.05f, 0.0f, 2.5f}, 60.0f, 0.04f));
    }

    RenderSettings settings(bool adaptive) const {
        RenderSettings s;
        s.photons = 40000;
        s.threads = 2;
        s.adaptive_radius = adaptive;
        return s;
    }

    std::vector<float> photon_splat(bool adaptive, int iterations, Stats* stats = nullptr) const {
        return test::progressive_image(scene, camera, settings(adaptive), iterations, stats);
    }

    std::vector<float> reference(int samples) const { return test::reference_image(scene, camera, samples); }
};

// Mean of the RGB of pixels [x0, x1) × [y0, y1) of a 32 × 32 RGBA image.
double block_mean(const std::vector<float>& rgba, int x0, int x1, int y0, int y1) {
    return test::block_mean(rgba, 32, x0, x1, y0, y1);
}
// Measured (8 iterations of 40 000 photons, the reference at 256 samples): the caustic's centre 2 × 2 pixels
// 0.90 of the reference (0.26 with one radius), the 4 × 4 around it 0.94 (0.51), the image 0.994 (1.001).
TEST(RadiusLevels, AFocusedCausticIsSharperAtTheSameEnergy) {
    const FocusedCaustic s;
    Stats stats;
    const std::vector<float> on = s.photon_splat(true, 8, &stats), off = s.photon_splat(false, 8);
    const std::vector<float> reference = s.reference(256);
    EXPECT_GT(stats.counters.at("photons_radius_level_2"), 0.0);
    const auto centre = [](const std::vector<float>& image, int half) {
        return block_mean(image, 16 - half, 16 + half, 16 - half, 16 + half);
    };
    const double centre_2 = centre(reference, 1), centre_4 = centre(reference, 2);
    ASSERT_GT(centre_2, 10.0 * centre(reference, 16)) << "the caustic is a bright spot at the centre";
    EXPECT_GT(centre(on, 1), 0.75 * centre_2);
    EXPECT_LT(centre(off, 1), 0.4 * centre_2) << "one radius blurs the spot (the test would not see a change)";
    EXPECT_NEAR(centre(on, 2) / centre_4, 1.0, 0.12);
    EXPECT_LT(centre(off, 2), 0.6 * centre_4);
    // Smaller discs move the light, they do not add or lose any.
    EXPECT_NEAR(centre(on, 16) / centre(off, 16), 1.0, 0.015);
    EXPECT_NEAR(centre(on, 16) / centre(reference, 16), 1.0, 0.02);
}

// The levels are splatted by the settings' method like the rest: every exact method still gives brute's image
// (the Caustics output too), whatever the threads, and their structures are predicted before they are allocated.
TEST(RadiusLevels, ExactMethodsStillEqualBrute) {
    const FocusedCaustic s;
    const auto render_with = [&](SplatMethod method, int threads) {
        RenderSettings settings = s.settings(true);
        settings.method = method;
        settings.threads = threads;
        settings.caustics_pass = true;
        RenderControl control;
        return render(s.scene, s.camera, settings, control);
    };
    const RenderResult brute = render_with(SplatMethod::brute, 2);
    ASSERT_GT(brute.stats.counters.at("photons_radius_level_2"), 0.0);
    for (const char* structure : {"radius_levels", "radius_level_photons"})
        EXPECT_LE(brute.stats.bytes.at(structure), brute.stats.predicted_bytes.at(structure)) << structure;
    for (SplatMethod method : test::exact_methods()) {
        SCOPED_TRACE(to_string(method));
        const RenderResult one = render_with(method, 1);
        for (FilmOutput output : {FilmOutput::indirect, FilmOutput::caustics}) {
            const std::vector<float>& expected = brute.film[output];
            const std::vector<float>& got = one.film[output];
            ASSERT_EQ(expected.size(), got.size());
            for (size_t i = 0; i < expected.size(); ++i)
                ASSERT_LE(std::fabs(expected[i] - got[i]), 1e-4f * std::fabs(expected[i]) + 1e-7f) << i;
        }
        EXPECT_EQ(render_with(method, 2).rgba(), one.rgba()) << "1 and 2 threads";
    }
}

// Off, every photon splats with the iteration's radius: the image of the render before levels.
TEST(RadiusLevels, OffMeansOneRadius) {
    const FocusedCaustic s;
    RenderControl control;
    const RenderResult off = render(s.scene, s.camera, s.settings(false), control);
    EXPECT_EQ(off.stats.counters.count("photons_radius_level_2"), 0u);
    EXPECT_EQ(off.stats.bytes.count("radius_levels"), 0u);
}

}  // namespace
