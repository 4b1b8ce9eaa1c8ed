// The scene as the core sees it: meshes in object space, instances that place a mesh in the world (a 4×4
// transform each; Embree instancing, so a thousand copies of a mesh cost one mesh), materials, textures,
// lights and a background. Everything is validated on entry (add_*), so later stages never meet NaNs or bad
// indices. Degenerate triangles (zero area, repeated vertices) are dropped and counted, not treated as errors.
//
// World space and render space. Transforms and positions arrive in the user's world space, in double (Blender's
// float32 matrices convert exactly). The scene keeps them, and hands every later stage float coordinates in
// *render space*: world minus origin(), a point in double near the middle of the placed geometry. Far from the
// world origin float32 cannot hold positions finely (7.8 mm apart at 1e5), but render-space coordinates stay
// about the scene's size wherever the scene is, so a scene moved by 1e5 renders like the same scene at the
// origin: the transform's large translation is subtracted in double, before anything becomes float. (A mesh
// whose *vertices* are far from its object origin arrives already rounded in float32 and keeps that error.)
// Render-space data are: Instance::to_world, lights() positions, bounds_min/max and world_triangle.
// Cameras are given in world space too; Camera::relative_to(origin()) puts one in render space, which every
// entry point that takes a Scene and a Camera does first.
#pragma once
#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "photonsplat/bump_shadowing.h"
#include "photonsplat/lights.h"
#include "photonsplat/materials.h"
#include "photonsplat/shader_program.h"
#include "photonsplat/textures.h"
#include "photonsplat/world.h"

namespace ps {

struct Stats;

class RayTracer;
class MeshBvh;
class BvhQueue;

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
    // Named per-vertex or per-corner values that node programs read (UV maps by name, colour attributes).
    struct Attribute {
        uint32_t id = 0;               // Scene::attribute_id of its name
        const float* data = nullptr;   // vertex_count × components, or triangle_count × 3 × components
        int components = 0;            // 1 to 4
        bool per_corner = false;
    };
    std::vector<Attribute> attributes;
    // Blender's texture space (Generated coordinates = (p − location) / size / 2 + 0.5); absent: the mesh's box.
    bool has_texspace = false;
    glm::vec3 texspace_location{0.0f}, texspace_size{1.0f};
    glm::dmat4 transform{1.0};             // object → world; used by add_mesh only
};

// Which rays see an instance (Cycles' object ray visibility); a bit set for a ray's kind = the ray can hit it.
enum RayVisibility : uint32_t {
    kCameraRays = 1u,    // the first segment of camera paths
    kShadowRays = 2u,    // direct-light shadow rays
    kIndirectRays = 4u,  // everything else: camera paths after a mirror or glass, photon paths
    kAllRays = 7u,
};
// The surfaces photons are stored on: those bounces see, and those only the camera sees, which a photon passes
// through after storing there (photons.cpp: the camera's paths on them gather what other surfaces send them).
constexpr uint32_t kPhotonReceivers = kCameraRays | kIndirectRays;

// A mesh in object space, as validated and kept by the scene. Only non-degenerate triangles are kept.
// Positions (and the bounds) are kept relative to `centre`: 0 for ordinary meshes (their coordinates are kept
// bit for bit), and for a mesh more than 64 of its sizes away from its object origin the centre of its box on
// the same power-of-two grid as Scene::origin(). Such a mesh (vertices far out, float32 input) then has small
// coordinates too (the subtraction is exact: both are multiples of float's spacing there), and instances place
// it through their transform times a translation by `centre`, taken in double. What stays is the input's own
// rounding (7.8 mm steps at 1e5).
struct MeshData {
    std::string name;
    glm::vec3 centre{0.0f};
    // positions and indices are Embree's vertex and index buffers too (shared, not copied): each has capacity
    // for one more element than it holds, since Embree reads the last one with a 16-byte load.
    std::vector<glm::vec3> positions;   // object space minus centre
    std::vector<uint32_t> indices;      // 3 per triangle
    // Shading normals, unit length: 3 per triangle (corner normals), or 1 per position where the input gave one
    // normal per vertex (a smooth mesh: a third of the memory); empty: flat shading. Read with corner_normal.
    std::vector<glm::vec3> normals;
    bool normals_per_vertex = false;
    std::vector<glm::vec2> uvs;         // 3 per triangle; empty: no UV map (every UV is 0, 0)
    std::vector<uint32_t> materials;    // 1 per triangle
    glm::vec3 bounds_min{0.0f}, bounds_max{0.0f};
    struct Attribute {
        uint32_t id = 0;                    // Scene::attribute_id
        std::vector<glm::vec4> corners;     // 3 per kept triangle; missing components 0, alpha 1
    };
    std::vector<Attribute> attributes;      // only those some material's program reads (the add-on's choice)
    glm::vec3 texspace_location{0.0f}, texspace_size{1.0f};  // object space (not minus centre)
    // Its Embree BVH when it is built ahead (Scene::set_build_bvhs_ahead, mesh_bvh.h), over positions and
    // indices: last, so that it goes (its build finished) before they do.
    std::shared_ptr<MeshBvh> bvh;

