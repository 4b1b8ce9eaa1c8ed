// The two light options of Blender 4.x/5.x Cycles that no rescaling in the add-on can express: a spot falloff
// without Cycles 3.4's cos θ factor (Light::spot_cosine = false), and point and spot lights that are true
// spheres (Light::sphere, Cycles 4.x with Soft Falloff off) instead of discs facing the receiver. Each against
// closed forms: the falloff, the cone's flux, the irradiance of a uniformly bright sphere, and photons that carry
// the flux with the profile's direction density and light a patch as the shadow rays do. Also the photons of
// Cycles 3.4's disc (first_hit_falloff), which this file's helpers measure as well.
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

// The same on a side × side grid of (u1, u2) cell centres: deterministic, and precise where few samples carry light.
double irradiance_grid(const Light& light, const glm::vec3& x, const glm::vec3& n, int side) {
    double sum = 0.0;
    for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j) {
            const LightIncidence in = sample_light_incidence(light, x, (i + 0.5f) / side, (j + 0.5f) / side);
            sum += in.value.x * std::max(0.0f, glm::dot(n, in.wi));
        }
    return sum / (static_cast<double>(side) * side);
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

TEST(Cycles4Lights, InsideASpherePointLightEverySurfaceGetsIOverRSquared) {
    // The inner wall of radiance L = I/(πR²) all around: E = πL = I/R², whatever the surface's orientation.
    const float radius = 0.5f;
    const Light light = sphere_point_light(radius, true);
    for (const glm::vec3& n : {glm::vec3(0, 0, 1), glm::normalize(glm::vec3(1, -2, 0.5f)), glm::vec3(0, 0, -1)}) {
        const double e = irradiance(light, {0.1f, -0.2f, 0.15f}, n, 400000);
        EXPECT_NEAR(e / (light.value.x / (radius * radius)), 1.0, 0.01);
    }
}

