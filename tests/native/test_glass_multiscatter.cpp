// Multiscatter GGX glass (glass_multiscatter.h): the walk it is tabulated from, and the lobes against the walk.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

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

namespace {

glm::vec3 toward(float cos_theta, float phi) {
    const float s = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
    return {s * std::cos(phi), s * std::sin(phi), cos_theta};
}

// The mean of Cycles' light-sample value over `keys` of its evaluation walk (white glass, tint `tint`).
float mean_light_value(float eta, float alpha, float tint, const glm::vec3& wi, const glm::vec3& wo, int keys) {
    double sum = 0.0;
    for (int k = 0; k < keys; ++k)
        sum += ps::cycles3_multi_glass_light_value(eta, alpha, glm::vec3(tint), wi, wo, 1, uint64_t(k) * 7919u + 1u).x;
    return float(sum / keys);
}

}  // namespace

TEST(GlassMultiscatter, CyclesLightValueIsItsFirstScatteringWithoutEtaSquaredWhereTheTintStopsTheRest) {
    // With a black tint Cycles' evaluation keeps its analytic first scattering only: the walk's own first
    // scattering (multi_ggx_glass_single) reflected, and transmitted without its η² where the light is the
    // steeper direction. Where the light is the more grazing, Cycles turns the path round with the same η, and its
    // value is not that (the reason its light samples and its walk disagree on such glass).
    const float alpha = 0.35f * 0.35f;
    const glm::vec3 black(0.0f);
    for (const float eta : {1.5f, 1.0f / 1.5f}) {
        const glm::vec3 wo = toward(0.7f, 0.0f);
        const glm::vec3 reflected = toward(0.5f, 2.8f);
        const float single_r = ps::multi_ggx_glass_single(eta, alpha, reflected, wo, nullptr);
        EXPECT_NEAR(ps::cycles3_multi_glass_light_value(eta, alpha, black, reflected, wo, 1, 5).x, single_r,
                    1e-4f * single_r + 1e-7f) << eta;
        // Transmitted, the light steeper than the view: not turned round.
        const glm::vec3 steep = -toward(0.9f, 0.1f);
        const float single_t = ps::multi_ggx_glass_single(eta, alpha, steep, wo, nullptr);
        ASSERT_GT(single_t, 0.0f) << eta;
        EXPECT_NEAR(ps::cycles3_multi_glass_light_value(eta, alpha, black, steep, wo, 1, 5).x * eta * eta, single_t,
                    1e-3f * single_t) << eta;
    }
    // Into glass of η 1.5, the light the more grazing (inside, cos 0.8) than the view (cos 0.95): turned round with
    // η kept, Cycles' value is far from the walk's.
    const glm::vec3 wo = toward(0.95f, 0.0f), grazing = -toward(0.8f, 0.1f);
    const float walk = ps::multi_ggx_glass_single(1.5f, alpha, grazing, wo, nullptr) / (1.5f * 1.5f);
    const float cycles = ps::cycles3_multi_glass_light_value(1.5f, alpha, black, grazing, wo, 1, 5).x;
    EXPECT_GT(std::fabs(cycles - walk), 0.2f * walk) << cycles << " " << walk;
}

TEST(GlassMultiscatter, CyclesLightValueAddsItsWalksLaterScatteringsReciprocally) {
    // Reflected, Cycles' evaluation is reciprocal (it evaluates from the steeper direction either way), its later
    // scatterings add light, tinted once each.
    const float eta = 1.5f, alpha = 0.8f * 0.8f;
    const glm::vec3 a = toward(0.8f, 0.0f), b = toward(0.3f, 2.0f);
    const int keys = 20000;
    const float ab = mean_light_value(eta, alpha, 1.0f, b, a, keys);
    const float ba = mean_light_value(eta, alpha, 1.0f, a, b, keys);
    EXPECT_NEAR(ab, ba, 0.03f * ab);
    const float first = mean_light_value(eta, alpha, 0.0f, b, a, 16);
    const float half = mean_light_value(eta, alpha, 0.5f, b, a, keys);
    EXPECT_GT(ab, first * 1.02f);
    EXPECT_GT(half, first);
    EXPECT_LT(half, ab);
}