    // The attribute with this id, or nullptr.
    const Attribute* attribute(uint32_t id) const {
        for (const Attribute& a : attributes)
            if (a.id == id) return &a;
        return nullptr;
    }

    // The shading normal at corner `corner` of kept triangle t (normals not empty).
    const glm::vec3& corner_normal(size_t t, int corner) const {
        return normals_per_vertex ? normals[indices[3 * t + corner]] : normals[3 * t + corner];
    }

    size_t triangle_count() const { return materials.size(); }
    size_t bytes() const;
    size_t attribute_bytes() const;
};

// A mesh placed in the world.
struct Instance {
    uint32_t mesh;
    std::string name;          // for messages (the Blender object or instance)
    glm::mat4 to_world{1.0f};  // object → render space (world − Scene::origin()), what Embree and shading use
    // The world-space translation as given (the linear part needs no more than to_world's float: a rotation or
    // scale rounds the same wherever the object is).
    glm::dvec3 world_translation{0.0};
    glm::mat3 normal_to_world{1.0f};  // inverse transpose of the linear part
    // The linear part stretches some directions more than others (a non-uniform scale or a shear): a normal's
    // direction then depends on whether it is normalised before or after interpolation (Scene::normals_in_world).
    bool stretched = false;
    // The largest coordinate of the mesh's object-space box through the linear part: hit points on this
    // instance carry float rounding of this size, whatever their render-space coordinates (offset_ray_origin).
    float rounding_scale = 0.0f;
    uint32_t visibility = kAllRays;   // RayVisibility bits
    // What Object Info nodes read.
    glm::vec4 color{1.0f};            // Blender's object colour
    float pass_index = 0.0f;          // Object Index
    float random = 0.0f;              // Cycles' per-object random number in [0, 1)
    // Cycles' shadow terminator geometry offset (Object > Shading > Shadow Terminator, 0.1 in Blender, 0 here
    // unless set): how close to grazing a shadow ray from this instance's smooth triangles starts on the smooth
    // surface instead of the flat one (shadow_terminator.h).
    float terminator_offset = 0.0f;
};

// The render-space box of an instance: its mesh's object-space box, corner by corner through to_world (grown
// into lo, hi).
void grow_by_instance_box(const MeshData& mesh, const Instance& instance, glm::vec3& lo, glm::vec3& hi);

