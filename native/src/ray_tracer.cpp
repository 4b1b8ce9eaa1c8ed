#include "photonsplat/ray_tracer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>

#include <embree3/rtcore.h>
#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>

#include "embree_api.h"
#include "mesh_bvh.h"
#include "photonsplat/scene.h"
#include "photonsplat/stats.h"

namespace ps {

namespace {

constexpr double kReach = 1e17;  // how far from an instance's origin a ray may start: inside Embree's 1.8e18

// What a mesh's vertices and triangle indices take in an Embree scene.
size_t mesh_bytes(const MeshData& mesh) {
    return mesh.positions.size() * 3 * sizeof(float) + mesh.triangle_count() * 3 * sizeof(unsigned);
}

// The instance a hit belongs to: named in instID inside an instance; placed triangles are its own geometry.
uint32_t hit_instance(unsigned inst_id, unsigned geom_id) {
    return inst_id != RTC_INVALID_GEOMETRY_ID ? inst_id : geom_id;
}

// Embree asserts (aborting the process, Blender with it) on a ray with a non-finite or huge origin or direction,
// or a negative or inverted range. Scene validation keeps such rays from being made; this is the last guard.
bool embree_accepts(const Ray& ray, float t_min, float t_max) {
    constexpr float kLarge = 1.8e18f;
    for (int i = 0; i < 3; ++i)
        if (!(std::fabs(ray.origin[i]) <= kLarge) || !(std::fabs(ray.direction[i]) <= kLarge)) return false;
    return t_min >= 0.0f && t_min <= t_max;
}

}  // namespace

// One Embree device per process, kept for its lifetime: creating devices per render is slow, and
// releasing one while another thread still uses it is how native add-ons crash Blender.
RTCDevice shared_device() {
    static RTCDevice device = [] {
        const EmbreeApi& rtc = embree_api();
        RTCDevice d = rtc.rtcNewDevice(nullptr);
        if (!d) throw std::runtime_error("Embree: could not create a device (error " +
                                         std::to_string(static_cast<int>(rtc.rtcGetDeviceError(nullptr))) + ")");
        return d;
    }();
    return device;
}

// Embree keeps an error code per device and thread: read it right after the calls that can fail.
void throw_on_embree_error(RTCDevice device, const char* what) {
    const EmbreeApi& rtc = embree_api();
    const RTCError error = rtc.rtcGetDeviceError(device);
    if (error == RTC_ERROR_NONE) return;
    const char* reason = error == RTC_ERROR_OUT_OF_MEMORY ? "out of memory" : "internal error";
    throw std::runtime_error(std::string("Embree: ") + what + " failed (" + reason + ", code " +
                             std::to_string(static_cast<int>(error)) + ")");
}

namespace {

// A flattened instance (zero scale) has no inverse: Embree gets the identity and the geometry is disabled.
bool is_flat(const Instance& instance) { return instance.normal_to_world == glm::mat3(0.0f); }

void set_instance_transform(RTCGeometry geometry, const Instance& instance) {
    const EmbreeApi& rtc = embree_api();
    const glm::mat4 m = is_flat(instance) ? glm::mat4(1.0f) : instance.to_world;
    // glm is column-major: exactly Embree's RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR.
    rtc.rtcSetGeometryTransform(geometry, 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, &m[0][0]);
}

}  // namespace

struct RayTracer::Impl {
    const EmbreeApi& rtc = embree_api();   // every Embree call goes through this table (embree_api.h says why)
    RTCScene top = nullptr;
    std::vector<RTCScene> meshes;          // one per MeshData traced as an instance (nullptr otherwise)
    // One per Instance (nullptr when its mesh is empty): its render-space triangles, or an instance of its mesh.
    std::vector<RTCGeometry> instances;
    std::vector<float*> placed_vertices;   // per Instance: Embree's vertex buffer of its placed triangles, or null

    ~Impl() {
        for (RTCGeometry g : instances)
            if (g) rtc.rtcReleaseGeometry(g);
        for (RTCScene s : meshes)
            if (s) rtc.rtcReleaseScene(s);
        if (top) rtc.rtcReleaseScene(top);
    }
};

namespace {

// A triangle geometry holding the mesh's triangles, its vertices to be written by the caller; throws when Embree
// cannot hold them.
RTCGeometry triangle_geometry(const EmbreeApi& rtc, RTCDevice device, const MeshData& mesh, float*& vertices) {
    const size_t triangles = mesh.triangle_count();
    RTCGeometry geometry = rtc.rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    vertices = static_cast<float*>(rtc.rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), mesh.positions.size()));
    auto* indices = static_cast<unsigned*>(rtc.rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0,
                                                                       RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangles));
    if (!vertices || !indices) {
        rtc.rtcReleaseGeometry(geometry);
        throw std::runtime_error("Embree: out of memory for mesh '" + mesh.name + "' (" + std::to_string(triangles) +
                                 " triangles)");
    }
    for (size_t i = 0; i < mesh.indices.size(); ++i) indices[i] = mesh.indices[i];
    return geometry;
}

