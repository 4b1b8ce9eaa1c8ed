#include "photonsplat/scene.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <string>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include "mesh_bvh.h"
#include "photonsplat/errors.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/stats.h"
#include "photonsplat/validation.h"

namespace ps {

namespace {

constexpr float kCentreRatio = 64.0f;  // see add_mesh_data: meshes this many sizes from their origin are re-centred

std::mutex& ray_tracer_mutex() {
    static std::mutex m;
    return m;
}

bool all_finite(const glm::dmat4& m) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(m[c][r])) return false;
    return true;
}

bool within_world(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::fabs(v.x) <= kMaxCoordinate &&
           std::fabs(v.y) <= kMaxCoordinate && std::fabs(v.z) <= kMaxCoordinate;
}

void require_finite_transform(const glm::dmat4& m, const std::string& field) {
    if (!all_finite(m)) throw InvalidInput(field, "contains NaN or infinity");
    if (!within_world(glm::dvec3(m[3])))
        throw InvalidInput(field, "places the object beyond ±1e15, where rays cannot be traced");
    // Only affine transforms place a mesh (Blender's world matrices always are).
    if (m[0][3] != 0.0 || m[1][3] != 0.0 || m[2][3] != 0.0 || m[3][3] != 1.0)
        throw InvalidInput(field, "must be affine (last row 0, 0, 0, 1)");
}

// A box's centre rounded to a multiple of q, the smallest power of two at least twice its largest side; 0 for
// a box that holds 0, and `keep` for an empty or flat-to-a-point box. Used for Scene::origin() and MeshData::centre.
glm::dvec3 grid_centre(const glm::dvec3& lo, const glm::dvec3& hi, const glm::dvec3& keep) {
    if (!(lo.x <= hi.x)) return keep;  // empty
    const glm::dvec3 extent = hi - lo;
    const double side = std::max(extent.x, std::max(extent.y, extent.z));
    if (!(side > 0.0)) return keep;
    const double q = std::exp2(std::ceil(std::log2(2.0 * side)));
    const glm::dvec3 centre = 0.5 * (lo + hi);
    return q * glm::dvec3(std::round(centre.x / q), std::round(centre.y / q), std::round(centre.z / q));
}

double frobenius(const glm::dmat3& m) {
    return std::sqrt(glm::dot(m[0], m[0]) + glm::dot(m[1], m[1]) + glm::dot(m[2], m[2]));
}

// The normal matrix, or false when the transform flattens space: a zero scale on some axis, or one that is flat
// to float precision. Embree traces a ray through an instance in the mesh's own space, M⁻¹·(o − t), and asserts
// (aborting the process, Blender with it) once a coordinate passes 1.8e18: a nearly singular M (axes nearly
// parallel: the fuzzer found one) or one that shrinks a mesh by more than kMaxInverseScale sends ordinary rays
// there. Such an instance covers nothing (its triangles are counted as dropped).
constexpr double kMaxCondition = 1e7;      // ‖M‖·‖M⁻¹‖ (Frobenius): past 2^24 its axes are not distinct in float
constexpr double kMaxInverseScale = 1e9;   // ‖M⁻¹‖: a mesh scaled down by a billion is below float's resolution
bool normal_matrix(const glm::mat4& m, glm::mat3& out) {
    const glm::dmat3 linear{glm::mat3(m)};
    const double det = glm::determinant(linear);
    if (!(std::fabs(det) > 0.0) || !std::isfinite(det)) return false;
    const glm::dmat3 inverse = glm::inverse(linear);
    const double inverse_norm = frobenius(inverse);
    if (!(frobenius(linear) * inverse_norm <= kMaxCondition) || !(inverse_norm <= kMaxInverseScale)) return false;
    out = glm::mat3(glm::transpose(inverse));
    for (int c = 0; c < 3; ++c)
        if (!is_finite(out[c])) return false;
    return true;
}

}  // namespace

size_t MeshData::bytes() const {
    return positions.capacity() * sizeof(glm::vec3) + indices.capacity() * sizeof(uint32_t) +
           normals.capacity() * sizeof(glm::vec3) + uvs.capacity() * sizeof(glm::vec2) +
           materials.capacity() * sizeof(uint32_t) + attribute_bytes();
}

