// Embree behind a small interface: closest hit and occlusion of single rays. A mesh that one instance shows is
// placed into the scene's BVH as render-space triangles (as Cycles applies the transform of a mesh that is not
// instanced): a ray then descends one BVH, not a top level and an instance's own, and where objects' boxes
// overlap (a room's walls, floor and furniture) it is not restarted in every instance it enters. That traced
// the atrium's direct light in 0.60 of the time (docs/benchmarks.md). A mesh shown by several instances keeps
// one BVH in object space, built and stored once, under an instance of it, and so does an object moved more than
// once (dragged in the viewport): moving an instance refits the top level only.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "photonsplat/camera.h"

struct RTCSceneTy;  // Embree's scene (RTCScene), kept out of this header

namespace ps {

struct MeshData;
struct Instance;

struct Hit {
    float t = 0.0f;
    uint32_t instance = 0;     // index into Scene::instances()
    uint32_t triangle = 0;     // index into that instance's mesh triangles
    float u = 0.0f, v = 0.0f;  // barycentrics of the triangle's 2nd and 3rd corners
};

class RayTracer {
public:
    RayTracer(const std::vector<MeshData>& meshes, const std::vector<Instance>& instances);
    ~RayTracer();
    RayTracer(const RayTracer&) = delete;
    RayTracer& operator=(const RayTracer&) = delete;

    // Closest hit with t in (t_min, t_max) among instances visible to `rays` (RayVisibility bits, scene.h);
    // false when the ray escapes.
    bool intersect(const Ray& ray, float t_min, float t_max, Hit& hit, uint32_t rays = 7u) const;
    // True when anything visible to `rays` lies between t_min and t_max along the ray.
    bool occluded(const Ray& ray, float t_min, float t_max, uint32_t rays = 7u) const;
    // Up to kPacketRays rays at once (Embree's ray packets): as intersect and occluded for each, faster where
    // the rays are coherent (from one point towards one light, or parallel and side by side). Results are
    // those of the single-ray calls.
    static constexpr int kPacketRays = 8;
    // Meshes of this many triangles or more stay instances even when shown once: their BVH can then be built
    // while the scene is exported (Scene::set_build_bvhs_ahead), where placed triangles must wait for the
    // transform and the first render, and entering an instance costs little beside traversing a mesh this big.
    static constexpr size_t kPlacedTriangleLimit = 262144;
    struct Packet;  // the rays of one packet call, clipped (ray_tracer.cpp)
    void intersect(const Ray* rays, const float* t_min, const float* t_max, int count, uint32_t visibility, Hit* hits,
                   bool* found) const;
    void occluded(const Ray* rays, const float* t_min, const float* t_max, int count, uint32_t visibility,
                  bool* blocked) const;
    // Applies new transforms of the listed instances (already stored in `instances`): a placed one is re-placed
    // on its first move and becomes an instance of its mesh on the next, an instance takes its new transform;
    // then the top level is recommitted. Not thread-safe against concurrent queries.
    void update_instances(const std::vector<MeshData>& meshes, const std::vector<Instance>& instances,
                          const std::vector<uint32_t>& moved);
    size_t bytes() const { return bytes_; }
    // The coordinate size whose float rounding a hit on the instance carries (offset_ray_origin): its mesh's
    // object-space size through the linear part when traced as an instance; for triangles placed in render
    // space, the render-space size of its box, since their corners were rounded there.
    float rounding_scale(uint32_t instance) const { return rounding_[instance]; }
    // Whether the instance's triangles are placed in render space (true) or traced as an instance (false).
    bool placed(uint32_t instance) const { return placed_[instance] != 0; }

private:
    // Embree traces a ray through an instance in the mesh's space, where its origin is M⁻¹·(o − t): that must
    // stay below Embree's 1.8e18 (it asserts, aborting Blender, past it). ‖M⁻¹·(o − t)‖ <= scale·‖o‖ + offset
    // over the enabled instances; a ray from farther than that allows starts where it enters the scene's box.
    void measure_reach(const std::vector<Instance>& instances);
    void place_triangles(const MeshData& mesh, const Instance& instance, uint32_t id);
    ::RTCSceneTy* mesh_scene(const std::vector<MeshData>& meshes, uint32_t mesh);
    void attach_instance(const std::vector<MeshData>& meshes, const Instance& instance, uint32_t id);
    bool clip_to_scene(const Ray& original, float& t_min, float& t_max, Ray& ray, float& shift) const;
    // Fills `packet` with the first min(count, kPacketRays) rays, clipped, counts them; returns that number.
    int clip_packet(const Ray* rays, const float* t_min, const float* t_max, int count, Packet& packet) const;

    struct Impl;
    Impl* impl_;
    size_t bytes_ = 0;
    std::vector<float> rounding_;    // per instance, rounding_scale()
    std::vector<uint8_t> placed_;    // per instance, placed()
    std::vector<uint8_t> moved_before_;  // per instance: moved once already (update_instances)
    double reach_scale_ = 0.0, reach_offset_ = 0.0;
    float near_enough_ = 0.0f;  // origins with every coordinate within this are reachable (clip_to_scene)
    glm::vec3 scene_lo_{0.0f}, scene_hi_{0.0f};  // the top level's bounds, render space
};

}  // namespace ps
