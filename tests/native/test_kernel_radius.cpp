// The automatic kernel radius: the boundary loss it weighs against photon noise matches a strip's analytic
// loss, is zero where the surface extends past every disc, and makes the first radius of progressive renders
// smaller where the scene's details are thinner than default_radius.
#include <cmath>

#include <gtest/gtest.h>

#include "photonsplat/kernel_radius.h"
#include "photonsplat/render.h"
#include "photonsplat/scene.h"
#include "test_scenes.h"

namespace {

using namespace ps;

uint32_t diffuse(Scene& scene) { return scene.add_material(Material{}); }

void add_plate(Scene& scene, float half, uint32_t material) {
    test::add_quad(scene, "plate", {-half, -half, 0}, {half, -half, 0}, {half, half, 0}, {-half, half, 0}, material);
}

TEST(KernelRadius, AStripLosesWhatItsEdgesPredict) {
    // A strip 1 m wide and 100 m long under a camera looking straight down: a disc of radius r <= 0.5 m can
    // reach past one edge at most, so the loss at a point is disc_beyond_edge of its distance to the nearer edge.
    // The expectation is averaged over the points boundary_loss uses (the documented grid of camera rays).
    Scene scene;
    test::add_quad(scene, "strip", {-0.5f, -50, 0}, {0.5f, -50, 0}, {0.5f, 50, 0}, {-0.5f, 50, 0}, diffuse(scene));
    const Camera camera = test::top_down_camera(1.6f);  // the strip fills the middle 86 % of the image's width
    const int grid = kBoundaryLossGrid;  // the image is 64 × 64: grid × grid points
    for (double r : {0.1, 0.2, 0.3, 0.5}) {
        double sum = 0.0;
        int seen = 0;
        for (int j = 0; j < grid; ++j) {
            for (int i = 0; i < grid; ++i) {
                const Ray ray = camera.generate_ray((i + 0.5f) * 64 / grid, (j + 0.5f) * 64 / grid);
                const double x = ray.origin.x - ray.origin.z / ray.direction.z * ray.direction.x;
                if (std::fabs(x) > 0.5) continue;  // background
                sum += test::disc_beyond_edge(0.5 - x, r) + test::disc_beyond_edge(x + 0.5, r);
                ++seen;
            }
        }
        ASSERT_GT(seen, 600);
        EXPECT_NEAR(boundary_loss(scene, camera, static_cast<float>(r)), sum / seen, 0.01) << "r = " << r;
    }
    EXPECT_EQ(boundary_loss(scene, camera, 0.2f), boundary_loss(scene, camera, 0.2f));  // deterministic
}

TEST(KernelRadius, AWideFloorKeepsTheDefaultRadius) {
    Scene scene;
    add_plate(scene, 50.0f, diffuse(scene));
    const Camera camera = test::top_down_camera(2.0f);
    EXPECT_EQ(boundary_loss(scene, camera, 1.0f), 0.0f);
    EXPECT_EQ(automatic_radius(scene, camera, 12500), default_radius(scene, 12500));
}

// Ten diffuse strips of the z = 0 plane, 5 cm wide, 20 cm apart, over 2 m (x from −1 to 0.85, y from −1 to 1).
void add_thin_strips(Scene& scene) {
    const uint32_t m = diffuse(scene);
    for (int i = 0; i < 10; ++i) {
        const float x = -1.0f + 0.2f * i;
        test::add_quad(scene, "strip", {x, -1, 0}, {x + 0.05f, -1, 0}, {x + 0.05f, 1, 0}, {x, 1, 0}, m);
    }
}

TEST(KernelRadius, ThinStripsShrinkTheRadius) {
    // default_radius (0.17 m at 12.5k photons) is far wider than a strip, so most of every disc falls between
    // strips.
    Scene scene;
    add_thin_strips(scene);
    const Camera camera = test::top_down_camera(2.5f);
    const float r0 = default_radius(scene, 12500);
    ASSERT_GT(r0, 0.15f);
    const float wide = boundary_loss(scene, camera, r0), narrow = boundary_loss(scene, camera, 0.01f);
    EXPECT_GT(wide, 0.5f);
    EXPECT_LT(narrow, wide);
    EXPECT_FLOAT_EQ(automatic_radius(scene, camera, 12500), 0.25f * r0);  // the smallest candidate
}

TEST(KernelRadius, NothingSeenOrOnlyMirrorsKeepTheDefaultRadius) {
    Scene empty;
    const Camera camera = test::top_down_camera(2.0f);
    EXPECT_EQ(boundary_loss(empty, camera, 0.5f), 0.0f);
    EXPECT_EQ(automatic_radius(empty, camera, 1000), default_radius(empty, 1000));

    Scene mirrors;
    Material mirror;
    mirror.kind = MaterialKind::mirror;
    add_plate(mirrors, 0.2f, mirrors.add_material(mirror));
    EXPECT_EQ(boundary_loss(mirrors, camera, 0.5f), 0.0f);
}

TEST(KernelRadius, OnlyProgressiveRendersTheCorrectionDoesNotCoverStartAtTheAutomaticRadius) {
    // The strips of ThinStripsShrinkTheRadius under a light: there the two radii differ.
    Scene scene;
    add_thin_strips(scene);
    scene.add_light(test::point_light("lamp", {0, 0, 2}, 100.0f));
    const Camera camera = test::top_down_camera(2.5f);
    RenderSettings settings;
    settings.photons = 2000;
    ASSERT_LT(automatic_radius(scene, camera, 2000), default_radius(scene, 2000));
    RenderControl control;
    const auto first_radius_of = [&](uint32_t passes, bool correction, SplatMethod method = SplatMethod::cluster_cone) {
        settings.iterations = passes;
        settings.boundary_correction = correction;
        settings.method = method;
        return static_cast<float>(render(scene, camera, settings, control).stats.values.at("radius"));
    };
    EXPECT_FLOAT_EQ(first_radius_of(1, true), default_radius(scene, 2000));
    EXPECT_FLOAT_EQ(first_radius_of(1, false), default_radius(scene, 2000));
    EXPECT_FLOAT_EQ(first_radius_of(2, true), default_radius(scene, 2000));  // the correction removes the bias
    EXPECT_FLOAT_EQ(first_radius_of(2, false), automatic_radius(scene, camera, 2000));
    // directional's approximate passes are not corrected: it weighs the bias as without the correction.
    EXPECT_FLOAT_EQ(first_radius_of(2, true, SplatMethod::directional), automatic_radius(scene, camera, 2000));
}

}  // namespace
