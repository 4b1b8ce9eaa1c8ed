#include "photonsplat/scattering.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <glm/geometric.hpp>

#include "photonsplat/brdf.h"
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

SurfacePoint surface_at(const Scene& scene, const Ray& ray, const Hit& hit) {
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
    glm::vec3 ng = glm::normalize(instance.normal_to_world * glm::cross(p1 - p0, p2 - p0));
    glm::vec3 ns = ng;
    if (!mesh.normals.empty()) {
        ns = instance.normal_to_world * (w * mesh.normals[3 * t] + hit.u * mesh.normals[3 * t + 1] +
                                         hit.v * mesh.normals[3 * t + 2]);
        const float len = glm::length(ns);
        ns = (len > 1e-12f && std::isfinite(len)) ? ns / len : ng;
    }
    // Blender's planes are visible from both sides: orient by the ray, never trust the winding alone.
    s.entering = glm::dot(ng, ray.direction) < 0.0f;
    if (!s.entering) ng = -ng;
    if (glm::dot(ns, ng) < 0.0f) ns = -ns;
    s.geometric_normal = ng;
    s.shading_normal = ns;
    s.material = &scene.materials()[mesh.materials[t]];
    s.color = s.material->color;
    s.rounding_scale = instance.rounding_scale;
    if (s.material->holdout) {
        s.color = glm::vec3(0.0f);  // absorbs whatever reaches it
    } else if (s.material->texture >= 0) {
        glm::vec2 uv(0.0f);
        if (!mesh.uvs.empty()) uv = w * mesh.uvs[3 * t] + hit.u * mesh.uvs[3 * t + 1] + hit.v * mesh.uvs[3 * t + 2];
        s.color = scene.textures()[s.material->texture].lookup(uv);
    }
    return s;
}

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

// Unpolarised Fresnel reflectance of a smooth dielectric; cos_i > 0 on the incident side, eta = n_i / n_t.
static float fresnel_dielectric(float cos_i, float eta, float& cos_t) {
    const float sin2_t = eta * eta * std::max(0.0f, 1.0f - cos_i * cos_i);
    if (sin2_t >= 1.0f) {
        cos_t = 0.0f;
        return 1.0f;  // total internal reflection
    }
    cos_t = std::sqrt(1.0f - sin2_t);
    const float r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    const float r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5f * (r_s * r_s + r_p * r_p);
}

namespace {

// What a glass surface does to a ray arriving along `direction`: both directions and the Fresnel reflectance
// (1 under total internal reflection, when `refracted` is unused).
struct GlassBranches {
    glm::vec3 reflected, refracted;
    float reflectance;
};

GlassBranches glass_branches(const Material& material, const SurfacePoint& surface, const glm::vec3& direction) {
    const glm::vec3 n = surface.shading_normal;  // faces the incoming ray
    const float cos_i = std::clamp(-glm::dot(direction, n), 0.0f, 1.0f);
    GlassBranches b;
    b.reflected = glm::normalize(direction + 2.0f * cos_i * n);
    // Entering the front face goes from air (1) into the material (ior); leaving goes back out.
    const float eta = surface.entering ? 1.0f / material.ior : material.ior;
    float cos_t = 0.0f;
    b.reflectance = fresnel_dielectric(cos_i, eta, cos_t);
    // Radiance's (n_t/n_i)² factor is left out: it cancels on the way in and out of closed objects.
    b.refracted = b.reflectance < 1.0f ? glm::normalize(eta * direction + (eta * cos_i - cos_t) * n) : b.reflected;
    return b;
}

}  // namespace

SpecularStep scatter_specular(const Material& material, const SurfacePoint& surface, const glm::vec3& direction,
                              float u) {
    if (material.kind != MaterialKind::glass) {
        // Mirror, or glossy smooth enough to be one: Fresnel-Schlick with the metal's tint as F0.
        const glm::vec3 n = surface.shading_normal;
        const float cos_i = std::clamp(-glm::dot(direction, n), 0.0f, 1.0f);
        const float m = std::pow(1.0f - cos_i, 5.0f);
        return {glm::normalize(direction + 2.0f * cos_i * n), surface.color + (glm::vec3(1.0f) - surface.color) * m,
                false};
    }
    const GlassBranches b = glass_branches(material, surface, direction);
    if (u < b.reflectance) return {b.reflected, glm::vec3(1.0f), false};
    return {b.refracted, surface.color, true};
}

SpecularSplit split_specular(const Material& material, const SurfacePoint& surface, const glm::vec3& direction) {
    if (material.kind != MaterialKind::glass) return {scatter_specular(material, surface, direction, 0.0f), {}, false};
    const GlassBranches b = glass_branches(material, surface, direction);
    if (!(b.reflectance < 1.0f)) return {{b.reflected, glm::vec3(1.0f), false}, {}, false};
    return {{b.reflected, glm::vec3(b.reflectance), false},
            {b.refracted, (1.0f - b.reflectance) * surface.color, true},
            true};
}

GlossyStep scatter_glossy(const Material& material, const SurfacePoint& surface, const glm::vec3& direction,
                          float u1, float u2) {
    // As for view samples: a shading normal turned away from the arriving direction falls back to the geometric one.
    const glm::vec3 n =
        glm::dot(surface.shading_normal, -direction) > 1e-3f ? surface.shading_normal : surface.geometric_normal;
    const GgxSample g = sample_ggx_reflection(surface.color, material.glossy_alpha(), n, -direction, u1, u2);
    const bool valid = g.pdf > 0.0f && glm::dot(g.direction, surface.geometric_normal) > 0.0f;
    return {g.direction, valid ? g.weight : glm::vec3(0.0f), valid};
}

}  // namespace ps