// Inside a sphere spot Cycles 4.5 applies no cone, but its spot-light intersection is one-sided (the ray must head
// towards the centre): from inside, the BSDF rays heading away never hit it, and a diffuse surface keeps only the
// light samples' ½ MIS weight along those directions. E = I/R² (3 + cos β)/4, β between the normal and the
// direction to the centre: the core gives those directions half the radiance.
TEST(Cycles4Lights, InsideASphereSpotTheDirectionsAwayFromTheCentreBringHalf) {
    const float radius = 0.5f;
    Light spot = spot_light(0.5f, 0.0f, false);  // a narrow cone: none of it applies inside
    spot.radius = radius;
    spot.sphere = true;
    spot.position = {0.1f, 0.2f, -0.1f};
    const glm::vec3 x(0.2f, -0.1f, 0.15f);
    const glm::vec3 to_centre = glm::normalize(spot.position - x);
    for (const glm::vec3& n : {glm::vec3(0, 0, 1), glm::vec3(0, 0, -1), glm::normalize(glm::vec3(1, -2, 0.5f)),
                               to_centre, -to_centre}) {
        const double e = irradiance(spot, x, n, 400000);
        const double expected = spot.value.x / (radius * radius) * (3.0 + glm::dot(n, to_centre)) / 4.0;
        EXPECT_NEAR(e / expected, 1.0, 0.01) << "cos β = " << glm::dot(n, to_centre);
    }
    // Each direction: the full I/(πR²) towards the centre's side, half of it away, as a BSDF ray finds it too.
    Rng rng(4, RngDomain::camera, 0);
    const double full = spot.value.x / (kPi * radius * radius);
    for (int i = 0; i < 500; ++i) {
        const LightIncidence in = sample_light_incidence(spot, x, rng.uniform(), rng.uniform());
        const double expected = glm::dot(in.wi, spot.position - x) > 0.0f ? full : 0.5 * full;
        EXPECT_NEAR(in.value.x * in.pdf / expected, 1.0, 1e-5);
        const LightHit h = intersect_light(spot, x, in.wi);
        ASSERT_TRUE(h.hit);
        EXPECT_NEAR(h.radiance.x / expected, 1.0, 1e-5);
        EXPECT_NEAR(h.pdf / in.pdf, 1.0, 1e-5);
        EXPECT_NEAR(h.distance / in.distance, 1.0, 1e-5);
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

// What Cycles 4.5.15 renders (CPU, 1024 samples, no denoising, max bounces 0): a white diffuse plane z = 0 cut by,
// or under, a sphere spot of radius 0.3 at (0, 0, h) pointing down, seen from above by an orthographic camera at
// 400 × 400 pixels over 1 m; E / I = π × the mean pixel on the ring of radius ρ (± 0.1 % from the ring's pixels,
// ~0.15 % lower than a point's value by the pixel filter where E falls steeply). Inside the sphere (d < 0.3) the
// old model gave I/R², 11.11, everywhere.
TEST(Cycles4Lights, SphereSpotMatchesCycles45OnAPlaneCuttingIt) {
    struct Ring {
        float h, size_degrees, blend, rho;
        double cycles;  // E / I
    };
    const Ring rings[] = {
        // 120°, centre 0.2 above the plane: (3 + cos β)/4 inside, per-ray cone outside.
        {0.2f, 120.0f, 0.0f, 0.00f, 11.1110}, {0.2f, 120.0f, 0.0f, 0.10f, 10.8196},
        {0.2f, 120.0f, 0.0f, 0.15f, 10.5555}, {0.2f, 120.0f, 0.0f, 0.20f, 10.2980},
        {0.2f, 120.0f, 0.0f, 0.25f, 5.4762},  {0.2f, 120.0f, 0.0f, 0.30f, 3.5701},
        {0.2f, 120.0f, 0.0f, 0.40f, 1.6299},
        // 60°, centre 0.2 BELOW the plane, which faces away from it: half the light right above the centre, and
        // the cone lights nothing outside the sphere.
        {-0.2f, 60.0f, 0.0f, 0.00f, 5.5556}, {-0.2f, 60.0f, 0.0f, 0.10f, 5.8484},
        {-0.2f, 60.0f, 0.0f, 0.15f, 6.1114}, {-0.2f, 60.0f, 0.0f, 0.20f, 6.3691},
        {-0.2f, 60.0f, 0.0f, 0.30f, 0.0},
        // 60° wholly above the plane (its sphere subtends more than the cone right below): the per-ray cone;
        // at ρ = 0 exactly I sin²30° / R² = 2.7778.
        {0.5f, 60.0f, 0.0f, 0.00f, 2.7778}, {0.5f, 60.0f, 0.0f, 0.15f, 2.2188},
        {0.5f, 60.0f, 0.0f, 0.25f, 1.4686}, {0.5f, 60.0f, 0.0f, 0.35f, 0.8294},
        // 60°, blend 0.3, centre 0.1 above the plane.
        {0.1f, 60.0f, 0.3f, 0.15f, 9.8746}, {0.1f, 60.0f, 0.3f, 0.25f, 9.3656},
        {0.1f, 60.0f, 0.3f, 0.35f, 0.2262},
    };
    for (const Ring& r : rings) {
        Light spot = spot_light(static_cast<float>(r.size_degrees * kPi / 180.0), r.blend, false);
        spot.radius = 0.3f;
        spot.sphere = true;
        spot.position = {0.0f, 0.0f, r.h};
        const double e = irradiance_grid(spot, {r.rho, 0.0f, 0.0f}, {0.0f, 0.0f, 1.0f}, 1000) / spot.value.x;
        if (r.cycles == 0.0)
            EXPECT_EQ(e, 0.0) << "h " << r.h << " rho " << r.rho;
        else
            std::printf("h %4.1f, %3.0f°, blend %.1f, rho %.2f: Cycles %.4f, ours %.4f, ratio %.4f\n", r.h,
                        r.size_degrees, r.blend, r.rho, r.cycles, e, e / r.cycles);
        if (r.cycles != 0.0)
            EXPECT_NEAR(e / r.cycles, 1.0, 0.003) << "h " << r.h << " size " << r.size_degrees << " rho " << r.rho;
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

TEST(Cycles4Lights, DiscLightPhotonsLightPatchesAsShadowRaysDo) {
    // Cycles 3.4's soft point and spot lights (and 4.x's with Soft Falloff on) are the disc of their radius facing
    // each receiver: I/(d² + R²) on the axis, not I/d². Photons leave as from the sphere and take d²/(d² + R²) at
    // their first hit (first_hit_falloff); on patches under the light and off to its side they must give what the
    // shadow rays give. Without that factor they were 20 % too bright under this light (R = 0.5 at d = 1), 10 %
    // off to its side.
    Light spot = spot_light(2.4f, 0.0f, true);  // every ray to the patches is inside its cone
    spot.radius = 0.5f;
    for (const Light& light : {sphere_point_light(0.5f, false), spot}) {
        const float rho = 0.2f;
        for (const glm::vec3 centre : {glm::vec3(0.0f, 0.0f, -1.0f), glm::vec3(1.2f, 0.0f, -1.0f)}) {
            double power = 0.0, unweighted = 0.0;
            const int n = 2000000;
            Rng rng(13, RngDomain::photon, 0);
            for (int i = 0; i < n; ++i) {
                const EmissionSample e = sample_light_emission(light, glm::vec3(0.0f), 1.0f, rng.uniform(),
                                                               rng.uniform(), rng.uniform(), rng.uniform());
                ASSERT_EQ(e.disc_radius, light.radius);
                if (!(e.direction.z < 0.0f)) continue;
                const float t = (centre.z - e.origin.z) / e.direction.z;
                const glm::vec3 p = e.origin + t * e.direction;
                if (glm::dot(p - centre, p - centre) >= rho * rho) continue;
                power += e.power.x * first_hit_falloff(e, p, {0, 0, 1});
                unweighted += e.power.x;
            }
            const double photons = power / n / (kPi * rho * rho);
            double shadow = 0.0;
            int points = 0;
            for (int i = 0; i < 16; ++i)
                for (int j = 0; j < 16; ++j) {
                    const float x = rho * ((i + 0.5f) / 8.0f - 1.0f), y = rho * ((j + 0.5f) / 8.0f - 1.0f);
                    if (x * x + y * y >= rho * rho) continue;
                    shadow += irradiance(light, centre + glm::vec3(x, y, 0.0f), {0, 0, 1}, 256, 1 + i * 16 + j);
                    ++points;
                }
            shadow /= points;
            EXPECT_NEAR(photons / shadow, 1.0, 0.025) << to_string(light.kind) << " at x = " << centre.x;
            EXPECT_GT(unweighted / n / (kPi * rho * rho) / shadow, 1.05) << "the factor matters here";
            std::printf("%s disc R = 0.5, patch at (%.1f, 0, -1): photons %.4f of shadow rays %.4f\n",
                        to_string(light.kind), centre.x, photons / shadow, shadow);
        }
    }
    // A sphere light keeps every photon's power: it gives the point law (SphereLightIrradianceIsThePointLawNearAndFar).
    Rng rng(3, RngDomain::photon, 0);
    const EmissionSample e = sample_light_emission(sphere_point_light(0.5f, true), glm::vec3(0.0f), 1.0f,
                                                   rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform());
    EXPECT_EQ(first_hit_falloff(e, glm::vec3(0.0f, 0.0f, -1.0f), {0, 0, 1}), 1.0f);
}

TEST(Cycles4Lights, DiscLightPhotonsLightSurfacesWithinItsRadiusAsShadowRaysDo) {
    // A ceiling 0.38 above a soft point light of radius 0.86 (seed 15 of the differential scenes): Cycles' disc,
    // turned towards each point of the ceiling, lights the points within its radius too, and crosses the horizon
    // of those beside it. Photons left the sphere, which lies partly beyond the ceiling: the ceiling within the
    // radius got none (0.2 of the light under the centre), its bounced light 7 % short. They leave the disc across
    // their direction now and take the ratio of what the two emitters show each receiver (first_hit_falloff).
    // A wall beside the light (its normal across the light's) is the horizon's other case; a spot's disc the same.
    const float radius = 0.86f, gap = 0.38f;
    // A spot's cone weighs each direction: a wide one and one of 69° whose edge crosses the patches' views.
    Light wide = spot_light(3.0f, 0.0f, true), narrow = spot_light(1.2f, 0.15f, true);
    for (Light* spot : {&wide, &narrow}) {
        spot->direction = {0, 0, 1};
        spot->radius = radius;
    }
    struct Patch {
        glm::vec3 centre, normal, along_u, along_v;
        float rho = 0.1f;  // half its side
    };
    const Patch patches[] = {
        {{0.0f, 0.0f, gap}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0}},   // above the centre, within the radius
        {{0.6f, 0.0f, gap}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0}},   // within the radius, off to the side
        {{0.9f, 0.0f, gap}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0}},   // just outside it: the disc crosses the horizon
        {{1.6f, 0.0f, gap}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0}},   // farther: the disc still crosses it
        {{0.7f, 0.0f, 0.0f}, {-1, 0, 0}, {0, 1, 0}, {0, 0, 1}},  // a wall within the radius, level with the centre
        {{0.0f, 0.0f, 2.0f}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0}, 0.25f},  // a higher ceiling, beyond two radii:
        {{1.3f, 0.0f, 2.0f}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0}, 0.25f},  // the 69° spot's edge crosses this one
    };
    constexpr int kPatches = sizeof(patches) / sizeof(patches[0]);
    for (const Light& light : {sphere_point_light(radius, false), wide, narrow}) {
        // Every photon is tried on every patch, each alone (the patch lies in a wall: a photon that starts beyond
        // it does not reach it).
        double power[kPatches] = {};
        const int n = 4000000;
        Rng rng(17, RngDomain::photon, 0);
        for (int i = 0; i < n; ++i) {
            const EmissionSample e = sample_light_emission(light, glm::vec3(0.0f), 1.0f, rng.uniform(), rng.uniform(),
                                                           rng.uniform(), rng.uniform());
            for (int k = 0; k < kPatches; ++k) {
                const Patch& patch = patches[k];
                if (!(glm::dot(e.origin - patch.centre, patch.normal) > 0.0f)) continue;
                const float towards = glm::dot(e.direction, patch.normal);
                if (!(towards < 0.0f)) continue;
                const glm::vec3 p = e.origin + (glm::dot(patch.centre - e.origin, patch.normal) / towards) * e.direction;
                const glm::vec3 q = p - patch.centre;
                if (std::fabs(glm::dot(q, patch.along_u)) >= patch.rho ||
                    std::fabs(glm::dot(q, patch.along_v)) >= patch.rho)
                    continue;
                power[k] += e.power.x * first_hit_falloff(e, p, patch.normal);
            }
        }
        for (int k = 0; k < kPatches; ++k) {
            const Patch& patch = patches[k];
            const float rho = patch.rho;
            const double photons = power[k] / n / (4.0 * rho * rho);
            double shadow = 0.0;
            for (int i = 0; i < 8; ++i)
                for (int j = 0; j < 8; ++j) {
                    const glm::vec3 x = patch.centre + (rho * ((i + 0.5f) / 4.0f - 1.0f)) * patch.along_u +
                                        (rho * ((j + 0.5f) / 4.0f - 1.0f)) * patch.along_v;
                    shadow += irradiance_grid(light, x, patch.normal, 64);
                }
            shadow /= 64.0;
            if (shadow < 1e-3 * light.value.x) continue;  // outside a spot's cone
            EXPECT_NEAR(photons / shadow, 1.0, 0.03)
                << to_string(light.kind) << " patch at (" << patch.centre.x << ", " << patch.centre.z << ")";
            std::printf("%s disc R = 0.86, patch at (%.1f, %.2f): photons %.4f of shadow rays %.4f\n",
                        to_string(light.kind), patch.centre.x, patch.centre.z, photons / shadow, shadow);
        }
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
