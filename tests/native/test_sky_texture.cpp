// The Sky Texture op (nodes/sky_texture.cpp) against Blender 3.4's Cycles itself.
//
// The goldens (golden/sky_goldens.h) are Cycles' renders, made with
//     blender -b --factory-startup --python tests/native/golden/make_sky_goldens.py
// (Debian's /usr/bin/blender 3.4.1, Cycles CPU, 1 sample, filter width 0.01, view transform Standard, float
// OpenEXR). Each pixel is a quad whose face attribute feeds the node's Vector exactly; the sun disc's pixels are
// the world seen by a camera aimed at the sun (the script says why and how).
//
// Tolerance: 1 % relative (of max(|value|, 1e-3)) for Nishita (sky, ground and sun disc) and Preetham. Hosek /
// Wilkie is evaluated as Preetham (its dataset is not reproduced here): its cases only print how far that is.
// Besides the goldens: the precomputation happens once per program at finalize_program and is shared; hostile
// directions and settings give finite colours; the cache is safe from several threads.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <thread>
#include <vector>

#include "golden/sky_goldens.h"
#include "nodes/sky_texture.h"
#include "photonsplat/errors.h"
#include "photonsplat/scene.h"
#include "photonsplat/shader_program.h"

namespace ps {
namespace {

std::vector<float> precomputed(const sky_goldens::Case& c) {
    std::vector<float> data;
    precompute_sky(c.type, c.sun_disc != 0, c.settings, data);
    return data;
}

double relative_error(float ours, float golden) {
    return std::fabs(double(ours) - double(golden)) / std::max(std::fabs(double(golden)), 1e-3);
}

TEST(SkyTexture, MatchesCyclesGoldens) {
    for (const auto& c : sky_goldens::kCases) {
        const std::vector<float> data = precomputed(c);
        ASSERT_EQ(static_cast<int64_t>(data.size()), sky_precomputed_floats(c.type)) << c.label;
        double worst = 0.0;
        for (int k = 0; k < c.n_points; ++k) {
            const float* g = c.data + 6 * k;
            const glm::vec3 ours = evaluate_sky(c.type, data.data(), glm::vec3(g[0], g[1], g[2]));
            for (int i = 0; i < 3; ++i) {
                ASSERT_TRUE(std::isfinite(ours[i])) << c.label;
                const double e = relative_error(ours[i], g[3 + i]);
                worst = std::max(worst, e);
                if (c.type != kSkyHosekWilkie)
                    EXPECT_LE(e, 0.01) << c.label << " point " << k << " (" << g[0] << ", " << g[1] << ", " << g[2]
                                       << ") channel " << i << ": ours " << ours[i] << ", Cycles " << g[3 + i];
            }
        }
        std::printf("  %-28s %2d points, largest relative difference %.3g%s\n", c.label, c.n_points, worst,
                    c.type == kSkyHosekWilkie ? " (Hosek / Wilkie approximated by Preetham)" : "");
    }
}

// The disc cases hold pixels inside the disc (and the texture just around it).
TEST(SkyTexture, GoldensCoverTheSunDisc) {
    int inside = 0;
    for (const auto& c : sky_goldens::kCases) {
        if (c.type != kSkyNishita || !c.sun_disc) continue;
        const std::vector<float> data = precomputed(c);
        const float elevation = data[6], rotation = data[7], half = 0.5f * data[8];
        const glm::vec3 sun(std::cos(elevation) * std::cos(rotation + 1.5707963f),
                            std::cos(elevation) * std::sin(rotation + 1.5707963f), std::sin(elevation));
        for (int k = 0; k < c.n_points; ++k) {
            const glm::vec3 d(c.data[6 * k], c.data[6 * k + 1], c.data[6 * k + 2]);
            if (std::acos(std::min(1.0f, glm::dot(glm::normalize(d), sun))) < half) ++inside;
        }
    }
    EXPECT_GE(inside, 20);
}

// A program: the sky op on vector register 0, colour into register 3, settings in the tables.
ShaderProgram sky_program(int type, int disc, const float* settings, int copies) {
    ShaderProgram p;
    p.registers.assign(3 + 3 * static_cast<size_t>(copies), 0.0f);
    p.registers[0] = 0.3f, p.registers[1] = 0.5f, p.registers[2] = 0.4f;
    p.tables.assign(settings, settings + kSkySettingsFloats);
    for (int i = 0; i < copies; ++i) {
        const int32_t out = 3 + 3 * i;
        p.code.insert(p.code.end(), {static_cast<int32_t>(ShaderOp::sky_texture), 4, 1, 1, type, disc, 0, -1, 0, out});
        p.outputs.push_back({ProgramTarget::emission, 0, out});
    }
    return p;
}

TEST(SkyTexture, PrecomputedOncePerProgramAtFinalize) {
    const auto& c = sky_goldens::kCases[0];  // Nishita, disc
    Scene scene;
    ShaderProgram p = sky_program(c.type, c.sun_disc, c.settings, 2);
    validate(p, 1, "program");
    finalize_program(p, scene);
    // Two identical skies share one copy; the constant direction folds into the registers.
    EXPECT_EQ(static_cast<int64_t>(p.tables.size()), kSkySettingsFloats + kNishitaFloats);
    EXPECT_TRUE(p.code.empty());
    validate(p, 1, "program");
    const glm::vec3 expected = evaluate_sky(c.type, p.tables.data() + kSkySettingsFloats, glm::vec3(0.3f, 0.5f, 0.4f));
    for (int k = 0; k < 3; ++k) {
        EXPECT_FLOAT_EQ(p.registers[3 + k], expected[k]);
        EXPECT_FLOAT_EQ(p.registers[6 + k], expected[k]);
    }
    EXPECT_GT(expected.x, 0.0f);

    // Not finalized: black, and no precomputation at run time.
    ShaderProgram raw = sky_program(c.type, c.sun_disc, c.settings, 1);
    std::vector<float> regs = raw.registers;
    run_program(raw, scene, ShaderGlobals{}, regs.data());
    EXPECT_EQ(regs[3], 0.0f);
    EXPECT_EQ(raw.tables.size(), static_cast<size_t>(kSkySettingsFloats));
}

TEST(SkyTexture, ValidationChecksItsTables) {
    const auto& c = sky_goldens::kCases[0];
    ShaderProgram p = sky_program(c.type, c.sun_disc, c.settings, 1);
    p.code[6] = 5;  // settings beyond the tables
    EXPECT_THROW(validate(p, 1, "program"), InvalidInput);
    p = sky_program(c.type, c.sun_disc, c.settings, 1);
    p.code[7] = 0;  // "precomputed" data that is not there
    EXPECT_THROW(validate(p, 1, "program"), InvalidInput);
    p = sky_program(7, 0, c.settings, 1);  // an unknown type: valid, black
    validate(p, 1, "program");
    Scene scene;
    finalize_program(p, scene);
    EXPECT_EQ(p.registers[3], 0.0f);
}

TEST(SkyTexture, HostileInputsGiveFiniteColours) {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    const glm::vec3 directions[] = {{nan, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f}, {inf, -inf, inf}, {1e30f, 1e30f, 1e30f},
                                    {0.0f, 0.0f, -1e-30f}, {-1e-38f, 1e-38f, 0.0f}, {0.0f, 0.0f, 1.0f},
                                    {0.0f, 0.0f, -1.0f}, {3.0f, -4.0f, 0.01f}};
    std::vector<std::vector<float>> settings;
    for (const auto& c : sky_goldens::kCases) settings.emplace_back(c.settings, c.settings + kSkySettingsFloats);
    std::vector<float> absurd(kSkySettingsFloats);
    const float absurd_values[][kSkySettingsFloats] = {
        {0, 0, 0, -5, -1, -1, -1, -10, 1e30f, -1e9f, -3, -3, -3},
        {1e30f, 1e30f, 1e30f, 1e30f, 1e30f, 1e30f, 1e30f, 1e30f, -1e30f, 1e30f, 1e30f, 1e30f, 1e30f},
        {nan, inf, -inf, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan},
        {0, 0, -1, 11, 2, 3.2f, 5, 1.5707963f, 0, 0, 0, 0, 0},
        {0, 1e-30f, 0, 1, 0, 0, 0, -1.5707963f, 6.2831853f, 59999, 10, 10, 10}};
    for (const auto& a : absurd_values) settings.emplace_back(a, a + kSkySettingsFloats);
    for (int type : {kSkyPreetham, kSkyHosekWilkie, kSkyNishita})
        for (int disc : {0, 1})
            for (const auto& s : settings) {
                std::vector<float> data;
                precompute_sky(type, disc != 0, s.data(), data);
                ASSERT_EQ(static_cast<int64_t>(data.size()), sky_precomputed_floats(type));
                for (const glm::vec3& d : directions) {
                    const glm::vec3 c = evaluate_sky(type, data.data(), d);
                    for (int k = 0; k < 3; ++k) {
                        EXPECT_TRUE(std::isfinite(c[k]) && c[k] >= 0.0f) << type << " " << d.x << " " << d.y;
                    }
                }
            }
}

TEST(SkyTexture, PrecomputationIsThreadSafe) {
    float s[kSkySettingsFloats];
    std::copy(sky_goldens::kCases[0].settings, sky_goldens::kCases[0].settings + kSkySettingsFloats, s);
    s[kSkySunElevation] = 0.4321f;  // a sky no other test asked for
    std::vector<std::vector<float>> results(4);
    std::vector<std::thread> threads;
    for (auto& r : results) threads.emplace_back([&r, &s] { precompute_sky(kSkyNishita, true, s, r); });
    for (auto& t : threads) t.join();
    for (const auto& r : results) EXPECT_EQ(r, results[0]);
}

}  // namespace
}  // namespace ps
