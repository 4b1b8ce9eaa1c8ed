// Cycles' bump shadowing term. Cycles multiplies every diffuse closure whose normal N is not the shading point's
// interpolated normal N_s (a Bump or Normal Map normal, or one tilted by ensure_valid_reflection) by a factor of the
// light's direction ω_i (closure/bsdf.h: bump_shadowing_term). It darkens the facets of a bump map that lean
// towards a light seen low over the smooth surface: with a bump normal tilted towards the light, N·ω_i overstates
// how much of the real surface faces it. Two versions of it:
//
// Cycles 3.x (after Chiang, Li and Burley, "Taming the Shadow Terminator", 2019):
//
//     g = (N_s·ω_i) / ((N·ω_i)(N_s·N)),   term = 1 for g ≥ 1, 0 for g < 0, else −g³ + g² + g.
//
// Cycles 4.x (after Conty Estevez, Lecocq and Stein, "A Microfacet-Based Shadowing Function to Solve the Bump
// Terminator Problem", 2019): 0 where ω_i and N lie on different sides of the smooth surface than N·ω_i says
// ((N_s·ω_i)(N_s·N)(N·ω_i) < 0); otherwise, where the material's Bump Map Correction is on (the default), GGX's
// Smith shadowing G1 of cos θ_i = |N_s·ω_i| for a roughness α² = min(1, tan²θ_d / 8), θ_d the bump's tilt
// (cos θ_d = |N_s·N|): 1 / (1 + Λ), Λ = (√(1 + α² tan²θ_i) − 1) / 2; 1 where either cosine is 1, 0 where
// cos θ_i < 1e-6. Without correction it is the side test alone. Measured in Cycles 4.5 and 5.0's kernels.
//
// Diffuse closures here are Cycles' (CLOSURE_IS_BSDF_DIFFUSE): Lambert and Oren–Nayar, Principled's diffuse and
// sheen, and translucency. Velvet is not one (Cycles 3.x applies the term to it only on directions drawn from it,
// with its diffuse label, not to its light samples; we follow the light samples). Without the term, a bump-mapped
// floor lit by a wall's bounce came out 1.02–1.13 of Cycles 3.4 in its blocks, in Photon Splat and in the
// reference alike.
//
// The term is a property of Cycles' camera paths: ω_i is where the light comes from. A photon scattering off such
// a surface arrives along that ω_i, so it takes the term of its arrival (shading.h: take_bump_shadowing).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace ps {

// Whether a closure of normal n takes the term at a point of interpolated normal smooth_n: n is not smooth_n, as
// Cycles compares them (exactly: an untouched normal is the interpolated one, bit for bit).
inline bool bump_shadowed(const glm::vec3& smooth_n, const glm::vec3& n) { return smooth_n != n; }

// Which term a material's diffuse closures take: the Blender version's (Scene::bump_shadowing) and, from 4.x on,
// the material's Bump Map Correction (Material::bump_map_correction).
enum class BumpShadowing : uint8_t { cycles3, cycles4, cycles4_uncorrected };

// The term for light from wi (unit, towards the light, on either side: the term is even in wi).
inline float bump_shadowing_term(BumpShadowing form, const glm::vec3& smooth_n, const glm::vec3& n,
                                 const glm::vec3& wi) {
    const float cos_si = glm::dot(smooth_n, wi), cos_sn = glm::dot(smooth_n, n), cos_ni = glm::dot(n, wi);
    if (form == BumpShadowing::cycles3) {
        const float denominator = cos_ni * cos_sn;
        const float g = denominator != 0.0f ? cos_si / denominator : 0.0f;  // Cycles' safe_divide
        if (g >= 1.0f) return 1.0f;
        if (!(g >= 0.0f)) return 0.0f;  // light on the far side of the smooth surface (or NaN)
        const float g2 = g * g;
        return -g2 * g + g2 + g;  // smooth at g = 1 (value 1, slope 0)
    }
    if (cos_si * cos_sn * cos_ni < 0.0f) return 0.0f;
    if (form == BumpShadowing::cycles4_uncorrected) return 1.0f;
    const float cos_i = std::fabs(cos_si), cos_d = std::fabs(cos_sn);
    if (cos_d >= 1.0f || cos_i >= 1.0f) return 1.0f;
    if (!(cos_i >= 1e-6f)) return 0.0f;
    const float alpha2 = std::clamp(0.125f * (1.0f / (cos_d * cos_d) - 1.0f), 0.0f, 1.0f);
    const float tan2_i = std::max(1.0f / (cos_i * cos_i) - 1.0f, 0.0f);
    return 1.0f / (1.0f + 0.5f * (std::sqrt(1.0f + alpha2 * tan2_i) - 1.0f));
}

}  // namespace ps