size_t MeshData::attribute_bytes() const {
    size_t bytes = 0;
    for (const Attribute& a : attributes) bytes += a.corners.capacity() * sizeof(glm::vec4);
    return bytes;
}

namespace {
std::atomic<uint64_t> g_scene_revisions{0};
}  // namespace

Scene::Scene() { touch(); }

void Scene::touch() const { revision_ = g_scene_revisions.fetch_add(1, std::memory_order_relaxed) + 1; }
Scene::~Scene() = default;

uint32_t Scene::add_material(const Material& material) {
    touch();
    const std::string where = "material '" + material.name + "'";
    validate(material, where);
    const auto check_texture = [&](int32_t texture, const std::string& field) {
        if (texture >= 0 && static_cast<size_t>(texture) >= textures_.size())
            throw InvalidInput(field, "is " + std::to_string(texture) + ", but the scene has " +
                                          std::to_string(textures_.size()) + " textures");
        if (texture < -1) throw InvalidInput(field, "must be -1 (none) or a texture index");
    };
    check_texture(material.texture, where + ".texture");
    for (size_t i = 0; i < material.closures.size(); ++i)
        check_texture(material.closures[i].texture, where + ".closures[" + std::to_string(i) + "].texture");
    Material lowered = material;
    finalize_program(lowered.program, *this);
    fold_constant_outputs(lowered);
    lower_simple_material(lowered);
    materials_.push_back(std::move(lowered));
    return static_cast<uint32_t>(materials_.size() - 1);
}

uint32_t Scene::add_texture(Texture texture) {
    touch();
    textures_.push_back(std::move(texture));
    return static_cast<uint32_t>(textures_.size() - 1);
}

void Scene::add_light(const Light& light) { add_light(light, glm::dvec3(light.position)); }

void Scene::add_light(const Light& light, const glm::dvec3& world_position) {
    const std::string where = std::string(to_string(light.kind)) + " light '" + light.name + "'";
    if (!within_world(world_position))
        throw InvalidInput(where + ".position", "must be finite and within ±1e15 on every axis");
    Light placed = light;
    placed.position = glm::vec3(world_position - origin_);
    validate(placed, where);
    lights_.push_back(placed);
    light_positions_.push_back(world_position);
}

void Scene::clear_lights() {
    lights_.clear();
    light_positions_.clear();
    if (!portals_.empty()) ++world_version_;
    portals_.clear();
}

void Scene::set_background(const glm::vec3& radiance) {
    require_nonnegative_rgb(radiance, "background");
    background_ = radiance;
    ++world_version_;
}

void Scene::set_world_program(ShaderProgram program, int map_resolution) {
    const std::string where = "world.program";
    if (map_resolution < 0 || map_resolution > 65536)
        throw InvalidInput("world.map_resolution", "must be 0 (automatic) or a width from 1 to 65536");
    validate(program, 0, where);
    for (size_t i = 0; i < program.outputs.size(); ++i)
        if (program.outputs[i].target != ProgramTarget::emission)
            throw InvalidInput(where + ".outputs[" + std::to_string(i) + "].target",
                               "must be 'emission': a world program sets only its radiance");
    finalize_program(program, *this);
    ++world_version_;
    world_map_resolution_ = map_resolution;
    if (program.code.empty()) {
        // Folded to a constant: the constant background, which costs nothing per ray.
        glm::vec3 radiance(0.0f);
        for (const ProgramOutput& o : program.outputs)
            radiance = glm::vec3(program.registers[size_t(o.register_)], program.registers[size_t(o.register_) + 1],
                                 program.registers[size_t(o.register_) + 2]);
        for (int c = 0; c < 3; ++c) radiance[c] = std::isfinite(radiance[c]) ? std::max(radiance[c], 0.0f) : 0.0f;
        world_program_.reset();
        background_ = radiance;
        return;
    }
    world_program_ = std::make_unique<ShaderProgram>(std::move(program));
}

