// Multiscatter GGX glass (glass_multiscatter.h): the walk it is tabulated from, and the lobes against the walk.
#include <gtest/gtest.h>

#include <cmath>

#include "photonsplat/closures.h"
#include "photonsplat/errors.h"
#include "photonsplat/glass_multiscatter.h"

namespace {

using ps::ClosureKind;
using ps::Distribution;

// The albedo of one multi_ggx_glass lobe (white weight) seen at cos θ_o, from stratified samples of its sampler.
float lobe_albedo(ClosureKind kind, float eta, float roughness, float cos_o, const glm::vec3& tint) {
    ps::Lobe lobe;
    lobe.kind = kind;
    lobe.distribution = Distribution::multi_ggx_glass;
    lobe.weight = glm::vec3(1.0f);
    lobe.specular_color = tint;
    lobe.alpha_x = lobe.alpha_y = roughness * roughness;
    lobe.eta = eta;
    const glm::vec3 n(0.0f, 0.0f, 1.0f), wo(std::sqrt(1.0f - cos_o * cos_o), 0.0f, cos_o);
    const int strata = 160;
    double sum = 0.0;
    for (int i = 0; i < strata; ++i) {
        for (int j = 0; j < strata; ++j) {
            const ps::LobeSample s = ps::lobe_sample(lobe, n, wo, (i + 0.5f) / strata, (j + 0.5f) / strata);
            if (s.pdf > 0.0f) sum += double(s.f.x) * std::fabs(s.direction.z) / s.pdf;
        }
    }
    return float(sum / (strata * strata));
}

struct Case {
    float eta, roughness, cos_o;
};
// Into the glass and out of it (past the critical angle at cos 0.5 and 0.3: η = 1/1.45 turns back below 0.72).
const Case kCases[] = {{1.45f, 0.3f, 0.9f}, {1.45f, 0.5f, 0.3f}, {1.45f, 0.8f, 0.6f},
                       {1.0f / 1.45f, 0.3f, 0.9f}, {1.0f / 1.45f, 0.5f, 0.5f}, {1.0f / 1.45f, 0.8f, 0.3f}};

}  // namespace

TEST(GlassMultiscatter, TheWalkKeepsTheLightOfWhiteGlass) {
    // A dielectric microsurface absorbs nothing: every walk leaves on one side or the other, but for the few still
    // on the surface after Cycles' ten scatterings (rough glass seen from inside).
    for (const Case& c : kCases) {
        const ps::GlassWalkEnergy e = ps::glass_walk_energy(c.eta, c.roughness * c.roughness, c.cos_o, 100000);
        float total = 0.0f;
        for (int j = 0; j < 3; ++j) total += e.reflect[j] + e.transmit[j];
        EXPECT_LE(total, 1.0f + 1e-6f);
        EXPECT_GT(total, c.roughness < 0.6f ? 0.999f : 0.99f) << c.eta << " " << c.roughness << " " << c.cos_o;
        // Rough glass scatters more than once: light the single-scattering Glass lobes leave out.
        if (c.roughness >= 0.5f) EXPECT_GT(e.reflect[1] + e.transmit[1], 0.01f);
    }
}

TEST(GlassMultiscatter, FirstScatteringEvaluatesAsTheWalkReturnsIt) {
    // multi_ggx_glass_single (Cycles' mf_eval of the first scattering, with η² across) integrates to the walk's
    // own first scattering on each side: the walk and its evaluation are one BSDF. With a tint of 0 the lobe keeps
    // only that (and the little of the first scattering the evaluation misses, given to its cosine part).
    for (const Case& c : kCases) {
        if (c.roughness > 0.5f) continue;  // rough and grazing, Cycles' two part ways (glass_multiscatter.h)
        const ps::GlassWalkEnergy e = ps::glass_walk_energy(c.eta, c.roughness * c.roughness, c.cos_o, 200000);
        const glm::vec3 black(0.0f);
        EXPECT_NEAR(lobe_albedo(ClosureKind::reflection, c.eta, c.roughness, c.cos_o, black), e.reflect[0], 0.006f)
            << c.eta << " " << c.roughness << " " << c.cos_o;
        EXPECT_NEAR(lobe_albedo(ClosureKind::refraction, c.eta, c.roughness, c.cos_o, black), e.transmit[0], 0.006f)
            << c.eta << " " << c.roughness << " " << c.cos_o;
    }
}

TEST(GlassMultiscatter, LobesReturnWhatTheWalkReturnsOnEachSide) {
    // The two lobes of a Multiscatter Glass give each side what Cycles' walk gives it, the tint once per scattering
    // after the first (tint^2 beyond two), within the table's interpolation.
    const glm::vec3 tint(0.6f);
    for (const Case& c : kCases) {
        const ps::GlassWalkEnergy e = ps::glass_walk_energy(c.eta, c.roughness * c.roughness, c.cos_o, 200000);
        const float reflect = e.reflect[0] + 0.6f * e.reflect[1] + 0.36f * e.reflect[2];
        const float transmit = e.transmit[0] + 0.6f * e.transmit[1] + 0.36f * e.transmit[2];
        EXPECT_NEAR(lobe_albedo(ClosureKind::reflection, c.eta, c.roughness, c.cos_o, tint), reflect, 0.015f)
            << c.eta << " " << c.roughness << " " << c.cos_o;
        EXPECT_NEAR(lobe_albedo(ClosureKind::refraction, c.eta, c.roughness, c.cos_o, tint), transmit, 0.015f)
            << c.eta << " " << c.roughness << " " << c.cos_o;
    }
}

TEST(GlassMultiscatter, IsAReflectionOrRefractionDistribution) {
    ps::Closure c;
    c.kind = ClosureKind::translucent;
    c.distribution = Distribution::multi_ggx_glass;
    EXPECT_THROW(ps::validate(c, 0, "closure"), ps::InvalidInput);
    c.kind = ClosureKind::refraction;
    c.alpha_x = c.alpha_y = 0.2f;
    EXPECT_NO_THROW(ps::validate(c, 0, "closure"));
    EXPECT_EQ(ps::distribution_from_string("multi_ggx_glass"), Distribution::multi_ggx_glass);
}
