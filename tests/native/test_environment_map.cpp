// The world's importance-sampling distribution: Cycles' equirectangular mapping, a pdf that integrates to 1
// and is the density sample() draws with, unbiased estimates of ∫ L dω, and the edge cases (zero maps, 1 × 1,
// the poles, an 8192 × 4096 map, input that must be refused).
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <glm/exponential.hpp>
#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "photonsplat/environment_map.h"
#include "photonsplat/errors.h"
#include "photonsplat/rng.h"

namespace {

using namespace ps;

constexpr double kPi = 3.14159265358979323846;

using TexelFn = std::function<glm::vec3(int x, int y)>;

std::vector<float> make_map(int width, int height, const TexelFn& texel) {
    std::vector<float> rgb(static_cast<size_t>(width) * height * 3);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const glm::vec3 t = texel(x, y);
            const size_t at = 3 * (static_cast<size_t>(y) * width + x);
            rgb[at] = t.x;
            rgb[at + 1] = t.y;
            rgb[at + 2] = t.z;
        }
    }
    return rgb;
}

double luminance(const glm::dvec3& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

// Cycles' direction_to_equirectangular, written out here in double so the tests do not lean on the code under test.
void cycles_uv(const glm::vec3& d, double& u, double& v) {
    const double len = std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z);
    u = (std::atan2(double(d.y), double(d.x)) - kPi) / (-2.0 * kPi);
    v = (std::acos(double(d.z) / len) - kPi) / (-kPi);
}

void cycles_cell(const glm::vec3& d, int width, int height, int& x, int& y) {
    double u, v;
    cycles_uv(d, u, v);
    x = std::min(width - 1, std::max(0, static_cast<int>(std::floor(u * width))));
    y = std::min(height - 1, std::max(0, static_cast<int>(std::floor(v * height))));
}

glm::vec3 direction_of(double u, double v) {
    const double phi = -2.0 * kPi * u + kPi, theta = -kPi * v + kPi;
    return glm::vec3(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                     float(std::cos(theta)));
}

// Exact solid angle of row y's cells: 2π / width × (cos θ_low − cos θ_high), θ = π (1 − v).
double cell_solid_angle(int y, int width, int height) {
    const double theta_high = kPi * (1.0 - double(y + 1) / height), theta_low = kPi * (1.0 - double(y) / height);
    return 2.0 * kPi / width * (std::cos(theta_high) - std::cos(theta_low));
}

// The probability of each cell as Cycles' background map weighs it: max(luminance, 0) × sin θ of its centre.
std::vector<double> cell_probabilities(int width, int height, const TexelFn& texel, bool with_sin_theta = true) {
    std::vector<double> p(static_cast<size_t>(width) * height);
    double total = 0.0;
    for (int y = 0; y < height; ++y) {
        const double s = with_sin_theta ? std::sin(kPi * (y + 0.5) / height) : 1.0;
        for (int x = 0; x < width; ++x) {
            p[size_t(y) * width + x] = std::max(0.0, luminance(texel(x, y))) * s;
            total += p[size_t(y) * width + x];
        }
    }
    for (double& q : p) q /= total;
    return p;
}

// ∫ pdf dω over one cell: k × k midpoints in (u, v) with dω = 2π² sin(πv) du dv.
double pdf_over_cell(const EnvironmentDistribution& env, int x, int y, int k = 4) {
    const int w = env.width(), h = env.height();
    double sum = 0.0;
    for (int b = 0; b < k; ++b) {
        const double v = (y + (b + 0.5) / k) / h;
        for (int a = 0; a < k; ++a) {
            const double u = (x + (a + 0.5) / k) / w;
            sum += env.pdf(direction_of(u, v)) * 2.0 * kPi * kPi * std::sin(kPi * v);
        }
    }
    return sum / (double(k) * k * w * h);
}

