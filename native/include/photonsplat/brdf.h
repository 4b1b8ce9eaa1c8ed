// The glossy lobe: GGX (Trowbridge–Reitz) microfacet reflection, as Cycles 3.4 renders Glossy BSDF and the
// Principled metal lobe. Written once here; view samples, direct light, every splat method and the photon tracer
// all evaluate or sample it through these functions.
//
//   f_r(ωi, ωo) = F(ωi·h) · D(h) · G1(ωi) · G1(ωo) / (4 |n·ωi| |n·ωo|),   h = normalize(ωi + ωo)
//
//   D(h)  = α² / (π ((n·h)² (α² − 1) + 1)²)               GGX normal distribution, α = Blender roughness²
//   G1(v) = 2 / (1 + sqrt(1 + α² tan²θ_v))                 Smith masking of GGX; separable G = G1(ωi)·G1(ωo),
//                                                          as Cycles 3.4's single-scatter GGX
//   F(c)  = F0 + (1 − F0)(1 − c)^5                          Fresnel–Schlick with the colour as F0 (metal tint)
//
// All directions are unit vectors pointing AWAY from the surface; `n` is the shading normal. The lobe is zero
// unless both directions are above n. It is symmetric in ωi and ωo (reciprocal) and, for F0 = 1, reflects at
// most all the light: ∫ f_r cos θi dωi = E[G1(ωi)] <= 1 (single scattering loses a little at high roughness).
//
// Sampling draws the visible normals of ωo (Heitz 2018, "Sampling the GGX distribution of visible normals"):
//   pdf(ωi) = G1(ωo) D(h) / (4 n·ωo),   weight f_r cos θi / pdf = F(ωo·h) · G1(ωi) <= 1
// so photon powers stay near equal under Russian roulette on the weight.
#pragma once
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace ps {

// Below this α the formulas lose precision in float; the material layer never goes that low (Blender roughness
// <= 0.05, α <= 0.0025, is rendered as a perfect mirror), this only keeps hand-made inputs finite.
constexpr float kMinGgxAlpha = 1e-4f;

// sin²θ between unit vectors a and n, accurate near θ = 0 (where 1 − cos² would cancel).
inline float ggx_sin2(const glm::vec3& n, const glm::vec3& a) {
    const glm::vec3 c = glm::cross(n, a);
    return glm::dot(c, c);
}

// GGX normal distribution D(h); h unit. Zero below the surface.
inline float ggx_distribution(const glm::vec3& n, const glm::vec3& h, float alpha) {
    const float cos_h = glm::dot(n, h);
    if (!(cos_h > 0.0f)) return 0.0f;
    const float a = std::max(alpha, kMinGgxAlpha);
    const float a2 = a * a;
    const float t = ggx_sin2(n, h) + cos_h * cos_h * a2;  // = (n·h)²(α²−1) + 1 for unit h
    constexpr float inv_pi = 0.318309886183790671538f;
    return a2 * inv_pi / (t * t);
}

// Smith masking G1(v) of GGX; zero when v is not above the surface.
inline float ggx_smith_g1(const glm::vec3& n, const glm::vec3& v, float alpha) {
    const float cos_v = glm::dot(n, v);
    if (!(cos_v > 0.0f)) return 0.0f;
    const float a = std::max(alpha, kMinGgxAlpha);
    const float tan2 = ggx_sin2(n, v) / (cos_v * cos_v);
    return 2.0f / (1.0f + std::sqrt(1.0f + a * a * tan2));
}

// Fresnel–Schlick: reflectance at cos θ between the light direction and the microfacet normal.
inline glm::vec3 fresnel_schlick(const glm::vec3& f0, float cos_theta) {
    const float m = std::clamp(1.0f - cos_theta, 0.0f, 1.0f);
    const float m2 = m * m;
    return f0 + (glm::vec3(1.0f) - f0) * (m2 * m2 * m);
}

// f_r(ωi, ωo) of the GGX lobe with Fresnel tint f0 and roughness α (already squared).
inline glm::vec3 ggx_reflection(const glm::vec3& f0, float alpha, const glm::vec3& n, const glm::vec3& wi,
                                const glm::vec3& wo) {
    const float cos_i = glm::dot(n, wi), cos_o = glm::dot(n, wo);
    if (!(cos_i > 0.0f) || !(cos_o > 0.0f)) return glm::vec3(0.0f);
    const glm::vec3 sum = wi + wo;
    const float len2 = glm::dot(sum, sum);
    if (!(len2 > 1e-12f)) return glm::vec3(0.0f);
    const glm::vec3 h = sum / std::sqrt(len2);
    const float d = ggx_distribution(n, h, alpha);
    const float g = ggx_smith_g1(n, wi, alpha) * ggx_smith_g1(n, wo, alpha);
    return fresnel_schlick(f0, glm::dot(wi, h)) * (d * g / (4.0f * cos_i * cos_o));
}

// Probability density (solid angle, of ωi) of sample_ggx_reflection choosing ωi for ωo.
inline float ggx_reflection_pdf(float alpha, const glm::vec3& n, const glm::vec3& wi, const glm::vec3& wo) {
    const float cos_i = glm::dot(n, wi), cos_o = glm::dot(n, wo);
    if (!(cos_i > 0.0f) || !(cos_o > 0.0f)) return 0.0f;
    const glm::vec3 sum = wi + wo;
    const float len2 = glm::dot(sum, sum);
    if (!(len2 > 1e-12f)) return 0.0f;
    const glm::vec3 h = sum / std::sqrt(len2);
    return ggx_smith_g1(n, wo, alpha) * ggx_distribution(n, h, alpha) / (4.0f * cos_o);
}

struct GgxSample {
    glm::vec3 direction;  // ωi, unit
    glm::vec3 weight;     // f_r cos θi / pdf = F · G1(ωi); 0 when the sample failed (ωi below the surface)
    float pdf;            // of ωi, solid angle; 0 when the sample failed
};

// Draws ωi for a given ωo (above n) from the visible normals of ωo. u1, u2 in [0, 1).
GgxSample sample_ggx_reflection(const glm::vec3& f0, float alpha, const glm::vec3& n, const glm::vec3& wo,
                                float u1, float u2);

}  // namespace ps
