// Cycles' bump shadowing term. Cycles 3.4 multiplies every diffuse closure whose normal N is not the shading
// point's interpolated normal N_s (a Bump or Normal Map normal, or one tilted by ensure_valid_reflection) by a factor
// of the light's direction ω_i (closure/bsdf.h: bump_shadowing_term, after Chiang, Li and Burley, "Taming the
// Shadow Terminator", 2019):
//
//     g = (N_s·ω_i) / ((N·ω_i)(N_s·N)),   term = 1 for g ≥ 1, 0 for g < 0, else −g³ + g² + g,
//
// which darkens the facets of a bump map that lean towards a light seen low over the smooth surface: with a bump
// normal tilted towards the light, N·ω_i overstates how much of the real surface faces it. Diffuse closures here
// are Cycles' (CLOSURE_IS_BSDF_DIFFUSE): Lambert and Oren–Nayar, Principled's diffuse and sheen, and translucency.
// Velvet is not one (Cycles applies the term to it only on directions drawn from it, with its diffuse label, not
// to its light samples; we follow the light samples). Without the term, a bump-mapped floor lit by a wall's bounce
// came out 1.02–1.13 of Cycles in its blocks, in Photon Splat and in the reference alike.
//
// The term is a property of Cycles' camera paths: ω_i is where the light comes from. A photon scattering off such
// a surface arrives along that ω_i, so it takes the term of its arrival (shading.h: take_bump_shadowing).
#pragma once
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace ps {

// Whether a closure of normal n takes the term at a point of interpolated normal smooth_n: n is not smooth_n, as
// Cycles compares them (exactly: an untouched normal is the interpolated one, bit for bit).
inline bool bump_shadowed(const glm::vec3& smooth_n, const glm::vec3& n) { return smooth_n != n; }

// The term for light from wi (unit, towards the light, on either side: the term is even in wi).
inline float bump_shadowing_term(const glm::vec3& smooth_n, const glm::vec3& n, const glm::vec3& wi) {
    const float denominator = glm::dot(n, wi) * glm::dot(smooth_n, n);
    const float g = denominator != 0.0f ? glm::dot(smooth_n, wi) / denominator : 0.0f;  // Cycles' safe_divide
    if (g >= 1.0f) return 1.0f;
    if (!(g >= 0.0f)) return 0.0f;  // light on the far side of the smooth surface (or NaN)
    const float g2 = g * g;
    return -g2 * g + g2 + g;  // smooth at g = 1 (value 1, slope 0)
}

}  // namespace ps