// A sky: a vertical gradient, a horizontal tint, two dark columns (luminance 0) and a sun.
constexpr int kSkyW = 16, kSkyH = 8, kSunX = 5, kSunY = 6;
glm::vec3 sky_texel(int x, int y) {
    if (x == 9 || x == 10) return glm::vec3(0.0f);
    if (x == kSunX && y == kSunY) return glm::vec3(400.0f, 380.0f, 300.0f);
    const float t = (y + 0.5f) / kSkyH;
    return glm::vec3(0.2f + 0.8f * t, 0.3f + 0.5f * t, 1.0f - 0.5f * x / float(kSkyW));
}
EnvironmentDistribution sky() { return EnvironmentDistribution(kSkyW, kSkyH, make_map(kSkyW, kSkyH, sky_texel)); }

// Mean and standard error of radiance / pdf (per channel) and luminance / pdf over n samples.
struct Estimate {
    glm::dvec3 mean{0.0}, error{0.0};
    double luminance_mean = 0.0, luminance_error = 0.0;
};
Estimate estimate(const EnvironmentDistribution& env, int n, uint64_t seed) {
    Rng rng(seed, RngDomain::direct_light, 0);
    glm::dvec3 sum(0.0), sum2(0.0);
    double lsum = 0.0, lsum2 = 0.0;
    for (int i = 0; i < n; ++i) {
        const float u1 = rng.uniform(), u2 = rng.uniform();
        const EnvironmentSample s = env.sample(u1, u2);
        if (s.pdf <= 0.0f) continue;  // a direction the sampler cannot draw (a pole), counted as 0
        const glm::dvec3 f = glm::dvec3(s.radiance) / double(s.pdf);
        sum += f;
        sum2 += f * f;
        const double l = luminance(s.radiance) / s.pdf;
        lsum += l;
        lsum2 += l * l;
    }
    Estimate e;
    e.mean = sum / double(n);
    e.error = glm::sqrt(glm::max(sum2 / double(n) - e.mean * e.mean, glm::dvec3(0.0)) / double(n));
    e.luminance_mean = lsum / n;
    e.luminance_error = std::sqrt(std::max(lsum2 / n - e.luminance_mean * e.luminance_mean, 0.0) / n);
    return e;
}

// |estimate − truth| within 5 standard errors and within `relative` of the truth.
void expect_estimate(double mean, double error, double truth, double relative, const std::string& what) {
    EXPECT_LE(std::fabs(mean - truth), 5.0 * error + 1e-12 * std::fabs(truth)) << what << ": " << mean << " vs " << truth;
    EXPECT_LE(std::fabs(mean - truth), relative * std::fabs(truth)) << what << ": " << mean << " vs " << truth;
}

TEST(EnvironmentMap, MappingIsCycles) {
    // Cycles: u = (atan2(y, x) − π) / (−2π), v = (acos(z) − π) / (−π).
    const struct {
        glm::vec3 d;
        float u, v;
    } cases[] = {
        {{0, 0, 1}, 0.5f, 1.0f},  // +Z: v = 1 (atan2(0, 0) = 0, so u = 0.5)
        {{0, 0, -1}, 0.5f, 0.0f}, {{1, 0, 0}, 0.5f, 0.5f},    {{0, 1, 0}, 0.25f, 0.5f},
        {{0, -1, 0}, 0.75f, 0.5f}, {{-1, 0, 0}, 0.0f, 0.5f},  // atan2(+0, −1) = π: u = 0
        {{-1, -0.0f, 0}, 1.0f, 0.5f},                         // atan2(−0, −1) = −π: u = 1, the same seam
        {{2, 0, 2}, 0.5f, 0.75f},                             // any length: 45° up
    };
    for (const auto& c : cases) {
        const glm::vec2 uv = direction_to_equirectangular(c.d);
        EXPECT_NEAR(uv.x, c.u, 1e-7) << c.d.x << " " << c.d.y << " " << c.d.z;
        EXPECT_NEAR(uv.y, c.v, 1e-7) << c.d.x << " " << c.d.y << " " << c.d.z;
    }
    EXPECT_EQ(direction_to_equirectangular(glm::vec3(0.0f)), glm::vec2(0.0f));
    EXPECT_EQ(direction_to_equirectangular(glm::vec3(NAN, 0, 1)), glm::vec2(0.0f));
    const glm::vec3 up = equirectangular_to_direction(0.3f, 1.0f), x = equirectangular_to_direction(0.5f, 0.5f);
    EXPECT_NEAR(up.z, 1.0f, 1e-7);
    EXPECT_NEAR(x.x, 1.0f, 1e-7);
    EXPECT_NEAR(x.y, 0.0f, 1e-7);
    EXPECT_NEAR(equirectangular_to_direction(0.25f, 0.5f).y, 1.0f, 1e-7);
}

