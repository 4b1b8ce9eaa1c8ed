// Photons aimed at mirrors and glass. A caustic needs a photon that reaches a specular object, and those are
// few wherever the specular objects subtend a small solid angle from the lights, so a caustic is lit by a few
// hundred photons per iteration while the rest of the photons light the walls (docs/architecture.md gives the
// caustic Cornell box's figures). Like Jensen's projection maps and ISPM's caustic photons, each iteration therefore also emits
// `aimed_photons` × photons extra photons from the point, spot and area lights into cones around the bounding
// spheres of the specular instances, and keeps from those only what they store as caustics (light → specular+
// → first diffuse or glossy hit; their path then ends).
//
// Caustic photons are then estimated from two sample sets, N photons from the lights' own direction densities
// p_l and M aimed photons from the cone density a_l, combined with the balance heuristic (Veach's multi-sample
// MIS): a caustic photon of light l leaving along ω, whichever set it came from, carries its usual power times
// 1 / (1 + M·q_l·a_l(ω) / (N·P_l·p_l(ω))), with P_l the chance that a photon is of light l and q_l that an aimed one
// is; everything else (the photons stored after the first diffuse bounce) comes from the N photons alone, as
// before. Both estimates stay unbiased, the photon map still divides by N, and the ordinary photons are exactly
// what they were without aiming: a scene without mirrors or glass pays nothing and renders the same bits.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "photonsplat/lights.h"

namespace ps {

class Scene;
class LightSources;
class Rng;

// A sphere bounding a specular instance's mirror and glass triangles (world space).
struct SpecularTarget {
    glm::vec3 center;
    float radius;
};

// One target per instance with specular triangles, at most kMaxSpecularTargets of them (each photon tests all
// of them); with more instances than that, one sphere around them all.
constexpr size_t kMaxSpecularTargets = 16;
std::vector<SpecularTarget> specular_targets(const Scene& scene);

// The cones from a point towards the targets that a light can send light to (a spot's cone, an area light's
// front side), each a target's sphere grown by `extra_radius` (a soft light's own radius), chosen in
// proportion to their solid angle and sampled uniformly inside: the density of a direction is then the number
// of cones holding it over their total solid angle.
class TargetCones {
public:
    TargetCones(const std::vector<SpecularTarget>& targets, const Light& light, const glm::vec3& from,
                float extra_radius);
    bool empty() const { return count_ == 0; }
    glm::vec3 sample(float u_cone, float u1, float u2) const;
    float pdf(const glm::vec3& direction) const;  // solid angle

private:
    struct Cone {
        glm::vec3 axis;
        float cos_max;
        float solid_angle;
    };
    Cone cones_[kMaxSpecularTargets];  // no allocation per photon
    size_t count_ = 0;
    float total_ = 0.0f;
};

// The aiming of one render pass: which sources aim, and the weights of caustic photons.
class CausticAim {
public:
    // `aimed_fraction` = M / N; `source_probability` = P_l of the ordinary photons (photons.cpp).
    CausticAim(const Scene& scene, const LightSources& sources, const std::vector<float>& source_probability,
               float aimed_fraction);

    bool active() const { return !aim_cdf_.empty(); }  // some light can aim at some target
    size_t pick_source(float u) const;                  // an aimed photon's light, with probability q_l
    float aimed_probability(size_t source) const { return aimed_probability_[source]; }
    const LightSources* light_sources() const { return &sources_; }

    // An aimed photon of `source`; power as sample_emission's (before dividing by P_l) times the balance
    // weight. Power 0: the photon carries nothing (its direction is outside a spot's cone).
    EmissionSample sample(size_t source, Rng& rng) const;
    // The balance weight of the caustic photons of an ordinary photon of `source` emitted as `emitted` by
    // sample_emission (1 when no cone holds its direction).
    float ordinary_caustic_weight(size_t source, const EmissionSample& emitted) const;

private:
    const LightSources& sources_;
    std::vector<SpecularTarget> targets_;
    std::vector<float> source_probability_;  // P_l
    std::vector<float> aimed_probability_;   // q_l (0 for sources that do not aim)
    std::vector<float> aim_cdf_;
    float aimed_fraction_;

    glm::vec3 anchor_of(const Light& light, const EmissionSample& emitted) const;
    float balance(size_t source, float aim_pdf, float own_pdf) const;
};

}  // namespace ps