void Scene::clear_world_program() {
    world_program_.reset();
    ++world_version_;
}

void Scene::add_portal(const Portal& portal) {
    const std::string where = "portal '" + portal.name + "'";
    if (!within_world(portal.corner)) throw InvalidInput(where + ".corner", "must be finite and within ±1e15 on every axis");
    const glm::vec3 n = glm::cross(portal.edge_u, portal.edge_v);
    if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z) || !(glm::length(n) > 0.0f))
        throw InvalidInput(where + ".edges", "must be finite and span a rectangle of non-zero area");
    portals_.push_back(portal);
    ++world_version_;
}

std::shared_ptr<const WorldLight> Scene::world_light() const {
    static std::mutex mutex;
    std::lock_guard<std::mutex> lock(mutex);
    if (!world_light_ || world_light_version_ != world_version_) {
        world_light_ = std::make_shared<const WorldLight>(*this);
        world_light_version_ = world_version_;
    }
    return world_light_;
}

uint32_t Scene::add_mesh_data(const MeshInput& mesh) {
    touch();
    const std::string where = "mesh '" + mesh.name + "'";
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
    const size_t uv_floats = mesh.uvs ? (mesh.uvs_per_corner ? mesh.triangle_count * 6 : mesh.vertex_count * 2) : 0;
    for (size_t i = 0; i < uv_floats; ++i)
        if (!std::isfinite(mesh.uvs[i]))
            throw InvalidInput(where + ".uvs", "uv " + std::to_string(i / 2) + " is NaN or infinite");

    for (size_t k = 0; k < mesh.attributes.size(); ++k) {
        const MeshInput::Attribute& a = mesh.attributes[k];
        const std::string field = where + ".attributes[" + std::to_string(k) + "]";
        if (a.id >= attribute_names_.size()) throw InvalidInput(field, "unknown attribute id " + std::to_string(a.id));
        if (a.components < 1 || a.components > 4)
            throw InvalidInput(field, "must have 1 to 4 components, got " + std::to_string(a.components));
        const size_t count = (a.per_corner ? mesh.triangle_count * 3 : mesh.vertex_count) * a.components;
        if (count > 0 && a.data == nullptr) throw InvalidInput(field, "missing");
        for (size_t i = 0; i < count; ++i)
            if (!std::isfinite(a.data[i]))
                throw InvalidInput(field, "value " + std::to_string(i / a.components) + " is NaN or infinite");
    }
    if (mesh.has_texspace) {
        for (int c = 0; c < 3; ++c)
            if (!std::isfinite(mesh.texspace_location[c]) || !std::isfinite(mesh.texspace_size[c]))
                throw InvalidInput(where + ".texspace", "must be finite");
    }

    // Everything is valid: keep the non-degenerate triangles, with per-corner normals, UVs and attributes.
    MeshData data;
    data.name = mesh.name;
    // One element more than held: Embree shares these buffers and reads their last element with a 16-byte load.
    data.positions.reserve(mesh.vertex_count + 1);
    data.positions.emplace_back(0.0f);
    data.positions.pop_back();
    for (size_t i = 0; i < mesh.vertex_count; ++i)
        data.positions.emplace_back(mesh.vertices[3 * i], mesh.vertices[3 * i + 1], mesh.vertices[3 * i + 2]);
    data.indices.reserve(3 * mesh.triangle_count + 1);
    data.indices.push_back(0u);
    data.indices.pop_back();
    data.materials.reserve(mesh.triangle_count);
    // Normals per vertex stay per vertex (normalised once each) when every one has a direction: each corner then
    // reads exactly what corner_normal below would have stored for it. A zero one falls back to the triangle's
    // own normal, which differs per triangle: such a mesh keeps corner normals.
    if (mesh.normals && !mesh.normals_per_corner) {
        data.normals.reserve(mesh.vertex_count);
        for (size_t i = 0; i < mesh.vertex_count && data.normals.size() == i; ++i) {
            const glm::vec3 v(mesh.normals[3 * i], mesh.normals[3 * i + 1], mesh.normals[3 * i + 2]);
            const float len = glm::length(v);
            if (len > 0.0f && std::isfinite(len)) data.normals.push_back(v / len);
        }
        data.normals_per_vertex = data.normals.size() == mesh.vertex_count;
        if (!data.normals_per_vertex) std::vector<glm::vec3>().swap(data.normals);
    }
    if (mesh.normals && !data.normals_per_vertex) data.normals.reserve(3 * mesh.triangle_count);
    if (mesh.uvs) data.uvs.reserve(3 * mesh.triangle_count);
    auto corner_normal = [&](size_t t, int corner, const glm::vec3& fallback) {
        const float* n = mesh.normals_per_corner ? mesh.normals + 9 * t + 3 * corner
                                                 : mesh.normals + 3 * static_cast<size_t>(mesh.triangles[3 * t + corner]);
        const glm::vec3 v(n[0], n[1], n[2]);
        const float len = glm::length(v);
        return (len > 0.0f && std::isfinite(len)) ? v / len : fallback;
    };
    auto corner_uv = [&](size_t t, int corner) {
        const float* uv = mesh.uvs_per_corner ? mesh.uvs + 6 * t + 2 * corner
                                              : mesh.uvs + 2 * static_cast<size_t>(mesh.triangles[3 * t + corner]);
        return glm::vec2(uv[0], uv[1]);
    };
    auto corner_attribute = [&](const MeshInput::Attribute& a, size_t t, int corner) {
        const size_t i = a.per_corner ? 3 * t + corner : static_cast<size_t>(mesh.triangles[3 * t + corner]);
        const float* v = a.data + i * a.components;
        glm::vec4 value(0.0f, 0.0f, 0.0f, 1.0f);
        for (int c = 0; c < a.components; ++c) value[c] = v[c];
        return value;
    };
    for (const MeshInput::Attribute& a : mesh.attributes) {
        data.attributes.emplace_back();
        data.attributes.back().id = a.id;
    }
    bool first = true;
    for (size_t t = 0; t < mesh.triangle_count; ++t) {
        const uint32_t i0 = mesh.triangles[3 * t], i1 = mesh.triangles[3 * t + 1], i2 = mesh.triangles[3 * t + 2];
        const glm::vec3 &v0 = data.positions[i0], &v1 = data.positions[i1], &v2 = data.positions[i2];
        const glm::vec3 ng_raw = glm::cross(v1 - v0, v2 - v0);
        const float len = glm::length(ng_raw);
        // Zero-area (or overflowing, or beyond kMaxCoordinate: Embree would assert) triangles can neither be hit
        // nor shaded.
        if (!(len > 0.0f) || !std::isfinite(len) || !within_world(v0) || !within_world(v1) || !within_world(v2)) {
            ++dropped_in_meshes_;
            continue;
        }
        data.indices.insert(data.indices.end(), {i0, i1, i2});
        if (mesh.normals && !data.normals_per_vertex) {
            const glm::vec3 ng = ng_raw / len;
            for (int c = 0; c < 3; ++c) data.normals.push_back(corner_normal(t, c, ng));
        }
        if (mesh.uvs)
            for (int c = 0; c < 3; ++c) data.uvs.push_back(corner_uv(t, c));
        for (size_t k = 0; k < mesh.attributes.size(); ++k)
            for (int c = 0; c < 3; ++c)
                data.attributes[k].corners.push_back(corner_attribute(mesh.attributes[k], t, c));
        data.materials.push_back(mesh.material_ids ? static_cast<uint32_t>(mesh.material_ids[t]) : 0u);
        if (first) data.bounds_min = data.bounds_max = v0;
        first = false;
        for (const glm::vec3& v : {v0, v1, v2}) {
            data.bounds_min = glm::min(data.bounds_min, v);
            data.bounds_max = glm::max(data.bounds_max, v);
        }
    }
    if (mesh.has_texspace) {
        data.texspace_location = mesh.texspace_location;
        data.texspace_size = mesh.texspace_size;
    } else if (!first) {
        // Blender's automatic texture space: the box, a zero extent counting as 1.
        data.texspace_location = 0.5f * (data.bounds_min + data.bounds_max);
        data.texspace_size = 0.5f * (data.bounds_max - data.bounds_min);
        for (int c = 0; c < 3; ++c)
            if (data.texspace_size[c] == 0.0f) data.texspace_size[c] = 1.0f;
    }
    // Far from the object origin, positions become relative to the mesh's centre (MeshData): exact, since the
    // centre is a multiple of a power of two at least the float spacing of any vertex near it. Only beyond 64
    // sizes from the object origin: nearer, vertices lose at most 6 bits to that distance, which the ray offset
    // covers (Instance::rounding_scale), and ordinary meshes keep their coordinates bit for bit.
    const glm::vec3 extent = data.bounds_max - data.bounds_min;
    const float side = std::max(extent.x, std::max(extent.y, extent.z));
    const glm::vec3 reach = glm::max(glm::abs(data.bounds_min), glm::abs(data.bounds_max));
    if (!first && std::max(reach.x, std::max(reach.y, reach.z)) > kCentreRatio * side) {
        data.centre = glm::vec3(grid_centre(glm::dvec3(data.bounds_min), glm::dvec3(data.bounds_max), glm::dvec3(0.0)));
        if (data.centre != glm::vec3(0.0f)) {
            for (glm::vec3& p : data.positions) p -= data.centre;
            data.bounds_min -= data.centre;
            data.bounds_max -= data.centre;
        }
    }
    // Only the vertices of kept triangles matter; the others stay (indices refer to them) but cost little.
    meshes_.reserve(meshes_.size() + 1);  // the push_back below cannot throw once a build reads `data`
    // Only a mesh too big to be placed in render space keeps the object-space BVH built here (a smaller one, shown
    // once, is placed, and shown many times is quick to build at the first render).
    if (build_bvhs_ahead_ && data.triangle_count() >= RayTracer::kPlacedTriangleLimit) {
        if (!bvh_queue_) bvh_queue_ = std::make_unique<BvhQueue>();
        data.bvh = bvh_queue_->start(data);  // reads the arrays' buffers, which stay put when `data` moves
    }
    meshes_.push_back(std::move(data));
    mesh_users_.push_back(0);
    return static_cast<uint32_t>(meshes_.size() - 1);
}

