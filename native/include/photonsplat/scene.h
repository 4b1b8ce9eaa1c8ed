// The scene as the core sees it: meshes in object space, instances that place a mesh in the world (a 4×4
// transform each; Embree instancing, so a thousand copies of a mesh cost one mesh), materials, textures,
// lights and a background. Everything is validated on entry (add_*), so later stages never meet NaNs or bad
// indices. Degenerate triangles (zero area, repeated vertices) are dropped and counted, not treated as errors.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "photonsplat/lights.h"
#include "photonsplat/materials.h"
#include "photonsplat/textures.h"

namespace ps {

class RayTracer;

// Input of add_mesh_data / add_mesh: raw arrays as the bindings receive them.
struct MeshInput {
    std::string name;
    const float* vertices = nullptr;       // vertex_count × 3, object space
    size_t vertex_count = 0;
    const int32_t* triangles = nullptr;    // triangle_count × 3 vertex indices
    size_t triangle_count = 0;
    const float* normals = nullptr;        // optional shading normals, see normals_per_corner
    bool normals_per_corner = false;       // false: vertex_count × 3; true: triangle_count × 3 corners × 3
    const float* uvs = nullptr;            // optional texture coordinates, see uvs_per_corner
    bool uvs_per_corner = false;           // false: vertex_count × 2; true: triangle_count × 3 corners × 2
    const int32_t* material_ids = nullptr; // optional, triangle_count scene material indices (default 0)
    glm::mat4 transform{1.0f};             // object → world; used by add_mesh only
};

// Which rays see an instance (Cycles' object ray visibility); a bit set for a ray's kind = the ray can hit it.
enum RayVisibility : uint32_t {
    kCameraRays = 1u,    // the first segment of camera paths
    kShadowRays = 2u,    // direct-light shadow rays
    kIndirectRays = 4u,  // everything else: camera paths after a mirror or glass, photon paths
    kAllRays = 7u,
};

// A mesh in object space, as validated and kept by the scene. Only non-degenerate triangles are kept.
struct MeshData {
    std::string name;
    std::vector<glm::vec3> positions;
    std::vector<uint32_t> indices;      // 3 per triangle
    std::vector<glm::vec3> normals;     // 3 per triangle (corner shading normals); empty: flat shading
    std::vector<glm::vec2> uvs;         // 3 per triangle; empty: no UV map (every UV is 0, 0)
    std::vector<uint32_t> materials;    // 1 per triangle
    glm::vec3 bounds_min{0.0f}, bounds_max{0.0f};

    size_t triangle_count() const { return materials.size(); }
    size_t bytes() const;
};

// A mesh placed in the world.
struct Instance {
    uint32_t mesh;
    std::string name;          // for messages (the Blender object or instance)
    glm::mat4 to_world{1.0f};
    glm::mat3 normal_to_world{1.0f};  // inverse transpose of the linear part
    uint32_t visibility = kAllRays;   // RayVisibility bits
};

// One triangle in world space (corner positions only), e.g. for sampling emissive surfaces.
struct WorldTriangle {
    glm::vec3 v0, v1, v2;
};

class Scene {
public:
    Scene();
    ~Scene();
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    uint32_t add_material(const Material& material);  // returns its index
    uint32_t add_texture(Texture texture);             // returns its index, for Material::texture
    uint32_t add_mesh_data(const MeshInput& mesh);     // object space, not placed anywhere yet; returns its id
    // Places mesh `mesh` in the world; returns the instance id. A transform that flattens the mesh (zero
    // scale) is accepted: the instance then covers nothing and its triangles are counted as dropped.
    uint32_t add_instance(uint32_t mesh, const glm::mat4& to_world, const std::string& name = "",
                          uint32_t visibility = kAllRays);
    // Moves an instance. Cost: O(1) here, then one refit of the top-level BVH (all instances, no triangle
    // touched) at the next render. Not to be called while a render of this scene runs.
    void set_instance_transform(uint32_t instance, const glm::mat4& to_world);
    void add_mesh(const MeshInput& mesh);              // add_mesh_data + add_instance(mesh.transform)
    void add_light(const Light& light);
    // Removes every light, so that moved or edited lights can be added again without rebuilding the meshes or
    // the BVH (lights are read afresh by each render). Not to be called while a render of this scene runs.
    void clear_lights();
    void set_background(const glm::vec3& radiance);    // world colour × strength, seen by camera rays

    const std::vector<Material>& materials() const { return materials_; }
    const std::vector<Texture>& textures() const { return textures_; }
    const std::vector<Light>& lights() const { return lights_; }
    const std::vector<MeshData>& meshes() const { return meshes_; }
    const std::vector<Instance>& instances() const { return instances_; }
    glm::vec3 background() const { return background_; }
    size_t dropped_triangles() const;
    size_t triangle_count() const;         // triangles in the world: every instance counts its mesh's
    size_t stored_triangle_count() const;  // triangles held in memory: each mesh once
    size_t bytes() const;                  // meshes + textures held by the scene (the BVH: ray_tracer().bytes())

    WorldTriangle world_triangle(uint32_t instance, uint32_t triangle) const;

    // World-space bounds of all geometry (empty scene: a unit box at the origin).
    glm::vec3 bounds_min() const;
    glm::vec3 bounds_max() const;

    // The Embree acceleration structure, built on first use after the last change. Thread-safe to query.
    const RayTracer& ray_tracer() const;

private:
    std::vector<Material> materials_;
    std::vector<Texture> textures_;
    std::vector<Light> lights_;
    std::vector<MeshData> meshes_;
    std::vector<Instance> instances_;
    glm::vec3 background_{0.0f};
    size_t dropped_in_meshes_ = 0;
    mutable std::unique_ptr<RayTracer> ray_tracer_;
    // Instances moved since the ray tracer was built: applied to it before its next use.
    mutable std::vector<uint32_t> moved_instances_;

    bool instance_is_flat(const Instance& instance) const;
    std::pair<glm::vec3, glm::vec3> world_bounds() const;  // bounds_min/max before their empty-scene fallback
};

}  // namespace ps
