#include "photonsplat/brdf.h"

#include "photonsplat/scattering.h"

namespace ps {

// Visible-normal sampling of GGX: in the frame (t1, t2, n), stretch ωo by α so the GGX microsurface becomes the
// unit hemisphere; the microfacet normals visible from the stretched direction are then the points of a disc
// seen face-on (its lower half foreshortened by the hemisphere's visible fraction); pick one uniformly, lift it
// onto the hemisphere and unstretch it: that normal h has density G1(ωo) max(0, ωo·h) D(h) / (n·ωo). Reflecting
// ωo about h turns it into pdf(ωi) = G1(ωo) D(h) / (4 n·ωo).
GgxSample sample_ggx_reflection(const glm::vec3& f0, float alpha, const glm::vec3& n, const glm::vec3& wo,
                                float u1, float u2) {
    GgxSample out{n, glm::vec3(0.0f), 0.0f};
    const float cos_o = glm::dot(n, wo);
    if (!(cos_o > 0.0f)) return out;
    const float a = std::max(alpha, kMinGgxAlpha);
    glm::vec3 t1, t2;
    orthonormal_basis(n, t1, t2);
    const glm::vec3 v = glm::normalize(glm::vec3(a * glm::dot(wo, t1), a * glm::dot(wo, t2), cos_o));

    // Basis of the disc perpendicular to the stretched direction.
    const float len2 = v.x * v.x + v.y * v.y;
    const glm::vec3 b1 = len2 > 1e-14f ? glm::vec3(-v.y, v.x, 0.0f) / std::sqrt(len2) : glm::vec3(1.0f, 0.0f, 0.0f);
    const glm::vec3 b2 = glm::cross(v, b1);

    // Uniform point on the disc, its far half squeezed to the part of the hemisphere that faces v.
    constexpr float two_pi = 6.28318530717958647692f;
    const float r = std::sqrt(u1), phi = two_pi * u2;
    const float p1 = r * std::cos(phi);
    float p2 = r * std::sin(phi);
    const float s = 0.5f * (1.0f + v.z);
    p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * p2;
    const glm::vec3 hs = p1 * b1 + p2 * b2 + std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2)) * v;

    // Unstretch into a GGX microfacet normal, back in world space.
    const glm::vec3 m = glm::normalize(glm::vec3(a * hs.x, a * hs.y, std::max(hs.z, 1e-6f)));
    const glm::vec3 h = glm::normalize(m.x * t1 + m.y * t2 + m.z * n);
    const float cos_oh = glm::dot(wo, h);
    if (!(cos_oh > 0.0f)) return out;
    const glm::vec3 wi = glm::normalize(2.0f * cos_oh * h - wo);
    out.direction = wi;
    if (!(glm::dot(n, wi) > 0.0f)) return out;  // reflected below the macrosurface: the path ends here
    out.weight = fresnel_schlick(f0, cos_oh) * ggx_smith_g1(n, wi, a);
    out.pdf = ggx_smith_g1(n, wo, a) * ggx_distribution(n, h, a) / (4.0f * cos_o);
    return out;
}

}  // namespace ps
