// Direct light against the analytic answer: a point light of intensity I over a Lambertian plane of albedo ρ
// gives reflected radiance L = ρ/π · I · cosθ / d² at every point of the plane.
#include <cmath>

#include <gtest/gtest.h>

#include "photonsplat/direct_light.h"
#include "photonsplat/render.h"
#include "photonsplat/render_control.h"
#include "photonsplat/view_samples.h"
#include "test_support.h"

namespace {

using namespace ps;

TEST(DirectLight, PointLightOverLambertianPlaneMatchesInverseSquareCosineLaw) {
    Scene scene;
    const float albedo = 0.8f;
    scene.add_material({"plane", MaterialKind::diffuse, glm::vec3(albedo), 1.45f, glm::vec3(0.0f)});
    test::add_ground(scene, 20.0f);
    Light light;
    light.kind = LightKind::point;
    light.position = {0.3f, -0.2f, 2.0f};
    light.value = glm::vec3(1000.0f / (4.0f * 3.14159265f));
    scene.add_light(light);

    const test::DirectView view =
        test::direct_light_view(scene, test::look_at({0, 0, 6}, {0, 0, 0}, 64, 64, 60.0f, {0, 1, 0}));
    const ViewSamples& samples = view.samples;
    const std::vector<glm::vec3>& direct = view.direct;
    ASSERT_EQ(samples.samples.size(), 64u * 64u);

    double worst = 0.0;
    for (size_t i = 0; i < samples.samples.size(); ++i) {
        const glm::vec3 x = samples.samples[i].position + samples.origin;
        const glm::vec3 to_light = light.position - x;
        const float d2 = glm::dot(to_light, to_light);
        const float cos_theta = to_light.z / std::sqrt(d2);
        const double expected = albedo / 3.14159265358979 * light.value.x * cos_theta / d2;
        worst = std::max(worst, std::fabs(direct[i].x - expected) / expected);
    }
    EXPECT_LT(worst, 0.01) << "worst relative error of direct light over the plane";
}

TEST(DirectLight, SunOnPlaneGivesIrradianceTimesAlbedoOverPi) {
    Scene scene;
    scene.add_material({"plane", MaterialKind::diffuse, glm::vec3(0.5f), 1.45f, glm::vec3(0.0f)});
    test::add_ground(scene, 20.0f);
    scene.add_light(test::sun_light(glm::normalize(glm::vec3(0.0f, 0.6f, -0.8f)), glm::vec3(3.0f)));
    const Camera camera = test::look_at({0, 0, 6}, {0, 0, 0}, 16, 16, 40.0f, {0, 1, 0});
    for (const glm::vec3& d : test::direct_light_view(scene, camera).direct)
        EXPECT_NEAR(d.y, 0.5f / 3.14159265f * 3.0f * 0.8f, 1e-4f);
}

TEST(DirectLight, AreaLightMatchesNumericalIntegral) {
    // A 1 m² square facing down at height 2 over the plane; irradiance at the centre below it by quadrature.
    Scene scene;
    scene.add_material({"plane", MaterialKind::diffuse, glm::vec3(0.8f), 1.45f, glm::vec3(0.0f)});
    test::add_ground(scene, 20.0f);
    Light area;
    area.kind = LightKind::area;
    area.position = {0, 0, 2};
    area.axis_u = {1, 0, 0};
    area.axis_v = {0, -1, 0};  // cross(u, v) = −z: shines down
    area.value = glm::vec3(25.0f);
    scene.add_light(area);
    DirectLightSettings settings;
    settings.samples_per_light = 4096;
    const std::vector<glm::vec3> direct =
        test::direct_light_view(scene, test::look_at({0, 0, 6}, {0, 0, 0}, 1, 1, 1.0f, {0, 1, 0}), settings).direct;
    double irradiance = 0.0;
    const int n = 400;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double x = (i + 0.5) / n - 0.5, y = (j + 0.5) / n - 0.5, h = 2.0;
            const double r2 = x * x + y * y + h * h;
            irradiance += 25.0 * h * h / (r2 * r2) / (n * n);
        }
    EXPECT_NEAR(direct[0].x, 0.8 / 3.14159265358979 * irradiance, 0.01 * 0.8 / 3.14159265358979 * irradiance);
}

}  // namespace

