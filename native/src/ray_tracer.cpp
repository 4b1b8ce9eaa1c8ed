#include "photonsplat/ray_tracer.h"

#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>

#include <embree3/rtcore.h>

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


// One Embree device per process, kept for its lifetime: creating devices per render is slow, and
// releasing one while another thread still uses it is how native add-ons crash Blender.
RTCDevice shared_device() {
    static RTCDevice device = [] {
        RTCDevice d = rtcNewDevice(nullptr);
        if (!d) throw std::runtime_error("Embree: could not create a device (error " +
                                         std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
        return d;
    }();
    return device;
}

// Embree keeps an error code per device and thread: read it right after the calls that can fail.
void throw_on_embree_error(RTCDevice device, const char* what) {
    const RTCError error = rtcGetDeviceError(device);
    if (error == RTC_ERROR_NONE) return;
    const char* reason = error == RTC_ERROR_OUT_OF_MEMORY ? "out of memory" : "internal error";
    throw std::runtime_error(std::string("Embree: ") + what + " failed (" + reason + ", code " +
                             std::to_string(static_cast<int>(error)) + ")");
}

}  // namespace

struct RayTracer::Impl {
    RTCScene scene = nullptr;
};

RayTracer::RayTracer(const std::vector<Triangle>& triangles) : impl_(new Impl) {
    RTCDevice device = shared_device();
    rtcGetDeviceError(device);  // clear what an earlier call on this thread may have left
    impl_->scene = rtcNewScene(device);
    if (!impl_->scene) {
        delete impl_;
        throw_on_embree_error(device, "creating a scene");
        throw std::runtime_error("Embree: creating a scene failed");
    }
    rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
    if (!triangles.empty()) {
        RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
            geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 3 * triangles.size()));
        auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
            geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangles.size()));
        if (!vertices || !indices) {
            rtcReleaseGeometry(geometry);
            rtcReleaseScene(impl_->scene);
            delete impl_;
            throw std::runtime_error("Embree: out of memory for " + std::to_string(triangles.size()) + " triangles");
        }
        for (size_t t = 0; t < triangles.size(); ++t) {
            const Triangle& tri = triangles[t];
            const glm::vec3 corners[3] = {tri.v0, tri.v1, tri.v2};
            for (int c = 0; c < 3; ++c) {
                vertices[9 * t + 3 * c + 0] = corners[c].x;
                vertices[9 * t + 3 * c + 1] = corners[c].y;
                vertices[9 * t + 3 * c + 2] = corners[c].z;
                indices[3 * t + c] = static_cast<unsigned>(3 * t + c);
            }
        }
        rtcCommitGeometry(geometry);
        rtcAttachGeometry(impl_->scene, geometry);
        rtcReleaseGeometry(geometry);
        bytes_ = triangles.size() * (9 * sizeof(float) + 3 * sizeof(unsigned));
    }
    rtcCommitScene(impl_->scene);
    try {
        throw_on_embree_error(device, "building the BVH");
    } catch (...) {
        rtcReleaseScene(impl_->scene);
        delete impl_;
        throw;
    }
}

RayTracer::~RayTracer() {
    rtcReleaseScene(impl_->scene);
    delete impl_;
}

bool RayTracer::intersect(const Ray& ray, float t_min, float t_max, Hit& hit) const {
    if (!embree_accepts(ray, t_min, t_max)) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    rh.ray.org_x = ray.origin.x;
    rh.ray.org_y = ray.origin.y;
    rh.ray.org_z = ray.origin.z;
    rh.ray.dir_x = ray.direction.x;
    rh.ray.dir_y = ray.direction.y;
    rh.ray.dir_z = ray.direction.z;
    rh.ray.tnear = t_min;
    rh.ray.tfar = t_max;
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    hit.t = rh.ray.tfar;
    hit.triangle = rh.hit.primID;
    hit.u = rh.hit.u;
    hit.v = rh.hit.v;
    return true;
}

bool RayTracer::occluded(const Ray& ray, float t_min, float t_max) const {
    if (!embree_accepts(ray, t_min, t_max)) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
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
    r.mask = 0xFFFFFFFFu;
    r.id = 0;
    r.flags = 0;
    rtcOccluded1(impl_->scene, &context, &r);
    return r.tfar == -std::numeric_limits<float>::infinity();
}

}  // namespace ps
