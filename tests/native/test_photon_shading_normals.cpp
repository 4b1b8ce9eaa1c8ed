// Photons on smooth-shaded surfaces (photon_shading_normals.h): the arrival and departure ratios, and a view
// sample's splat taking the arrival ratio against the photon's own triangle.
#include <gtest/gtest.h>

#include <cmath>

#include <glm/geometric.hpp>

#include "photonsplat/photon_shading_normals.h"
#include "photonsplat/splat.h"

namespace ps {
namespace {

constexpr double kInvPi = 0.318309886183790671538;

TEST(PhotonShadingNormals, RatiosAreOneOnFlatShadedTriangles) {
    const glm::vec3 n(0.0f, 0.0f, 1.0f), w = glm::normalize(glm::vec3(0.7f, 0.1f, 0.2f));
    EXPECT_EQ(photon_arrival_ratio(n, n, w), 1.0f);
    EXPECT_EQ(photon_departure_ratio(n, n, w), 1.0f);
    // Within kTiltedShadingCosine of the triangle's normal: still exactly 1 (a flat mesh's rounded normals).
    const glm::vec3 almost = glm::normalize(glm::vec3(1e-4f, 0.0f, 1.0f));
    EXPECT_FALSE(shading_normal_tilted(almost, n));
    EXPECT_EQ(photon_arrival_ratio(almost, n, w), 1.0f);
}

TEST(PhotonShadingNormals, RatiosOfATiltedNormal) {
    const glm::vec3 ng(0.0f, 0.0f, 1.0f), ns = glm::normalize(glm::vec3(0.3f, 0.0f, 1.0f));
    const glm::vec3 towards = glm::normalize(glm::vec3(1.0f, 0.0f, 1.0f)), away = glm::normalize(glm::vec3(-1.0f, 0.0f, 1.0f));
    EXPECT_NEAR(photon_arrival_ratio(ns, ng, towards), glm::dot(ns, towards) / glm::dot(ng, towards), 1e-6);
    EXPECT_GT(photon_arrival_ratio(ns, ng, towards), 1.0f);
    EXPECT_LT(photon_arrival_ratio(ns, ng, away), 1.0f);
    EXPECT_NEAR(photon_departure_ratio(ns, ng, towards), glm::dot(ng, towards) / glm::dot(ns, towards), 1e-6);
    // Above the triangle but below the shading normal's horizon: nothing (Cycles' closures give it nothing).
    const glm::vec3 under = glm::normalize(glm::vec3(-1.0f, 0.0f, 0.2f));
    ASSERT_GT(glm::dot(ng, under), 0.0f);
    ASSERT_LT(glm::dot(ns, under), 0.0f);
    EXPECT_EQ(photon_arrival_ratio(ns, ng, under), 0.0f);
    EXPECT_EQ(photon_departure_ratio(ns, ng, under), 0.0f);
    // Grazing the triangle: bounded.
    const glm::vec3 grazing = glm::normalize(glm::vec3(1.0f, 0.0f, 1e-6f));
    EXPECT_EQ(photon_arrival_ratio(ns, ng, grazing), kMaxShadingNormalRatio);
    // Either orientation of the pair (the far side of a surface).
    EXPECT_EQ(photon_arrival_ratio(-ns, -ng, -towards), photon_arrival_ratio(ns, ng, towards));
}

// One Lambert sample, one photon: f Φ (n_s·ω_i) / (n_g·ω_i) with the photon's own n_g.
TEST(PhotonShadingNormals, SplatTakesTheArrivalRatioAgainstThePhotonsTriangle) {
    ViewSample s{};
    s.normal = glm::vec3(0.0f, 0.0f, 1.0f);
    s.shading_normal = glm::normalize(glm::vec3(0.3f, 0.0f, 1.0f));
    s.albedo = glm::vec3(1.0f);
    s.throughput = glm::vec3(1.0f);
    s.wo = s.normal;
    Photon photon{};
    photon.wi = glm::normalize(glm::vec3(1.0f, 0.0f, 1.0f));
    photon.normal = glm::normalize(glm::vec3(0.1f, 0.0f, 1.0f));  // a neighbouring facet
    photon.power = glm::vec3(2.0f);
    SplatParams params;
    params.radius = 1.0f;
    params.emitted = 1;
    const glm::dvec3 f = photon_reflected_flux(s, nullptr, glm::vec3(0.0f), photon, params);
    const double expected = 2.0 * kInvPi * glm::dot(s.shading_normal, photon.wi) / glm::dot(photon.normal, photon.wi);
    EXPECT_NEAR(f.x, expected, 1e-6 * expected);
    // Flat-shaded: f Φ alone, whatever the photon's triangle.
    s.shading_normal = s.normal;
    EXPECT_NEAR(photon_reflected_flux(s, nullptr, glm::vec3(0.0f), photon, params).x, 2.0 * kInvPi, 1e-9);
}

}  // namespace
}  // namespace ps