namespace {

using namespace ps;

TEST(DirectLight, UniformSkyOverAPlaneGivesAlbedoTimesSkyRadiance) {
    Scene scene;
    scene.add_material({"plane", MaterialKind::diffuse, glm::vec3(0.6f), 1.45f, glm::vec3(0.0f)});
    test::add_ground(scene, 1000.0f);
    scene.set_background(glm::vec3(0.5f, 1.0f, 2.0f));
    const test::DirectView view =
        test::direct_light_view(scene, test::look_at({0, 0, 1}, {0, 0, 0}, 8, 8, 20.0f, {0, 1, 0}));
    for (const glm::vec3& d : view.direct) {
        EXPECT_NEAR(d.x, 0.6f * 0.5f, 1e-3f);
        EXPECT_NEAR(d.z, 0.6f * 2.0f, 4e-3f);
    }
}

}  // namespace

namespace {

using namespace ps;

// Per-pixel variance over seeds of the direct light from a sky seen through a square opening in a roof, with
// `samples` shadow rays a view sample.
double sky_through_opening_variance(int samples) {
    Scene scene;
    scene.add_material({"floor", MaterialKind::diffuse, glm::vec3(0.5f), 1.45f, glm::vec3(0.0f)});
    test::add_quad(scene, "floor", {-4, -4, 0}, {4, -4, 0}, {4, 4, 0}, {-4, 4, 0}, 0);
    // A roof at height 1 with a 1 m square opening above the origin (four quads around it, facing down).
    const float z = 1.0f;
    test::add_quad(scene, "roof_w", {-4, -4, z}, {-4, 4, z}, {-0.5f, 4, z}, {-0.5f, -4, z}, 0);
    test::add_quad(scene, "roof_e", {0.5f, -4, z}, {0.5f, 4, z}, {4, 4, z}, {4, -4, z}, 0);
    test::add_quad(scene, "roof_s", {-0.5f, -4, z}, {-0.5f, -0.5f, z}, {0.5f, -0.5f, z}, {0.5f, -4, z}, 0);
    test::add_quad(scene, "roof_n", {-0.5f, 0.5f, z}, {-0.5f, 4, z}, {0.5f, 4, z}, {0.5f, 0.5f, z}, 0);
    scene.set_background(glm::vec3(1.0f));
    const Camera camera = test::look_at({0, 0, 0.9f}, {0, 0, 0}, 16, 16, 90.0f, {0, 1, 0});
    RenderControl control;
    Stats stats;
    const ViewSamples vs = generate_view_samples(scene, camera, ViewSampleSettings{}, control, stats);
    constexpr int kSeeds = 64;
    std::vector<double> sum(vs.samples.size(), 0.0), sum2(vs.samples.size(), 0.0);
    for (int seed = 0; seed < kSeeds; ++seed) {
        DirectLightSettings settings;
        settings.seed = uint64_t(seed);
        settings.samples_per_light = samples;
        const std::vector<glm::vec3> direct = compute_direct_light(scene, vs, settings, control, stats);
        for (size_t i = 0; i < direct.size(); ++i) {
            sum[i] += direct[i].x;
            sum2[i] += double(direct[i].x) * direct[i].x;
        }
    }
    double variance = 0.0;
    for (size_t i = 0; i < sum.size(); ++i) variance += sum2[i] / kSeeds - (sum[i] / kSeeds) * (sum[i] / kSeeds);
    return variance / double(sum.size());
}

TEST(DirectLight, ShadowRaysOfALightAreStratified) {
    // n independent rays would have 1/n of one ray's variance; stratified over the light's sampling square they
    // cover the opening evenly and do better where visibility changes smoothly with direction: about 0.83 of
    // that with 4 rays and 0.60 with 16 (the strata of 4 are coarse rings and half-discs of the hemisphere),
    // under the bounds below with room for the seeds' noise.
    const double one = sky_through_opening_variance(1);
    const double four = sky_through_opening_variance(4);
    const double sixteen = sky_through_opening_variance(16);
    ASSERT_GT(one, 0.0);
    EXPECT_LT(four, 0.92 * one / 4.0) << "one ray " << one << ", four " << four;
    EXPECT_LT(sixteen, 0.75 * one / 16.0) << "one ray " << one << ", sixteen " << sixteen;
}

}  // namespace
