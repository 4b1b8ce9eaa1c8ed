// Cycles' per-light switches in the core: Multiple Importance (Light::multiple_importance) and Cast Shadow
// (Light::cast_shadow). tests/blender/test_light_switches.py renders the same against Cycles 3.4.
#include <gtest/gtest.h>

#include "photonsplat/direct_light.h"
#include "photonsplat/light_sources.h"
#include "photonsplat/lights.h"
#include "test_support.h"

namespace {

using namespace ps;

Light point_light_above(bool cast_shadow) {
    Light light;
    light.kind = LightKind::point;
    light.position = {0.0f, 0.0f, 2.0f};
    light.value = glm::vec3(50.0f);
    light.cast_shadow = cast_shadow;
    return light;
}

// A Lambert floor, with or without a square slab 1 m above it that hides the light from its middle.
std::vector<glm::vec3> floor_direct_light(bool slab, bool cast_shadow) {
    Scene scene;
    scene.add_material({"grey", MaterialKind::diffuse, glm::vec3(0.6f), 1.45f, glm::vec3(0.0f)});
    test::add_ground(scene, 5.0f);
    if (slab) test::add_quad(scene, "slab", {-0.5f, -0.5f, 1}, {0.5f, -0.5f, 1}, {0.5f, 0.5f, 1}, {-0.5f, 0.5f, 1}, 0);
    scene.add_light(point_light_above(cast_shadow));
    // Seen from below the slab's plane, so that the camera sees the floor under it.
    return test::direct_light_view(scene, test::look_at({0, -3, 0.8f}, {0, 0, 0}, 16, 16, 60.0f, {0, 0, 1})).direct;
}

TEST(LightSwitches, ALightWithoutShadowsLightsTheFloorUnderAnOccluderAsIfItWereNotThere) {
    const std::vector<glm::vec3> open = floor_direct_light(false, true);
    const std::vector<glm::vec3> shadowed = floor_direct_light(true, true);
    const std::vector<glm::vec3> shadowless = floor_direct_light(true, false);
    ASSERT_EQ(open.size(), shadowless.size());
    double open_sum = 0.0, shadowed_sum = 0.0;
    for (size_t i = 0; i < open.size(); ++i) {
        open_sum += open[i].x;
        shadowed_sum += shadowed[i].x;
        EXPECT_NEAR(shadowless[i].x, open[i].x, 1e-5f * (1.0f + open[i].x)) << "sample " << i;
    }
    EXPECT_LT(shadowed_sum, 0.9 * open_sum) << "the slab must hide part of the floor when the light casts shadows";
}

TEST(LightSwitches, ALightWithoutMultipleImportanceIsNotFoundByBsdfRaysNorThroughMirrors) {
    Scene scene;
    scene.add_material({"grey", MaterialKind::diffuse, glm::vec3(0.6f), 1.45f, glm::vec3(0.0f)});
    test::add_ground(scene, 5.0f);
    Light area;
    area.kind = LightKind::area;
    area.position = {0, 0, 2};
    area.axis_u = {1, 0, 0};
    area.axis_v = {0, -1, 0};
    area.value = glm::vec3(10.0f);
    scene.add_light(area);
    area.multiple_importance = false;
    area.cast_shadow = false;
    scene.add_light(area);
    const LightSources sources(scene);
    ASSERT_EQ(sources.size(), 2u);
    EXPECT_TRUE(sources.found_by_bsdf_rays(0));
    EXPECT_TRUE(sources.casts_shadow(0));
    EXPECT_FALSE(sources.found_by_bsdf_rays(1));
    EXPECT_FALSE(sources.casts_shadow(1));
    // A photon reflected by a mirror straight from the light stands for a camera path that meets the light by a
    // BSDF ray: it keeps all for a true mirror (pdf 0) with MIS on, nothing with MIS off, whatever the mirror.
    const glm::vec3 x(0.0f), up(0.0f, 0.0f, 1.0f);
    EXPECT_EQ(sources.mirror_weight(0, x, x, up, up, 0.0f), 1.0f);
    EXPECT_EQ(sources.mirror_weight(1, x, x, up, up, 0.0f), 0.0f);
    EXPECT_EQ(sources.mirror_weight(1, x, x, up, up, 10.0f), 0.0f);
}

}  // namespace