// Whether an instance's triangles go into the top level in render space: its mesh is shown by no other instance
// (a shared mesh is stored once, under instances), is under kPlacedTriangleLimit, and the instance lies within 64
// of its own sizes of the render origin, so that its corners, rounded in render space, lose at most 6 bits of
// what object space kept (as MeshData's re-centring allows); farther out it stays an instance, exact in its own
// space.
bool places_triangles(const MeshData& mesh, const Instance& instance, uint32_t users) {
    if (users != 1 || is_flat(instance) || mesh.triangle_count() >= RayTracer::kPlacedTriangleLimit) return false;
    glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
    grow_by_instance_box(mesh, instance, lo, hi);
    const glm::vec3 reach = glm::max(glm::abs(lo), glm::abs(hi));
    const glm::vec3 extent = hi - lo;
    const float side = std::max(extent.x, std::max(extent.y, extent.z));
    return std::max(reach.x, std::max(reach.y, reach.z)) <= 64.0f * side;
}

}  // namespace

RayTracer::RayTracer(const std::vector<MeshData>& meshes, const std::vector<Instance>& instances) : impl_(new Impl) {
    try {
        const EmbreeApi& rtc = impl_->rtc;
        RTCDevice device = shared_device();
        rtc.rtcGetDeviceError(device);  // clear what an earlier call on this thread may have left
        std::vector<uint32_t> users(meshes.size(), 0);
        for (const Instance& instance : instances) ++users[instance.mesh];
        rounding_.assign(instances.size(), 0.0f);
        placed_.assign(instances.size(), 0);
        moved_before_.assign(instances.size(), 0);
        impl_->placed_vertices.assign(instances.size(), nullptr);
        for (uint32_t i = 0; i < instances.size(); ++i) {
            const MeshData& mesh = meshes[instances[i].mesh];
            placed_[i] = mesh.triangle_count() > 0 && places_triangles(mesh, instances[i], users[instances[i].mesh]);
        }
        impl_->meshes.assign(meshes.size(), nullptr);
        impl_->top = rtc.rtcNewScene(device);
        if (!impl_->top) throw_on_embree_error(device, "creating the scene");
        // Dynamic: a moved object rebuilds its own part and the top, not the whole scene.
        rtc.rtcSetSceneFlags(impl_->top, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_DYNAMIC);
        impl_->instances.assign(instances.size(), nullptr);  // stays null for an empty mesh
        for (uint32_t i = 0; i < instances.size(); ++i) {
            const MeshData& mesh = meshes[instances[i].mesh];
            if (mesh.triangle_count() == 0) continue;
            if (!placed_[i]) {
                attach_instance(meshes, instances[i], i);
                continue;
            }
            RTCGeometry geometry = triangle_geometry(rtc, device, mesh, impl_->placed_vertices[i]);
            impl_->instances[i] = geometry;  // owned from here on, released by ~Impl
            place_triangles(mesh, instances[i], i);
            bytes_ += mesh_bytes(mesh);
            rtc.rtcSetGeometryMask(geometry, instances[i].visibility);
            rtc.rtcCommitGeometry(geometry);
            // The geometry id is the instance index: hits name their instance directly.
            rtc.rtcAttachGeometryByID(impl_->top, geometry, i);
        }
        rtc.rtcCommitScene(impl_->top);
        throw_on_embree_error(device, "building the BVH");
        measure_reach(instances);
    } catch (...) {
        delete impl_;
        throw;
    }
}

RayTracer::~RayTracer() { delete impl_; }

// The object-space BVH of mesh m, built on first use and shared by every instance of it.
RTCScene RayTracer::mesh_scene(const std::vector<MeshData>& meshes, uint32_t m) {
    if (impl_->meshes[m]) return impl_->meshes[m];
    const MeshData& mesh = meshes[m];
    // Built ahead while the scene was being filled (mesh_bvh.h), else here; one reference is ours.
    RTCScene scene = mesh.bvh ? mesh.bvh->retain() : nullptr;
    if (!scene) scene = build_mesh_scene(mesh_buffers(mesh));
    impl_->meshes[m] = scene;
    bytes_ += mesh_bytes(mesh);
    return scene;
}

