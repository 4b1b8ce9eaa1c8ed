// The world as a light (world.h) with a Nishita sky and its sun disc, the hardest world to sample: a quarter-degree
// disc 10⁵ times brighter than the sky around it. Light samples must agree with their own density, estimate the
// sky's irradiance (checked against a quadrature of the program itself, fine over the disc), and stay free of
// fireflies; portals must keep every light sample's density consistent too.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <glm/geometric.hpp>

#include "golden/sky_goldens.h"
#include "nodes/sky_texture.h"
#include "photonsplat/rng.h"
#include "photonsplat/scene.h"
#include "photonsplat/shader_program.h"
#include "photonsplat/world.h"
#include "test_scenes.h"

namespace ps {
namespace {

constexpr double kPi = 3.14159265358979323846;

// emission = Sky Texture(Generated), the direction in the world; `settings` of a golden case, scaled by `strength`.
ShaderProgram sky_world(const float* settings, int type, int disc) {
    ShaderProgram p;
    p.registers.assign(24, 0.0f);
    p.tables.assign(settings, settings + kSkySettingsFloats);
    p.code = {static_cast<int32_t>(ShaderOp::texture_coordinate), 3, 0, 7, 0, -1, 0x3f800000 /* width 1.0f */, 0, 3, 6, 9, 12, 15, 18,
              static_cast<int32_t>(ShaderOp::sky_texture), 4, 1, 1, type, disc, 0, -1, 0, 21};
    p.outputs.push_back({ProgramTarget::emission, 0, 21});
    return p;
}

void add_floor(Scene& scene) {
    static const float v[12] = {-5, -5, 0, 5, -5, 0, 5, 5, 0, -5, 5, 0};
    static const int32_t t[6] = {0, 1, 2, 0, 2, 3};
    Material m;
    m.name = "floor";
    const int32_t id = static_cast<int32_t>(scene.add_material(m));
    const int32_t ids[2] = {id, id};
    scene.add_mesh(test::mesh_input("floor", v, 4, t, 2, ids));
}

const sky_goldens::Case& high_sun() {
    for (const auto& c : sky_goldens::kCases)
        if (std::string(c.label) == "nishita high sun") return c;
    return sky_goldens::kCases[0];
}

// ∫ L cos θ dω over the upper hemisphere by quadrature of the program: a 512 × 2048 grid, plus a fine grid over
// the sun's cone (the coarse grid's cells there are replaced).
double horizontal_irradiance(const Scene& scene, const glm::vec3& sun, double half_angle) {
    const auto lum = [](const glm::vec3& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; };
    double e = 0.0;
    const int nt = 512, np = 2048;
    for (int i = 0; i < nt; ++i) {
        const double th = (i + 0.5) / nt * kPi / 2;
        for (int j = 0; j < np; ++j) {
            const double ph = (j + 0.5) / np * 2 * kPi;
            const glm::vec3 d(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)), float(std::cos(th)));
            if (std::acos(std::min(1.0, double(glm::dot(d, sun)))) < 1.5 * half_angle) continue;
            e += lum(world_radiance(scene, d, ShaderRay::shadow)) * std::cos(th) * std::sin(th) * (kPi / 2 / nt) *
                 (2 * kPi / np);
        }
    }
    // The cone of 1.5 × the disc's radius, in polar coordinates about the sun.
    glm::vec3 b1 = glm::normalize(glm::cross(sun, glm::vec3(0, 0, 1))), b2 = glm::cross(sun, b1);
    const int nr = 400, na = 400;
    const double outer = 1.5 * half_angle;
    for (int i = 0; i < nr; ++i) {
        const double a = (i + 0.5) / nr * outer;
        for (int j = 0; j < na; ++j) {
            const double ph = (j + 0.5) / na * 2 * kPi;
            const glm::vec3 d = glm::normalize(float(std::cos(a)) * sun +
                                               float(std::sin(a)) * (float(std::cos(ph)) * b1 + float(std::sin(ph)) * b2));
            if (d.z <= 0.0f) continue;
            e += lum(world_radiance(scene, d, ShaderRay::shadow)) * d.z * std::sin(a) * (outer / nr) * (2 * kPi / na);
        }
    }
    return e;
}

