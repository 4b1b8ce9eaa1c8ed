// A mesh's Embree BVH built ahead: on a thread of the scene's own, as soon as add_mesh_data has stored the mesh,
// while the caller goes on filling the scene (issue 19: the add-on reads the next mesh from Blender meanwhile, on
// one core, while Embree builds on the others). RayTracer takes the built BVH instead of building it (and builds
// it itself where none was started). Scene::set_build_bvhs_ahead turns it on; off, no thread is ever started.
#pragma once
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <embree3/rtcore.h>
#include <glm/vec3.hpp>

namespace ps {

struct MeshData;

// The one Embree device of the process, and its error check (ray_tracer.cpp).
RTCDevice shared_device();
void throw_on_embree_error(RTCDevice device, const char* what);

// What a mesh BVH is built over: MeshData's own arrays (their heap buffers stay put when the MeshData moves).
struct MeshBuffers {
    std::string name;
    const glm::vec3* positions = nullptr;
    size_t position_count = 0;
    const uint32_t* indices = nullptr;  // 3 per triangle
    size_t triangle_count = 0;
};
MeshBuffers mesh_buffers(const MeshData& mesh);

// An Embree scene of one triangle geometry over the buffers (shared, not copied); the caller owns its reference.
RTCScene build_mesh_scene(const MeshBuffers& buffers);

class MeshBvh {
public:
    explicit MeshBvh(MeshBuffers buffers) : buffers_(std::move(buffers)) {}
    ~MeshBvh();
    MeshBvh(const MeshBvh&) = delete;
    MeshBvh& operator=(const MeshBvh&) = delete;
    // Waits for the build and returns the scene with a reference for the caller; rethrows the build's error;
    // nullptr when the build was dropped (the scene went away first).
    RTCScene retain();

private:
    friend class BvhQueue;
    void finish(RTCScene scene, std::exception_ptr error);
    MeshBuffers buffers_;
    std::mutex mutex_;
    std::condition_variable done_changed_;
    bool done_ = false;
    RTCScene scene_ = nullptr;
    std::exception_ptr error_;
};

// Builds one mesh BVH after another on one thread (started with the first), so that a scene of many meshes
// neither starts a thread per mesh nor builds them all at once.
class BvhQueue {
public:
    BvhQueue() = default;
    ~BvhQueue();  // drops the builds not started, waits for the running one
    BvhQueue(const BvhQueue&) = delete;
    BvhQueue& operator=(const BvhQueue&) = delete;
    std::shared_ptr<MeshBvh> start(const MeshData& mesh);

private:
    void run();
    std::mutex mutex_;
    std::condition_variable pending_changed_;
    std::deque<std::shared_ptr<MeshBvh>> pending_;
    bool stop_ = false;
    std::thread thread_;
};

}  // namespace ps
