#include "photonsplat/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "photonsplat/errors.h"

namespace ps {

namespace {

std::string size_text(const ImageView& v) {
    return std::to_string(v.height) + "×" + std::to_string(v.width) + "×" + std::to_string(v.channels);
}

void check_one(const ImageView& v, const char* field) {
    if (!v.pixels || v.width < 1 || v.height < 1)
        throw InvalidInput(field, "must be a non-empty (H, W, 3) or (H, W, 4) image, got " + size_text(v));
    if (v.channels != 3 && v.channels != 4)
        throw InvalidInput(field, "must have 3 or 4 channels (alpha is ignored), got " + size_text(v));
    const size_t n = static_cast<size_t>(v.width) * v.height;
    for (size_t p = 0; p < n; ++p)
        for (int c = 0; c < 3; ++c)
            if (!std::isfinite(v.pixels[p * v.channels + c]))
                throw InvalidInput(field, "contains NaN or infinity at pixel (" + std::to_string(p / v.width) + ", " +
                                              std::to_string(p % v.width) + ")");
}

void check_pair(const ImageView& image, const ImageView& reference) {
    check_one(image, "image");
    check_one(reference, "reference");
    if (image.width != reference.width || image.height != reference.height)
        throw InvalidInput("reference", "size " + size_text(reference) + " does not match the image's " +
                                            size_text(image));
}

// IEC 61966-2-1 encoding of a linear value already clamped to [0, 1].
double srgb_encode(double v) { return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055; }

// The normalised 11-tap Gaussian of σ = 1.5, as scipy.ndimage builds it for skimage (truncate 3.5 → radius 5).
std::vector<double> gaussian_taps() {
    std::vector<double> w(2 * kSsimRadius + 1);
    double sum = 0.0;
    for (int i = -kSsimRadius; i <= kSsimRadius; ++i) sum += w[i + kSsimRadius] = std::exp(-0.5 * i * i / (kSsimSigma * kSsimSigma));
    for (double& x : w) x /= sum;
    return w;
}

// Separable Gaussian filter evaluated only where the whole window is inside: output (h − 10) × (w − 10).
std::vector<double> filter_valid(const std::vector<double>& in, int width, int height) {
    static const std::vector<double> taps = gaussian_taps();
    const int k = 2 * kSsimRadius + 1, ow = width - k + 1, oh = height - k + 1;
    std::vector<double> rows(static_cast<size_t>(height) * ow), out(static_cast<size_t>(oh) * ow);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < ow; ++x) {
            double s = 0.0;
            for (int t = 0; t < k; ++t) s += taps[t] * in[static_cast<size_t>(y) * width + x + t];
            rows[static_cast<size_t>(y) * ow + x] = s;
        }
    for (int y = 0; y < oh; ++y)
        for (int x = 0; x < ow; ++x) {
            double s = 0.0;
            for (int t = 0; t < k; ++t) s += taps[t] * rows[static_cast<size_t>(y + t) * ow + x];
            out[static_cast<size_t>(y) * ow + x] = s;
        }
    return out;
}

}  // namespace

std::vector<double> display_luma(const ImageView& v, const char* field) {
    check_one(v, field);
    const size_t n = static_cast<size_t>(v.width) * v.height;
    std::vector<double> y(n);
    constexpr double weights[3] = {0.2126, 0.7152, 0.0722};
    for (size_t p = 0; p < n; ++p) {
        double s = 0.0;
        for (int c = 0; c < 3; ++c)
            s += weights[c] * srgb_encode(std::clamp(static_cast<double>(v.pixels[p * v.channels + c]), 0.0, 1.0));
        y[p] = s;
    }
    return y;
}

double psnr(const ImageView& image, const ImageView& reference) {
    check_pair(image, reference);
    const std::vector<double> a = display_luma(image, "image"), b = display_luma(reference, "reference");
    double sum = 0.0;
    for (size_t i = 0; i < a.size(); ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
    const double mse = sum / static_cast<double>(a.size());
    if (mse == 0.0) return std::numeric_limits<double>::infinity();
    return 10.0 * std::log10(1.0 / mse);
}

double ssim(const ImageView& image, const ImageView& reference) {
    check_pair(image, reference);
    const int k = 2 * kSsimRadius + 1;
    if (image.width < k || image.height < k)
        throw InvalidInput("image", "must be at least 11×11 for SSIM (its window is 11×11), got " + size_text(image));
    const std::vector<double> a = display_luma(image, "image"), b = display_luma(reference, "reference");
    const size_t n = a.size();
    std::vector<double> aa(n), bb(n), ab(n);
    for (size_t i = 0; i < n; ++i) {
        aa[i] = a[i] * a[i];
        bb[i] = b[i] * b[i];
        ab[i] = a[i] * b[i];
    }
    const int w = image.width, h = image.height;
    const std::vector<double> mu_a = filter_valid(a, w, h), mu_b = filter_valid(b, w, h);
    const std::vector<double> m_aa = filter_valid(aa, w, h), m_bb = filter_valid(bb, w, h), m_ab = filter_valid(ab, w, h);
    constexpr double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;  // (K1·L)², (K2·L)² with data range L = 1
    double sum = 0.0;
    for (size_t i = 0; i < mu_a.size(); ++i) {
        const double va = m_aa[i] - mu_a[i] * mu_a[i], vb = m_bb[i] - mu_b[i] * mu_b[i];
        const double cov = m_ab[i] - mu_a[i] * mu_b[i];
        sum += ((2.0 * mu_a[i] * mu_b[i] + c1) * (2.0 * cov + c2)) /
               ((mu_a[i] * mu_a[i] + mu_b[i] * mu_b[i] + c1) * (va + vb + c2));
    }
    return sum / static_cast<double>(mu_a.size());
}

namespace {
template <typename Term>
double mean_over_channels(const ImageView& image, const ImageView& reference, Term term) {
    check_pair(image, reference);
    const size_t n = static_cast<size_t>(image.width) * image.height;
    double sum = 0.0;
    for (size_t p = 0; p < n; ++p)
        for (int c = 0; c < 3; ++c)
            sum += term(static_cast<double>(image.pixels[p * image.channels + c]),
                        static_cast<double>(reference.pixels[p * reference.channels + c]));
    return sum / static_cast<double>(3 * n);
}
}  // namespace

double rmse(const ImageView& image, const ImageView& reference) {
    return std::sqrt(mean_over_channels(image, reference, [](double a, double b) { return (a - b) * (a - b); }));
}

double relmse(const ImageView& image, const ImageView& reference) {
    return mean_over_channels(image, reference,
                              [](double a, double b) { return (a - b) * (a - b) / (b * b + kRelMseEpsilon); });
}

}  // namespace ps
