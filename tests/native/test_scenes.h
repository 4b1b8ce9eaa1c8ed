// Small scenes built in code for the native tests: a Cornell box with a glass and a mirror sphere, a plane.
#pragma once
#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>

#include "photonsplat/camera.h"
#include "photonsplat/scene.h"

namespace ps::test {

// A mesh of vertex_count vertices (xyz each) and triangle_count triangles (three vertex indices each), with a
// material per triangle where `materials` is given (else material 0), placed by `transform`.
inline MeshInput mesh_input(const char* name, const float* vertices, size_t vertex_count, const int32_t* triangles,
                            size_t triangle_count, const int32_t* materials = nullptr,
                            const glm::dmat4& transform = glm::dmat4(1.0)) {
    MeshInput mesh;
    mesh.name = name;
    mesh.vertices = vertices;
    mesh.vertex_count = vertex_count;
    mesh.triangles = triangles;
    mesh.triangle_count = triangle_count;
    mesh.material_ids = materials;
    mesh.transform = transform;
    return mesh;
}

inline void add_quad(Scene& scene, const char* name, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d,
                     uint32_t material, const glm::dmat4& transform = glm::dmat4(1.0)) {
    const float v[12] = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, d.x, d.y, d.z};
    const int32_t t[6] = {0, 1, 2, 0, 2, 3};
    const int32_t m[2] = {static_cast<int32_t>(material), static_cast<int32_t>(material)};
    scene.add_mesh(mesh_input(name, v, 4, t, 2, m, transform));
}

// The square [-half, half]² of the z = 0 plane, named "plane", facing +z.
inline void add_ground(Scene& scene, float half, uint32_t material = 0) {
    add_quad(scene, "plane", {-half, -half, 0}, {half, -half, 0}, {half, half, 0}, {-half, half, 0}, material);
}

// A mesh from flat arrays: xyz per vertex, three vertex indices and one material per triangle, optional normals.
inline void add_mesh(Scene& scene, const char* name, const std::vector<float>& v, const std::vector<int32_t>& t,
                     const std::vector<int32_t>& m, const std::vector<float>* normals = nullptr,
                     const glm::dmat4& transform = glm::dmat4(1.0)) {
    MeshInput mesh = mesh_input(name, v.data(), v.size() / 3, t.data(), t.size() / 3, m.data(), transform);
    mesh.normals = normals ? normals->data() : nullptr;
    scene.add_mesh(mesh);
}

inline void add_sphere(Scene& scene, const char* name, glm::vec3 center, float radius, uint32_t material,
                       int rings = 24, int segments = 48) {
    std::vector<float> v, n;
    std::vector<int32_t> t, m;
    for (int i = 0; i <= rings; ++i) {
        const float theta = 3.14159265f * i / rings;
        for (int j = 0; j <= segments; ++j) {
            const float phi = 2.0f * 3.14159265f * j / segments;
            glm::vec3 dir(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
            glm::vec3 p = center + radius * dir;
            v.insert(v.end(), {p.x, p.y, p.z});
            n.insert(n.end(), {dir.x, dir.y, dir.z});
        }
    }
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const int a = i * (segments + 1) + j, b = a + segments + 1;
            t.insert(t.end(), {a, b, a + 1, a + 1, b, b + 1});
            m.insert(m.end(), {static_cast<int32_t>(material), static_cast<int32_t>(material)});
        }
    add_mesh(scene, name, v, t, m, &n);  // degenerate pole triangles are dropped by the scene
}

