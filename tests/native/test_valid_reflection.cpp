// The closures' normal on smooth meshes (scattering.h, SurfacePoint::shading_normal): Cycles 3.x tilts the
// interpolated normal towards the triangle just enough that the view's mirror image stays above the triangle.
#include <cmath>

#include <gtest/gtest.h>

#include "photonsplat/ray_tracer.h"
#include "photonsplat/scattering.h"
#include "test_support.h"

namespace {

using namespace ps;

constexpr float kDegree = 0.01745329251994329577f;
constexpr float kLean = 30.0f * kDegree, kView = 40.0f * kDegree;

// One triangle in z = 0 whose corner normals all lean 30° towards +x: the normals of a coarse smooth mesh near
// its silhouette.
void leaning_triangle(Scene& scene) {
    scene.add_material({"mirror", MaterialKind::mirror, glm::vec3(0.9f), 1.45f, glm::vec3(0.0f)});
    const float s = std::sin(kLean), c = std::cos(kLean);
    const std::vector<float> v = {-1, -1, 0, 1, -1, 0, 0, 1, 0};
    const std::vector<float> n = {s, 0, c, s, 0, c, s, 0, c};
    test::add_mesh(scene, "leaning", v, {0, 1, 2}, {0}, &n);
}

SurfacePoint seen_along(const Scene& scene, const glm::vec3& direction) {
    Hit hit;
    hit.u = hit.v = 1.0f / 3.0f;
    hit.t = 1.0f;
    return surface_at(scene, Ray{-direction, direction}, hit);
}

glm::vec3 mirror_of(const glm::vec3& wo, const glm::vec3& n) { return 2.0f * glm::dot(wo, n) * n - wo; }

TEST(ValidReflection, AGrazingViewReflectsAboveTheTriangle) {
    Scene scene;
    leaning_triangle(scene);
    // From −x, 40° above the triangle (and above the leaning normal's horizon): about the leaning normal the view
    // would reflect into the triangle.
    const glm::vec3 wo = glm::normalize(glm::vec3(-std::cos(kView), 0.0f, std::sin(kView)));
    const SurfacePoint s = seen_along(scene, -wo);
    const glm::vec3 ng = s.geometric_normal;
    ASSERT_NEAR(ng.z, 1.0f, 1e-6f);
    EXPECT_LT(glm::dot(mirror_of(wo, s.smooth_normal), ng), 0.0f);  // the untilted normal's mirror image: below
    // The tilted one: as shallow as Cycles allows (min(0.9 ng·wo, 0.01)) and no shallower.
    const float reflected = glm::dot(mirror_of(wo, s.shading_normal), ng);
    EXPECT_NEAR(reflected, std::min(0.9f * glm::dot(ng, wo), 0.01f), 1e-3f);
    EXPECT_NEAR(glm::length(s.shading_normal), 1.0f, 1e-5f);
    EXPECT_NEAR(s.shading_normal.y, 0.0f, 1e-6f);                        // turned within the plane of n and ng
    EXPECT_GT(glm::dot(s.shading_normal, ng), glm::dot(s.smooth_normal, ng));  // towards the triangle's normal
    EXPECT_GT(s.shading_normal.x, 0.0f);                                  // but not past it
    EXPECT_GT(glm::dot(s.shading_normal, wo), 0.0f);
}

TEST(ValidReflection, OtherViewsKeepTheInterpolatedNormal) {
    Scene scene;
    leaning_triangle(scene);
    for (const glm::vec3 wo : {glm::vec3(0, 0, 1), glm::normalize(glm::vec3(1, 0, 0.3f)),
                               glm::normalize(glm::vec3(0.2f, 0.5f, 1.0f))}) {
        const SurfacePoint s = seen_along(scene, -wo);
        EXPECT_GT(glm::dot(mirror_of(wo, s.smooth_normal), s.geometric_normal), 0.01f);
        EXPECT_EQ(s.shading_normal, s.smooth_normal);
    }
    // Flat shading has nothing to tilt.
    Scene flat;
    flat.add_material({"mirror", MaterialKind::mirror, glm::vec3(0.9f), 1.45f, glm::vec3(0.0f)});
    test::add_mesh(flat, "flat", {-1, -1, 0, 1, -1, 0, 0, 1, 0}, {0, 1, 2}, {0});
    const SurfacePoint f = seen_along(flat, -glm::normalize(glm::vec3(1.0f, 0.0f, 0.05f)));
    EXPECT_EQ(f.shading_normal, f.geometric_normal);
}

}  // namespace