// Puts instance `id` into the top level as an instance of its mesh's object-space BVH.
void RayTracer::attach_instance(const std::vector<MeshData>& meshes, const Instance& instance, uint32_t id) {
    const EmbreeApi& rtc = impl_->rtc;
    RTCScene scene = mesh_scene(meshes, instance.mesh);
    RTCGeometry geometry = rtc.rtcNewGeometry(shared_device(), RTC_GEOMETRY_TYPE_INSTANCE);
    impl_->instances[id] = geometry;
    rtc.rtcSetGeometryInstancedScene(geometry, scene);
    rtc.rtcSetGeometryTimeStepCount(geometry, 1);
    set_instance_transform(geometry, instance);
    rounding_[id] = instance.rounding_scale;
    bytes_ += sizeof(glm::mat4) + 64;  // transform + a top-level BVH node, roughly
    rtc.rtcSetGeometryMask(geometry, instance.visibility);
    rtc.rtcCommitGeometry(geometry);
    rtc.rtcAttachGeometryByID(impl_->top, geometry, id);  // the id is the instance index, as placed triangles'
    if (is_flat(instance)) rtc.rtcDisableGeometry(geometry);
}

// Writes the instance's triangles' corners in render space into its geometry's vertex buffer, and the rounding
// they carry.
void RayTracer::place_triangles(const MeshData& mesh, const Instance& instance, uint32_t id) {
    float* vertices = impl_->placed_vertices[id];
    float scale = 0.0f;
    for (size_t k = 0; k < mesh.positions.size(); ++k) {
        const glm::vec3 q(instance.to_world * glm::vec4(mesh.positions[k], 1.0f));
        vertices[3 * k + 0] = q.x;
        vertices[3 * k + 1] = q.y;
        vertices[3 * k + 2] = q.z;
        if (std::isfinite(q.x + q.y + q.z))
            scale = std::max(scale, std::max(std::fabs(q.x), std::max(std::fabs(q.y), std::fabs(q.z))));
    }
    rounding_[id] = std::max(scale, instance.rounding_scale);
}

void RayTracer::update_instances(const std::vector<MeshData>& meshes, const std::vector<Instance>& instances,
                                 const std::vector<uint32_t>& moved) {
    const EmbreeApi& rtc = impl_->rtc;
    for (uint32_t i : moved) {
        RTCGeometry geometry = impl_->instances[i];
        if (!geometry) continue;
        if (placed_[i] && !moved_before_[i]) {
            // A first move re-places its triangles: the scene then renders as a fresh one would, bit for bit.
            moved_before_[i] = 1;
            place_triangles(meshes[instances[i].mesh], instances[i], i);
            rtc.rtcUpdateGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0);
            rtc.rtcCommitGeometry(geometry);
            if (is_flat(instances[i]))
                rtc.rtcDisableGeometry(geometry);
            else
                rtc.rtcEnableGeometry(geometry);
            continue;
        }
        if (placed_[i]) {
            // Moved again: being dragged. From now on an instance of its mesh (as Cycles keeps what moves in the
            // viewport), so that each step refits the top level instead of rebuilding the object's BVH.
            rtc.rtcDetachGeometry(impl_->top, i);
            rtc.rtcReleaseGeometry(geometry);
            impl_->instances[i] = nullptr;
            impl_->placed_vertices[i] = nullptr;
            placed_[i] = 0;
            attach_instance(meshes, instances[i], i);
            continue;
        }
        set_instance_transform(geometry, instances[i]);
        rounding_[i] = instances[i].rounding_scale;
        rtc.rtcCommitGeometry(geometry);
        if (is_flat(instances[i]))
            rtc.rtcDisableGeometry(geometry);
        else
            rtc.rtcEnableGeometry(geometry);
    }
    rtc.rtcCommitScene(impl_->top);
    throw_on_embree_error(shared_device(), "updating instance transforms");
    measure_reach(instances);
}

