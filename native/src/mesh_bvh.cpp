#include "mesh_bvh.h"

#include <stdexcept>
#include <utility>

#include "embree_api.h"
#include "photonsplat/scene.h"

namespace ps {

namespace {
constexpr size_t kCompactBvhTriangles = 1u << 19;  // 524,288
}  // namespace

MeshBuffers mesh_buffers(const MeshData& mesh) {
    return {mesh.name, mesh.positions.data(), mesh.positions.size(), mesh.indices.data(), mesh.triangle_count()};
}

RTCScene build_mesh_scene(const MeshBuffers& mesh) {
    const EmbreeApi& rtc = embree_api();
    RTCDevice device = shared_device();
    rtc.rtcGetDeviceError(device);  // clear what an earlier call on this thread may have left
    RTCScene scene = rtc.rtcNewScene(device);
    if (!scene) throw_on_embree_error(device, "creating a mesh scene");
    // A mesh of millions of triangles gets Embree's compact leaves (triangles by index into the shared positions,
    // not copies of their corners): a third of the BVH's memory for slightly slower traversal; smaller meshes keep
    // the faster leaves, whose memory does not matter.
    const bool compact = mesh.triangle_count >= kCompactBvhTriangles;
    rtc.rtcSetSceneFlags(scene, compact ? RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_COMPACT : RTC_SCENE_FLAG_ROBUST);
    RTCGeometry geometry = rtc.rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    // Embree reads the mesh's own arrays (one copy of each: a 4-million-triangle scene would hold 72 MB twice).
    // They outlive the scene (MeshData owns both, see MeshData::bvh), and MeshData keeps room for Embree's
    // 16-byte read of the last element.
    static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "positions are packed float triples");
    rtc.rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, mesh.positions, 0,
                                   sizeof(glm::vec3), mesh.position_count);
    rtc.rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, mesh.indices, 0,
                                   3 * sizeof(uint32_t), mesh.triangle_count);
    if (rtc.rtcGetDeviceError(device) != RTC_ERROR_NONE) {
        rtc.rtcReleaseGeometry(geometry);
        rtc.rtcReleaseScene(scene);
        throw std::runtime_error("Embree: could not share the buffers of mesh '" + mesh.name + "' (" +
                                 std::to_string(mesh.triangle_count) + " triangles)");
    }
    rtc.rtcSetGeometryMask(geometry, 0xFFFFFFFFu);  // visibility is decided by the instance's mask
    rtc.rtcCommitGeometry(geometry);
    rtc.rtcAttachGeometryByID(scene, geometry, 0);
    rtc.rtcReleaseGeometry(geometry);
    rtc.rtcCommitScene(scene);
    if (rtc.rtcGetDeviceError(device) != RTC_ERROR_NONE) {
        rtc.rtcReleaseScene(scene);
        throw_on_embree_error(device, "building a mesh BVH");
        throw std::runtime_error("Embree: building a mesh BVH failed");
    }
    return scene;
}

MeshBvh::~MeshBvh() {
    if (scene_) embree_api().rtcReleaseScene(scene_);
}

RTCScene MeshBvh::retain() {
    std::unique_lock<std::mutex> lock(mutex_);
    done_changed_.wait(lock, [this] { return done_; });
    if (error_) std::rethrow_exception(error_);
    if (scene_) embree_api().rtcRetainScene(scene_);
    return scene_;
}

void MeshBvh::finish(RTCScene scene, std::exception_ptr error) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        scene_ = scene;
        error_ = std::move(error);
        done_ = true;
    }
    done_changed_.notify_all();
}

std::shared_ptr<MeshBvh> BvhQueue::start(const MeshData& mesh) {
    auto bvh = std::make_shared<MeshBvh>(mesh_buffers(mesh));
    {
        std::lock_guard<std::mutex> lock(mutex_);
        pending_.push_back(bvh);
        if (!thread_.joinable()) thread_ = std::thread([this] { run(); });
    }
    pending_changed_.notify_one();
    return bvh;
}

void BvhQueue::run() {
    for (;;) {
        std::shared_ptr<MeshBvh> bvh;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            pending_changed_.wait(lock, [this] { return stop_ || !pending_.empty(); });
            if (stop_) return;
            bvh = std::move(pending_.front());
            pending_.pop_front();
        }
        try {
            bvh->finish(build_mesh_scene(bvh->buffers_), nullptr);
        } catch (...) {
            bvh->finish(nullptr, std::current_exception());
        }
    }
}

BvhQueue::~BvhQueue() {
    std::deque<std::shared_ptr<MeshBvh>> dropped;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
        dropped.swap(pending_);
    }
    pending_changed_.notify_all();
    if (thread_.joinable()) thread_.join();
    for (const auto& bvh : dropped) bvh->finish(nullptr, nullptr);
}

}  // namespace ps
