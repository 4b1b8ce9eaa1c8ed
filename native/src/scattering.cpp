#include "photonsplat/scattering.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <glm/geometric.hpp>

#include "photonsplat/closures.h"
#include "photonsplat/material_program.h"
#include "photonsplat/materials.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/scene.h"

namespace ps {

namespace {
constexpr float kPi = 3.14159265358979323846f;
}
// Hit points on a mesh with large object-space coordinates carry about 4 ulps of them (barycentric interpolation,
// the instance transform, Embree's transform of the next ray back into object space): twice that is the step off.
// Measured on the Cornell box with its vertices at 1e5 (test_hard_cases.cpp): 4 and 8 ulps show no acne; 32 ulps
// (25 cm there) already let shadow rays start outside the box's walls.
constexpr float kScaleUlps = 8.0f;

float luminance(const glm::vec3& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

SurfacePoint surface_at(const Scene& scene, const Ray& ray, const Hit& hit, ShaderRay kind) {
    const Instance& instance = scene.instances()[hit.instance];
    const MeshData& mesh = scene.meshes()[instance.mesh];
    const size_t t = hit.triangle;
    const float w = 1.0f - hit.u - hit.v;
    const glm::vec3& p0 = mesh.positions[mesh.indices[3 * t]];
    const glm::vec3& p1 = mesh.positions[mesh.indices[3 * t + 1]];
    const glm::vec3& p2 = mesh.positions[mesh.indices[3 * t + 2]];
    SurfacePoint s;
    s.position = glm::vec3(instance.to_world * glm::vec4(w * p0 + hit.u * p1 + hit.v * p2, 1.0f));
    // Normals go through the inverse transpose; it also keeps the winding normal's side right under mirroring.
    // A stretched instance of a mesh no other instance shows turns each corner normal before interpolating
    // (Scene::normals_in_world), as Cycles does where it applied the transform.
    glm::vec3 ng = glm::normalize(instance.normal_to_world * glm::cross(p1 - p0, p2 - p0));
    glm::vec3 ns = ng;
    if (!mesh.normals.empty() && scene.normals_in_world(instance)) {
        const auto corner = [&](int c) {
            const glm::vec3 n = instance.normal_to_world * mesh.corner_normal(t, c);
            const float len = glm::length(n);
            return len > 0.0f ? n / len : n;
        };
        ns = w * corner(0) + hit.u * corner(1) + hit.v * corner(2);
        const float len = glm::length(ns);
        ns = (len > 1e-12f && std::isfinite(len)) ? ns / len : ng;
    } else if (!mesh.normals.empty()) {
        ns = instance.normal_to_world * (w * mesh.corner_normal(t, 0) + hit.u * mesh.corner_normal(t, 1) +
                                         hit.v * mesh.corner_normal(t, 2));
        const float len = glm::length(ns);
        ns = (len > 1e-12f && std::isfinite(len)) ? ns / len : ng;
    }
    // Blender's planes are visible from both sides: orient by the ray, never trust the winding alone.
    s.entering = glm::dot(ng, ray.direction) < 0.0f;
    if (!s.entering) ng = -ng;
    if (glm::dot(ns, ng) < 0.0f) ns = -ns;
    s.geometric_normal = ng;
    s.smooth_normal = ns;
    // Cycles 3.x gives every closure of a mesh the interpolated normal tilted towards the triangle just enough that
    // the view's mirror image stays above the triangle (svm_node_closure_bsdf: ensure_valid_reflection). Without it,
    // a smooth low-poly mirror seen at a grazing angle reflected views into itself where Cycles reflects them along
    // its facets (test_valid_reflection.py: an 80-face mirror sphere 0.964 of Cycles' image, 1.002 with it).
    s.shading_normal = mesh.normals.empty() ? ns : ensure_valid_reflection(ng, -ray.direction, ns);
    s.instance = hit.instance;
    s.triangle = hit.triangle;
    s.bary = glm::vec2(hit.u, hit.v);
    s.distance = hit.t;
    s.ray_kind = kind;
    s.material = &scene.materials()[mesh.materials[t]];
    s.rounding_scale = scene.ray_tracer().rounding_scale(hit.instance);
    s.uv = glm::vec2(0.0f);
    if (s.material->textured && !mesh.uvs.empty())
        s.uv = w * mesh.uvs[3 * t] + hit.u * mesh.uvs[3 * t + 1] + hit.v * mesh.uvs[3 * t + 2];
    s.tangent = glm::vec3(0.0f);
    if (s.material->anisotropic) {
        // Cycles' default tangent: radial about the object's Z axis, (−y, x, 0) in object space, carried to the
        // world as a direction and made perpendicular to the shading normal.
        const glm::vec3 p = w * p0 + hit.u * p1 + hit.v * p2;
        glm::vec3 t_world = glm::mat3(instance.to_world) * glm::vec3(-p.y, p.x, 0.0f);
        t_world -= ns * glm::dot(ns, t_world);
        const float len = glm::length(t_world);
        if (len > 1e-12f && std::isfinite(len)) {
            s.tangent = t_world / len;
        } else {  // on the axis itself: any tangent
            glm::vec3 b2;
            orthonormal_basis(ns, s.tangent, b2);
        }
    }
    if (s.material->program_normal) s.shading_normal = program_normal(scene, s, -ray.direction);
    return s;
}

bool inside_transmitter(const SurfacePoint& s) { return !s.entering && s.material->transmits; }

glm::vec3 offset_ray_origin(const glm::vec3& p, const glm::vec3& n, float rounding_scale) {
    constexpr float origin = 1.0f / 32.0f, float_scale = 1.0f / 65536.0f, int_scale = 256.0f;
    glm::vec3 result;
    for (int i = 0; i < 3; ++i) {
        // Where the rounding of the mesh's own coordinates outgrows the offset for p's (below), step off by it.
        const float ulp = std::nextafter(rounding_scale, std::numeric_limits<float>::infinity()) - rounding_scale;
        if (kScaleUlps * ulp > std::max(float_scale, int_scale * std::fabs(p[i]) * std::numeric_limits<float>::epsilon())) {
            result[i] = p[i] + kScaleUlps * ulp * n[i];
            continue;
        }
        int32_t offset = static_cast<int32_t>(int_scale * n[i]);
        int32_t bits;
        std::memcpy(&bits, &p[i], sizeof bits);
        bits += (p[i] < 0.0f) ? -offset : offset;
        float moved;
        std::memcpy(&moved, &bits, sizeof moved);
        result[i] = std::fabs(p[i]) < origin ? p[i] + float_scale * n[i] : moved;
    }
    return result;
}

void orthonormal_basis(const glm::vec3& n, glm::vec3& b1, glm::vec3& b2) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float b = n.x * n.y * a;
    b1 = glm::vec3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    b2 = glm::vec3(b, sign + n.y * n.y * a, -n.y);
}

glm::vec3 sample_cosine_hemisphere(const glm::vec3& n, float u1, float u2) {
    const float r = std::sqrt(u1);
    const float phi = 2.0f * kPi * u2;
    glm::vec3 b1, b2;
    orthonormal_basis(n, b1, b2);
    const float z = std::sqrt(std::max(0.0f, 1.0f - u1));
    return glm::normalize(r * std::cos(phi) * b1 + r * std::sin(phi) * b2 + z * n);
}

glm::vec3 sample_uniform_sphere(float u1, float u2) {
    const float z = 1.0f - 2.0f * u1;
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    const float phi = 2.0f * kPi * u2;
    return glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
}

glm::vec3 sample_uniform_cone(const glm::vec3& axis, float cos_max, float u1, float u2) {
    const float cos_theta = 1.0f - u1 * (1.0f - cos_max);
    const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
    const float phi = 2.0f * kPi * u2;
    glm::vec3 b1, b2;
    orthonormal_basis(axis, b1, b2);
    return glm::normalize(sin_theta * std::cos(phi) * b1 + sin_theta * std::sin(phi) * b2 + cos_theta * axis);
}

}  // namespace ps