TEST(EnvironmentMap, DirectionsRoundTripThroughUv) {
    Rng rng(11, RngDomain::direct_light, 0);
    for (int i = 0; i < 100000; ++i) {
        const float u = rng.uniform(), v = rng.uniform();
        const glm::vec3 d = equirectangular_to_direction(u, v);
        EXPECT_NEAR(glm::length(d), 1.0f, 1e-6f);
        const glm::vec2 back = direction_to_equirectangular(d);
        // u is undefined at the poles; away from them both come back to float precision.
        if (v > 1e-3f && v < 1.0f - 1e-3f) {
            ASSERT_NEAR(back.x, u, 2e-6f) << u << " " << v;
        }
        ASSERT_NEAR(back.y, v, 2e-6f) << u << " " << v;
        // And a direction (any length) through uv and back.
        const glm::vec3 e(2.0f * rng.uniform() - 1.0f, 2.0f * rng.uniform() - 1.0f, 2.0f * rng.uniform() - 1.0f);
        if (glm::length(e) < 1e-3f) continue;
        const glm::vec2 uv = direction_to_equirectangular(e);
        const glm::vec3 f = equirectangular_to_direction(uv.x, uv.y);
        ASSERT_NEAR(glm::length(f - glm::normalize(e)), 0.0f, 2e-6f);
    }
}

TEST(EnvironmentMap, RowZeroIsTheBottomAndColumnZeroStartsAtMinusX) {
    const int w = 8, h = 4;
    for (int bright_row : {0, h - 1}) {
        const EnvironmentDistribution env(w, h, make_map(w, h, [&](int x, int y) {
            return glm::vec3(y == bright_row && x == 0 ? 1.0f : 0.0f);
        }));
        Rng rng(5, RngDomain::direct_light, bright_row);
        const float z_edge = float(std::cos(kPi / h));  // row 0: z < −cos(π/h); row h − 1: z > cos(π/h)
        for (int i = 0; i < 10000; ++i) {
            const EnvironmentSample s = env.sample(rng.uniform(), rng.uniform());
            if (bright_row == 0) {
                ASSERT_LE(s.direction.z, -z_edge + 1e-6f);
            } else {
                ASSERT_GE(s.direction.z, z_edge - 1e-6f);
            }
            // Column 0 spans u ∈ [0, 1/8], φ = π − 2πu ∈ [135°, 180°]: the octant from −X towards +Y.
            ASSERT_LE(s.direction.x, 1e-6f);
            ASSERT_GE(s.direction.y, -1e-6f);
            ASSERT_LE(s.direction.y, -s.direction.x + 1e-6f);
        }
        EXPECT_EQ(env.radiance(glm::vec3(-1.0f, 0.1f, bright_row == 0 ? -5.0f : 5.0f)), glm::vec3(1.0f));
        EXPECT_EQ(env.radiance(glm::vec3(-1.0f, -0.1f, bright_row == 0 ? -5.0f : 5.0f)), glm::vec3(0.0f));
    }
}

