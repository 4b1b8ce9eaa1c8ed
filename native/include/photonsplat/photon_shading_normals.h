// Photons on smooth-shaded and bump-mapped surfaces. A surface's closures are written, as Cycles writes them,
// against its shading normal n_s: what it reflects towards the camera is ∫ f(ω_i, ω_o) (n_s·ω_i) L_i dω_i. Photons
// measure light per unit of the triangle's own area, that is (n_g·ω_i) L_i dω_i. So wherever light is carried by
// photons, a photon arriving along ω_i counts (n_s·ω_i)/(n_g·ω_i) of its flux, both where a view sample receives it
// and where a surface scatters it on; and one that leaves along ω_o, drawn against n_s as Cycles draws its
// directions, carries (n_g·ω_o)/(n_s·ω_o) of what it would elsewhere, since the flux leaving a triangle goes as
// (n_g·ω_o) L_o (Veach 1997, §5.3: the adjoint BSDF under shading normals). On flat-shaded triangles both are 1.
// Without them an 80-face smooth sphere under floor-bounced light came out 0.90–1.13 of the reference in its
// 8 × 8 blocks; 0.97–1.01 with them (its flat-shaded twin: 0.94–1.04, the kernel's bias on the facets).
//
// Which shading normal. Cycles 3.x tilts the interpolated normal by ensure_valid_reflection against where its path
// comes from (scattering.cpp), so a camera path that reaches a smooth surface along ω_o (where the photon goes
// next) shades it with n_c(ω_o), not with the normal tilted against the photon's arrival, and gives its diffuse
// parts the bump shadowing term of that tilt. Where the two normals differ (a low-poly smooth mesh seen at a
// grazing angle: light passed between its own parts) the photon scatters as that camera path sees the surface
// (exit_normal; photons.cpp: scatters_as_seen_from_exit): the arrival ratio and f taken with n_c(ω_o), and ω_o
// drawn over the whole hemisphere above the triangle, where Cycles' camera paths arrive from, not only above the
// arrival's normal. Before, a Lambert Suzanne (smooth, 500 faces) alone under three lights had 0.59 of Cycles'
// diffuse indirect light (tools/indirect_compare.py, differential seed 192), and 0.86 after. Its flat-shaded twin
// has 0.94: the kernel's bias in its crevices, which shrinks with the radius. Most of the rest is the cap below
// (0.88 with a cap of 1000).

#pragma once
#include <algorithm>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "photonsplat/closures.h"
#include "photonsplat/scattering.h"

namespace ps {

// A bound on either ratio: each grows without limit as a direction nears one triangle's horizon but not the other
// normal's, where the Monte Carlo weight would spike (both are rare there: their expected values stay finite).
constexpr float kMaxShadingNormalRatio = 10.0f;

// Shading normals closer than this to their triangle's (about 0.08°) count as the triangle's: the ratios are then
// exactly 1, so that splatting methods may take a diffuse sample's f for every ω_i at once (splat.h).
constexpr float kTiltedShadingCosine = 0.999999f;

inline bool shading_normal_tilted(const glm::vec3& ns, const glm::vec3& ng) {
    return !(glm::dot(ns, ng) >= kTiltedShadingCosine);
}

// The share of a photon arriving along wi (unit, back towards where it came from) that the surface responds to:
// (n_s·ω_i)/(n_g·ω_i), 0 where the two normals put ω_i on different sides. Either orientation of the pair will do.
inline float photon_arrival_ratio(const glm::vec3& ns, const glm::vec3& ng, const glm::vec3& wi) {
    if (!shading_normal_tilted(ns, ng)) return 1.0f;
    const float cos_s = glm::dot(ns, wi), cos_g = glm::dot(ng, wi);
    if (!(cos_s * cos_g > 0.0f)) return 0.0f;
    return std::min(cos_s / cos_g, kMaxShadingNormalRatio);
}

// The factor on a photon leaving along wo that was drawn, and weighed, against the shading normal:
// (n_g·ω_o)/(n_s·ω_o); 0 where the two normals put ω_o on different sides.
inline float photon_departure_ratio(const glm::vec3& ns, const glm::vec3& ng, const glm::vec3& wo) {
    if (!shading_normal_tilted(ns, ng)) return 1.0f;
    const float cos_s = glm::dot(ns, wo), cos_g = glm::dot(ng, wo);
    if (!(cos_s * cos_g > 0.0f)) return 0.0f;
    return std::min(cos_g / cos_s, kMaxShadingNormalRatio);
}

// The normal a camera path arriving at s along wo (unit, away from s) shades s's closures with: the interpolated
// normal tilted against wo (Cycles 3.x's ensure_valid_reflection).
inline glm::vec3 exit_normal(const SurfacePoint& s, const glm::vec3& wo) {
    return ensure_valid_reflection(s.geometric_normal, wo, s.smooth_normal);
}

// Both, for a photon that arrived at s along wi and scatters on along wo (not for one passing straight through),
// where s's shading normal serves for both ways (a flat triangle, or a program's normal).
inline float shading_normal_ratios(const SurfacePoint& s, const glm::vec3& wi, const glm::vec3& wo) {
    return photon_arrival_ratio(s.shading_normal, s.geometric_normal, wi) *
           photon_departure_ratio(s.shading_normal, s.geometric_normal, wo);
}

}  // namespace ps