void Scene::place(Instance& instance, const glm::dmat4& to_world) const {
    const MeshData& mesh = meshes_[instance.mesh];
    // Object space as kept is relative to the mesh's centre: the translation that places it is to_world's
    // image of the centre, in double.
    instance.world_translation = glm::dvec3(to_world * glm::dvec4(glm::dvec3(mesh.centre), 1.0));
    // The translation leaves world space in double, before anything is rounded to float.
    glm::dmat4 relative = to_world;
    relative[3] = glm::dvec4(instance.world_translation - origin_, 1.0);
    instance.to_world = glm::mat4(relative);
    // A re-centred mesh scaled up can land beyond ±1e15, where rays cannot be traced: it then covers nothing
    // (counted as dropped), like a flattened one.
    if (!normal_matrix(instance.to_world, instance.normal_to_world) || !within_world(instance.world_translation)) {
        instance.normal_to_world = glm::mat3(0.0f);
        instance.to_world[3] = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
        instance.world_translation = glm::dvec3(0.0);
    }
    const glm::mat3 linear(instance.to_world);
    // Stretched: NᵀN is not a multiple of the identity (N the normal matrix), to float precision.
    const glm::mat3 gram = glm::transpose(instance.normal_to_world) * instance.normal_to_world;
    const float scale = (gram[0][0] + gram[1][1] + gram[2][2]) / 3.0f;
    instance.stretched = false;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (std::fabs(gram[i][j] - (i == j ? scale : 0.0f)) > 1e-5f * scale) instance.stretched = true;
    instance.rounding_scale = 0.0f;
    for (int corner = 0; corner < 8; ++corner) {
        const glm::vec3 p((corner & 1) ? mesh.bounds_max.x : mesh.bounds_min.x,
                          (corner & 2) ? mesh.bounds_max.y : mesh.bounds_min.y,
                          (corner & 4) ? mesh.bounds_max.z : mesh.bounds_min.z);
        const glm::vec3 q = glm::abs(linear * p);
        instance.rounding_scale = std::max(instance.rounding_scale, std::max(q.x, std::max(q.y, q.z)));
    }
}