TEST(EnvironmentMap, PdfIntegratesToOneAndToEachCellsProbability) {
    const std::vector<double> p = cell_probabilities(kSkyW, kSkyH, sky_texel);
    const EnvironmentDistribution env = sky();
    double total = 0.0;
    for (int y = 0; y < kSkyH; ++y) {
        for (int x = 0; x < kSkyW; ++x) {
            const double cell = pdf_over_cell(env, x, y);
            EXPECT_NEAR(cell, p[size_t(y) * kSkyW + x], 1e-6 + 1e-5 * p[size_t(y) * kSkyW + x]) << x << ", " << y;
            total += cell;
        }
    }
    EXPECT_NEAR(total, 1.0, 1e-5);
    // The sun's cell takes its share: 400-ish luminance against a sky of ~0.5.
    EXPECT_GT(p[size_t(kSunY) * kSkyW + kSunX], 0.2);
    // Dark columns: pdf 0, radiance 0.
    EXPECT_EQ(env.pdf(direction_of(9.5 / kSkyW, 0.5)), 0.0f);
    EXPECT_EQ(env.radiance(direction_of(10.5 / kSkyW, 0.3)), glm::vec3(0.0f));

    // The same integral on a (θ, φ) grid that does not line up with the cells: only its edges' error remains.
    const int nt = 997, np = 2003;
    double grid = 0.0;
    for (int i = 0; i < nt; ++i) {
        const double theta = kPi * (i + 0.5) / nt;
        for (int j = 0; j < np; ++j) {
            const double phi = 2.0 * kPi * (j + 0.5) / np;
            const glm::vec3 d(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                              float(std::cos(theta)));
            grid += env.pdf(d) * std::sin(theta);
        }
    }
    grid *= (kPi / nt) * (2.0 * kPi / np);
    EXPECT_NEAR(grid, 1.0, 2e-3);
}

TEST(EnvironmentMap, SampledPdfAndRadianceAreThoseOfTheDirection) {
    std::vector<EnvironmentDistribution> maps;
    maps.push_back(sky());
    maps.emplace_back(1, 1, std::vector<float>{0.5f, 1.0f, 2.0f});
    maps.emplace_back(7, 3, make_map(7, 3, [](int x, int y) { return glm::vec3(float(x * y + 1), 0.5f, float(x)); }));
    for (size_t m = 0; m < maps.size(); ++m) {
        const EnvironmentDistribution& env = maps[m];
        Rng rng(17, RngDomain::direct_light, m);
        int zero = 0;
        for (int i = 0; i < 200000; ++i) {
            const EnvironmentSample s = env.sample(rng.uniform(), rng.uniform());
            ASSERT_NEAR(glm::length(s.direction), 1.0f, 1e-6f);
            ASSERT_TRUE(std::isfinite(s.pdf));
            ASSERT_EQ(s.pdf, env.pdf(s.direction)) << "map " << m;
            ASSERT_EQ(s.radiance, env.radiance(s.direction)) << "map " << m;
            zero += s.pdf == 0.0f;
        }
        EXPECT_EQ(zero, 0) << "map " << m;  // no sample lands where the sampler cannot draw it
    }
}

TEST(EnvironmentMap, HistogramOfSamplesMatchesThePdf) {
    // 2 × 2 bins per cell in (u, v): the cells' probabilities (luminance × sin θ) and uniform placement inside a
    // cell in u and v (Cycles' sampler, whose pdf carries the Jacobian 1 / 2π² sin θ of the exact direction).
    const int w = kSkyW, h = kSkyH, n = 2000000;
    const EnvironmentDistribution env = sky();
    std::vector<double> count(size_t(w) * h * 4, 0.0);
    Rng rng(23, RngDomain::direct_light, 0);
    for (int i = 0; i < n; ++i) {
        const EnvironmentSample s = env.sample(rng.uniform(), rng.uniform());
        double u, v;
        cycles_uv(s.direction, u, v);
        const int bx = std::min(2 * w - 1, int(std::floor(u * 2 * w))), by = std::min(2 * h - 1, int(std::floor(v * 2 * h)));
        count[size_t(by) * 2 * w + bx] += 1.0;
    }
    auto chi_square = [&](const std::vector<double>& p_cell, int& dof) {
        double chi2 = 0.0, pooled_expected = 0.0, pooled_count = 0.0;
        dof = -1;
        for (int by = 0; by < 2 * h; ++by) {
            for (int bx = 0; bx < 2 * w; ++bx) {
                const double expected = n * p_cell[size_t(by / 2) * w + bx / 2] / 4.0;
                const double c = count[size_t(by) * 2 * w + bx];
                if (expected < 5.0) {  // the dark columns: pooled into one bin
                    pooled_expected += expected;
                    pooled_count += c;
                    continue;
                }
                chi2 += (c - expected) * (c - expected) / expected;
                ++dof;
            }
        }
        EXPECT_EQ(pooled_expected, 0.0);  // the only faint bins are the dark columns,
        EXPECT_EQ(pooled_count, 0.0);     // never drawn
        return chi2;
    };
    int dof = 0;
    const double chi2 = chi_square(cell_probabilities(w, h, sky_texel), dof);
    const double critical = dof + 5.0 * std::sqrt(2.0 * dof);  // ~5 σ above the mean of χ²(dof)
    EXPECT_EQ(dof, 4 * w * h - 4 * 2 * h - 1);
    EXPECT_LT(chi2, critical) << "dof " << dof;
    // The same counts against weights without sin θ fail by far: the test sees the weighting.
    int dof_flat = 0;
    EXPECT_GT(chi_square(cell_probabilities(w, h, sky_texel, false), dof_flat), 10.0 * critical);
    // The sun's four bins to 1 % each.
    const double sun = cell_probabilities(w, h, sky_texel)[size_t(kSunY) * w + kSunX];
    for (int q = 0; q < 4; ++q) {
        const double c = count[size_t(2 * kSunY + q / 2) * 2 * w + 2 * kSunX + q % 2];
        EXPECT_NEAR(c / (n * sun / 4.0), 1.0, 0.01);
    }
}

