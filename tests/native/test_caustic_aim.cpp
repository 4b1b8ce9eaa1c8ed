// Photons aimed at mirrors and glass (caustic_aim.h): the targets are the specular objects, the cone density is
// a density, caustic photons multiply by the predicted factor, the estimates stay unbiased for every light
// that aims, the ordinary photons are untouched, and a scene without mirrors or glass renders the same bits.
// The unbiasedness checks trace 2.2M photon paths per light kind: most of this file's time.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "photonsplat/caustic_aim.h"
#include "photonsplat/errors.h"
#include "photonsplat/photons.h"
#include "photonsplat/render.h"
#include "photonsplat/rng.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/stats.h"
#include "test_scenes.h"

namespace {

using namespace ps;

constexpr float kPi = 3.14159265358979f;

TEST(CausticAim, TargetsAreTheSpecularSpheres) {
    Scene scene;
    test::build_cornell_box(scene, true);
    const std::vector<SpecularTarget> targets = specular_targets(scene);
    ASSERT_EQ(targets.size(), 2u) << "the glass and the mirror sphere; the diffuse walls are no target";
    EXPECT_NEAR(targets[0].center.x, -0.4f, 1e-3f);
    EXPECT_NEAR(targets[0].center.z, 0.4f, 1e-3f);
    EXPECT_NEAR(targets[0].radius, 0.4f, 1e-3f);
    EXPECT_NEAR(targets[1].center.y, 0.4f, 1e-3f);
    EXPECT_NEAR(targets[1].radius, 0.3f, 1e-3f);

    Scene plain;
    test::build_cornell_box(plain, false);
    EXPECT_TRUE(specular_targets(plain).empty());
}

TEST(CausticAim, ManySpecularInstancesShareOneSphere) {
    Scene scene;
    test::build_cornell_box(scene, false);
    const uint32_t mirror = scene.add_material({"mirror", MaterialKind::mirror, glm::vec3(0.9f), 1.45f, glm::vec3(0.0f)});
    for (int i = 0; i < 20; ++i) test::add_sphere(scene, "ball", {-0.9f + 0.09f * i, 0.0f, 0.5f}, 0.04f, mirror, 6, 12);
    const std::vector<SpecularTarget> targets = specular_targets(scene);
    ASSERT_EQ(targets.size(), 1u);
    for (int i = 0; i < 20; ++i) {
        const glm::vec3 ball(-0.9f + 0.09f * i, 0.0f, 0.5f);
        EXPECT_LE(glm::length(ball - targets[0].center) + 0.04f, targets[0].radius + 1e-4f) << "it holds ball " << i;
    }
}

TEST(CausticAim, ConeDensityIntegratesToOneAndHoldsItsSamples) {
    const std::vector<SpecularTarget> targets = {{{0.0f, 0.0f, 2.0f}, 0.5f}, {{0.3f, 0.0f, 2.0f}, 0.5f},
                                                 {{0.0f, -3.0f, 0.0f}, 0.2f}};
    Light light = test::point_light("lamp", {0.0f, 0.0f, 0.0f}, 100.0f);
    const TargetCones cones(targets, light, light.position, 0.0f);
    ASSERT_FALSE(cones.empty());
    // ∫ pdf dω by uniform directions; overlapping cones make the density a sum, which must still integrate to 1.
    Rng rng(3, RngDomain::photon, 0);
    double integral = 0.0;
    const int n = 400000;
    for (int i = 0; i < n; ++i) integral += cones.pdf(sample_uniform_sphere(rng.uniform(), rng.uniform()));
    EXPECT_NEAR(integral * 4.0 * kPi / n, 1.0, 0.02);
    for (int i = 0; i < 1000; ++i) {
        const glm::vec3 d = cones.sample(rng.uniform(), rng.uniform(), rng.uniform());
        EXPECT_GT(cones.pdf(d), 0.0f);
    }
    // A spot pointing away from every target aims at none of them.
    light.kind = LightKind::spot;
    light.direction = {1.0f, 0.0f, 0.0f};
    light.spot_size = 0.5f;
    EXPECT_TRUE(TargetCones(targets, light, light.position, 0.0f).empty());
}

// Caustic and other stored power of one photon map, per emitted (ordinary) photon.
struct StoredPower {
    double caustic = 0.0, other = 0.0;
    size_t caustic_count = 0;
};

StoredPower stored_power(const Scene& scene, uint64_t photons, float aimed, uint64_t seed) {
    PhotonSettings settings;
    settings.count = photons;
    settings.seed = seed;
    settings.aimed_fraction = aimed;
    RenderControl control;
    Stats stats;
    const PhotonMap map = trace_photons(scene, settings, control, stats);
    StoredPower s;
    for (const Photon& p : map.photons) {
        const double l = luminance(p.power);
        if (p.flags & kCaustic) {
            s.caustic += l;
            ++s.caustic_count;
        } else {
            s.other += l;
        }
    }
    s.caustic /= double(map.emitted);
    s.other /= double(map.emitted);
    return s;
}

TEST(CausticAim, CausticPhotonsMultiplyByThePredictedFactor) {
    // One mirror ball under a point lamp: an ordinary photon hits it with probability Ω_ball/4π, an aimed one with
    // probability Ω_ball/Ω_cone, and after the hit both go on alike; so caustic photons multiply by
    // 1 + aimed · 4π/Ω_cone.
    Scene scene;
    test::build_cornell_box(scene, false);
    scene.clear_lights();
    scene.add_light(test::point_light("lamp", {0.0f, 0.0f, 1.8f}, 100.0f));
    const uint32_t mirror = scene.add_material({"mirror", MaterialKind::mirror, glm::vec3(1.0f), 1.45f, glm::vec3(0.0f)});
    test::add_sphere(scene, "ball", {0.2f, 0.3f, 0.6f}, 0.25f, mirror);
    const std::vector<SpecularTarget> targets = specular_targets(scene);
    ASSERT_EQ(targets.size(), 1u);
    const float d = glm::length(targets[0].center - glm::vec3(0.0f, 0.0f, 1.8f));
    const double cone = 2.0 * kPi * (1.0 - std::sqrt(1.0 - double(targets[0].radius) * targets[0].radius / (d * d)));
    const float aimed = 0.25f;
    const double predicted = 1.0 + aimed * 4.0 * kPi / cone;
    const StoredPower off = stored_power(scene, 200000, 0.0f, 11), on = stored_power(scene, 200000, aimed, 11);
    ASSERT_GT(off.caustic_count, 1000u);
    const double factor = double(on.caustic_count) / double(off.caustic_count);
    EXPECT_GT(predicted, 5.0) << "the check must be able to tell";
    EXPECT_NEAR(factor, predicted, 0.06 * predicted) << "caustic photons " << off.caustic_count << " -> " << on.caustic_count;
    // The ordinary photons are the same ones: their other photons are identical.
    EXPECT_EQ(on.other, off.other);
}

// Mean and standard error of the stored power over `runs` photon maps of different seeds.
struct Estimate {
    double caustic = 0.0, caustic_error = 0.0, other = 0.0, other_error = 0.0;
};

Estimate estimate(const Scene& scene, float aimed, uint64_t first_seed, int runs, uint64_t photons) {
    std::vector<StoredPower> all;
    for (int i = 0; i < runs; ++i) all.push_back(stored_power(scene, photons, aimed, first_seed + uint64_t(i)));
    Estimate e;
    for (const StoredPower& s : all) e.caustic += s.caustic / runs, e.other += s.other / runs;
    double vc = 0.0, vo = 0.0;
    for (const StoredPower& s : all) vc += (s.caustic - e.caustic) * (s.caustic - e.caustic), vo += (s.other - e.other) * (s.other - e.other);
    e.caustic_error = std::sqrt(vc / (runs - 1) / runs);
    e.other_error = std::sqrt(vo / (runs - 1) / runs);
    return e;
}

void expect_unbiased(const Scene& scene, const char* what) {
    // Without aiming the caustics are the noisier estimate: more runs for it.
    const Estimate off = estimate(scene, 0.0f, 100, 32, 50000);
    const Estimate on = estimate(scene, 0.5f, 200, 12, 50000);
    ASSERT_GT(off.caustic, 0.0) << what;
    const double caustic_error = std::sqrt(off.caustic_error * off.caustic_error + on.caustic_error * on.caustic_error);
    EXPECT_LT(std::fabs(on.caustic - off.caustic), 4.0 * caustic_error)
        << what << ": caustic power " << off.caustic << " ± " << off.caustic_error << " without aiming, " << on.caustic
        << " ± " << on.caustic_error << " with";
    EXPECT_LT(on.caustic_error, off.caustic_error) << what << ": aiming lowers the caustics' noise";
    std::printf("%s: caustic %.5g ± %.2g without aiming, %.5g ± %.2g with; other %.5g ± %.2g, %.5g ± %.2g\n", what,
                off.caustic, off.caustic_error, on.caustic, on.caustic_error, off.other, off.other_error, on.other,
                on.other_error);
    const double other_error = std::sqrt(off.other_error * off.other_error + on.other_error * on.other_error);
    EXPECT_LT(std::fabs(on.other - off.other), 4.0 * other_error) << what << ": other indirect power";
}

TEST(CausticAim, UnbiasedForPointSpotAndAreaLights) {
    {
        Scene scene;
        test::build_cornell_box(scene, true);  // a soft point lamp (radius 0.02) over a glass and a mirror ball
        expect_unbiased(scene, "point");
    }
    {
        Scene scene;
        test::build_cornell_box(scene, true);
        scene.clear_lights();
        Light spot = test::point_light("spot", {0.2f, -0.3f, 1.8f}, 100.0f, 0.05f);
        spot.kind = LightKind::spot;
        spot.direction = glm::normalize(glm::vec3(-0.5f, 0.3f, -1.0f));
        spot.spot_size = 1.2f;  // the glass ball inside the cone, the mirror ball at its soft edge
        spot.spot_blend = 0.3f;
        scene.add_light(spot);
        expect_unbiased(scene, "spot");
    }
    {
        Scene scene;
        test::build_cornell_box(scene, true);
        scene.clear_lights();
        Light area;
        area.name = "panel";
        area.kind = LightKind::area;
        area.position = {0.0f, 0.0f, 1.95f};
        area.axis_u = {0.5f, 0.0f, 0.0f};
        area.axis_v = {0.0f, -0.5f, 0.0f};  // faces down
        area.value = glm::vec3(30.0f);
        scene.add_light(area);
        expect_unbiased(scene, "area");
    }
    {
        // Glass with a diffuse part (as Principled glass with a clearcoat has a lobe beside its sharp parts): the
        // inside of the ball stores caustic photons, and an aimed photon must go on from there to the floor as an
        // ordinary one does. Aimed photons that stopped at their first stored photon lost the floor's caustic
        // behind such a ball (seed 138 of the differential scenes: the image 0.90 of Cycles).
        Scene scene;
        test::build_cornell_box(scene, false);
        scene.clear_lights();
        scene.add_light(test::point_light("lamp", {0.0f, 0.0f, 1.8f}, 100.0f));
        Material glass{"coated glass", MaterialKind::glass, glm::vec3(1.0f), 1.5f, glm::vec3(0.0f)};
        lower_simple_material(glass);
        glass.kind = MaterialKind::closures;
        for (Closure& c : glass.closures) c.color *= 0.85f;
        Closure diffuse;
        diffuse.color = glm::vec3(0.15f);
        glass.closures.push_back(diffuse);
        test::add_sphere(scene, "ball", {0.1f, 0.2f, 0.5f}, 0.35f, scene.add_material(glass));
        expect_unbiased(scene, "glass with a diffuse part");
    }
}

TEST(CausticAim, ASceneWithoutMirrorsOrGlassRendersTheSameBits) {
    Scene scene;
    test::build_cornell_box(scene, false);
    RenderSettings settings;
    settings.photons = 5000;
    RenderControl control;
    settings.aimed_photons = 0.0f;
    const RenderResult off = render(scene, test::cornell_camera(24, 24), settings, control);
    settings.aimed_photons = 0.5f;
    const RenderResult on = render(scene, test::cornell_camera(24, 24), settings, control);
    EXPECT_EQ(off.rgba(), on.rgba());
    EXPECT_EQ(on.stats.counters.count("aimed_photons_emitted"), 0u);
}

TEST(CausticAim, BadFractionIsRefusedByName) {
    Scene scene;
    test::build_cornell_box(scene, true);
    RenderControl control;
    for (float bad : {-0.1f, std::nanf(""), 17.0f}) {
        RenderSettings settings;
        settings.aimed_photons = bad;
        try {
            render(scene, test::cornell_camera(8, 8), settings, control);
            ADD_FAILURE() << "accepted aimed_photons = " << bad;
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find("aimed_photons"), std::string::npos) << e.what();
        }
    }
}

}  // namespace