TEST(World, NishitaSunLightSamplesAreConsistentAndEstimateTheIrradiance) {
    const auto& c = high_sun();
    Scene scene;
    add_floor(scene);
    scene.set_world_program(sky_world(c.settings, c.type, 1), 0);
    const auto world = scene.world_light();
    ASSERT_FALSE(world->constant());
    ASSERT_NE(world->map(), nullptr);

    const glm::vec3 x(0.0f, 0.0f, 1e-3f), n(0.0f, 0.0f, 1.0f);
    Rng rng(7, RngDomain::direct_light, 0);
    const int samples = 200000;
    double sum = 0.0, sum2 = 0.0, largest = 0.0;
    for (int k = 0; k < samples; ++k) {
        const LightIncidence in = world->sample_incidence(x, n, rng.uniform(), rng.uniform(), rng.uniform());
        ASSERT_TRUE(std::isfinite(in.pdf));
        if (!(in.pdf > 0.0f)) continue;
        // The density is the one pdf() gives, and value × pdf the program's radiance.
        ASSERT_NEAR(in.pdf, world->pdf(x, n, in.wi), 1e-4f * in.pdf);
        const glm::vec3 L = world_radiance(scene, in.wi, ShaderRay::shadow);
        ASSERT_NEAR(in.value.y * in.pdf, L.y, 1e-4f * std::max(L.y, 1.0f));
        if (in.wi.z <= 0.0f) continue;
        const double v = (0.2126 * in.value.x + 0.7152 * in.value.y + 0.0722 * in.value.z) * in.wi.z;
        sum += v;
        sum2 += v * v;
        largest = std::max(largest, v);
    }
    const double mean = sum / samples, sd = std::sqrt(std::max(0.0, sum2 / samples - mean * mean));
    const float* d = nullptr;
    std::vector<float> pre;
    precompute_sky(c.type, true, c.settings, pre);
    d = pre.data();
    const double elevation = d[6], azimuth = d[7] + kPi / 2, half = 0.5 * d[8];
    const glm::vec3 sun(float(std::cos(elevation) * std::cos(azimuth)), float(std::cos(elevation) * std::sin(azimuth)),
                        float(std::sin(elevation)));
    const double expected = horizontal_irradiance(scene, sun, half);
    std::printf("  horizontal irradiance: sampled %.5g (relative std of one sample %.3g, largest %.3g x mean), "
                "quadrature %.5g\n", mean, sd / mean, largest / mean, expected);
    EXPECT_NEAR(mean, expected, 0.01 * expected);
    // The disc is sampled as a cone: no sample is a firefly (one-sample std of an equal-time map alone: > 10).
    EXPECT_LT(sd / mean, 2.0);
    EXPECT_LT(largest / mean, 20.0);
}

TEST(World, PortalAndMapDensitiesAgreeWithTheSampler) {
    const auto& c = high_sun();
    Scene scene;
    add_floor(scene);
    scene.set_world_program(sky_world(c.settings, c.type, 1), 64);
    Portal portal;
    portal.name = "window";
    portal.corner = glm::dvec3(-1.0, 1.0, 3.0);  // the square |x|, |y| <= 1 at z = 3
    portal.edge_u = glm::vec3(2.0f, 0.0f, 0.0f);
    portal.edge_v = glm::vec3(0.0f, -2.0f, 0.0f);  // light passes downwards: cross(u, v) = -Z
    scene.add_portal(portal);
    const auto world = scene.world_light();
    EXPECT_EQ(world->map()->width(), 64);
    const glm::vec3 x(0.2f, 0.1f, 0.5f), n(0.0f, 0.0f, 1.0f);
    Rng rng(3, RngDomain::direct_light, 1);
    int through_portal = 0;
    for (int k = 0; k < 20000; ++k) {
        const LightIncidence in = world->sample_incidence(x, n, rng.uniform(), rng.uniform(), rng.uniform());
        if (!(in.pdf > 0.0f)) continue;
        ASSERT_NEAR(in.pdf, world->pdf(x, n, in.wi), 1e-4f * in.pdf);
        const float t = (3.0f - x.z) / in.wi.z;
        const glm::vec3 y = x + t * in.wi;
        if (in.wi.z > 0.0f && std::fabs(y.x) <= 1.0f && std::fabs(y.y) <= 1.0f) ++through_portal;
    }
    // A sixth of the samples go through the portal (Cycles' weights: portal 1, sun 4, map 1), plus the map's and
    // the sun's that happen to.
    EXPECT_GT(through_portal, 20000 / 6 - 300);
    // Below the portal's plane, on its outside, no portal can be sampled: the map and the sun only.
    const glm::vec3 outside(0.0f, 0.0f, 4.0f);
    for (int k = 0; k < 1000; ++k) {
        const LightIncidence in = world->sample_incidence(outside, n, rng.uniform(), rng.uniform(), rng.uniform());
        if (in.pdf > 0.0f) ASSERT_NEAR(in.pdf, world->pdf(outside, n, in.wi), 1e-4f * in.pdf);
    }
}

TEST(World, ChangesRebuildTheLightAndNothingElseDoes) {
    const auto& c = high_sun();
    Scene scene;
    add_floor(scene);
    scene.set_world_program(sky_world(c.settings, c.type, 0), 32);
    const auto first = scene.world_light();
    EXPECT_EQ(scene.world_light(), first);  // cached
    scene.set_background(glm::vec3(0.5f));
    const auto second = scene.world_light();
    EXPECT_NE(second, first);
    scene.clear_world_program();
    EXPECT_TRUE(scene.world_light()->constant());
}

}  // namespace
}  // namespace ps
