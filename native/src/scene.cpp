#include "photonsplat/scene.h"

#include <cmath>
#include <limits>
#include <mutex>
#include <string>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include "photonsplat/errors.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/validation.h"

namespace ps {

namespace {

std::mutex& ray_tracer_mutex() {
    static std::mutex m;
    return m;
}

}  // namespace

Scene::Scene() = default;
Scene::~Scene() = default;

uint32_t Scene::add_material(const Material& material) {
    validate(material, "material '" + material.name + "'");
    materials_.push_back(material);
    return static_cast<uint32_t>(materials_.size() - 1);
}

void Scene::add_light(const Light& light) {
    validate(light, std::string(to_string(light.kind)) + " light '" + light.name + "'");
    lights_.push_back(light);
}

void Scene::set_background(const glm::vec3& radiance) {
    require_nonnegative_rgb(radiance, "background");
    background_ = radiance;
}

void Scene::add_mesh(const MeshInput& mesh) {
    const std::string where = "mesh '" + mesh.name + "'";
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(mesh.transform[c][r]))
                throw InvalidInput(where + ".transform", "contains NaN or infinity");
    if (mesh.vertex_count > 0 && mesh.vertices == nullptr) throw InvalidInput(where + ".vertices", "missing");
    if (mesh.triangle_count > 0 && mesh.triangles == nullptr) throw InvalidInput(where + ".triangles", "missing");
    if (mesh.vertex_count > static_cast<size_t>(std::numeric_limits<int32_t>::max()))
        throw InvalidInput(where + ".vertices", "too many vertices");

    for (size_t i = 0; i < mesh.vertex_count * 3; ++i)
        if (!std::isfinite(mesh.vertices[i]))
            throw InvalidInput(where + ".vertices", "vertex " + std::to_string(i / 3) + " is NaN or infinite");
    for (size_t i = 0; i < mesh.triangle_count * 3; ++i) {
        const int32_t index = mesh.triangles[i];
        if (index < 0 || static_cast<size_t>(index) >= mesh.vertex_count)
            throw InvalidInput(where + ".triangles", "triangle " + std::to_string(i / 3) + " uses vertex " +
                                                         std::to_string(index) + ", but the mesh has " +
                                                         std::to_string(mesh.vertex_count) + " vertices");
    }
    if (mesh.material_ids) {
        for (size_t t = 0; t < mesh.triangle_count; ++t) {
            const int32_t id = mesh.material_ids[t];
            if (id < 0 || static_cast<size_t>(id) >= materials_.size())
                throw InvalidInput(where + ".material_ids",
                                   "triangle " + std::to_string(t) + " uses material " + std::to_string(id) +
                                       ", but the scene has " + std::to_string(materials_.size()) + " materials");
        }
    } else if (materials_.empty() && mesh.triangle_count > 0) {
        throw InvalidInput(where + ".material_ids", "the scene has no material yet; add one first");
    }
    const size_t normal_floats = mesh.normals ? (mesh.normals_per_corner ? mesh.triangle_count * 9 : mesh.vertex_count * 3) : 0;
    for (size_t i = 0; i < normal_floats; ++i)
        if (!std::isfinite(mesh.normals[i]))
            throw InvalidInput(where + ".normals", "normal " + std::to_string(i / 3) + " is NaN or infinite");

    // Everything is valid: transform to world space. Normals go through the inverse transpose.
    const glm::mat4& m = mesh.transform;
    const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(m)));
    const bool mirrored = glm::determinant(glm::mat3(m)) < 0.0f;
    const uint32_t object = static_cast<uint32_t>(object_names_.size());
    object_names_.push_back(mesh.name);

    auto vertex = [&](int32_t i) {
        const float* p = mesh.vertices + 3 * static_cast<size_t>(i);
        return glm::vec3(m * glm::vec4(p[0], p[1], p[2], 1.0f));
    };
    auto normal_at = [&](size_t t, int corner, const glm::vec3& fallback) {
        if (!mesh.normals) return fallback;
        const float* n = mesh.normals_per_corner ? mesh.normals + 9 * t + 3 * corner
                                                 : mesh.normals + 3 * static_cast<size_t>(mesh.triangles[3 * t + corner]);
        glm::vec3 w = normal_matrix * glm::vec3(n[0], n[1], n[2]);
        const float len = glm::length(w);
        return (len > 0.0f && std::isfinite(len)) ? w / len : fallback;
    };

    triangles_.reserve(triangles_.size() + mesh.triangle_count);
    for (size_t t = 0; t < mesh.triangle_count; ++t) {
        Triangle tri;
        tri.v0 = vertex(mesh.triangles[3 * t + 0]);
        tri.v1 = vertex(mesh.triangles[3 * t + 1]);
        tri.v2 = vertex(mesh.triangles[3 * t + 2]);
        glm::vec3 ng = glm::cross(tri.v1 - tri.v0, tri.v2 - tri.v0);
        const float len = glm::length(ng);
        // Zero-area (or, after a huge transform, overflowing or beyond kMaxCoordinate) triangles can neither be
        // hit nor shaded.
        if (!(len > 0.0f) || !std::isfinite(len) || !within_world(tri.v0) || !within_world(tri.v1) ||
            !within_world(tri.v2)) {
            ++dropped_triangles_;
            continue;
        }
        ng /= len;
        if (mirrored) ng = -ng;  // keep the winding's normal consistent with the transformed shading normals
        tri.n0 = normal_at(t, 0, ng);
        tri.n1 = normal_at(t, 1, ng);
        tri.n2 = normal_at(t, 2, ng);
        tri.material = mesh.material_ids ? static_cast<uint32_t>(mesh.material_ids[t]) : 0u;
        tri.object = object;
        if (triangles_.empty()) bounds_min_ = bounds_max_ = tri.v0;
        for (const glm::vec3& v : {tri.v0, tri.v1, tri.v2}) {
            bounds_min_ = glm::min(bounds_min_, v);
            bounds_max_ = glm::max(bounds_max_, v);
        }
        triangles_.push_back(tri);
    }
    std::lock_guard<std::mutex> lock(ray_tracer_mutex());
    ray_tracer_.reset();
}

glm::vec3 Scene::bounds_min() const { return triangles_.empty() ? glm::vec3(-0.5f) : bounds_min_; }
glm::vec3 Scene::bounds_max() const { return triangles_.empty() ? glm::vec3(0.5f) : bounds_max_; }

const RayTracer& Scene::ray_tracer() const {
    std::lock_guard<std::mutex> lock(ray_tracer_mutex());
    if (!ray_tracer_) ray_tracer_ = std::make_unique<RayTracer>(triangles_);
    return *ray_tracer_;
}

}  // namespace ps