TEST(EnvironmentMap, EstimatesTheIntegralOfRadiance) {
    const int n = 400000;
    {  // Constant: 4π L.
        const glm::vec3 l(0.5f, 1.0f, 2.0f);
        for (auto [w, h] : {std::pair{16, 8}, std::pair{1, 1}, std::pair{3, 5}}) {
            const EnvironmentDistribution env(w, h, make_map(w, h, [&](int, int) { return l; }));
            EXPECT_NEAR(env.integral(), 4.0 * kPi * luminance(l), 1e-13 * 4.0 * kPi);
            const Estimate e = estimate(env, n, 1);
            for (int c = 0; c < 3; ++c) {
                expect_estimate(e.mean[c], e.error[c], 4.0 * kPi * l[c], 0.01,
                                "constant " + std::to_string(w) + "x" + std::to_string(h) + " channel " + std::to_string(c));
            }
        }
    }
    {  // Bright only above the horizon (an even height puts the horizon on a row edge): 2π L.
        const int w = 32, h = 16;
        const glm::vec3 l(3.0f, 2.0f, 1.0f);
        const EnvironmentDistribution env(w, h, make_map(w, h, [&](int, int y) { return y >= h / 2 ? l : glm::vec3(0.0f); }));
        EXPECT_NEAR(env.integral(), 2.0 * kPi * luminance(l), 1e-13 * 2.0 * kPi);
        const Estimate e = estimate(env, n, 2);
        for (int c = 0; c < 3; ++c) expect_estimate(e.mean[c], e.error[c], 2.0 * kPi * l[c], 0.01, "upper hemisphere");
        Rng rng(3, RngDomain::direct_light, 0);
        for (int i = 0; i < 10000; ++i) ASSERT_GE(env.sample(rng.uniform(), rng.uniform()).direction.z, 0.0f);
    }
    {  // A small sun alone, then over a dim sky: S Ω_cell (+ sky × the rest of the sphere).
        const int w = 64, h = 64, sx = 37, sy = 50;
        const glm::vec3 sun(1.0e4f, 9.0e3f, 8.0e3f), dim(0.1f, 0.1f, 0.2f);
        const double omega = cell_solid_angle(sy, w, h);
        for (bool with_sky : {false, true}) {
            const glm::vec3 rest = with_sky ? dim : glm::vec3(0.0f);
            const EnvironmentDistribution env(
                w, h, make_map(w, h, [&](int x, int y) { return x == sx && y == sy ? sun : rest; }));
            const glm::dvec3 truth = glm::dvec3(sun) * omega + glm::dvec3(rest) * (4.0 * kPi - omega);
            EXPECT_NEAR(env.integral(), luminance(truth), 1e-12 * luminance(truth));
            const Estimate e = estimate(env, n, 4);
            for (int c = 0; c < 3; ++c) expect_estimate(e.mean[c], e.error[c], truth[c], 0.01, "sun");
        }
    }
    {  // The sky: luminance / pdf averages to integral(), the exact integral of the nearest-texel map.
        const EnvironmentDistribution env = sky();
        double truth = 0.0;
        for (int y = 0; y < kSkyH; ++y)
            for (int x = 0; x < kSkyW; ++x) truth += luminance(sky_texel(x, y)) * cell_solid_angle(y, kSkyW, kSkyH);
        EXPECT_NEAR(env.integral(), truth, 1e-12 * truth);
        const Estimate e = estimate(env, n, 5);
        expect_estimate(e.luminance_mean, e.luminance_error, truth, 0.01, "sky");
    }
}

