// The emission guide (emission_guide.h): a density over the sun's disc learnt from pilot photons. It must be
// unbiased (the same expected image with and without it) and must pay off where photons are wasted: a closed
// room lit by the sun through a skylight, where most unguided photons land on the roof.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "photonsplat/emission_guide.h"
#include "photonsplat/render.h"
#include "photonsplat/render_control.h"
#include "photonsplat/rng.h"
#include "photonsplat/scene.h"
#include "test_scenes.h"

namespace ps {
namespace {

TEST(EmissionGuide, UniformWhenNothingIsUseful) {
    EXPECT_TRUE(EmissionGuide().uniform());
    EXPECT_TRUE(EmissionGuide::from_usefulness(std::vector<double>(EmissionGuide::kCells, 0.0)).uniform());
    std::vector<double> bad(EmissionGuide::kCells, 1.0);
    bad[7] = std::numeric_limits<double>::quiet_NaN();
    EXPECT_TRUE(EmissionGuide::from_usefulness(bad).uniform());
    bad[7] = -1.0;
    EXPECT_TRUE(EmissionGuide::from_usefulness(bad).uniform());
    EXPECT_TRUE(EmissionGuide::from_usefulness(std::vector<double>(3, 1.0)).uniform());  // wrong size
    float u1 = 0.25f, u2 = 0.75f;
    EXPECT_EQ(EmissionGuide().sample(0.5f, u1, u2), 1.0f);
    EXPECT_EQ(u1, 0.25f);
    EXPECT_EQ(u2, 0.75f);
}

// E[weight · f(u)] over guided samples is ∫ f over the square, for any f: here the indicator of a disc, of
// a band and of one cell, with the useful cells elsewhere.
TEST(EmissionGuide, WeightedSamplesIntegrateLikeUniformOnes) {
    std::vector<double> usefulness(EmissionGuide::kCells, 0.0);
    for (int c = 0; c < 40; ++c) usefulness[size_t(c * 7 % EmissionGuide::kCells)] = 1.0 + c % 3;
    const EmissionGuide guide = EmissionGuide::from_usefulness(usefulness);
    ASSERT_FALSE(guide.uniform());
    double pdf_sum = 0.0, max_weight = 0.0;
    for (int c = 0; c < EmissionGuide::kCells; ++c) pdf_sum += guide.pdf(c);
    EXPECT_NEAR(pdf_sum / EmissionGuide::kCells, 1.0, 1e-4);
    const auto disc = [](float x, float y) { return (x - 0.6f) * (x - 0.6f) + (y - 0.3f) * (y - 0.3f) < 0.04f; };
    const auto band = [](float x, float) { return x > 0.1f && x < 0.2f; };
    const auto cell = [](float x, float y) { return x < 1.0f / 32 && y < 1.0f / 32; };
    double sums[3] = {0, 0, 0};
    const int n = 400000;
    for (int i = 0; i < n; ++i) {
        Rng rng(1, RngDomain::photon, uint64_t(i));
        float u1 = rng.uniform(), u2 = rng.uniform();
        const float w = guide.sample(rng.uniform(), u1, u2);
        ASSERT_TRUE(u1 >= 0.0f && u1 < 1.0f && u2 >= 0.0f && u2 < 1.0f);
        max_weight = std::max(max_weight, double(w));
        sums[0] += disc(u1, u2) ? w : 0.0;
        sums[1] += band(u1, u2) ? w : 0.0;
        sums[2] += cell(u1, u2) ? w : 0.0;
    }
    EXPECT_LE(max_weight, 1.0 / EmissionGuide::kUniformShare + 1e-3);
    EXPECT_NEAR(sums[0] / n, 3.14159265 * 0.04, 0.004);
    EXPECT_NEAR(sums[1] / n, 0.1, 0.003);
    EXPECT_NEAR(sums[2] / n, 1.0 / 1024, 0.0002);
}

// A closed 2 × 2 × 2 room with a 0.6 × 0.6 skylight, a sun high above, the camera inside.
void build_skylit_room(Scene& scene) {
    const uint32_t white = scene.add_material({"white", MaterialKind::diffuse, glm::vec3(0.7f), 1.45f, glm::vec3(0.0f)});
    const uint32_t red = scene.add_material({"red", MaterialKind::diffuse, glm::vec3(0.7f, 0.2f, 0.1f), 1.45f, glm::vec3(0.0f)});
    test::add_quad(scene, "floor", {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, white);
    test::add_quad(scene, "front", {-1, -1, 0}, {-1, -1, 2}, {1, -1, 2}, {1, -1, 0}, white);
    test::add_quad(scene, "back", {-1, 1, 0}, {1, 1, 0}, {1, 1, 2}, {-1, 1, 2}, white);
    test::add_quad(scene, "left", {-1, -1, 0}, {-1, 1, 0}, {-1, 1, 2}, {-1, -1, 2}, red);
    test::add_quad(scene, "right", {1, -1, 0}, {1, -1, 2}, {1, 1, 2}, {1, 1, 0}, white);
    const float h = 0.3f;  // the skylight is [-h, h]² in the roof z = 2
    test::add_quad(scene, "roof_south", {-1, -1, 2}, {-1, -h, 2}, {1, -h, 2}, {1, -1, 2}, white);
    test::add_quad(scene, "roof_north", {-1, h, 2}, {-1, 1, 2}, {1, 1, 2}, {1, h, 2}, white);
    test::add_quad(scene, "roof_west", {-1, -h, 2}, {-1, h, 2}, {-h, h, 2}, {-h, -h, 2}, white);
    test::add_quad(scene, "roof_east", {h, -h, 2}, {h, h, 2}, {1, h, 2}, {1, -h, 2}, white);
    Light sun;
    sun.name = "sun";
    sun.kind = LightKind::sun;
    sun.direction = glm::normalize(glm::vec3(0.15f, 0.1f, -1.0f));
    sun.value = glm::vec3(5.0f);
    scene.add_light(sun);
}

TEST(EmissionGuide, SkylitRoomStoresManyMorePhotonsForTheSameImage) {
    Scene scene;
    build_skylit_room(scene);
    const Camera camera = test::look_at({0.0f, -0.9f, 1.0f}, {0.2f, 1.0f, 0.6f}, 40, 30, 70.0f);
    RenderSettings settings;
    settings.photons = 400000;
    settings.radius = 0.2f;
    settings.method = SplatMethod::cluster;
    settings.direct_samples = 1;
    RenderControl control;
    settings.guide_photons = false;
    const RenderResult plain = render(scene, camera, settings, control);
    settings.guide_photons = true;
    const RenderResult guided = render(scene, camera, settings, control);
    EXPECT_EQ(plain.stats.counters.count("guided_light_sources"), 0u);
    EXPECT_EQ(guided.stats.counters.at("guided_light_sources"), 1.0);
    const double stored_plain = plain.stats.counters.at("photons_stored");
    const double stored_guided = guided.stats.counters.at("photons_stored");
    double sum_plain = 0.0, sum_guided = 0.0;
    for (size_t i = 0; i < plain.film[ps::FilmOutput::indirect].size(); ++i) {
        ASSERT_TRUE(std::isfinite(guided.film[ps::FilmOutput::indirect][i]));
        sum_plain += plain.film[ps::FilmOutput::indirect][i];
        sum_guided += guided.film[ps::FilmOutput::indirect][i];
    }
    std::printf("skylit room, %llu photons: stored %.0f unguided, %.0f guided (%.1f×); mean indirect guided / "
                "unguided = %.4f\n",
                static_cast<unsigned long long>(settings.photons), stored_plain, stored_guided,
                stored_guided / stored_plain, sum_guided / sum_plain);
    ASSERT_GT(sum_plain, 0.0);
    EXPECT_GT(stored_guided, 5.0 * stored_plain);
    EXPECT_NEAR(sum_guided / sum_plain, 1.0, 0.05);
}

}  // namespace
}  // namespace ps
