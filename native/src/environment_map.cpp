// The world's importance-sampling distribution (environment_map.h). Built as Cycles' background map (a marginal
// CDF over rows, a conditional CDF per row, weights luminance × sin θ of the cell centre) and sampled as its
// background_map_sample / background_map_pdf do, with the pdf read from the CDFs' differences so that it is
// the density the sampler really has.
#include "photonsplat/environment_map.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <sstream>

#include "photonsplat/errors.h"

namespace ps {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr const char* kField = "environment map";

bool finite(const glm::vec3& d) { return std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z); }

// Into [0, 1): NaN and negatives to 0, 1 and above to the largest float below 1.
float unit_interval(float u) {
    if (!(u >= 0.0f)) return 0.0f;
    if (u >= 1.0f) return std::nextafter(1.0f, 0.0f);
    return u;
}

}  // namespace

glm::vec2 direction_to_equirectangular(const glm::vec3& direction) {
    if (!finite(direction) || (direction.x == 0.0f && direction.y == 0.0f && direction.z == 0.0f)) {
        return glm::vec2(0.0f);
    }
    const double x = direction.x, y = direction.y, z = direction.z;
    // atan2 of (r, z) rather than acos(z / length): accurate next to the poles as well.
    const double theta = std::atan2(std::hypot(x, y), z);
    const double u = (std::atan2(y, x) - kPi) / (-2.0 * kPi);
    const double v = (theta - kPi) / (-kPi);
    return glm::vec2(static_cast<float>(u), static_cast<float>(v));
}

glm::vec3 equirectangular_to_direction(float u, float v) {
    const double phi = -2.0 * kPi * static_cast<double>(u) + kPi;
    const double theta = -kPi * static_cast<double>(v) + kPi;
    const double sin_theta = std::sin(theta);
    return glm::vec3(static_cast<float>(sin_theta * std::cos(phi)), static_cast<float>(sin_theta * std::sin(phi)),
                     static_cast<float>(std::cos(theta)));
}

size_t EnvironmentDistribution::checked_texel_count(int width, int height) {
    if (width < 1 || height < 1) {
        std::ostringstream what;
        what << "needs at least 1 × 1 texels, got " << width << " × " << height;
        throw InvalidInput(kField, what.str());
    }
    return static_cast<size_t>(width) * static_cast<size_t>(height);
}

EnvironmentDistribution::EnvironmentDistribution(int width, int height, std::vector<float> rgb)
    : width_(width), height_(height), rgb_(std::move(rgb)) {
    const size_t cells = checked_texel_count(width, height);
    if (rgb_.size() != cells * 3) {
        std::ostringstream what;
        what << "a " << width << " × " << height << " RGB map has " << cells * 3 << " floats, got " << rgb_.size();
        throw InvalidInput(kField, what.str());
    }
    for (size_t i = 0; i < rgb_.size(); ++i) {
        if (!std::isfinite(rgb_[i])) {
            const size_t cell = i / 3;
            std::ostringstream what;
            what << "texel (" << cell % static_cast<size_t>(width) << ", " << cell / static_cast<size_t>(width)
                 << ") channel " << "RGB"[i % 3] << " is " << rgb_[i] << "; radiances must be finite";
            throw InvalidInput(kField, what.str());
        }
    }

    const size_t row_stride = static_cast<size_t>(width) + 1;
    conditional_.assign(static_cast<size_t>(height) * row_stride, 0.0f);
    marginal_.assign(static_cast<size_t>(height) + 1, 0.0);
    // Row weights luminance × sin θ of the row's centre (the same for the whole row, so the conditional CDF
    // needs the luminance alone). Sums in double: 8192 columns or 4096 rows of float sums would lose the faint
    // cells next to a sun.
    double total = 0.0;
    std::vector<double> running(static_cast<size_t>(width));  // a row's running sums, then normalised
    for (int y = 0; y < height; ++y) {
        float* cdf = &conditional_[static_cast<size_t>(y) * row_stride];
        const float* row = &rgb_[static_cast<size_t>(y) * static_cast<size_t>(width) * 3];
        double sum = 0.0;
        for (int x = 0; x < width; ++x) {
            const float* t = row + 3 * static_cast<size_t>(x);
            // environment_luminance's weights, in double: a map's integral to double precision.
            const double luminance = 0.2126 * t[0] + 0.7152 * t[1] + 0.0722 * t[2];
            sum += std::max(luminance, 0.0);
            running[static_cast<size_t>(x)] = sum;
        }
        if (sum > 0.0) {  // cdf[0] stays 0
            for (int x = 1; x < width; ++x) {
                cdf[x] = static_cast<float>(running[static_cast<size_t>(x) - 1] / sum);
            }
        } else {
            for (int x = 1; x < width; ++x) cdf[x] = static_cast<float>(static_cast<double>(x) / width);
        }
        cdf[width] = 1.0f;
        const double sin_theta = std::sin(kPi * (static_cast<double>(y) + 0.5) / height);
        total += sum * sin_theta;
        marginal_[static_cast<size_t>(y) + 1] = total;
    }
    if (total > 0.0) {
        for (int y = 1; y < height; ++y) marginal_[static_cast<size_t>(y)] /= total;
        marginal_[static_cast<size_t>(height)] = 1.0;
        // A row's exact solid angle is 2π (cos θ_low − cos θ_high) = 4π sin θ_centre sin(π / 2h), so the integral
        // of the nearest-texel map is the marginal's total times 4π sin(π / 2h) / width.
        integral_ = total * 4.0 * kPi * std::sin(kPi / (2.0 * height)) / width;
    } else {
        std::fill(marginal_.begin(), marginal_.end(), 0.0);
        integral_ = 0.0;
    }
}