// Z up, box [-1,1]×[-1,1]×[0,2] open towards −y, a small point light under the ceiling.
inline void build_cornell_box(Scene& scene, bool with_spheres) {
    const uint32_t white = scene.add_material({"white", MaterialKind::diffuse, glm::vec3(0.75f), 1.45f, glm::vec3(0.0f)});
    const uint32_t red = scene.add_material({"red", MaterialKind::diffuse, glm::vec3(0.75f, 0.1f, 0.1f), 1.45f, glm::vec3(0.0f)});
    const uint32_t green = scene.add_material({"green", MaterialKind::diffuse, glm::vec3(0.1f, 0.75f, 0.1f), 1.45f, glm::vec3(0.0f)});
    add_quad(scene, "floor", {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, white);
    add_quad(scene, "ceiling", {-1, -1, 2}, {-1, 1, 2}, {1, 1, 2}, {1, -1, 2}, white);
    add_quad(scene, "back", {-1, 1, 0}, {1, 1, 0}, {1, 1, 2}, {-1, 1, 2}, white);
    add_quad(scene, "left", {-1, -1, 0}, {-1, 1, 0}, {-1, 1, 2}, {-1, -1, 2}, red);
    add_quad(scene, "right", {1, -1, 0}, {1, -1, 2}, {1, 1, 2}, {1, 1, 0}, green);
    if (with_spheres) {
        const uint32_t glass = scene.add_material({"glass", MaterialKind::glass, glm::vec3(1.0f), 1.5f, glm::vec3(0.0f)});
        const uint32_t mirror = scene.add_material({"mirror", MaterialKind::mirror, glm::vec3(0.95f), 1.45f, glm::vec3(0.0f)});
        add_sphere(scene, "glass_sphere", {-0.4f, 0.1f, 0.4f}, 0.4f, glass);
        add_sphere(scene, "mirror_sphere", {0.45f, 0.4f, 0.3f}, 0.3f, mirror);
    }
    Light light;
    light.name = "lamp";
    light.kind = LightKind::point;
    light.position = {0.0f, 0.0f, 1.8f};
    light.value = glm::vec3(100.0f / (4.0f * 3.14159265f));  // a 100 W Blender point light
    light.radius = 0.02f;
    scene.add_light(light);
}

inline glm::mat4 perspective(float fov_y_degrees, float aspect, float near, float far) {
    const float f = 1.0f / std::tan(fov_y_degrees * 3.14159265f / 360.0f);
    glm::mat4 p(0.0f);
    p[0][0] = f / aspect;
    p[1][1] = f;
    p[2][2] = (far + near) / (near - far);
    p[3][2] = 2.0f * far * near / (near - far);
    p[2][3] = -1.0f;
    return p;
}

inline glm::mat4 look_at_matrix(glm::vec3 eye, glm::vec3 target, glm::vec3 up = {0, 0, 1}) {
    const glm::vec3 forward = glm::normalize(target - eye);
    const glm::vec3 right = glm::normalize(glm::cross(forward, up));
    const glm::vec3 true_up = glm::cross(right, forward);
    glm::mat4 to_world(1.0f);
    to_world[0] = glm::vec4(right, 0.0f);
    to_world[1] = glm::vec4(true_up, 0.0f);
    to_world[2] = glm::vec4(-forward, 0.0f);
    to_world[3] = glm::vec4(eye, 1.0f);
    return to_world;
}

inline Camera look_at(glm::vec3 eye, glm::vec3 target, int width, int height, float fov_y = 40.0f,
                      glm::vec3 up = {0, 0, 1}, float near = 0.1f) {
    return Camera(look_at_matrix(eye, target, up), perspective(fov_y, static_cast<float>(width) / height, near, 1000.0f * near),
                  width, height);
}

inline Camera cornell_camera(int width, int height) { return look_at({0, -3.9f, 1}, {0, 0, 1}, width, height); }

// An axis-aligned closed box [lo, hi] as 12 triangles (faces wound outwards; materials are double-sided).
inline void add_box(Scene& scene, const char* name, glm::vec3 lo, glm::vec3 hi, uint32_t material,
                    const glm::dmat4& transform = glm::dmat4(1.0)) {
    const glm::vec3 c[8] = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z},
                            {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
    const int q[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {3, 7, 6, 2}, {0, 4, 7, 3}, {1, 2, 6, 5}};
    std::vector<float> v;
    std::vector<int32_t> t, m;
    for (const auto& face : q) {
        const int32_t base = static_cast<int32_t>(v.size() / 3);
        for (int k = 0; k < 4; ++k) v.insert(v.end(), {c[face[k]].x, c[face[k]].y, c[face[k]].z});
        t.insert(t.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
        m.insert(m.end(), {static_cast<int32_t>(material), static_cast<int32_t>(material)});
    }
    add_mesh(scene, name, v, t, m, nullptr, transform);
}

inline Light point_light(const char* name, glm::vec3 position, float watts, float radius = 0.0f) {
    Light light;
    light.name = name;
    light.kind = LightKind::point;
    light.position = position;
    light.value = glm::vec3(watts / (4.0f * 3.14159265f));  // Blender's point light of `watts`
    light.radius = radius;
    return light;
}

// A sun of `irradiance` travelling along `direction` (unit).
inline Light sun_light(glm::vec3 direction, glm::vec3 irradiance) {
    Light light;
    light.kind = LightKind::sun;
    light.direction = direction;
    light.value = irradiance;
    return light;
}

// The Cornell box scaled by `scale` and moved by `offset`, lamp power scaled by scale² so that irradiance (and
// so the image) does not change; its camera likewise (near clip scaled too).
inline void build_transformed_cornell_box(Scene& scene, float scale, glm::vec3 offset) {
    const uint32_t white = scene.add_material({"white", MaterialKind::diffuse, glm::vec3(0.75f), 1.45f, glm::vec3(0.0f)});
    const uint32_t red = scene.add_material({"red", MaterialKind::diffuse, glm::vec3(0.75f, 0.1f, 0.1f), 1.45f, glm::vec3(0.0f)});
    const uint32_t glass = scene.add_material({"glass", MaterialKind::glass, glm::vec3(1.0f), 1.5f, glm::vec3(0.0f)});
    auto P = [&](float x, float y, float z) { return offset + scale * glm::vec3(x, y, z); };
    add_quad(scene, "floor", P(-1, -1, 0), P(1, -1, 0), P(1, 1, 0), P(-1, 1, 0), white);
    add_quad(scene, "ceiling", P(-1, -1, 2), P(-1, 1, 2), P(1, 1, 2), P(1, -1, 2), white);
    add_quad(scene, "back", P(-1, 1, 0), P(1, 1, 0), P(1, 1, 2), P(-1, 1, 2), white);
    add_quad(scene, "left", P(-1, -1, 0), P(-1, 1, 0), P(-1, 1, 2), P(-1, -1, 2), red);
    add_quad(scene, "right", P(1, -1, 0), P(1, -1, 2), P(1, 1, 2), P(1, 1, 0), white);
    add_box(scene, "glass_block", P(-0.5f, -0.2f, 0.0f), P(0.0f, 0.3f, 0.6f), glass);
    scene.add_light(point_light("lamp", P(0.0f, 0.0f, 1.8f), 100.0f * scale * scale));
}

inline Camera transformed_cornell_camera(float scale, glm::vec3 offset, int width, int height) {
    return look_at(offset + scale * glm::vec3(0, -3.9f, 1), offset + scale * glm::vec3(0, 0, 1), width, height, 40.0f,
                   {0, 0, 1}, 0.1f * scale);
}

// The Cornell box above (scale 1) the way Blender gives a scene moved by `offset`: every mesh in object space,
// placed by an object-to-world transform whose translation is `offset`; the lamp and the camera at offset +
// their place, in double. Without the box's ties (see SameImageMovedBy1e3And1e5): the glass block stands 1 cm
// above the floor, and the camera is off the box's symmetry plane. in_vertices: the offset is in the vertices
// instead (float32, rounded to its spacing there), the transforms are the identity.
inline void build_moved_cornell_box(Scene& scene, glm::dvec3 offset, bool in_vertices = false) {
    const uint32_t white = scene.add_material({"white", MaterialKind::diffuse, glm::vec3(0.75f), 1.45f, glm::vec3(0.0f)});
    const uint32_t red = scene.add_material({"red", MaterialKind::diffuse, glm::vec3(0.75f, 0.1f, 0.1f), 1.45f, glm::vec3(0.0f)});
    const uint32_t glass = scene.add_material({"glass", MaterialKind::glass, glm::vec3(1.0f), 1.5f, glm::vec3(0.0f)});
    // The lamp first: the render origin moves as the meshes are added, and re-expresses it (scene.h).
    scene.add_light(point_light("lamp", {}, 100.0f), offset + glm::dvec3(0.0, 0.0, 1.8f));
    glm::dmat4 moved(1.0);
    if (!in_vertices) moved[3] = glm::dvec4(offset, 1.0);
    auto P = [&](float x, float y, float z) {
        return in_vertices ? glm::vec3(offset + glm::dvec3(x, y, z)) : glm::vec3(x, y, z);
    };
    add_quad(scene, "floor", P(-1, -1, 0), P(1, -1, 0), P(1, 1, 0), P(-1, 1, 0), white, moved);
    add_quad(scene, "ceiling", P(-1, -1, 2), P(-1, 1, 2), P(1, 1, 2), P(1, -1, 2), white, moved);
    add_quad(scene, "back", P(-1, 1, 0), P(1, 1, 0), P(1, 1, 2), P(-1, 1, 2), white, moved);
    add_quad(scene, "left", P(-1, -1, 0), P(-1, 1, 0), P(-1, 1, 2), P(-1, -1, 2), red, moved);
    add_quad(scene, "right", P(1, -1, 0), P(1, -1, 2), P(1, 1, 2), P(1, 1, 0), white, moved);
    add_box(scene, "glass_block", P(-0.5f, -0.2f, 0.01f), P(0.0f, 0.3f, 0.6f), glass, moved);
}

inline Camera moved_cornell_camera(glm::dvec3 offset, int width, int height) {
    const glm::vec3 eye(0.11f, -3.9f, 1.07f);
    glm::dmat4 to_world(look_at_matrix(eye, {0, 0, 1}));
    to_world[3] = glm::dvec4(offset + glm::dvec3(eye), 1.0);
    return Camera(to_world, perspective(40.0f, static_cast<float>(width) / height, 0.1f, 100.0f), width, height);
}

// Straight down at the origin from `height`, 64 × 64 pixels: a plane perpendicular to the view maps the image
// grid to an even grid on it.
inline Camera top_down_camera(float height) { return look_at({0, 0, height}, {0, 0, 0}, 64, 64, 40.0f, {0, 1, 0}); }

// The fraction of a disc of radius r centred a distance d from a straight edge that lies beyond it.
inline double disc_beyond_edge(double d, double r) {
    if (d >= r) return 0.0;
    const double c = d / r;
    return (std::acos(c) - c * std::sqrt(1.0 - c * c)) / M_PI;
}

}  // namespace ps::test