TEST(EnvironmentMap, FromFunctionBakesCellCentres) {
    // L = max(z, 0) grey: ∫ L dω = π. Baked at cell centres (midpoint rule) on 128 rows: error ~ (π/h)² / 24.
    const int w = 64, h = 128;
    const EnvironmentDistribution env = EnvironmentDistribution::from_function(
        w, h, [](const glm::vec3& d) { return glm::vec3(std::max(d.z, 0.0f)); });
    EXPECT_NEAR(env.integral(), kPi, 1e-4 * kPi);
    const Estimate e = estimate(env, 400000, 6);
    expect_estimate(e.luminance_mean, e.luminance_error, env.integral(), 0.01, "max(z, 0)");
    // The texel of cell (x, y) is the function at its centre direction.
    const glm::vec3 centre = equirectangular_to_direction((3 + 0.5f) / w, (100 + 0.5f) / h);
    EXPECT_EQ(env.radiance(centre), glm::vec3(std::max(centre.z, 0.0f)));
    EXPECT_EQ(env.pdf(glm::vec3(0.3f, 0.2f, -1.0f)), 0.0f);  // below the horizon the map is 0
}

TEST(EnvironmentMap, ZeroMapsSampleNothing) {
    for (const glm::vec3& value : {glm::vec3(0.0f), glm::vec3(-1.0f, -2.0f, -3.0f)}) {  // negative weighs 0
        const EnvironmentDistribution env(8, 4, make_map(8, 4, [&](int, int) { return value; }));
        EXPECT_TRUE(env.is_zero());
        EXPECT_EQ(env.integral(), 0.0);
        Rng rng(7, RngDomain::direct_light, 0);
        for (int i = 0; i < 1000; ++i) {
            const EnvironmentSample s = env.sample(rng.uniform(), rng.uniform());
            ASSERT_EQ(s.pdf, 0.0f);
            ASSERT_EQ(s.radiance, glm::vec3(0.0f));
            ASSERT_EQ(s.direction, glm::vec3(0.0f, 0.0f, 1.0f));
        }
        for (const glm::vec3& d : {glm::vec3(1, 0, 0), glm::vec3(0, 0, 1), glm::vec3(0.3f, -0.4f, -0.5f)}) {
            EXPECT_EQ(env.pdf(d), 0.0f);
        }
    }
    // A zero vector or NaN direction, and out-of-range numbers, never give NaN.
    const EnvironmentDistribution env = sky();
    EXPECT_EQ(env.pdf(glm::vec3(0.0f)), 0.0f);
    EXPECT_EQ(env.pdf(glm::vec3(NAN, 0.0f, 1.0f)), 0.0f);
    EXPECT_EQ(env.radiance(glm::vec3(0.0f)), glm::vec3(0.0f));
    for (float u : {-1.0f, 1.0f, 2.0f, NAN}) {
        const EnvironmentSample s = env.sample(u, u);
        EXPECT_TRUE(std::isfinite(s.pdf) && std::isfinite(s.direction.x) && std::isfinite(s.direction.z)) << u;
        EXPECT_EQ(s.pdf, env.pdf(s.direction));
    }
}

