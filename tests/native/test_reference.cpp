// The reference renderer's building blocks: light hits agree with light sampling (what MIS relies on), the
// render is deterministic for any thread count, cancels, and refuses bad settings. The analytic and Cycles
// cross-checks are in tests/python/test_reference.py and tests/blender/test_reference_cycles.py.
#include <cmath>

#include <gtest/gtest.h>

#include "photonsplat/errors.h"
#include "photonsplat/light_sources.h"
#include "photonsplat/lights.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/reference.h"
#include "photonsplat/render_control.h"
#include "photonsplat/rng.h"
#include "test_scenes.h"

namespace {

using namespace ps;

// For every light with a size: the direction sample_light_incidence draws, traced back with intersect_light,
// hits the light at the sampled distance with the same density, and radiance / pdf = value.
TEST(Reference, LightHitsAgreeWithLightSampling) {
    std::vector<Light> lights(7);
    lights[0].kind = LightKind::point;
    lights[0].position = {0.2f, 0.1f, 2.0f};
    lights[0].radius = 0.3f;
    lights[0].value = glm::vec3(5.0f);
    lights[1].kind = LightKind::area;
    lights[1].position = {-0.5f, 0.3f, 1.5f};
    lights[1].axis_u = {0.8f, 0.0f, 0.1f};
    lights[1].axis_v = {0.0f, -0.5f, 0.0f};  // emits towards cross(u, v): downwards
    lights[1].value = glm::vec3(3.0f);
    lights[2].kind = LightKind::sun;
    lights[2].direction = {0.3f, 0.2f, -1.0f};
    lights[2].angle = 0.1f;
    lights[2].value = glm::vec3(2.0f);
    lights[3].kind = LightKind::spot;  // a spot with a size is a disc like the point light's, times its cone
    lights[3].position = {0.4f, -0.3f, 1.8f};
    lights[3].direction = glm::vec3(0.1f, -0.2f, 0.0f) - lights[3].position;
    lights[3].radius = 0.25f;
    lights[3].spot_size = 1.2f;
    lights[3].spot_blend = 0.4f;
    lights[3].value = glm::vec3(4.0f);
    lights[4] = lights[0];  // the point light as a true sphere (Cycles 4.x, Soft Falloff off)
    lights[4].sphere = true;
    lights[5] = lights[3];  // the spot as a sphere, with Cycles 4.x's falloff
    lights[5].sphere = true;
    lights[5].spot_cosine = false;
    lights[6] = lights[1];  // a disk or ellipse light: the ellipse inscribed in the rectangle
    lights[6].ellipse = true;
    const glm::vec3 x(0.1f, -0.2f, 0.0f);
    Rng rng(1, RngDomain::camera, 0);
    for (const Light& light : lights) {
        int hits = 0;
        for (int i = 0; i < 200; ++i) {
            const LightIncidence in = sample_light_incidence(light, x, rng.uniform(), rng.uniform());
            if (in.value == glm::vec3(0.0f)) continue;
            const LightHit h = intersect_light(light, x, in.wi);
            ASSERT_TRUE(h.hit) << to_string(light.kind);
            ++hits;
            EXPECT_NEAR(h.pdf / in.pdf, 1.0, 1e-3) << to_string(light.kind);
            if (std::isfinite(in.distance)) EXPECT_NEAR(h.distance / in.distance, 1.0, 1e-4);
            EXPECT_NEAR(h.radiance.x / h.pdf / in.value.x, 1.0, 1e-3) << to_string(light.kind);
        }
        EXPECT_GT(hits, 150);
        // A direction well away from the light misses it.
        EXPECT_FALSE(intersect_light(light, x, glm::vec3(0.0f, 0.0f, -1.0f)).hit);
    }
    // An ellipse light is seen as an ellipse, not as its rectangle: seed 156 of the differential runs showed a
    // disk light's square to the camera, 4/π of Cycles' brightness there.
    const Light& ellipse = lights[6];
    const auto towards = [&](float a, float b) {
        return glm::normalize(ellipse.position + a * ellipse.axis_u + b * ellipse.axis_v - x);
    };
    EXPECT_TRUE(intersect_light(ellipse, x, towards(0.3f, 0.3f)).hit);     // a² + b² = 0.18 < 1/4
    EXPECT_FALSE(intersect_light(ellipse, x, towards(0.4f, 0.4f)).hit);    // inside the rectangle, outside the ellipse
    EXPECT_TRUE(intersect_light(lights[1], x, towards(0.4f, 0.4f)).hit);   // the rectangle light itself
    Light delta;
    delta.position = {0, 0, 1};
    EXPECT_FALSE(intersect_light(delta, x, glm::normalize(delta.position - x)).hit);
}

TEST(Reference, EmissivePdfAgreesWithEmitterSampling) {
    Scene scene;
    Material lamp;
    lamp.name = "lamp";
    lamp.emission = glm::vec3(2.0f);
    scene.add_material(lamp);
    test::add_quad(scene, "lamp", {-1, -1, 2}, {1, -1, 2}, {1, 1, 2.5f}, {-1, 1, 2.5f}, 0);
    const LightSources sources(scene);
    ASSERT_EQ(sources.size(), 1u);
    const glm::vec3 x(0.3f, 0.2f, 0.0f), n(0, 0, 1);
    Rng rng(2, RngDomain::camera, 0);
    for (int i = 0; i < 100; ++i) {
        const LightIncidence in = sources.sample_incidence(0, x, n, rng.uniform(), rng.uniform(), rng.uniform());
        // Which triangle: the one the ray from x meets.
        const RayTracer& tracer = scene.ray_tracer();
        Hit hit;
        ASSERT_TRUE(tracer.intersect(Ray{x, in.wi}, 0.0f, 100.0f, hit));
        EXPECT_NEAR(sources.emissive_pdf(hit.instance, hit.triangle, x, x + hit.t * in.wi) / in.pdf, 1.0, 1e-3);
    }
}

TEST(Reference, DeterministicForAnyThreadCountAndCancellable) {
    Scene scene;
    test::build_cornell_box(scene, true);
    const Camera camera = test::cornell_camera(24, 24);
    ReferenceSettings settings;
    settings.samples = 2;
    settings.caustic_photons = 4000;
    RenderControl control;
    settings.threads = 1;
    const ReferenceResult one = render_reference(scene, camera, settings, control);
    settings.threads = 3;
    const ReferenceResult three = render_reference(scene, camera, settings, control);
    EXPECT_EQ(one.rgba, three.rgba);
    EXPECT_EQ(one.stats.values.at("samples"), 2.0);
    RenderControl cancelled;
    cancelled.request_cancel();
    EXPECT_THROW(render_reference(scene, camera, settings, cancelled), Cancelled);
}

TEST(Reference, RefusesBadSettings) {
    ReferenceSettings s;
    s.samples = 0;
    EXPECT_THROW(validate(s), InvalidInput);
    s = ReferenceSettings{};
    s.time_limit = -1.0;
    EXPECT_THROW(validate(s), InvalidInput);
    s = ReferenceSettings{};
    s.caustic_radius = std::nanf("");
    EXPECT_THROW(validate(s), InvalidInput);
}

}  // namespace
