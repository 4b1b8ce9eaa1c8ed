// Cycles' bump shadowing terms, 3.x's and 4.x's (bump_shadowing.h): their values, which closures take them
// (shading.h), and a view sample's splat taking them per photon.
#include <gtest/gtest.h>

#include <cmath>

#include <glm/geometric.hpp>

#include "photonsplat/bump_shadowing.h"
#include "photonsplat/scene.h"
#include "photonsplat/shading.h"
#include "photonsplat/splat.h"

namespace ps {
namespace {

constexpr float kInvPi = 0.318309886183790671538f;

const glm::vec3 kSmooth(0.0f, 0.0f, 1.0f);
// A bump normal leaning towards +x, and light low from +x, which it overstates: the term darkens it.
const glm::vec3 kBumped = glm::normalize(glm::vec3(0.5f, 0.0f, 1.0f));
const glm::vec3 kLowLight = glm::normalize(glm::vec3(1.0f, 0.0f, 0.3f));
constexpr BumpShadowing k3 = BumpShadowing::cycles3, k4 = BumpShadowing::cycles4,
                        k4_uncorrected = BumpShadowing::cycles4_uncorrected;

TEST(BumpShadowing, TermFollowsCycles) {
    // g = (N_s·ω)/((N·ω)(N_s·N)) in (0, 1): −g³ + g² + g.
    const float g = glm::dot(kSmooth, kLowLight) / (glm::dot(kBumped, kLowLight) * glm::dot(kSmooth, kBumped));
    ASSERT_GT(g, 0.0f);
    ASSERT_LT(g, 1.0f);
    EXPECT_NEAR(bump_shadowing_term(k3, kSmooth, kBumped, kLowLight), -g * g * g + g * g + g, 1e-6f);
    EXPECT_LT(bump_shadowing_term(k3, kSmooth, kBumped, kLowLight), 1.0f);
    // Light from where the bump leans away (g ≥ 1), or along the bump normal itself: untouched.
    EXPECT_EQ(bump_shadowing_term(k3, kSmooth, kBumped, glm::normalize(glm::vec3(-0.5f, 0.0f, 1.0f))), 1.0f);
    EXPECT_EQ(bump_shadowing_term(k3, kSmooth, kBumped, kBumped), 1.0f);
    // Below the smooth surface but above the bump's horizon: nothing.
    const glm::vec3 under = glm::normalize(glm::vec3(1.0f, 0.0f, -0.1f));
    ASSERT_GT(glm::dot(kBumped, under), 0.0f);
    EXPECT_EQ(bump_shadowing_term(k3, kSmooth, kBumped, under), 0.0f);
    // Even in ω (translucency's light comes from the other side), and finite on the bump's horizon.
    EXPECT_EQ(bump_shadowing_term(k3, kSmooth, kBumped, -kLowLight), bump_shadowing_term(k3, kSmooth, kBumped, kLowLight));
    const glm::vec3 horizon = glm::normalize(glm::cross(kBumped, glm::vec3(0.0f, 1.0f, 0.0f)));
    EXPECT_TRUE(std::isfinite(bump_shadowing_term(k3, kSmooth, kBumped, horizon)));
    EXPECT_FALSE(bump_shadowed(kSmooth, kSmooth));
    EXPECT_TRUE(bump_shadowed(kSmooth, kBumped));
}

TEST(BumpShadowing, Cycles4TermIsGgxShadowingOfTheBumpsTilt) {
    // The bump leans tan θ_d = 0.5 off the smooth normal, the light comes from tan θ_i = 1/0.3 off it: GGX's G1 of
    // θ_i for α² = tan²θ_d / 8 = 1/32.
    const double tan2_i = 1.0 / (0.3 * 0.3), alpha2 = 0.25 / 8.0;
    const double g1 = 1.0 / (1.0 + 0.5 * (std::sqrt(1.0 + alpha2 * tan2_i) - 1.0));
    EXPECT_NEAR(bump_shadowing_term(k4, kSmooth, kBumped, kLowLight), g1, 1e-6);
    EXPECT_GT(bump_shadowing_term(k4, kSmooth, kBumped, kLowLight), bump_shadowing_term(k3, kSmooth, kBumped, kLowLight));
    // Light along the smooth normal, or an untilted normal: untouched. A tilt past 70.5° (tan²θ_d / 8 ≥ 1) is α² = 1.
    EXPECT_EQ(bump_shadowing_term(k4, kSmooth, kBumped, kSmooth), 1.0f);
    EXPECT_EQ(bump_shadowing_term(k4, kSmooth, kSmooth, kLowLight), 1.0f);
    const glm::vec3 steep = glm::normalize(glm::vec3(3.0f, 0.0f, 1.0f));  // tan²θ_d = 9
    const double g1_steep = 1.0 / (1.0 + 0.5 * (std::sqrt(1.0 + tan2_i) - 1.0));
    EXPECT_NEAR(bump_shadowing_term(k4, kSmooth, steep, kLowLight), g1_steep, 1e-6);
    // Even in ω; light and normal on different sides of the smooth surface than N·ω says: nothing, corrected or not.
    EXPECT_EQ(bump_shadowing_term(k4, kSmooth, kBumped, -kLowLight), bump_shadowing_term(k4, kSmooth, kBumped, kLowLight));
    const glm::vec3 under = glm::normalize(glm::vec3(1.0f, 0.0f, -0.1f));
    ASSERT_GT(glm::dot(kBumped, under), 0.0f);
    EXPECT_EQ(bump_shadowing_term(k4, kSmooth, kBumped, under), 0.0f);
    EXPECT_EQ(bump_shadowing_term(k4_uncorrected, kSmooth, kBumped, under), 0.0f);
    // Without Bump Map Correction: the side test alone.
    EXPECT_EQ(bump_shadowing_term(k4_uncorrected, kSmooth, kBumped, kLowLight), 1.0f);
    // Grazing the smooth surface, or not a number: 0, finite.
    EXPECT_EQ(bump_shadowing_term(k4, kSmooth, kBumped, glm::vec3(1.0f, 0.0f, 0.0f)), 0.0f);
    EXPECT_EQ(bump_shadowing_term(k4, kSmooth, kBumped, glm::vec3(std::nanf(""))), 0.0f);
    // A view sample records which term: the flags give the form back.
    for (const BumpShadowing form : {k3, k4, k4_uncorrected}) EXPECT_EQ(bump_form_of(bump_form_flags(form)), form);
}

TEST(BumpShadowing, SceneGivesEachMaterialItsForm) {
    Scene scene;
    Material corrected, uncorrected;
    uncorrected.bump_map_correction = false;
    EXPECT_EQ(scene.bump_shadowing(corrected), k3);
    EXPECT_EQ(scene.bump_shadowing(uncorrected), k3);  // Blender 3.x has no such setting
    scene.set_cycles4_bump_shadowing(true);
    EXPECT_EQ(scene.bump_shadowing(corrected), k4);
    EXPECT_EQ(scene.bump_shadowing(uncorrected), k4_uncorrected);
}

Bsdf bumped_bsdf() {
    Bsdf b;
    b.n = kBumped;
    b.ng = kSmooth;
    b.smooth_n = kSmooth;
    b.bump_shadowed = true;
    b.wo = glm::normalize(glm::vec3(-0.2f, 0.3f, 1.0f));
    b.lambert = glm::vec3(0.5f);
    Lobe oren_nayar;
    oren_nayar.kind = ClosureKind::diffuse;
    oren_nayar.roughness = 0.5f;
    oren_nayar.weight = glm::vec3(0.2f);
    Lobe glossy;
    glossy.kind = ClosureKind::reflection;
    glossy.distribution = Distribution::ggx;
    glossy.alpha_x = glossy.alpha_y = 0.3f;
    glossy.weight = glm::vec3(0.3f);
    b.lobes[0] = oren_nayar;
    b.lobes[1] = glossy;
    b.lobe_count = 2;
    return b;
}

// The diffuse parts (Lambert, Oren–Nayar) take the term of ω_i; a microfacet lobe does not.
TEST(BumpShadowing, DiffusePartsTakeItGlossyOnesDoNot) {
    const Bsdf b = bumped_bsdf();
    const float term = bump_shadowing_term(k3, kSmooth, kBumped, kLowLight);
    ASSERT_LT(term, 0.9f);
    const glm::vec3 diffuse = b.lambert * kInvPi + lobe_eval(b.lobes[0], b.n, kLowLight, b.wo).f;
    const glm::vec3 glossy = lobe_eval(b.lobes[1], b.n, kLowLight, b.wo).f;
    const glm::vec3 f = bsdf_eval(b, kLowLight);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(f[c], diffuse[c] * term + glossy[c], 1e-5f * f[c]);
    Bsdf plain = b;
    plain.bump_shadowed = false;
    EXPECT_GT(bsdf_eval(plain, kLowLight).x, f.x);
    // A photon arriving along ω takes the term once, for every way it leaves: its diffuse weights scaled.
    Bsdf photon = b;
    take_bump_shadowing(photon, kLowLight);
    EXPECT_FALSE(photon.bump_shadowed);
    EXPECT_NEAR(photon.lambert.x, b.lambert.x * term, 1e-6f);
    EXPECT_NEAR(photon.lobes[0].weight.x, b.lobes[0].weight.x * term, 1e-6f);
    EXPECT_EQ(photon.lobes[1].weight, b.lobes[1].weight);
}

// A sampled direction's weight carries the term as its value does (Cycles multiplies eval, not the pdf).
TEST(BumpShadowing, SampledWeightsCarryIt) {
    const Bsdf b = bumped_bsdf();
    Bsdf plain = b;
    plain.bump_shadowed = false;
    int compared = 0;
    for (int i = 0; i < 64; ++i) {
        const float u0 = (i + 0.5f) / 64.0f, u1 = std::fmod(0.618034f * i, 1.0f), u2 = std::fmod(0.754878f * i, 1.0f);
        const BsdfSample s = bsdf_sample(b, u0, u1, u2), p = bsdf_sample(plain, u0, u1, u2);
        if (s.kind != ScatterKind::lobes || p.kind != ScatterKind::lobes) continue;
        ASSERT_EQ(s.direction, p.direction);
        const glm::vec3 expected = (bsdf_eval(b, s.direction) / bsdf_eval(plain, s.direction)) * p.weight;
        EXPECT_NEAR(s.weight.y, expected.y, 1e-4f * expected.y);
        ++compared;
    }
    EXPECT_GT(compared, 32);
}

// A bump-shadowed Lambert view sample: f Φ times the term of the photon's direction; the far side's flipped
// normals give the same.
TEST(BumpShadowing, SplatTakesItPerPhoton) {
    ViewSample s{};
    s.normal = s.smooth_normal = kSmooth;
    s.shading_normal = kBumped;
    s.flags = kBumpShadowed;
    s.albedo = glm::vec3(1.0f);
    s.throughput = glm::vec3(1.0f);
    s.wo = kSmooth;
    Photon photon{};
    photon.wi = kLowLight;
    photon.normal = kSmooth;
    photon.power = glm::vec3(2.0f);
    SplatParams params;
    params.radius = 1.0f;
    const double arrival = glm::dot(kBumped, kLowLight) / glm::dot(kSmooth, kLowLight);
    const double expected = 2.0 / 3.14159265358979 * arrival * bump_shadowing_term(k3, kSmooth, kBumped, kLowLight);
    EXPECT_NEAR(photon_reflected_flux(s, nullptr, s.position, photon, params).x, expected, 1e-6);
    EXPECT_TRUE(sample_shading_tilted(s));
    ViewSample far = s;
    far.normal = far.smooth_normal = -kSmooth;
    far.shading_normal = -kBumped;
    photon.wi = -kLowLight;
    photon.normal = -kSmooth;
    EXPECT_NEAR(photon_reflected_flux(far, nullptr, far.position, photon, params).x, expected, 1e-6);
    // Cycles 4.x's term where the flags say so.
    s.flags = kBumpShadowed | bump_form_flags(k4);
    photon.wi = kLowLight;
    photon.normal = kSmooth;
    EXPECT_NEAR(photon_reflected_flux(s, nullptr, s.position, photon, params).x,
                2.0 / 3.14159265358979 * arrival * bump_shadowing_term(k4, kSmooth, kBumped, kLowLight), 1e-6);
}

}  // namespace
}  // namespace ps