TEST(EnvironmentMap, NegativeTexelsWeighNothing) {
    // A texel of negative luminance (an HDRI's ringing) is never drawn and leaves the others' weights alone.
    const int w = 4, h = 2;
    const glm::vec3 negative(-5.0f, -5.0f, -5.0f);
    const EnvironmentDistribution env(w, h, make_map(w, h, [&](int x, int y) {
        return x == 1 && y == 1 ? negative : glm::vec3(1.0f);
    }));
    const glm::vec3 inside = direction_of(1.5 / w, 1.5 / h);
    EXPECT_EQ(env.pdf(inside), 0.0f);
    EXPECT_EQ(env.radiance(inside), negative);  // the map as given
    EXPECT_NEAR(env.integral(), 4.0 * kPi - cell_solid_angle(1, w, h), 1e-13);
    EXPECT_NEAR(pdf_over_cell(env, 0, 1), 1.0 / 7.0, 1e-6);  // 7 equal cells (both rows have sin θ_centre = sin 45°)
    Rng rng(31, RngDomain::direct_light, 0);
    for (int i = 0; i < 10000; ++i) ASSERT_NE(env.sample(rng.uniform(), rng.uniform()).radiance, negative);
}

TEST(EnvironmentMap, OneTexelIsAConstantSky) {
    const EnvironmentDistribution env(1, 1, std::vector<float>{1.0f, 1.0f, 1.0f});
    // One cell: v uniform over [0, 1], so the density is 1 / (2π² sin θ).
    EXPECT_FLOAT_EQ(env.pdf(glm::vec3(1, 0, 0)), float(1.0 / (2.0 * kPi * kPi)));
    EXPECT_FLOAT_EQ(env.pdf(glm::vec3(0, -1, 1)), float(1.0 / (2.0 * kPi * kPi * std::sqrt(0.5))));
    EXPECT_EQ(env.pdf(glm::vec3(0, 0, 1)), 0.0f);  // the poles themselves: sin θ = 0, as Cycles
    EXPECT_EQ(env.pdf(glm::vec3(0, 0, -1)), 0.0f);
    EXPECT_NEAR(pdf_over_cell(env, 0, 0, 64), 1.0, 1e-5);
}

TEST(EnvironmentMap, PoleRowsStayFiniteAndIntegrate) {
    // Only the top row lights: its cells' sin θ_centre is sin(π / 2h), the pdf ~ 1 / sin θ inside it.
    const int w = 16, h = 64;
    const EnvironmentDistribution env(w, h, make_map(w, h, [&](int, int y) { return glm::vec3(y == h - 1 ? 2.0f : 0.0f); }));
    double total = 0.0;
    for (int x = 0; x < w; ++x) total += pdf_over_cell(env, x, h - 1, 16);
    EXPECT_NEAR(total, 1.0, 1e-5);
    EXPECT_NEAR(env.integral(), 2.0 * w * cell_solid_angle(h - 1, w, h), 1e-12);
    const Estimate e = estimate(env, 200000, 8);
    expect_estimate(e.mean.x, e.error.x, 2.0 * w * cell_solid_angle(h - 1, w, h), 0.01, "top row");
    // A hair from the pole: large and finite; on it: 0.
    const float near_pole = env.pdf(glm::vec3(1e-30f, 0.0f, 1.0f));
    EXPECT_TRUE(std::isfinite(near_pole));
    EXPECT_GT(near_pole, 1e20f);
    EXPECT_EQ(env.pdf(glm::vec3(0.0f, 0.0f, 1.0f)), 0.0f);
    // The last u2 before 1 samples right next to the pole, with a finite pdf.
    const EnvironmentSample s = env.sample(0.5f, std::nextafter(1.0f, 0.0f));
    EXPECT_TRUE(std::isfinite(s.pdf));
    EXPECT_GT(s.pdf, 0.0f);
    EXPECT_GT(s.direction.z, 0.999f);
}