// One placed triangle in render space (corner positions only), e.g. for sampling emissive surfaces.
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
    // May move origin() (see recentre), which re-expresses every instance and light in the new render space.
    uint32_t add_instance(uint32_t mesh, const glm::dmat4& to_world, const std::string& name = "",
                          uint32_t visibility = kAllRays);
    // Moves an instance. Cost: O(1) here, then one refit of the top-level BVH (all instances, no triangle
    // touched) at the next render. Keeps origin() (moving n instances one by one must not cost O(n · scene));
    // fit_origin() after the moves puts it where a new scene would have it. Not to be called while a render of
    // this scene runs.
    void set_instance_transform(uint32_t instance, const glm::dmat4& to_world);
    // Moves origin() to where the instances are now (O(instances)): after it, the scene renders bit for bit as a
    // scene built anew with the same content. Cheap when nothing moved far: the origin only changes when the
    // instances' box grows or shifts by about its size. Not to be called while a render of this scene runs.
    void fit_origin();
    void add_mesh(const MeshInput& mesh);              // add_mesh_data + add_instance(mesh.transform)
    // Adds a light; its position (point, spot: centre; area: centre) is light.position, in world space, or
    // `world_position` in double where given (light.position is then not read).
    void add_light(const Light& light);
    void add_light(const Light& light, const glm::dvec3& world_position);
    // Removes every light, so that moved or edited lights can be added again without rebuilding the meshes or
    // the BVH (lights are read afresh by each render). Not to be called while a render of this scene runs.
    void clear_lights();
    void set_background(const glm::vec3& radiance);    // world colour × strength, seen by camera rays
    // The world as a node program evaluated per direction (world.h): its outputs set only the emission (the
    // radiance). A program that folds to a constant becomes set_background's constant. map_resolution: width of
    // the importance map (height: half), 0 = automatic (the widest Environment Texture's image, else 1024).
    // Validated: throws InvalidInput. clear_world_program() goes back to the constant background.
    void set_world_program(ShaderProgram program, int map_resolution);
    void clear_world_program();
    const ShaderProgram* world_program() const { return world_program_ ? &*world_program_ : nullptr; }
    int world_map_resolution() const { return world_map_resolution_; }
    // A rectangle the world lights the scene through (Cycles' portal lights); clear_lights() removes them too.
    void add_portal(const Portal& portal);
    const std::vector<Portal>& portals() const { return portals_; }
    // The world as a light: built on first use after a change of the world, its portals or the origin.
    std::shared_ptr<const WorldLight> world_light() const;
    // Object Info's colour, pass index and random number of an instance.
    void set_instance_info(uint32_t instance, const glm::vec4& color, float pass_index, float random);
    // Instance::terminator_offset, in [0, 1].
    void set_instance_terminator_offset(uint32_t instance, float offset);
    // Whether some instance has a terminator offset and smooth normals: shadow rays may start lifted.
    bool any_terminator_offset() const;
    // The id of a mesh attribute name (UV map or colour attribute) that programs and meshes refer to; names are
    // registered on first use.
    uint32_t attribute_id(const std::string& name);
    const std::vector<std::string>& attribute_names() const { return attribute_names_; }
    // The camera that Camera Data and the camera / window texture coordinates see: each render sets it from its
    // own camera before shading (two renders of one scene with different cameras must not run at once).
    void set_shader_camera(const ShaderCamera& camera) const {
        shader_camera_ = camera;
        touch();
    }
    const ShaderCamera& shader_camera() const { return shader_camera_; }
    // Changes with every change of what a shader program reads (materials, textures, instances and their
    // transforms, the origin, the shader camera), and differs between any two scenes: a cache of program results
    // keyed by it never outlives what it was computed from.
    uint64_t revision() const { return revision_; }

    const std::vector<Material>& materials() const { return materials_; }
    const std::vector<Texture>& textures() const { return textures_; }
    const std::vector<Light>& lights() const { return lights_; }  // positions in render space
    const std::vector<MeshData>& meshes() const { return meshes_; }
    // Whether the smooth normals of `instance` are Cycles' of a transform it applied: for its final renders
    // Cycles bakes the transform of a mesh that one object alone shows into the mesh (apply_static_transforms),
    // each corner normal turned into the world and normalised there, then interpolated; a mesh several objects
    // show keeps object space, interpolated first and turned after. The two differ only where the transform
    // stretches (Instance::stretched): a glossy UV sphere scaled 1.31 × 0.78 × 1.27 moved its highlight, the
    // sphere's light 0.98 of Cycles' (differential seed 34).
    bool normals_in_world(const Instance& instance) const {
        return instance.stretched && instance.mesh < mesh_users_.size() && mesh_users_[instance.mesh] == 1;
    }
    const std::vector<Instance>& instances() const { return instances_; }
    glm::vec3 background() const { return background_; }
    size_t dropped_triangles() const;
    size_t triangle_count() const;         // triangles in the world: every instance counts its mesh's
    size_t stored_triangle_count() const;  // triangles held in memory: each mesh once
    size_t bytes() const;                  // meshes + textures held by the scene (the BVH: ray_tracer().bytes())

    // The world point that render space is relative to: render = world − origin(). 0 for any scene whose
    // geometry's bounds hold the world origin (so such scenes render exactly as they would without it).
    glm::dvec3 origin() const { return origin_; }

    WorldTriangle world_triangle(uint32_t instance, uint32_t triangle) const;  // render space

    // Render-space bounds of all geometry (empty scene: a unit box at the render origin).
    glm::vec3 bounds_min() const;
    glm::vec3 bounds_max() const;

    // The Embree acceleration structure, built on first use after the last change. Thread-safe to query.
    const RayTracer& ray_tracer() const;
    // On: add_mesh_data starts building each mesh's BVH on a thread of the scene's own and returns, so that the
    // caller fills the rest of the scene meanwhile (the add-on: its next mesh read from Blender); ray_tracer()
    // then takes them. The same BVHs either way. Off (the default): no thread, every BVH built by ray_tracer().
    void set_build_bvhs_ahead(bool on) { build_bvhs_ahead_ = on; }
    bool build_bvhs_ahead() const { return build_bvhs_ahead_; }
    // The estimate that light samples take (closures.h): light_sample (the default) as Cycles 3.x evaluates its
    // Multiscatter GGX's random walk towards a light, light_sample_as_walk for Cycles 4.x, whose lobe is the same
    // both ways. Never walk: light samples value refractions as Cycles does there (eval_refraction).
    void set_multiscatter_light_estimate(MultiScatterEstimate e) {
        multiscatter_light_estimate_ = e == MultiScatterEstimate::walk ? MultiScatterEstimate::light_sample_as_walk : e;
    }
    MultiScatterEstimate multiscatter_light_estimate() const { return multiscatter_light_estimate_; }
    // Which bump shadowing term diffuse closures under a bumped or tilted normal take (bump_shadowing.h): Cycles
    // 3.x's (the default), or 4.x's, which each material's Bump Map Correction switches.
    void set_cycles4_bump_shadowing(bool on) { cycles4_bump_shadowing_ = on; }
    bool cycles4_bump_shadowing() const { return cycles4_bump_shadowing_; }
    BumpShadowing bump_shadowing(const Material& m) const {
        if (!cycles4_bump_shadowing_) return BumpShadowing::cycles3;
        return m.bump_map_correction ? BumpShadowing::cycles4 : BumpShadowing::cycles4_uncorrected;
    }

