// The scene as the core sees it: triangle meshes in world space with a material per face, lights, and a
// background. Everything is validated on entry (add_*), so later stages never meet NaNs or bad indices.
// Degenerate triangles (zero area, repeated vertices) are dropped and counted, not treated as errors.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "photonsplat/lights.h"
#include "photonsplat/materials.h"

namespace ps {

class RayTracer;

// Input of add_mesh: raw arrays as the bindings receive them.
struct MeshInput {
    std::string name;
    const float* vertices = nullptr;       // vertex_count × 3, object space
    size_t vertex_count = 0;
    const int32_t* triangles = nullptr;    // triangle_count × 3 vertex indices
    size_t triangle_count = 0;
    const float* normals = nullptr;        // optional shading normals, see normals_per_corner
    bool normals_per_corner = false;       // false: vertex_count × 3; true: triangle_count × 3 corners × 3
    const int32_t* material_ids = nullptr; // optional, triangle_count scene material indices (default 0)
    glm::mat4 transform{1.0f};             // object → world
};

// One triangle in world space, ready for shading.
struct Triangle {
    glm::vec3 v0, v1, v2;
    glm::vec3 n0, n1, n2;  // shading normals at the corners (the geometric normal when none were given)
    uint32_t material;
    uint32_t object;       // index into Scene::object_names()
};

class Scene {
public:
    Scene();
    ~Scene();
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    uint32_t add_material(const Material& material);  // returns its index
    void add_mesh(const MeshInput& mesh);
    void add_light(const Light& light);
    void set_background(const glm::vec3& radiance);    // world colour × strength, seen by camera rays

    const std::vector<Material>& materials() const { return materials_; }
    const std::vector<Light>& lights() const { return lights_; }
    const std::vector<Triangle>& triangles() const { return triangles_; }
    const std::vector<std::string>& object_names() const { return object_names_; }
    glm::vec3 background() const { return background_; }
    size_t dropped_triangles() const { return dropped_triangles_; }

    // World-space bounds of all geometry (empty scene: a unit box at the origin).
    glm::vec3 bounds_min() const;
    glm::vec3 bounds_max() const;

    // The Embree acceleration structure, built on first use after the last change. Thread-safe to query.
    const RayTracer& ray_tracer() const;

private:
    std::vector<Material> materials_;
    std::vector<Light> lights_;
    std::vector<Triangle> triangles_;
    std::vector<std::string> object_names_;
    glm::vec3 background_{0.0f};
    glm::vec3 bounds_min_{0.0f}, bounds_max_{0.0f};
    size_t dropped_triangles_ = 0;
    mutable std::unique_ptr<RayTracer> ray_tracer_;
};

}  // namespace ps