// The render origin: the centre of the placed box rounded to a multiple of q, the smallest power of two at
// least twice the box's largest side. Why this rule:
//  - a box that holds the world origin gets origin 0 (each |centre| <= side/2 < q/2): for scenes around the
//    origin render space is world space, coordinates unchanged;
//  - render coordinates stay within side/2 + q/2 < 2.5 sides of 0: float precision as for the same scene at
//    the world origin, within two bits;
//  - the origin moves only when the box grows or shifts by about its size, so adding n instances re-expresses
//    the scene O(log) times, not n times; and a multiple of a power of two is exact in double.
// Why the geometry's box and not the camera: it is the camera-independent middle of what rays hit (a camera
// far from its scene sees it small, where float's rounding at the camera's distance no longer shows), and the
// scene stays valid for any camera and for renders that share it (the viewport).
bool Scene::recentre() {
    touch();
    const glm::dvec3 origin = grid_centre(placed_min_, placed_max_, origin_);
    // Beyond ±1e15 (geometry scaled up past where coordinates are accepted) the origin stays: render-space
    // coordinates of accepted positions then stay within ±2e15, far inside float's range.
    if (origin == origin_ || !within_world(origin)) return false;
    origin_ = origin;
    ++world_version_;
    for (Instance& instance : instances_)
        instance.to_world[3] = glm::vec4(glm::vec3(instance.world_translation - origin_), 1.0f);
    for (size_t i = 0; i < lights_.size(); ++i) lights_[i].position = glm::vec3(light_positions_[i] - origin_);
    return true;
}

