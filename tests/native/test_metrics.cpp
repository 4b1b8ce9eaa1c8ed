// Image metrics (metrics.h): definitions on small hand-checkable images; agreement with scikit-image is
// checked in tests/python/test_metrics.py.
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "photonsplat/errors.h"
#include "photonsplat/metrics.h"

namespace {

std::vector<float> gradient_image(int w, int h, float scale) {
    std::vector<float> p(static_cast<size_t>(w) * h * 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) p[(static_cast<size_t>(y) * w + x) * 3 + c] = scale * (x + 2 * y + c) / (w + 2 * h);
    return p;
}

}  // namespace

TEST(Metrics, IdenticalImages) {
    const auto a = gradient_image(16, 12, 1.0f);
    const ps::ImageView v{a.data(), 16, 12, 3};
    EXPECT_DOUBLE_EQ(ps::ssim(v, v), 1.0);
    EXPECT_EQ(ps::psnr(v, v), std::numeric_limits<double>::infinity());  // documented: as scikit-image
    EXPECT_EQ(ps::rmse(v, v), 0.0);
    EXPECT_EQ(ps::relmse(v, v), 0.0);
}

TEST(Metrics, DisplayLumaClampsAndEncodes) {
    // Linear 0.5 grey → sRGB 0.7354; above 1 clamps to 1; negative to 0; luma weights sum to 1.
    const std::vector<float> p = {0.5f, 0.5f, 0.5f, 4.0f, 2.0f, 9.0f, -1.0f, -0.5f, 0.0f};
    const std::vector<double> y = ps::display_luma(ps::ImageView{p.data(), 3, 1, 3});
    EXPECT_NEAR(y[0], 0.735357, 1e-6);
    EXPECT_NEAR(y[1], 1.0, 1e-12);
    EXPECT_NEAR(y[2], 0.0, 1e-12);
}

TEST(Metrics, PsnrOfAUniformOffset) {
    // Two flat display values 0.5 and 0.6 after encoding: MSE 0.01, PSNR 20 dB. Linear values chosen so the
    // encoded luma is exactly those: invert the sRGB curve.
    auto linear = [](double e) { return static_cast<float>(std::pow((e + 0.055) / 1.055, 2.4)); };
    const std::vector<float> a(12 * 12 * 3, linear(0.5)), b(12 * 12 * 3, linear(0.6));
    EXPECT_NEAR(ps::psnr(ps::ImageView{a.data(), 12, 12, 3}, ps::ImageView{b.data(), 12, 12, 3}), 20.0, 1e-4);
}

TEST(Metrics, LinearErrors) {
    const std::vector<float> a = {1, 2, 3, 0, 0, 0}, b = {1, 2, 5, 0, 0, 1};
    const ps::ImageView va{a.data(), 2, 1, 3}, vb{b.data(), 2, 1, 3};
    EXPECT_NEAR(ps::rmse(va, vb), std::sqrt((4.0 + 1.0) / 6.0), 1e-12);
    EXPECT_NEAR(ps::relmse(va, vb), (4.0 / (25.0 + ps::kRelMseEpsilon) + 1.0 / (1.0 + ps::kRelMseEpsilon)) / 6.0, 1e-12);
}

TEST(Metrics, SsimFallsWithNoiseAndIgnoresAlpha) {
    const int w = 24, h = 20;
    const auto a = gradient_image(w, h, 0.8f);
    std::vector<float> noisy = a, rgba(static_cast<size_t>(w) * h * 4);
    for (size_t i = 0; i < noisy.size(); ++i) noisy[i] += (i * 7919 % 13 < 6 ? 0.05f : -0.05f);
    for (size_t p = 0; p < static_cast<size_t>(w) * h; ++p) {
        for (int c = 0; c < 3; ++c) rgba[p * 4 + c] = noisy[p * 3 + c];
        rgba[p * 4 + 3] = 0.3f;
    }
    const ps::ImageView va{a.data(), w, h, 3}, vn{noisy.data(), w, h, 3}, v4{rgba.data(), w, h, 4};
    const double s = ps::ssim(vn, va);
    EXPECT_LT(s, 0.99);
    EXPECT_GT(s, 0.0);
    EXPECT_DOUBLE_EQ(ps::ssim(v4, va), s);
}

TEST(Metrics, BadInputNamesTheField) {
    const auto a = gradient_image(16, 12, 1.0f), b = gradient_image(12, 16, 1.0f);
    const ps::ImageView va{a.data(), 16, 12, 3}, vb{b.data(), 12, 16, 3};
    try {
        ps::ssim(va, vb);
        FAIL();
    } catch (const ps::InvalidInput& e) {
        EXPECT_EQ(e.field(), "reference");
    }
    const auto small = gradient_image(10, 10, 1.0f);
    const ps::ImageView vs{small.data(), 10, 10, 3};
    EXPECT_THROW(ps::ssim(vs, vs), ps::InvalidInput);  // below the 11×11 window
    EXPECT_NO_THROW(ps::psnr(vs, vs));
    std::vector<float> nan = a;
    nan[5] = std::nanf("");
    try {
        ps::rmse(ps::ImageView{nan.data(), 16, 12, 3}, va);
        FAIL();
    } catch (const ps::InvalidInput& e) {
        EXPECT_EQ(e.field(), "image");
    }
}
