// Smooth normals under a stretching transform (Scene::normals_in_world): an instance of a mesh no other instance
// shows turns each corner normal into the world and normalises it before interpolating, as Cycles does where it
// applied the transform; a mesh several instances show interpolates in object space and turns the result.
#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "photonsplat/ray_tracer.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"

namespace {

using namespace ps;

// One triangle in z = 0 whose three corner normals lean apart (a coarse smooth mesh).
uint32_t leaning_corners(Scene& scene) {
    if (scene.materials().empty())
        scene.add_material({"grey", MaterialKind::diffuse, glm::vec3(0.5f), 1.45f, glm::vec3(0.0f)});
    static const std::vector<float> v = {-1, -1, 0, 1, -1, 0, 0, 1, 0};
    static const std::vector<int32_t> t = {0, 1, 2};
    static std::vector<float> n;
    n.clear();
    for (const glm::vec3 c : {glm::vec3(-0.6f, -0.2f, 1.0f), glm::vec3(0.7f, -0.3f, 1.0f), glm::vec3(0.1f, 0.8f, 1.0f)}) {
        const glm::vec3 u = glm::normalize(c);
        n.insert(n.end(), {u.x, u.y, u.z});
    }
    MeshInput mesh;
    mesh.name = "leaning";
    mesh.vertices = v.data();
    mesh.vertex_count = 3;
    mesh.triangles = t.data();
    mesh.triangle_count = 1;
    mesh.normals = n.data();
    return scene.add_mesh_data(mesh);
}

glm::vec3 normal_at(const Scene& scene, uint32_t instance, float u, float v) {
    Hit hit;
    hit.instance = instance;
    hit.triangle = 0;
    hit.u = u;
    hit.v = v;
    hit.t = 1.0f;
    // Straight down onto the triangle's placed plane, from above its point.
    const Instance& placed = scene.instances()[instance];
    const glm::vec3 p = glm::vec3(placed.to_world * glm::vec4((1 - u - v) * glm::vec3(-1, -1, 0) +
                                                                  u * glm::vec3(1, -1, 0) + v * glm::vec3(0, 1, 0),
                                                              1.0f));
    const glm::vec3 up = glm::normalize(placed.normal_to_world * glm::vec3(0, 0, 1));
    return surface_at(scene, Ray{p + up, -up}, hit).smooth_normal;
}

// Cycles' two ways, from the object-space corner normals and the transform's normal matrix.
glm::vec3 turned_first(const glm::mat3& to_world_normals, float u, float v, const std::vector<glm::vec3>& n) {
    const auto w = [&](int c) { return glm::normalize(to_world_normals * n[c]); };
    return glm::normalize((1 - u - v) * w(0) + u * w(1) + v * w(2));
}
glm::vec3 interpolated_first(const glm::mat3& to_world_normals, float u, float v, const std::vector<glm::vec3>& n) {
    return glm::normalize(to_world_normals * ((1 - u - v) * n[0] + u * n[1] + v * n[2]));
}

TEST(StretchedNormals, AMeshShownOnceTurnsItsCornerNormalsBeforeInterpolating) {
    const glm::dmat4 stretch = glm::scale(glm::rotate(glm::dmat4(1.0), 0.7, glm::dvec3(0.3, 1.0, 0.2)),
                                          glm::dvec3(1.31, 0.78, 1.27));
    const std::vector<glm::vec3> n = {glm::normalize(glm::vec3(-0.6f, -0.2f, 1.0f)),
                                      glm::normalize(glm::vec3(0.7f, -0.3f, 1.0f)),
                                      glm::normalize(glm::vec3(0.1f, 0.8f, 1.0f))};
    Scene once;
    const uint32_t mesh = leaning_corners(once);
    const uint32_t alone = once.add_instance(mesh, stretch, "alone");
    const glm::mat3 nm = once.instances()[alone].normal_to_world;
    EXPECT_TRUE(once.instances()[alone].stretched);
    EXPECT_TRUE(once.normals_in_world(once.instances()[alone]));
    const glm::vec3 got = normal_at(once, alone, 0.2f, 0.5f);
    const glm::vec3 cycles = turned_first(nm, 0.2f, 0.5f, n), other = interpolated_first(nm, 0.2f, 0.5f, n);
    EXPECT_GT(glm::length(cycles - other), 1e-3f);  // the stretch makes the two ways differ here
    EXPECT_NEAR(glm::length(got - cycles), 0.0f, 1e-5f);

    // The same mesh shown twice: object space, for both.
    Scene twice;
    const uint32_t shared = leaning_corners(twice);
    const uint32_t first = twice.add_instance(shared, stretch, "first");
    twice.add_instance(shared, glm::translate(glm::dmat4(1.0), glm::dvec3(10, 0, 0)) * stretch, "second");
    EXPECT_FALSE(twice.normals_in_world(twice.instances()[first]));
    EXPECT_NEAR(glm::length(normal_at(twice, first, 0.2f, 0.5f) - other), 0.0f, 1e-5f);
}

TEST(StretchedNormals, ARotationAndAUniformScaleDoNotStretch) {
    Scene scene;
    const uint32_t mesh = leaning_corners(scene);
    const glm::dmat4 turn = glm::scale(glm::rotate(glm::dmat4(1.0), 1.1, glm::dvec3(1.0, 0.4, -0.3)), glm::dvec3(2.5));
    const uint32_t id = scene.add_instance(mesh, turn, "turned");
    EXPECT_FALSE(scene.instances()[id].stretched);
    EXPECT_FALSE(scene.normals_in_world(scene.instances()[id]));
    // Mirrored (a negative scale on one axis) is no stretch either.
    const uint32_t mirrored = scene.add_instance(leaning_corners(scene), glm::scale(glm::dmat4(1.0), glm::dvec3(-1, 1, 1)));
    EXPECT_FALSE(scene.instances()[mirrored].stretched);
}

}  // namespace
