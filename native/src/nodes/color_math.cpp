#include "color_math.h"

#include <cmath>

namespace ps {

// Cycles 3.4 builds xyz_to_rgb as (aces_interchange → scene linear, from OCIO) × inverse(its own 6-digit
// ACES AP0 → XYZ D65 matrix). With Blender 3.4's config that is inverse(srgb_to_xyz.spimtx) × OCIO's
// "ACES-AP0_to_CIE-XYZ-D65_BFD" (Bradford) × inverse(Cycles' rounded copy of it): Rec.709's matrix, perturbed in
// the sixth digit. These are that product, computed in double (numpy) from the config's data; the row of its
// inverse that gives Y is kRgbToY, which matches Cycles' RGB to BW to 7 digits in the golden renders.
namespace {
constexpr float kXyzToRgb[3][3] = {
    {3.240455118f, -1.537140185f, -0.498532185f},
    {-0.969266327f, 1.876010460f, 0.041555676f},
    {0.055643195f, -0.204025343f, 1.057224738f},
};
}  // namespace

const glm::vec3 kRgbToY(0.212672996f, 0.715152639f, 0.072175460f);

float cycles_luminance(const glm::vec3& rgb) { return rgb.x * kRgbToY.x + rgb.y * kRgbToY.y + rgb.z * kRgbToY.z; }

glm::vec3 xyz_to_rgb(const glm::vec3& xyz) {
    glm::vec3 out;
    for (int r = 0; r < 3; ++r) out[r] = kXyzToRgb[r][0] * xyz.x + kXyzToRgb[r][1] * xyz.y + kXyzToRgb[r][2] * xyz.z;
    return out;
}

glm::vec3 rgb_to_hsv(const glm::vec3& rgb) {
    // Cycles takes the maximum with fmaxf and the minimum with its own min; the mix matters only for NaN.
    const float cmax_ = std::fmax(rgb.x, std::fmax(rgb.y, rgb.z));
    const float cmin_ = cmin(rgb.x, cmin(rgb.y, rgb.z));
    const float delta = cmax_ - cmin_;
    const float v = cmax_;
    const float s = cmax_ != 0.0f ? delta / cmax_ : 0.0f;
    float h = 0.0f;
    if (s != 0.0f) {
        // Distance of each channel below the maximum, in units of the spread; the hue sector follows from which
        // channel is the maximum (red first on ties, as Cycles tests them).
        const glm::vec3 c = (glm::vec3(cmax_) - rgb) / delta;
        if (rgb.x == cmax_)
            h = c.z - c.y;
        else if (rgb.y == cmax_)
            h = 2.0f + c.x - c.z;
        else
            h = 4.0f + c.y - c.x;
        h /= 6.0f;
        if (h < 0.0f) h += 1.0f;
    }
    return {h, s, v};
}

glm::vec3 hsv_to_rgb(const glm::vec3& hsv) {
    float h = hsv.x;
    const float s = hsv.y, v = hsv.z;
    if (s == 0.0f) return glm::vec3(v);
    if (h == 1.0f) h = 0.0f;
    h *= 6.0f;
    const float i = std::floor(h);
    const float f = h - i;
    const float p = v * (1.0f - s);
    const float q = v * (1.0f - s * f);
    const float t = v * (1.0f - s * (1.0f - f));
    // Sectors outside 0..4 (a hue outside [0, 1), which Hue/Saturation can produce) all fall to the last one,
    // as in Cycles.
    if (i == 0.0f) return {v, t, p};
    if (i == 1.0f) return {q, v, p};
    if (i == 2.0f) return {p, v, t};
    if (i == 3.0f) return {p, q, v};
    if (i == 4.0f) return {t, p, v};
    return {v, p, q};
}

glm::vec3 rgb_to_hsl(const glm::vec3& rgb) {
    const float cmax_ = std::fmax(rgb.x, std::fmax(rgb.y, rgb.z));
    const float cmin_ = cmin(rgb.x, cmin(rgb.y, rgb.z));
    const float l = cmin(1.0f, (cmax_ + cmin_) / 2.0f);
    float h = 0.0f, s = 0.0f;
    if (cmax_ != cmin_) {
        const float delta = cmax_ - cmin_;
        s = l > 0.5f ? delta / (2.0f - cmax_ - cmin_) : delta / (cmax_ + cmin_);
        if (cmax_ == rgb.x)
            h = (rgb.y - rgb.z) / delta + (rgb.y < rgb.z ? 6.0f : 0.0f);
        else if (cmax_ == rgb.y)
            h = (rgb.z - rgb.x) / delta + 2.0f;
        else
            h = (rgb.x - rgb.y) / delta + 4.0f;
    }
    return {h / 6.0f, s, l};
}

glm::vec3 hsl_to_rgb(const glm::vec3& hsl) {
    const float h = hsl.x, s = hsl.y, l = hsl.z;
    // Each channel's position on the hue hexagon, a trapezoid in [0, 1], then scaled by the chroma about l.
    const float nr = cclamp(std::fabs(h * 6.0f - 3.0f) - 1.0f, 0.0f, 1.0f);
    const float ng = cclamp(2.0f - std::fabs(h * 6.0f - 2.0f), 0.0f, 1.0f);
    const float nb = cclamp(2.0f - std::fabs(h * 6.0f - 4.0f), 0.0f, 1.0f);
    const float chroma = (1.0f - std::fabs(2.0f * l - 1.0f)) * s;
    return {(nr - 0.5f) * chroma + l, (ng - 0.5f) * chroma + l, (nb - 0.5f) * chroma + l};
}

}  // namespace ps