private:
    std::vector<Material> materials_;
    std::vector<Texture> textures_;
    std::vector<Light> lights_;
    std::vector<glm::dvec3> light_positions_;  // world space, one per light
    std::vector<MeshData> meshes_;
    std::vector<uint32_t> mesh_users_;  // per mesh, how many instances show it
    // After meshes_: goes first, dropping the builds not started and waiting for the running one.
    bool build_bvhs_ahead_ = false;
    MultiScatterEstimate multiscatter_light_estimate_ = MultiScatterEstimate::light_sample;
    bool cycles4_bump_shadowing_ = false;
    std::unique_ptr<BvhQueue> bvh_queue_;
    std::vector<Instance> instances_;
    glm::vec3 background_{0.0f};
    std::unique_ptr<ShaderProgram> world_program_;
    int world_map_resolution_ = 0;
    std::vector<Portal> portals_;
    uint64_t world_version_ = 0;  // changes with the world, its portals and the origin
    mutable std::shared_ptr<const WorldLight> world_light_;
    mutable uint64_t world_light_version_ = ~uint64_t(0);
    std::vector<std::string> attribute_names_;
    mutable ShaderCamera shader_camera_;
    mutable uint64_t revision_ = 0;
    void touch() const;  // a new revision_
    glm::dvec3 origin_{0.0};
    // World-space box of the instances as placed by add_instance (and as they are after fit_origin), in double.
    glm::dvec3 placed_min_{std::numeric_limits<double>::infinity()};
    glm::dvec3 placed_max_{-std::numeric_limits<double>::infinity()};
    size_t dropped_in_meshes_ = 0;
    mutable std::unique_ptr<RayTracer> ray_tracer_;
    // The tracer is built and no instance moved since: ray_tracer() returns it without taking the lock (every
    // shadow ray asks for it; a lock per ray cost 8 % of a frame on 2 threads).
    mutable std::atomic<bool> tracer_current_{false};
    // Instances moved since the ray tracer was built: applied to it before its next use.
    mutable std::vector<uint32_t> moved_instances_;

    bool instance_is_flat(const Instance& instance) const;
    std::pair<glm::vec3, glm::vec3> render_bounds() const;  // bounds_min/max before their empty-scene fallback
    // Sets the instance's transforms from `to_world` (world space) and its rounding_scale.
    void place(Instance& instance, const glm::dmat4& to_world) const;
    void include_in_placed_box(const Instance& instance);
    bool recentre();  // origin_ from placed_min_/max_; re-expresses instances and lights if it moved (true)
};

// Records the scene's size in stats (counters "triangles", "dropped_triangles", "lights") and the bytes of its
// ray tracer, building the tracer first if no render has yet (timed as the stage "scene_build"), and the
// world's importance map, baking it first if the world changed (the stage "world_map").
void report_scene(const Scene& scene, Stats& stats);

}  // namespace ps
