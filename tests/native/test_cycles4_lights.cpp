// The two light options of Blender 4.x/5.x Cycles that no rescaling in the add-on can express: a spot falloff
// without Cycles 3.4's cos θ factor (Light::spot_cosine = false), and point and spot lights that are true
// spheres (Light::sphere, Cycles 4.x with Soft Falloff off) instead of discs facing the receiver. Each against
// closed forms: the falloff, the cone's flux, the irradiance of a uniformly bright sphere, and photons that carry
// the flux with the profile's direction density and light a patch as the shadow rays do.
#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "photonsplat/errors.h"
#include "photonsplat/lights.h"
#include "photonsplat/rng.h"

namespace {

using namespace ps;
constexpr double kPi = 3.14159265358979323846;

Light spot_light(float size, float blend, bool cosine) {
    Light spot;
    spot.kind = LightKind::spot;
    spot.value = glm::vec3(10.0f);
    spot.direction = {0, 0, -1};
    spot.spot_size = size;
    spot.spot_blend = blend;
    spot.spot_cosine = cosine;
    return spot;
}

Light sphere_point_light(float radius, bool sphere) {
    Light light;
    light.kind = LightKind::point;
    light.value = glm::vec3(10.0f);
    light.radius = radius;
    light.sphere = sphere;
    return light;
}

glm::vec3 off_axis(double theta) {  // a unit direction θ from the spot's axis −z
    return {static_cast<float>(std::sin(theta)), 0.0f, static_cast<float>(-std::cos(theta))};
}

// Irradiance at x on a surface of normal n, E = ∫ L cos dω, by `n_samples` shadow-ray samples of the light.
double irradiance(const Light& light, const glm::vec3& x, const glm::vec3& n, int n_samples, uint64_t seed = 1) {
    Rng rng(seed, RngDomain::camera, 0);
    double sum = 0.0;
    for (int i = 0; i < n_samples; ++i) {
        const LightIncidence in = sample_light_incidence(light, x, rng.uniform(), rng.uniform());
        sum += in.value.x * std::max(0.0f, glm::dot(n, in.wi));
    }
    return sum / n_samples;
}

TEST(Cycles4Lights, SpotWithoutCosineHasTheSmoothstepFalloffOnly) {
    // Blender's 75° spot with a small blend: 30° off the axis lies in the hard part of the cone.
    const float size = static_cast<float>(75.0 * kPi / 180.0), blend = 0.15f;
    const double theta = 30.0 * kPi / 180.0;
    const Light v34 = spot_light(size, blend, true), v4 = spot_light(size, blend, false);
    validate(v4, "spot");
    EXPECT_NEAR(v4.spot_attenuation({0, 0, -1}), 1.0f, 1e-6f);
    EXPECT_NEAR(v4.spot_attenuation(off_axis(theta)), 1.0f, 1e-6f);
    EXPECT_NEAR(v34.spot_attenuation(off_axis(theta)), std::cos(theta), 1e-6);
    // Halfway through the blend the smoothstep is 1/2, with no cos θ.
    const double c = std::cos(0.5 * size);
    const double in_blend = std::acos(c + 0.5 * (1.0 - c) * blend);
    EXPECT_NEAR(v4.spot_attenuation(off_axis(in_blend)), 0.5f, 1e-4f);
    EXPECT_EQ(v4.spot_attenuation(off_axis(0.5 * size + 0.01)), 0.0f);

    // What Cycles 4.5 measures: a receiver 30° off the axis gets the same light from the spot as from a point
    // light of the same intensity (ratio 1.0000; Cycles 3.4: cos 30° = 0.866).
    Light point;
    point.kind = LightKind::point;
    point.value = v4.value;
    const glm::vec3 x = 2.0f * off_axis(theta);
    const float from_point = sample_light_incidence(point, x, 0.5f, 0.5f).value.x;
    EXPECT_NEAR(sample_light_incidence(v4, x, 0.5f, 0.5f).value.x / from_point, 1.0, 1e-5);
    EXPECT_NEAR(sample_light_incidence(v34, x, 0.5f, 0.5f).value.x / from_point, std::cos(theta), 1e-5);
}

TEST(Cycles4Lights, SpotWithoutCosineFluxIsItsConeIntegral) {
    for (const float blend : {0.0f, 0.4f, 1.0f}) {
        for (const float size : {0.3f, 1.2f, 3.0f}) {
            const Light spot = spot_light(size, blend, false);
            double integral = 0.0;  // ∫ I(ω) dω over θ
            const int steps = 200000;
            for (int i = 0; i < steps; ++i) {
                const double t = (i + 0.5) * kPi / steps;
                integral += spot.spot_attenuation(off_axis(t)) * 2.0 * kPi * std::sin(t) * (kPi / steps);
            }
            const double flux = light_flux(spot, 1.0f).x;
            const double c = std::cos(0.5 * size), s = (1.0 - c) * blend;
            EXPECT_NEAR(flux, 10.0 * integral, 1e-3 * flux) << "size " << size << " blend " << blend;
            EXPECT_NEAR(flux, 10.0 * 2.0 * kPi * (1.0 - c - 0.5 * s), 1e-5 * flux) << "closed form";
            // Without the cos θ the same cone sends more: ∫ S > ∫ μ S.
            EXPECT_GT(flux, light_flux(spot_light(size, blend, true), 1.0f).x);
        }
    }
}

TEST(Cycles4Lights, SpotPhotonsCarryTheFluxWithTheProfilesDirections) {
    for (const bool cosine : {true, false}) {
        const Light spot = spot_light(1.6f, 0.5f, cosine);
        const double flux = light_flux(spot, 1.0f).x, c = std::cos(0.8);
        // Power per bin of μ = cos θ against ∫_bin I(μ) 2π dμ, and the photon count per bin against the
        // direction density that emission_direction_pdf states.
        constexpr int kBins = 10, n = 400000;
        std::vector<double> power(kBins, 0.0), count(kBins, 0.0);
        double total = 0.0;
        Rng rng(7, RngDomain::photon, 0);
        for (int i = 0; i < n; ++i) {
            const EmissionSample e = sample_light_emission(spot, glm::vec3(0.0f), 1.0f, rng.uniform(), rng.uniform(),
                                                           rng.uniform(), rng.uniform());
            const double mu = -e.direction.z;
            ASSERT_GE(mu, c - 1e-5);
            const int bin = std::min(kBins - 1, static_cast<int>((mu - c) / (1.0 - c) * kBins));
            power[bin] += e.power.x;
            count[bin] += 1.0;
            total += e.power.x;
            // The power of a photon is its intensity over its direction density, as emission_along gives it.
            const float pdf = emission_direction_pdf(spot, spot.position, e.direction);
            EXPECT_NEAR(e.power.x * pdf, spot.value.x * spot.spot_attenuation(e.direction), 1e-3f);
            EXPECT_NEAR(emission_along(spot, spot.position, e.direction, 0.5f, 0.5f).power.x, e.power.x,
                        1e-4f * std::max(1.0f, e.power.x));
        }
        EXPECT_NEAR(total / n, flux, 0.005 * flux) << "cosine " << cosine;
        for (int b = 0; b < kBins; ++b) {
            const double lo = c + (1.0 - c) * b / kBins, hi = c + (1.0 - c) * (b + 1) / kBins;
            double expected_power = 0.0, expected_count = 0.0;
            const int steps = 2000;
            for (int k = 0; k < steps; ++k) {
                const double mu = lo + (hi - lo) * (k + 0.5) / steps;
                const glm::vec3 d = off_axis(std::acos(mu));
                expected_power += spot.value.x * spot.spot_attenuation(d) * 2.0 * kPi * (hi - lo) / steps;
                expected_count += emission_direction_pdf(spot, spot.position, d) * 2.0 * kPi * (hi - lo) / steps;
            }
            if (expected_power > 0.02 * flux)
                EXPECT_NEAR(power[b] / n / expected_power, 1.0, 0.03) << "cosine " << cosine << " bin " << b;
            EXPECT_NEAR(count[b] / n, expected_count, 0.004) << "cosine " << cosine << " bin " << b;
        }
        // Without the cos θ the hard-edged cone is drawn uniformly in μ.
        if (!cosine) EXPECT_NEAR(count[0] / count[kBins - 1], 1.0, 0.05);
    }
}

// A uniformly bright sphere of radiance L wholly above a surface gives it E = π L (R/d)² cos θ = I cos θ / d², the
// inverse-square law of a point light at its centre, at any distance; Cycles 3.4's disc of radius R facing the
// receiver gives I/(d² + R²) at normal incidence: sphere / disc = 1 + (R/d)².
TEST(Cycles4Lights, SphereLightIrradianceIsThePointLawNearAndFar) {
    const float radius = 0.5f;
    const Light sphere = sphere_point_light(radius, true), disc = sphere_point_light(radius, false);
    validate(sphere, "sphere");
    const float intensity = sphere.value.x;
    for (const float d_over_r : {2.0f, 10.0f}) {
        const float d = d_over_r * radius;
        const glm::vec3 x(0.0f, 0.0f, -d), up(0.0f, 0.0f, 1.0f);
        const double e_sphere = irradiance(sphere, x, up, 200000), e_disc = irradiance(disc, x, up, 200000);
        EXPECT_NEAR(e_sphere / (intensity / (d * d)), 1.0, 2e-3) << "d = " << d_over_r << " R";
        EXPECT_NEAR(e_disc / (intensity / (d * d + radius * radius)), 1.0, 2e-3) << "d = " << d_over_r << " R";
        const double ratio = e_sphere / e_disc, expected = 1.0 + 1.0 / (d_over_r * d_over_r);
        EXPECT_NEAR(ratio, expected, 3e-3) << "sphere / disc at d = " << d_over_r << " R";
        std::printf("sphere / disc irradiance at d = %g R: %.4f (analytic %.4f)\n", d_over_r, ratio, expected);
    }
    // Tilted 45° at d = 2R (the sphere's 30° half-angle keeps it above the horizon): I cos 45° / d².
    const glm::vec3 x(0.0f, 0.0f, -2.0f * radius), tilted = glm::normalize(glm::vec3(1.0f, 0.0f, 1.0f));
    const double e_tilted = intensity * std::cos(kPi / 4.0) / (4.0 * radius * radius);
    EXPECT_NEAR(irradiance(sphere, x, tilted, 200000) / e_tilted, 1.0, 3e-3);
    // A millimetre sphere 100 m away: its cone is 1e-10 sr wide, below float's 1 − cos resolution, and still
    // gives the point light's irradiance.
    const Light tiny = sphere_point_light(1e-3f, true);
    EXPECT_NEAR(irradiance(tiny, {0.0f, 0.0f, -100.0f}, {0.0f, 0.0f, 1.0f}, 1000) / (intensity / 1e4), 1.0, 1e-3);
}

TEST(Cycles4Lights, InsideASphereLightEverySurfaceGetsIOverRSquared) {
    // The inner wall of radiance L = I/(πR²) all around: E = πL = I/R², whatever the surface's orientation, and
    // for a spot too (Cycles 4.x applies no cone inside its sphere).
    const float radius = 0.5f;
    Light spot = spot_light(0.5f, 0.0f, false);
    spot.radius = radius;
    spot.sphere = true;
    for (const Light& light : {sphere_point_light(radius, true), spot}) {
        for (const glm::vec3& n : {glm::vec3(0, 0, 1), glm::normalize(glm::vec3(1, -2, 0.5f))}) {
            const double e = irradiance(light, {0.1f, -0.2f, 0.15f}, n, 400000);
            EXPECT_NEAR(e / (light.value.x / (radius * radius)), 1.0, 0.01) << to_string(light.kind);
        }
    }
}

TEST(Cycles4Lights, FromInsideASphereEveryDirectionHitsItsWall) {
    // Reference.LightHitsAgreeWithLightSampling checks spheres from outside; inside, intersect_light must find
    // the wall along every direction sample_light_incidence draws, at its distance and with its density.
    Light light = sphere_point_light(0.5f, true);
    light.position = {0.2f, 0.1f, 0.3f};
    const glm::vec3 x(0.3f, -0.1f, 0.2f);
    Rng rng(9, RngDomain::camera, 0);
    for (int i = 0; i < 500; ++i) {
        const LightIncidence in = sample_light_incidence(light, x, rng.uniform(), rng.uniform());
        const LightHit h = intersect_light(light, x, in.wi);
        ASSERT_TRUE(h.hit);
        EXPECT_NEAR(h.pdf, 1.0 / (4.0 * kPi), 1e-6);
        EXPECT_NEAR(h.pdf / in.pdf, 1.0, 1e-5);
        EXPECT_NEAR(h.distance / in.distance, 1.0, 1e-5);
        EXPECT_NEAR(glm::length(x + in.distance * in.wi - light.position), light.radius, 1e-5f);
        EXPECT_NEAR(h.radiance.x / h.pdf / in.value.x, 1.0, 1e-5);
    }
}

TEST(Cycles4Lights, SphereSpotAttenuatesEachRayAlongItsOwnDirection) {
    Light spot = spot_light(1.0f, 0.0f, false);  // a hard 57° cone, half angle 0.5
    spot.radius = 0.4f;
    spot.sphere = true;
    // Far away it is the point spot: full inside the cone, dark outside.
    const glm::vec3 inside = 50.0f * off_axis(0.3), outside = 50.0f * off_axis(0.7);
    EXPECT_NEAR(irradiance(spot, inside, -glm::normalize(inside), 1000) * 2500.0 / spot.value.x, 1.0, 1e-3);
    EXPECT_EQ(irradiance(spot, outside, -glm::normalize(outside), 1000), 0.0);
    // Near the sphere, just outside the cone's edge as seen from the centre, part of the sphere is still seen
    // along directions inside the cone: some light, less than the full sphere's.
    const glm::vec3 near = 1.0f * off_axis(0.55);
    const double e = irradiance(spot, near, -glm::normalize(near), 100000);
    EXPECT_GT(e, 0.05 * spot.value.x);
    EXPECT_LT(e, 0.95 * spot.value.x);
    // Every sampled ray carries the cone's attenuation along itself.
    Rng rng(3, RngDomain::camera, 0);
    for (int i = 0; i < 1000; ++i) {
        const LightIncidence in = sample_light_incidence(spot, near, rng.uniform(), rng.uniform());
        const double radiance = spot.value.x / (kPi * spot.radius * spot.radius) * spot.spot_attenuation(-in.wi);
        EXPECT_NEAR(in.value.x * in.pdf, radiance, 1e-4 * std::max(1.0, radiance));
    }
}

// Photons of a sphere light leave its surface outwards and, traced to a disc of radius ρ facing the light at
// distance h on its axis (wholly below the sphere), bring it the mean irradiance of I cos θ / r² over the disc:
// 2 I h / ρ² · (1/h − 1/√(h² + ρ²)), what the shadow rays give too.
TEST(Cycles4Lights, SpherePhotonsLightANearPatchAsShadowRaysDo) {
    const float radius = 0.5f, h = 2.0f * radius, rho = radius;
    Light spot = spot_light(2.1f, 0.0f, false);  // every ray from the sphere to the patch is inside its cone
    spot.radius = radius;
    spot.sphere = true;
    for (const Light& light : {sphere_point_light(radius, true), spot}) {
        const double intensity = light.value.x;
        const double expected = 2.0 * intensity * h / (rho * rho) * (1.0 / h - 1.0 / std::sqrt(h * h + rho * rho));
        double power = 0.0;
        const int n = 400000;
        Rng rng(11, RngDomain::photon, 0);
        for (int i = 0; i < n; ++i) {
            const EmissionSample e = sample_light_emission(light, glm::vec3(0.0f), 1.0f, rng.uniform(), rng.uniform(),
                                                           rng.uniform(), rng.uniform());
            // On the sphere, leaving it outwards.
            ASSERT_NEAR(glm::length(e.origin - light.position), radius, 1e-5f);
            ASSERT_GE(glm::dot(e.origin - light.position, e.direction), -1e-6f);
            if (!(e.direction.z < 0.0f)) continue;
            const float t = (-h - e.origin.z) / e.direction.z;
            const glm::vec3 p = e.origin + t * e.direction;
            if (p.x * p.x + p.y * p.y < rho * rho) power += e.power.x;
        }
        const double photons = power / n / (kPi * rho * rho);
        EXPECT_NEAR(photons / expected, 1.0, 0.02) << to_string(light.kind);
        // Shadow rays: the disc's mean irradiance on a 32 × 32 grid of its points.
        double shadow = 0.0;
        int points = 0;
        for (int i = 0; i < 32; ++i)
            for (int j = 0; j < 32; ++j) {
                const float x = rho * ((i + 0.5f) / 16.0f - 1.0f), y = rho * ((j + 0.5f) / 16.0f - 1.0f);
                if (x * x + y * y >= rho * rho) continue;
                shadow += irradiance(light, {x, y, -h}, {0, 0, 1}, 256, 1 + i * 32 + j);
                ++points;
            }
        EXPECT_NEAR(shadow / points / expected, 1.0, 0.01) << to_string(light.kind);
        std::printf("%s sphere, patch at h = 2R: photons %.4f, shadow rays %.4f of analytic %.4f\n",
                    to_string(light.kind), photons / expected, shadow / points / expected, expected);
    }
}

TEST(Cycles4Lights, SphereSpotPhotonsAimedAlongADirectionMatchTheirEmission) {
    // emission_along (caustic photons) starts a sphere's photon on its front, with the power sample_light_emission
    // gives that direction.
    Light spot = spot_light(1.4f, 0.3f, false);
    spot.position = {0.3f, -0.2f, 1.0f};
    spot.radius = 0.2f;
    spot.sphere = true;
    Rng rng(5, RngDomain::photon, 0);
    for (int i = 0; i < 2000; ++i) {
        const EmissionSample e = sample_light_emission(spot, glm::vec3(0.0f), 1.0f, rng.uniform(), rng.uniform(),
                                                       rng.uniform(), rng.uniform());
        const EmissionSample along =
            emission_along(spot, emission_anchor(spot, 0.0f, 0.0f), e.direction, rng.uniform(), rng.uniform());
        EXPECT_NEAR(along.power.x, e.power.x, 1e-4f * std::max(1.0f, e.power.x));
        EXPECT_NEAR(glm::length(along.origin - spot.position), spot.radius, 1e-5f);
        EXPECT_GE(glm::dot(along.origin - spot.position, e.direction), -1e-6f);
    }
}

TEST(Cycles4Lights, NewFieldsAreRefusedWhereTheyMeanNothing) {
    Light sun;
    sun.kind = LightKind::sun;
    sun.value = glm::vec3(1.0f);
    sun.sphere = true;
    EXPECT_THROW(validate(sun, "sun"), InvalidInput);
    Light area;
    area.kind = LightKind::area;
    area.value = glm::vec3(1.0f);
    area.sphere = true;
    EXPECT_THROW(validate(area, "area"), InvalidInput);
    Light point = sphere_point_light(0.1f, true);
    EXPECT_NO_THROW(validate(point, "point"));
    point.spot_cosine = false;
    EXPECT_THROW(validate(point, "point"), InvalidInput);
    Light spot = spot_light(1.0f, 0.2f, false);
    spot.sphere = true;
    EXPECT_NO_THROW(validate(spot, "spot"));
    spot.radius = 0.0f;  // a sphere of radius 0 is the point spot: allowed, and a delta light
    EXPECT_NO_THROW(validate(spot, "spot"));
    EXPECT_TRUE(light_is_delta(spot));
}

}  // namespace
