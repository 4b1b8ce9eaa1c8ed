#include "photonsplat/textures.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

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
    if (channels != 1 && channels != 3 && channels != 4)
        throw InvalidInput(where + ".pixels", "must have 1, 3 or 4 channels, got " + std::to_string(channels));
    if (pixels == nullptr) throw InvalidInput(where + ".pixels", "missing");
    const size_t count = static_cast<size_t>(width) * height;
    texels_.resize(count);
    for (size_t i = 0; i < count; ++i) {
        const float* p = pixels + i * channels;
        glm::vec3 c = channels == 1 ? glm::vec3(p[0]) : glm::vec3(p[0], p[1], p[2]);
        for (int k = 0; k < 3; ++k) {
            if (!std::isfinite(c[k]))
                throw InvalidInput(where + ".pixels", "texel " + std::to_string(i) + " is NaN or infinite");
            float v = std::clamp(c[k], 0.0f, 1.0f);
            c[k] = space == ColorSpace::srgb ? srgb_to_linear(v) : v;
        }
        texels_[i] = c;
    }
}

const glm::vec3& Texture::texel(int x, int y) const {
    // Repeat: wrap both ways, also for negative coordinates.
    x %= width_;
    y %= height_;
    if (x < 0) x += width_;
    if (y < 0) y += height_;
    return texels_[static_cast<size_t>(y) * width_ + x];
}

glm::vec3 Texture::lookup(const glm::vec2& uv) const {
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return texels_[0];
    // Keep the coordinates small before converting to int (a UV of 1e9 must not overflow).
    const float u = uv.x - std::floor(uv.x), v = uv.y - std::floor(uv.y);
    const float x = u * width_ - 0.5f, y = v * height_ - 0.5f;
    const float fx = std::floor(x), fy = std::floor(y);
    const float tx = x - fx, ty = y - fy;
    const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
    return (1.0f - ty) * ((1.0f - tx) * texel(x0, y0) + tx * texel(x0 + 1, y0)) +
           ty * ((1.0f - tx) * texel(x0, y0 + 1) + tx * texel(x0 + 1, y0 + 1));
}

}  // namespace ps