// The instance's world-space box (its mesh's box corners through its transform, in double) joins the placed box.
void Scene::include_in_placed_box(const Instance& instance) {
    const MeshData& mesh = meshes_[instance.mesh];
    if (instance_is_flat(instance) || mesh.triangle_count() == 0) return;
    glm::dmat4 to_world(instance.to_world);
    to_world[3] = glm::dvec4(instance.world_translation, 1.0);
    for (int corner = 0; corner < 8; ++corner) {
        const glm::dvec3 p((corner & 1) ? mesh.bounds_max.x : mesh.bounds_min.x,
                           (corner & 2) ? mesh.bounds_max.y : mesh.bounds_min.y,
                           (corner & 4) ? mesh.bounds_max.z : mesh.bounds_min.z);
        const glm::dvec3 w(to_world * glm::dvec4(p, 1.0));
        placed_min_ = glm::min(placed_min_, w);
        placed_max_ = glm::max(placed_max_, w);
    }
}

void Scene::fit_origin() {
    touch();
    placed_min_ = glm::dvec3(std::numeric_limits<double>::infinity());
    placed_max_ = glm::dvec3(-std::numeric_limits<double>::infinity());
    for (const Instance& instance : instances_) include_in_placed_box(instance);
    if (!recentre()) return;
    // Every instance's render-space translation changed: the next render builds the BVH anew, as for a new
    // scene (updated in place, every object placed as render-space triangles would become an instance: the
    // same picture, other rounding), so that the scene renders bit for bit as a fresh one.
    std::lock_guard<std::mutex> lock(ray_tracer_mutex());
    tracer_current_ = false;
    ray_tracer_.reset();
    moved_instances_.clear();
}

void Scene::set_instance_info(uint32_t instance, const glm::vec4& color, float pass_index, float random) {
    touch();
    if (instance >= instances_.size())
        throw InvalidInput("instance", "is " + std::to_string(instance) + ", but the scene has " +
                                           std::to_string(instances_.size()) + " instances");
    const std::string where = "instance '" + instances_[instance].name + "'.object_info";
    for (int c = 0; c < 4; ++c)
        if (!std::isfinite(color[c])) throw InvalidInput(where + ".color", "must be finite");
    if (!std::isfinite(pass_index)) throw InvalidInput(where + ".pass_index", "must be finite");
    if (!std::isfinite(random)) throw InvalidInput(where + ".random", "must be finite");
    Instance& i = instances_[instance];
    i.color = color;
    i.pass_index = pass_index;
    i.random = random;
}