void RayTracer::measure_reach(const std::vector<Instance>& instances) {
    reach_scale_ = reach_offset_ = 0.0;
    for (uint32_t i = 0; i < instances.size(); ++i) {
        const Instance& instance = instances[i];
        if (is_flat(instance) || placed_[i]) continue;  // placed triangles take rays as they are
        // normal_to_world is M⁻¹ transposed: the same Frobenius norm, which bounds the spectral one.
        const glm::dmat3 n(instance.normal_to_world);
        const double scale = std::sqrt(glm::dot(n[0], n[0]) + glm::dot(n[1], n[1]) + glm::dot(n[2], n[2]));
        reach_scale_ = std::max(reach_scale_, scale);
        reach_offset_ = std::max(reach_offset_, scale * glm::length(glm::dvec3(glm::vec3(instance.to_world[3]))));
    }
    // Origins within this coordinate are reachable for certain (clip_to_scene), with a margin for its rounding.
    near_enough_ = reach_scale_ > 0.0 ? float(0.5 * (kReach - reach_offset_) / (reach_scale_ * std::sqrt(3.0))) : 1e17f;
    if (!(near_enough_ > 0.0f)) near_enough_ = 0.0f;
    RTCBounds bounds;
    impl_->rtc.rtcGetSceneBounds(impl_->top, &bounds);
    scene_lo_ = glm::vec3(bounds.lower_x, bounds.lower_y, bounds.lower_z);
    scene_hi_ = glm::vec3(bounds.upper_x, bounds.upper_y, bounds.upper_z);
}

// A ray whose origin lies too far for every instance's space to hold it (a camera or a light absurdly far from a
// mesh scaled down) is moved forward to where it enters the scene's box, since nothing lies before that; `shift`
// says by how much. False when it misses the box or the box itself is out of reach, or when Embree would refuse the
// ray (embree_accepts). Ordinary rays are untouched.
bool RayTracer::clip_to_scene(const Ray& original, float& t_min, float& t_max, Ray& ray, float& shift) const {
    if (!embree_accepts(original, t_min, t_max)) return false;
    ray = original;
    const auto reachable = [&](const glm::vec3& o) {
        if (std::fabs(o.x) <= near_enough_ && std::fabs(o.y) <= near_enough_ && std::fabs(o.z) <= near_enough_)
            return true;  // every ray of an ordinary scene: one comparison a coordinate
        const double far = std::max(std::fabs(double(o.x)), std::max(std::fabs(double(o.y)), std::fabs(double(o.z))));
        return reach_scale_ * std::sqrt(3.0) * far + reach_offset_ <= kReach;
    };
    shift = 0.0f;
    if (reachable(ray.origin)) return true;
    float enter = 0.0f, leave = std::numeric_limits<float>::infinity();
    for (int i = 0; i < 3; ++i) {
        const float inverse = 1.0f / ray.direction[i];
        float a = (scene_lo_[i] - ray.origin[i]) * inverse, b = (scene_hi_[i] - ray.origin[i]) * inverse;
        if (a > b) std::swap(a, b);
        if (!(a <= b)) continue;  // parallel to the slab (0 · ∞): the origin is inside it or never enters
        enter = std::max(enter, a);
        leave = std::min(leave, b);
    }
    if (!(enter <= leave) || !(enter < t_max)) return false;
    shift = enter;
    ray.origin = ray.origin + shift * ray.direction;
    t_min = std::max(0.0f, t_min - shift);
    t_max = t_max - shift;
    return t_min <= t_max && reachable(ray.origin);
}

namespace {

// Embree's ray for the part [t_min, t_max] of `ray`, seen by the instances whose mask shares a bit with `rays`.
RTCRay embree_ray(const Ray& ray, float t_min, float t_max, uint32_t rays) {
    RTCRay r;
    r.org_x = ray.origin.x;
    r.org_y = ray.origin.y;
    r.org_z = ray.origin.z;
    r.dir_x = ray.direction.x;
    r.dir_y = ray.direction.y;
    r.dir_z = ray.direction.z;
    r.tnear = t_min;
    r.tfar = t_max;
    r.time = 0.0f;
    r.mask = rays;
    r.id = 0;
    r.flags = 0;
    return r;
}

}  // namespace