bool EnvironmentDistribution::locate(const glm::vec3& direction, int& x, int& y, double& sin_theta) const {
    if (!finite(direction)) return false;
    const double dx = direction.x, dy = direction.y, dz = direction.z;
    const double r = std::hypot(dx, dy);
    const double length = std::hypot(r, dz);
    if (length == 0.0) return false;
    sin_theta = r / length;
    const double u = (kPi - std::atan2(dy, dx)) / (2.0 * kPi);
    const double v = 1.0 - std::atan2(r, dz) / kPi;
    x = static_cast<int>(std::clamp(std::floor(u * width_), 0.0, width_ - 1.0));
    y = static_cast<int>(std::clamp(std::floor(v * height_), 0.0, height_ - 1.0));
    return true;
}

float EnvironmentDistribution::cell_pdf(int x, int y, double sin_theta) const {
    if (is_zero() || sin_theta <= 0.0) return 0.0f;
    const size_t row = static_cast<size_t>(y) * (static_cast<size_t>(width_) + 1);
    const double p_row = marginal_[static_cast<size_t>(y) + 1] - marginal_[static_cast<size_t>(y)];
    const double p_column = static_cast<double>(conditional_[row + static_cast<size_t>(x) + 1]) -
                            static_cast<double>(conditional_[row + static_cast<size_t>(x)]);
    // Density per unit uv area, then per unit solid angle: dω = 2π² sin θ du dv.
    const double uv_density = p_row * p_column * width_ * height_;
    const double pdf = uv_density / (2.0 * kPi * kPi * sin_theta);
    return static_cast<float>(std::min(pdf, static_cast<double>(FLT_MAX)));  // finite even a hair off a pole
}

glm::vec3 EnvironmentDistribution::texel(int x, int y) const {
    const float* t = &rgb_[3 * (static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x))];
    return glm::vec3(t[0], t[1], t[2]);
}

EnvironmentSample EnvironmentDistribution::sample(float u1, float u2) const {
    EnvironmentSample s = sample_direction(u1, u2);
    if (s.pdf > 0.0f) s.radiance = radiance(s.direction);
    return s;
}

EnvironmentSample EnvironmentDistribution::sample_direction(float u1, float u2) const {
    EnvironmentSample s;
    if (is_zero()) return s;
    u1 = unit_interval(u1);
    u2 = unit_interval(u2);

    // The row: marginal_[y] <= u2 < marginal_[y + 1] (so the row has a positive probability).
    const double rv = u2;
    const auto row_end = std::upper_bound(marginal_.begin() + 1, marginal_.end(), rv);
    const int y = static_cast<int>(row_end - marginal_.begin()) - 1;
    const double dv = (rv - marginal_[static_cast<size_t>(y)]) /
                      (marginal_[static_cast<size_t>(y) + 1] - marginal_[static_cast<size_t>(y)]);

    // The column within it, likewise.
    const float* cdf = &conditional_[static_cast<size_t>(y) * (static_cast<size_t>(width_) + 1)];
    const float* column_end = std::upper_bound(cdf + 1, cdf + width_ + 1, u1);
    const int x = static_cast<int>(column_end - cdf) - 1;
    const double du = (static_cast<double>(u1) - cdf[x]) / (static_cast<double>(cdf[x + 1]) - cdf[x]);

    // The direction of (u, v), rounded to float, and the cell it lies in. Where rounding carries it across the
    // cell's edge (a draw right on the edge, or on a pole, where every column meets: about one draw in a
    // million), it is drawn again a thousandth of the cell inside the edge, so that every sample lies in the
    // cell it was drawn from and has that cell's (positive) probability.
    auto place = [&](double fu, double fv, int& cx, int& cy, double& cell_sin_theta) {
        const double u = (x + fu) / width_, v = (y + fv) / height_;
        const double phi = kPi - 2.0 * kPi * u;
        const double sin_theta = std::sin(kPi * v);  // θ = π (1 − v)
        const double cos_theta = -std::cos(kPi * v);
        s.direction = glm::vec3(static_cast<float>(sin_theta * std::cos(phi)),
                                static_cast<float>(sin_theta * std::sin(phi)), static_cast<float>(cos_theta));
        return locate(s.direction, cx, cy, cell_sin_theta) && cx == x && cy == y && cell_sin_theta > 0.0;
    };
    int cx = x, cy = y;
    double cell_sin_theta = 0.0;
    if (!place(du, dv, cx, cy, cell_sin_theta)) {
        constexpr double inside = 1e-3;
        place(std::clamp(du, inside, 1.0 - inside), std::clamp(dv, inside, 1.0 - inside), cx, cy, cell_sin_theta);
    }
    // The pdf of the cell the direction lies in: identical to pdf() of it.
    s.pdf = cell_pdf(cx, cy, cell_sin_theta);
    return s;
}

float EnvironmentDistribution::pdf(const glm::vec3& direction) const {
    int x = 0, y = 0;
    double sin_theta = 0.0;
    if (is_zero() || !locate(direction, x, y, sin_theta)) return 0.0f;
    return cell_pdf(x, y, sin_theta);
}

glm::vec3 EnvironmentDistribution::radiance(const glm::vec3& direction) const {
    int x = 0, y = 0;
    double sin_theta = 0.0;
    if (!locate(direction, x, y, sin_theta)) return glm::vec3(0.0f);
    return texel(x, y);
}

}  // namespace ps