TEST(EnvironmentMap, RefusesBadInput) {
    auto expect_refused = [](const std::function<void()>& build, const std::string& words) {
        try {
            build();
            ADD_FAILURE() << "accepted; expected: " << words;
        } catch (const InvalidInput& e) {
            EXPECT_EQ(e.field(), "environment map");
            EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
        }
    };
    std::vector<float> nan_map = make_map(4, 2, [](int, int) { return glm::vec3(1.0f); });
    nan_map[3 * (1 * 4 + 3) + 1] = std::numeric_limits<float>::quiet_NaN();
    expect_refused([&] { EnvironmentDistribution(4, 2, nan_map); }, "texel (3, 1) channel G is nan");
    std::vector<float> inf_map = make_map(4, 2, [](int, int) { return glm::vec3(1.0f); });
    inf_map[2] = -std::numeric_limits<float>::infinity();
    expect_refused([&] { EnvironmentDistribution(4, 2, inf_map); }, "texel (0, 0) channel B is -inf");
    expect_refused([] { EnvironmentDistribution(4, 2, std::vector<float>(23, 1.0f)); }, "has 24 floats, got 23");
    expect_refused([] { EnvironmentDistribution(0, 2, {}); }, "at least 1 × 1 texels, got 0 × 2");
    expect_refused([] { EnvironmentDistribution(3, -1, {}); }, "got 3 × -1");
    expect_refused(
        [] { EnvironmentDistribution::from_function(4, 4, [](const glm::vec3& d) { return glm::vec3(d.z > 0.9f ? NAN : 1.0f); }); },
        "is nan");
}

TEST(EnvironmentMap, LargestMapSamplesItsSun) {
    // 8192 × 4096 (a 8K HDRI): 33.5 M cells, 100 M floats; a sun of 10⁶ over a sky of 10⁻².
    const int w = 8192, h = 4096, sx = 6000, sy = 3500;
    std::vector<float> rgb(size_t(w) * h * 3, 0.01f);
    for (int c = 0; c < 3; ++c) rgb[3 * (size_t(sy) * w + sx) + c] = 1.0e6f;
    const EnvironmentDistribution env(w, h, std::move(rgb));
    const double omega = cell_solid_angle(sy, w, h);
    const double sky = double(0.01f);  // the float the map holds
    const double truth = 1.0e6 * omega + sky * (4.0 * kPi - omega);
    EXPECT_NEAR(env.integral(), truth, 1e-11 * truth);  // 33.5 M terms summed in double
    // The sun's probability: its weight over the whole (luminance × sin θ_centre; luminance of grey = grey).
    double sky_weight = 0.0;
    for (int y = 0; y < h; ++y) sky_weight += std::sin(kPi * (y + 0.5) / h) * w * sky;
    const double sun_weight = std::sin(kPi * (sy + 0.5) / h) * (1.0e6 - sky);
    const double p_sun = sun_weight / (sun_weight + sky_weight);
    Rng rng(29, RngDomain::direct_light, 0);
    const int n = 200000;
    int in_sun = 0, zero = 0;
    for (int i = 0; i < n; ++i) {
        const EnvironmentSample s = env.sample(rng.uniform(), rng.uniform());
        ASSERT_TRUE(std::isfinite(s.pdf));
        ASSERT_EQ(s.pdf, env.pdf(s.direction));
        zero += s.pdf == 0.0f;
        int x, y;
        cycles_cell(s.direction, w, h, x, y);
        in_sun += x == sx && y == sy;
    }
    EXPECT_EQ(zero, 0);
    const double sigma = std::sqrt(n * p_sun * (1.0 - p_sun));
    EXPECT_NEAR(in_sun, n * p_sun, 5.0 * sigma) << "p_sun " << p_sun;
    // The sun cell's ∫ pdf dω is p_sun, and the far corner of the map is still reachable.
    EXPECT_NEAR(pdf_over_cell(env, sx, sy), p_sun, 1e-5 * p_sun);
    const double p_corner = std::sin(kPi * (h - 0.5) / h) * sky / (sun_weight + sky_weight);
    EXPECT_NEAR(pdf_over_cell(env, w - 1, h - 1), p_corner, 1e-3 * p_corner);
}

}  // namespace