void Scene::set_instance_terminator_offset(uint32_t instance, float offset) {
    touch();
    if (instance >= instances_.size())
        throw InvalidInput("instance", "is " + std::to_string(instance) + ", but the scene has " +
                                           std::to_string(instances_.size()) + " instances");
    if (!(offset >= 0.0f && offset <= 1.0f))
        throw InvalidInput("instance '" + instances_[instance].name + "'.terminator_offset",
                           "must be in [0, 1] (Cycles' Geometry Offset)");
    instances_[instance].terminator_offset = offset;
}

bool Scene::any_terminator_offset() const {
    for (const Instance& i : instances_)
        if (i.terminator_offset > 0.0f && !meshes_[i.mesh].normals.empty() && !instance_is_flat(i)) return true;
    return false;
}

uint32_t Scene::attribute_id(const std::string& name) {
    for (size_t i = 0; i < attribute_names_.size(); ++i)
        if (attribute_names_[i] == name) return static_cast<uint32_t>(i);
    attribute_names_.push_back(name);
    return static_cast<uint32_t>(attribute_names_.size() - 1);
}

uint32_t Scene::add_instance(uint32_t mesh, const glm::dmat4& to_world, const std::string& name, uint32_t visibility) {
    touch();
    const std::string label = name.empty() ? (mesh < meshes_.size() ? meshes_[mesh].name : std::string("?")) : name;
    const std::string where = "instance '" + label + "'";
    if (mesh >= meshes_.size())
        throw InvalidInput(where + ".mesh", "is " + std::to_string(mesh) + ", but the scene has " +
                                                std::to_string(meshes_.size()) + " meshes");
    require_finite_transform(to_world, where + ".transform");
    if (visibility > kAllRays) throw InvalidInput(where + ".visibility", "unknown ray visibility bits");
    if (instances_.size() >= static_cast<size_t>(std::numeric_limits<int32_t>::max()))
        throw InvalidInput(where, "too many instances");
    Instance instance;
    instance.mesh = mesh;
    instance.name = label;
    instance.visibility = visibility;
    place(instance, to_world);
    include_in_placed_box(instance);
    instances_.push_back(std::move(instance));
    ++mesh_users_[mesh];
    recentre();
    std::lock_guard<std::mutex> lock(ray_tracer_mutex());
    tracer_current_ = false;
    ray_tracer_.reset();
    moved_instances_.clear();
    return static_cast<uint32_t>(instances_.size() - 1);
}

void Scene::set_instance_transform(uint32_t id, const glm::dmat4& to_world) {
    touch();
    if (id >= instances_.size())
        throw InvalidInput("instance", "id " + std::to_string(id) + " out of range (the scene has " +
                                           std::to_string(instances_.size()) + " instances)");
    Instance& instance = instances_[id];
    require_finite_transform(to_world, "instance '" + instance.name + "'.transform");
    place(instance, to_world);
    std::lock_guard<std::mutex> lock(ray_tracer_mutex());
    if (ray_tracer_) {
        tracer_current_ = false;
        moved_instances_.push_back(id);
    }
}

void Scene::add_mesh(const MeshInput& mesh) {
    // Check the transform before keeping the mesh, so a bad call leaves the scene as it was.
    require_finite_transform(mesh.transform, "mesh '" + mesh.name + "'.transform");
    const uint32_t id = add_mesh_data(mesh);
    add_instance(id, mesh.transform, mesh.name);
}

bool Scene::instance_is_flat(const Instance& instance) const {
    return instance.normal_to_world == glm::mat3(0.0f);
}

size_t Scene::dropped_triangles() const {
    size_t dropped = dropped_in_meshes_;
    for (const Instance& instance : instances_)
        if (instance_is_flat(instance)) dropped += meshes_[instance.mesh].triangle_count();
    return dropped;
}

