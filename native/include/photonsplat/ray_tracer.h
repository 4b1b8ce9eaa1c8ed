// Embree behind a small interface: closest hit and occlusion of single rays, over the scene's triangles.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "photonsplat/camera.h"

namespace ps {

struct Triangle;

struct Hit {
    float t = 0.0f;
    uint32_t triangle = 0;   // index into Scene::triangles()
    float u = 0.0f, v = 0.0f;  // barycentrics of v1 and v2
};

class RayTracer {
public:
    explicit RayTracer(const std::vector<Triangle>& triangles);
    ~RayTracer();
    RayTracer(const RayTracer&) = delete;
    RayTracer& operator=(const RayTracer&) = delete;

    // Closest hit with t in (t_min, t_max); false when the ray escapes.
    bool intersect(const Ray& ray, float t_min, float t_max, Hit& hit) const;
    // True when anything lies between t_min and t_max along the ray.
    bool occluded(const Ray& ray, float t_min, float t_max) const;
    size_t bytes() const { return bytes_; }

private:
    struct Impl;
    Impl* impl_;
    size_t bytes_ = 0;
};

}  // namespace ps
