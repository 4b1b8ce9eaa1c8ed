#include "photonsplat/textures.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <glm/common.hpp>

#include "photonsplat/errors.h"

namespace ps {

namespace {

// The sRGB transfer curve (IEC 61966-2-1), encoded value in [0, 1] -> linear.
float srgb_to_linear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

}  // namespace

ColorSpace color_space_from_string(const std::string& name) {
    if (name == "sRGB" || name == "srgb") return ColorSpace::srgb;
    if (name == "linear" || name == "Linear") return ColorSpace::linear;
    throw InvalidInput("texture.color_space", "must be 'sRGB' or 'linear', got '" + name + "'");
}

Texture::Texture(std::string name, const float* pixels, int width, int height, int channels, ColorSpace space)
    : name_(std::move(name)), width_(width), height_(height) {
    const std::string where = "texture '" + name_ + "'";
    if (width < 1 || height < 1 || width > kMaxTextureSide || height > kMaxTextureSide)
        throw InvalidInput(where + ".pixels", "size must be 1 to 65536 per side, got " + std::to_string(width) +
                                                  "×" + std::to_string(height));
    if (channels < 1 || channels > 4)
        throw InvalidInput(where + ".pixels", "must have 1 to 4 channels, got " + std::to_string(channels));
    if (pixels == nullptr) throw InvalidInput(where + ".pixels", "missing");
    const size_t count = static_cast<size_t>(width) * height;
    texels_.resize(count);
    for (size_t i = 0; i < count; ++i) {
        const float* p = pixels + i * channels;
        glm::vec4 c(p[0], p[0], p[0], 1.0f);
        if (channels == 2) c.w = p[1];
        if (channels >= 3) c = glm::vec4(p[0], p[1], p[2], channels == 4 ? p[3] : 1.0f);
        for (int k = 0; k < 4; ++k) {
            if (!std::isfinite(c[k]))
                throw InvalidInput(where + ".pixels", "texel " + std::to_string(i) + " is NaN or infinite");
            if (k < 3 && space == ColorSpace::srgb) c[k] = srgb_to_linear(std::max(c[k], 0.0f));
        }
        texels_[i] = c;
    }
}

namespace {

// A texel coordinate folded into [0, size) by the extension; -1: outside (Clip).
int fold(int i, int size, TextureExtension extension) {
    switch (extension) {
        case TextureExtension::repeat: {
            i %= size;
            return i < 0 ? i + size : i;
        }
        case TextureExtension::extend: return std::clamp(i, 0, size - 1);
        case TextureExtension::clip: return i < 0 || i >= size ? -1 : i;
        case TextureExtension::mirror: {
            const int period = 2 * size;
            int m = i % period;
            if (m < 0) m += period;
            return m < size ? m : period - 1 - m;
        }
    }
    return -1;
}

// The cubic B-spline weights of the four texels around a point at fraction t past the second.
void bspline_weights(float t, float w[4]) {
    const float s = 1.0f - t;
    w[0] = s * s * s / 6.0f;
    w[1] = (4.0f - 6.0f * t * t + 3.0f * t * t * t) / 6.0f;
    w[2] = (1.0f + 3.0f * t + 3.0f * t * t - 3.0f * t * t * t) / 6.0f;
    w[3] = t * t * t / 6.0f;
}

// Keeps coordinates small before converting to int (a UV of 1e9 must not overflow); exact for repeat and mirror,
// whose patterns have period 1 and 2.
float reduce(float u, TextureExtension extension) {
    if (extension == TextureExtension::repeat) return u - std::floor(u);
    if (extension == TextureExtension::mirror) return u - 2.0f * std::floor(0.5f * u);
    return std::clamp(u, -2.0f, 3.0f);
}

}  // namespace

glm::vec4 Texture::texel(int x, int y, TextureExtension extension, TextureAlpha alpha) const {
    x = fold(x, width_, extension);
    y = fold(y, height_, extension);
    if (x < 0 || y < 0) return glm::vec4(0.0f);
    glm::vec4 t = texels_[static_cast<size_t>(y) * width_ + x];
    if (alpha != TextureAlpha::channel_packed) t = glm::vec4(glm::vec3(t) * t.w, t.w);  // associated
    return t;
}

glm::vec3 Texture::lookup(const glm::vec2& uv) const {
    const glm::vec4 c = sample(uv.x, uv.y, TextureInterpolation::linear, TextureExtension::repeat,
                               TextureAlpha::channel_packed);
    return glm::clamp(glm::vec3(c), 0.0f, 1.0f);
}

glm::vec4 Texture::sample(float u, float v, TextureInterpolation interpolation, TextureExtension extension,
                          TextureAlpha alpha) const {
    if (!std::isfinite(u) || !std::isfinite(v)) return glm::vec4(0.0f);
    u = reduce(u, extension);
    v = reduce(v, extension);
    glm::vec4 r(0.0f);
    if (interpolation == TextureInterpolation::closest) {
        r = texel(static_cast<int>(std::floor(u * width_)), static_cast<int>(std::floor(v * height_)), extension,
                  alpha);
    } else {
        const float x = u * width_ - 0.5f, y = v * height_ - 0.5f;
        const float fx = std::floor(x), fy = std::floor(y);
        const float tx = x - fx, ty = y - fy;
        const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
        if (interpolation == TextureInterpolation::linear) {
            r = (1.0f - ty) * ((1.0f - tx) * texel(x0, y0, extension, alpha) + tx * texel(x0 + 1, y0, extension, alpha)) +
                ty * ((1.0f - tx) * texel(x0, y0 + 1, extension, alpha) + tx * texel(x0 + 1, y0 + 1, extension, alpha));
        } else {
            float wx[4], wy[4];
            bspline_weights(tx, wx);
            bspline_weights(ty, wy);
            for (int j = 0; j < 4; ++j)
                for (int i = 0; i < 4; ++i) r += wx[i] * wy[j] * texel(x0 - 1 + i, y0 - 1 + j, extension, alpha);
        }
    }
    // Cycles unassociates only where alpha is strictly between 0 and 1.
    if (alpha == TextureAlpha::unassociated && r.w != 1.0f && r.w != 0.0f) r = glm::vec4(glm::vec3(r) / r.w, r.w);
    return r;
}

}  // namespace ps
