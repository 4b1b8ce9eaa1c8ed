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

namespace ps {

namespace {

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
    std::vector<RTCScene> meshes;          // one per MeshData (nullptr when it has no triangles)
    std::vector<RTCGeometry> instances;    // one per Instance (nullptr when its mesh is empty)

    ~Impl() {
        for (RTCGeometry g : instances)
            if (g) rtc.rtcReleaseGeometry(g);
        for (RTCScene s : meshes)
            if (s) rtc.rtcReleaseScene(s);
        if (top) rtc.rtcReleaseScene(top);
    }
};

RayTracer::RayTracer(const std::vector<MeshData>& meshes, const std::vector<Instance>& instances) : impl_(new Impl) {
    try {
        const EmbreeApi& rtc = impl_->rtc;
        RTCDevice device = shared_device();
        rtc.rtcGetDeviceError(device);  // clear what an earlier call on this thread may have left
        for (const MeshData& mesh : meshes) {
            const size_t triangles = mesh.triangle_count();
            if (triangles == 0) {
                impl_->meshes.push_back(nullptr);
                continue;
            }
            // Built ahead while the scene was being filled (mesh_bvh.h), else here; one reference is ours.
            RTCScene scene = mesh.bvh ? mesh.bvh->retain() : nullptr;
            if (!scene) scene = build_mesh_scene(mesh_buffers(mesh));
            impl_->meshes.push_back(scene);
            bytes_ += mesh.positions.size() * 3 * sizeof(float) + triangles * 3 * sizeof(unsigned);
        }

        impl_->top = rtc.rtcNewScene(device);
        if (!impl_->top) throw_on_embree_error(device, "creating the scene");
        // Dynamic: moving instances refits the top level instead of rebuilding it from scratch.
        rtc.rtcSetSceneFlags(impl_->top, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_DYNAMIC);
        for (uint32_t i = 0; i < instances.size(); ++i) {
            RTCScene mesh = impl_->meshes[instances[i].mesh];
            if (!mesh) {
                impl_->instances.push_back(nullptr);
                continue;
            }
            RTCGeometry geometry = rtc.rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
            rtc.rtcSetGeometryInstancedScene(geometry, mesh);
            rtc.rtcSetGeometryTimeStepCount(geometry, 1);
            set_instance_transform(geometry, instances[i]);
            rtc.rtcSetGeometryMask(geometry, instances[i].visibility);
            rtc.rtcCommitGeometry(geometry);
            // The geometry id is the instance index: hits name their instance directly.
            rtc.rtcAttachGeometryByID(impl_->top, geometry, i);
            if (is_flat(instances[i])) rtc.rtcDisableGeometry(geometry);
            impl_->instances.push_back(geometry);
        }
        rtc.rtcCommitScene(impl_->top);
        throw_on_embree_error(device, "building the BVH");
        measure_reach(instances);
        bytes_ += instances.size() * (sizeof(glm::mat4) + 64);  // transform + a top-level BVH node, roughly
    } catch (...) {
        delete impl_;
        throw;
    }
}

RayTracer::~RayTracer() { delete impl_; }

void RayTracer::update_instances(const std::vector<Instance>& instances, const std::vector<uint32_t>& moved) {
    const EmbreeApi& rtc = impl_->rtc;
    for (uint32_t i : moved) {
        RTCGeometry geometry = impl_->instances[i];
        if (!geometry) continue;
        set_instance_transform(geometry, instances[i]);
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
    for (const Instance& instance : instances) {
        if (is_flat(instance)) continue;
        // normal_to_world is M⁻¹ transposed: the same Frobenius norm, which bounds the spectral one.
        const glm::dmat3 n(instance.normal_to_world);
        const double scale = std::sqrt(glm::dot(n[0], n[0]) + glm::dot(n[1], n[1]) + glm::dot(n[2], n[2]));
        reach_scale_ = std::max(reach_scale_, scale);
        reach_offset_ = std::max(reach_offset_, scale * glm::length(glm::dvec3(glm::vec3(instance.to_world[3]))));
    }
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
    constexpr double kReach = 1e17;  // an order of magnitude inside Embree's limit
    const auto reachable = [&](const glm::vec3& o) {
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
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    rh.ray = embree_ray(ray, t_min, t_max, rays);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    impl_->rtc.rtcIntersect1(impl_->top, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID || rh.hit.instID[0] == RTC_INVALID_GEOMETRY_ID) return false;
    hit.t = rh.ray.tfar + shift;
    hit.instance = rh.hit.instID[0];
    hit.triangle = rh.hit.primID;
    hit.u = rh.hit.u;
    hit.v = rh.hit.v;
    return true;
}

bool RayTracer::occluded(const Ray& original, float t_min, float t_max, uint32_t rays) const {
    Ray ray;
    float shift = 0.0f;
    if (!clip_to_scene(original, t_min, t_max, ray, shift)) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay r = embree_ray(ray, t_min, t_max, rays);
    impl_->rtc.rtcOccluded1(impl_->top, &context, &r);
    return r.tfar == -std::numeric_limits<float>::infinity();
}

}  // namespace ps
