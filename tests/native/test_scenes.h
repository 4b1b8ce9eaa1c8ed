// Small scenes built in code for the native tests: a Cornell box with a glass and a mirror sphere, a plane.
#pragma once
#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>

#include "photonsplat/camera.h"
#include "photonsplat/scene.h"

namespace ps::test {

inline void add_quad(Scene& scene, const char* name, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d,
                     uint32_t material) {
    const float v[12] = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, d.x, d.y, d.z};
    const int32_t t[6] = {0, 1, 2, 0, 2, 3};
    const int32_t m[2] = {static_cast<int32_t>(material), static_cast<int32_t>(material)};
    MeshInput mesh;
    mesh.name = name;
    mesh.vertices = v;
    mesh.vertex_count = 4;
    mesh.triangles = t;
    mesh.triangle_count = 2;
    mesh.material_ids = m;
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
    MeshInput mesh;
    mesh.name = name;
    mesh.vertices = v.data();
    mesh.vertex_count = v.size() / 3;
    mesh.triangles = t.data();
    mesh.triangle_count = t.size() / 3;
    mesh.normals = n.data();
    mesh.material_ids = m.data();
    scene.add_mesh(mesh);  // degenerate pole triangles are dropped by the scene
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

inline Camera look_at(glm::vec3 eye, glm::vec3 target, int width, int height, float fov_y = 40.0f,
                      glm::vec3 up = {0, 0, 1}) {
    const glm::vec3 forward = glm::normalize(target - eye);
    const glm::vec3 right = glm::normalize(glm::cross(forward, up));
    const glm::vec3 true_up = glm::cross(right, forward);
    glm::mat4 to_world(1.0f);
    to_world[0] = glm::vec4(right, 0.0f);
    to_world[1] = glm::vec4(true_up, 0.0f);
    to_world[2] = glm::vec4(-forward, 0.0f);
    to_world[3] = glm::vec4(eye, 1.0f);
    return Camera(to_world, perspective(fov_y, static_cast<float>(width) / height, 0.1f, 100.0f), width, height);
}

inline Camera cornell_camera(int width, int height) { return look_at({0, -3.9f, 1}, {0, 0, 1}, width, height); }

}  // namespace ps::test