TEST(GlassMultiscatter, ReportedDensityIsMfGlassPdfOnEachLobesSide) {
    // lobe_reported_pdf of the two lobes of a Multiscatter Glass: Cycles' mf_glass_pdf on each one's side, nothing
    // on the other; over the sphere it is about a density (Cycles' fit of a cosine lobe beside the single
    // scattering's).
    const float eta = 1.45f, roughness = 0.5f;
    ps::Lobe r;
    r.kind = ClosureKind::reflection;
    r.distribution = Distribution::multi_ggx_glass;
    r.weight = r.specular_color = glm::vec3(1.0f);
    r.alpha_x = r.alpha_y = roughness * roughness;
    r.eta = eta;
    ps::Lobe t = r;
    t.kind = ClosureKind::refraction;
    const glm::vec3 n(0.0f, 0.0f, 1.0f), wo = toward(0.6f, 0.0f);
    const glm::vec3 up = toward(0.4f, 2.5f), down = -toward(0.7f, 0.5f);
    EXPECT_FLOAT_EQ(ps::lobe_reported_pdf(r, n, up, wo), ps::cycles3_multi_glass_pdf(eta, r.alpha_x, up, wo));
    EXPECT_EQ(ps::lobe_reported_pdf(r, n, down, wo), 0.0f);
    EXPECT_FLOAT_EQ(ps::lobe_reported_pdf(t, n, down, wo), ps::cycles3_multi_glass_pdf(eta, r.alpha_x, down, wo));
    EXPECT_EQ(ps::lobe_reported_pdf(t, n, up, wo), 0.0f);
    // Uniform directions over the sphere, stratified.
    const int strata = 400;
    double sum = 0.0;
    for (int i = 0; i < strata; ++i) {
        for (int j = 0; j < strata; ++j) {
            const float z = 1.0f - 2.0f * (i + 0.5f) / strata, phi = 6.2831853f * (j + 0.5f) / strata;
            const glm::vec3 wi = toward(std::fabs(z), phi) * glm::vec3(1.0f, 1.0f, z < 0.0f ? -1.0f : 1.0f);
            sum += ps::lobe_reported_pdf(r, n, wi, wo) + ps::lobe_reported_pdf(t, n, wi, wo);
        }
    }
    const double integral = sum * 4.0 * 3.14159265 / (double(strata) * strata);
    EXPECT_GT(integral, 0.8);
    EXPECT_LT(integral, 1.1);
}

TEST(GlassMultiscatter, CyclesNumbersOfOnePathAreOneSequenceShifted) {
    // lcg_state_init(rng_hash + rng_offset + sample * scramble) with rng_offset 16 more per surface met: the k-th
    // number at the next vertex is the k-th at this one plus 16 a^k (mod 2^32), a = 1103515245, for every path.
    for (const uint32_t path : {0u, 12345u, 0xdeadbeefu}) {
        ps::CyclesLcg here = ps::CyclesLcg::at_vertex(path, 3), next = ps::CyclesLcg::at_vertex(path, 4);
        uint32_t step = 16u * 1103515245u;  // 16 a^k, from k = 1 (lcg_init steps once before the first number)
        for (int k = 0; k < 8; ++k) {
            step *= 1103515245u;
            const double shift = double(step) / 4294967295.0;
            double d = double(next.uniform()) - double(here.uniform()) - shift;
            d -= std::floor(d + 0.5);  // modulo 1
            EXPECT_NEAR(d, 0.0, 1e-6) << path << " " << k;
        }
    }
}

TEST(GlassMultiscatter, ASlabMeetsCyclesWalksAsTheyRunOnItsNumbers) {
    // A slab of Multiscatter Glass (roughness 0.45, IOR 1.36) seen at cos 0.3: a path that enters through the top
    // meets the bottom face from inside. Cycles' own walks (its kernel's mf_sample for glass compiled on its own
    // LCG, seeded as shade_surface.h seeds it per vertex) pass 0.490 of the light out through the bottom; on
    // independent numbers the same walks pass 0.336 (measured with 4M paths each). Ours on CyclesLcg and on
    // independent paths' numbers must give the same two figures.
    const float eta = 1.36f, alpha = 0.447f * 0.447f;
    const glm::vec3 wo = toward(0.3f, 0.0f), tint(1.0f);
    const int paths = 400000;
    for (const bool cycles_numbers : {true, false}) {
        double through = 0.0;
        for (int p = 0; p < paths; ++p) {
            const uint32_t path = uint32_t(p) * 2654435761u + 17u;
            ps::CyclesLcg top = ps::CyclesLcg::at_vertex(path, 0);
            ps::CyclesLcg bottom = ps::CyclesLcg::at_vertex(cycles_numbers ? path : path ^ 0x9e3779b9u, 1);
            glm::vec3 in(0.0f), out(0.0f);
            const glm::vec3 w0 = ps::cycles3_multi_glass_walk_sample(eta, alpha, tint, wo, top, in);
            if (!(w0.x > 0.0f) || !(in.z < 0.0f)) continue;
            const glm::vec3 w1 = ps::cycles3_multi_glass_walk_sample(1.0f / eta, alpha, tint, -in, bottom, out);
            if (w1.x > 0.0f && out.z < 0.0f) through += double(w0.x) * w1.x;
        }
        std::printf("slab: %s numbers pass %.4f\n", cycles_numbers ? "Cycles'" : "independent", through / paths);
        EXPECT_NEAR(through / paths, cycles_numbers ? 0.490 : 0.336, 0.006) << cycles_numbers;
    }
}