size_t Scene::triangle_count() const {
    size_t count = 0;
    for (const Instance& instance : instances_)
        if (!instance_is_flat(instance)) count += meshes_[instance.mesh].triangle_count();
    return count;
}

size_t Scene::stored_triangle_count() const {
    size_t count = 0;
    for (const MeshData& mesh : meshes_) count += mesh.triangle_count();
    return count;
}

size_t Scene::bytes() const {
    size_t total = instances_.capacity() * sizeof(Instance);
    for (const MeshData& mesh : meshes_) total += mesh.bytes();
    for (const Texture& texture : textures_) total += texture.bytes();
    return total;
}

WorldTriangle Scene::world_triangle(uint32_t instance, uint32_t triangle) const {
    const Instance& inst = instances_[instance];
    const MeshData& mesh = meshes_[inst.mesh];
    auto corner = [&](int c) {
        return glm::vec3(inst.to_world * glm::vec4(mesh.positions[mesh.indices[3 * triangle + c]], 1.0f));
    };
    return {corner(0), corner(1), corner(2)};
}

// The render-space box of every placed instance: its mesh's box corners through its transform. {+inf, −inf}
// when nothing is placed.
void grow_by_instance_box(const MeshData& mesh, const Instance& instance, glm::vec3& lo, glm::vec3& hi) {
    for (int corner = 0; corner < 8; ++corner) {
        const glm::vec3 p((corner & 1) ? mesh.bounds_max.x : mesh.bounds_min.x,
                          (corner & 2) ? mesh.bounds_max.y : mesh.bounds_min.y,
                          (corner & 4) ? mesh.bounds_max.z : mesh.bounds_min.z);
        const glm::vec3 w(instance.to_world * glm::vec4(p, 1.0f));
        lo = glm::min(lo, w);
        hi = glm::max(hi, w);
    }
}

std::pair<glm::vec3, glm::vec3> Scene::render_bounds() const {
    glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
    for (const Instance& instance : instances_) {
        const MeshData& mesh = meshes_[instance.mesh];
        if (instance_is_flat(instance) || mesh.triangle_count() == 0) continue;
        grow_by_instance_box(mesh, instance, lo, hi);
    }
    return {lo, hi};
}

glm::vec3 Scene::bounds_min() const {
    const glm::vec3 lo = render_bounds().first;
    return std::isfinite(lo.x) ? lo : glm::vec3(-0.5f);
}

glm::vec3 Scene::bounds_max() const {
    const glm::vec3 hi = render_bounds().second;
    return std::isfinite(hi.x) ? hi : glm::vec3(0.5f);
}

const RayTracer& Scene::ray_tracer() const {
    if (tracer_current_.load(std::memory_order_acquire)) return *ray_tracer_;
    std::lock_guard<std::mutex> lock(ray_tracer_mutex());
    if (!ray_tracer_) {
        ray_tracer_ = std::make_unique<RayTracer>(meshes_, instances_);
    } else if (!moved_instances_.empty()) {
        ray_tracer_->update_instances(meshes_, instances_, moved_instances_);
    }
    moved_instances_.clear();
    tracer_current_.store(true, std::memory_order_release);
    return *ray_tracer_;
}

void report_scene(const Scene& scene, Stats& stats) {
    stats.counters["triangles"] = static_cast<double>(scene.triangle_count());
    stats.counters["dropped_triangles"] = static_cast<double>(scene.dropped_triangles());
    stats.counters["lights"] = static_cast<double>(scene.lights().size());
    {
        StageTimer t(stats, "scene_build");
        stats.bytes["embree_scene"] = static_cast<double>(scene.ray_tracer().bytes());
    }
    // The world's importance map, baked once per change of the world (world.h).
    if (scene.world_program() != nullptr || !scene.portals().empty()) {
        StageTimer t(stats, "world_map");
        const auto world = scene.world_light();
        if (world->map()) {
            stats.counters["world_map_cells"] = double(world->map()->width()) * double(world->map()->height());
            stats.bytes["world_map"] = double(world->map()->width()) * double(world->map()->height()) * 4.0 * sizeof(float);
        }
    }
}

}  // namespace ps