bool RayTracer::intersect(const Ray& original, float t_min, float t_max, Hit& hit, uint32_t rays) const {
    Ray ray;
    float shift = 0.0f;
    if (!clip_to_scene(original, t_min, t_max, ray, shift)) return false;
    count_rays(1);
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    rh.ray = embree_ray(ray, t_min, t_max, rays);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    impl_->rtc.rtcIntersect1(impl_->top, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    hit.t = rh.ray.tfar + shift;
    hit.instance = hit_instance(rh.hit.instID[0], rh.hit.geomID);
    hit.triangle = rh.hit.primID;
    hit.u = rh.hit.u;
    hit.v = rh.hit.v;
    return true;
}

bool RayTracer::occluded(const Ray& original, float t_min, float t_max, uint32_t rays) const {
    Ray ray;
    float shift = 0.0f;
    if (!clip_to_scene(original, t_min, t_max, ray, shift)) return false;
    count_rays(1);
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay r = embree_ray(ray, t_min, t_max, rays);
    impl_->rtc.rtcOccluded1(impl_->top, &context, &r);
    return r.tfar == -std::numeric_limits<float>::infinity();
}

// A packet of up to 8 rays for Embree: the lanes past the count and the rays clip_to_scene refuses are inactive.
struct RayTracer::Packet {
    alignas(32) int valid[RayTracer::kPacketRays];
    float shift[RayTracer::kPacketRays];
    Ray ray[RayTracer::kPacketRays];
    float lo[RayTracer::kPacketRays], hi[RayTracer::kPacketRays];
};

namespace {

template <typename EmbreeRay8>
void fill(const RayTracer::Packet& packet, uint32_t visibility, EmbreeRay8& r) {
    for (int i = 0; i < RayTracer::kPacketRays; ++i) {
        const bool active = packet.valid[i] != 0;
        r.org_x[i] = active ? packet.ray[i].origin.x : 0.0f;
        r.org_y[i] = active ? packet.ray[i].origin.y : 0.0f;
        r.org_z[i] = active ? packet.ray[i].origin.z : 0.0f;
        r.dir_x[i] = active ? packet.ray[i].direction.x : 0.0f;
        r.dir_y[i] = active ? packet.ray[i].direction.y : 0.0f;
        r.dir_z[i] = active ? packet.ray[i].direction.z : 1.0f;
        r.tnear[i] = active ? packet.lo[i] : 0.0f;
        r.tfar[i] = active ? packet.hi[i] : -1.0f;
        r.time[i] = 0.0f;
        r.mask[i] = visibility;
        r.id[i] = static_cast<unsigned>(i);
        r.flags[i] = 0;
    }
}

}  // namespace

int RayTracer::clip_packet(const Ray* rays, const float* t_min, const float* t_max, int count, Packet& packet) const {
    count = std::clamp(count, 0, kPacketRays);
    count_rays(static_cast<uint64_t>(count));
    for (int i = 0; i < kPacketRays; ++i) {
        packet.shift[i] = 0.0f;
        bool active = false;
        if (i < count) {
            packet.lo[i] = t_min[i];
            packet.hi[i] = t_max[i];
            active = clip_to_scene(rays[i], packet.lo[i], packet.hi[i], packet.ray[i], packet.shift[i]);
        }
        packet.valid[i] = active ? -1 : 0;
    }
    return count;
}

void RayTracer::intersect(const Ray* rays, const float* t_min, const float* t_max, int count, uint32_t visibility,
                          Hit* hits, bool* found) const {
    Packet packet;
    count = clip_packet(rays, t_min, t_max, count, packet);
    RTCRayHit8 rh;
    fill(packet, visibility, rh.ray);
    for (int i = 0; i < kPacketRays; ++i) {
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
    }
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    impl_->rtc.rtcIntersect8(packet.valid, impl_->top, &context, &rh);
    for (int i = 0; i < count; ++i) {
        found[i] = packet.valid[i] != 0 && rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
        if (!found[i]) continue;
        hits[i].t = rh.ray.tfar[i] + packet.shift[i];
        hits[i].instance = hit_instance(rh.hit.instID[0][i], rh.hit.geomID[i]);
        hits[i].triangle = rh.hit.primID[i];
        hits[i].u = rh.hit.u[i];
        hits[i].v = rh.hit.v[i];
    }
}

void RayTracer::occluded(const Ray* rays, const float* t_min, const float* t_max, int count, uint32_t visibility,
                         bool* blocked) const {
    Packet packet;
    count = clip_packet(rays, t_min, t_max, count, packet);
    RTCRay8 r;
    fill(packet, visibility, r);
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    impl_->rtc.rtcOccluded8(packet.valid, impl_->top, &context, &r);
    for (int i = 0; i < count; ++i)
        blocked[i] = packet.valid[i] != 0 && r.tfar[i] == -std::numeric_limits<float>::infinity();
}

}  // namespace ps
