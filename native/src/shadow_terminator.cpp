#include "photonsplat/shadow_terminator.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"

namespace ps {

namespace {

// The share of the lift a light direction takes (Cycles' offset_amount): full for directions within `cutoff` of
// the shading or the triangle's horizon, none beyond twice it.
float lift_share(float cutoff, const glm::vec3& n, const glm::vec3& side, const glm::vec3& wi) {
    if (!(cutoff > 0.0f)) return 0.0f;
    const float nl = std::fabs(glm::dot(n, wi));
    const float ngl = glm::dot(side, wi);
    const float share = nl < cutoff ? 2.0f - (ngl + nl) / cutoff : 1.0f - ngl / cutoff;
    return std::clamp(share, 0.0f, 1.0f);
}

}  // namespace

TerminatorLift terminator_lift(const Scene& scene, const SurfacePoint& s, const glm::vec3& side) {
    TerminatorLift out;
    const Instance& instance = scene.instances()[s.instance];
    const MeshData& mesh = scene.meshes()[instance.mesh];
    if (!(instance.terminator_offset > 0.0f) || mesh.normals.empty()) return out;
    const size_t t = s.triangle;
    const glm::vec3 v[3] = {mesh.positions[mesh.indices[3 * t]], mesh.positions[mesh.indices[3 * t + 1]],
                            mesh.positions[mesh.indices[3 * t + 2]]};
    glm::vec3 n[3] = {mesh.corner_normal(t, 0), mesh.corner_normal(t, 1), mesh.corner_normal(t, 2)};
    // Barycentric weights of the corners, as Cycles names them: u for the first, v the second, w the third.
    const float u = 1.0f - s.bary.x - s.bary.y, v1 = s.bary.x, w = s.bary.y;
    // Cycles computes the lift with the corner normals as they are, towards the side its interpolated normal
    // faces, or with them turned, towards the other; both give the same as turning the normals to face the
    // light's side first (object space: the winding normal's side, or the other). On the front face the
    // geometric normal is the winding one.
    const glm::vec3 winding = glm::cross(v[1] - v[0], v[2] - v[0]);
    const glm::vec3 interpolated = u * n[0] + v1 * n[1] + w * n[2];
    const bool side_is_winding = (glm::dot(side, s.geometric_normal) > 0.0f) == s.entering;
    if ((glm::dot(interpolated, winding) > 0.0f) != side_is_winding)
        for (glm::vec3& c : n) c = -c;
    const glm::vec3 p = u * v[0] + v1 * v[1] + w * v[2];
    const glm::vec3 normal = u * n[0] + v1 * n[1] + w * n[2];  // not normalised, as Cycles
    // The parabola through the corners' tangent planes...
    const float a = glm::dot(n[2] - n[0], v[0] - v[2]);
    const float b = glm::dot(n[2] - n[1], v[1] - v[2]);
    const float c = glm::dot(n[1] - n[0], v[1] - v[0]);
    const float parabola = a * u * (u - 1.0f) + (a + b + c) * u * v1 + b * v1 * (v1 - 1.0f);
    // ... bounded by each corner's plane lifted over the other corners.
    float h[3];
    for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3, k = (i + 2) % 3;
        const float over = std::max(std::max(glm::dot(v[j] - v[i], n[i]), glm::dot(v[k] - v[i], n[i])), 0.0f);
        h[i] = std::max(glm::dot(v[i] - p, n[i]) + over, 0.0f);
    }
    const float height = std::max(std::min(std::min(h[0], h[1]), h[2]), 0.5f * parabola);
    // Object space to render space as a direction (Cycles' object_dir_transform).
    const glm::vec3 lift = glm::mat3(instance.to_world) * (normal * height);
    if (!std::isfinite(lift.x + lift.y + lift.z) || lift == glm::vec3(0.0f)) return out;
    out.lift = lift;
    out.cutoff = instance.terminator_offset;
    return out;
}

glm::vec3 terminator_origin(const glm::vec3& x, const TerminatorLift& t, const glm::vec3& n, const glm::vec3& side,
                            const glm::vec3& wi) {
    const float share = lift_share(t.cutoff, n, side, wi);
    return share > 0.0f ? x + t.lift * share : x;
}

bool terminator_reaches_below(const TerminatorLift& t, const glm::vec3& n, const glm::vec3& side,
                              const glm::vec3& wi) {
    return lift_share(t.cutoff, n, side, wi) > 0.0f && glm::dot(n, wi) * glm::dot(n, side) > 0.0f;
}

}  // namespace ps
