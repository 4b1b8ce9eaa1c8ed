// Images for Image and Environment Texture nodes. Texels are stored as scene-linear RGBA with straight
// (unassociated) alpha, unclamped: an sRGB-encoded image is decoded once on load, so lookups never convert.
// lookup() is the base-colour shortcut of a closure (Cycles' defaults: Linear, Repeat, clamped to a
// reflectance); sample() is the node's full lookup (interpolation, extension, alpha association).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace ps {

enum class TextureInterpolation : uint8_t { linear, closest, cubic };  // Cycles' Smart renders as cubic on CPUs
enum class TextureExtension : uint8_t { repeat, extend, clip, mirror };
// What the colour output carries where alpha < 1 (Cycles interpolates associated colour, then unassociates unless
// the image's alpha is channel-packed or ignored).
enum class TextureAlpha : uint8_t { unassociated, associated, channel_packed };

enum class ColorSpace {
    srgb,    // 8-bit photos and paintings: decoded with the sRGB transfer curve
    linear,  // scene-linear data (EXR, HDR) and non-colour data: used as stored
};
ColorSpace color_space_from_string(const std::string& name);  // "sRGB" | "linear"; throws InvalidInput

constexpr int kMaxTextureSide = 65536;  // texels per side, at most

class Texture {
public:
    // `pixels`: height × width × channels floats (1 grey, 2 grey + alpha, 3 or 4 channels), row 0 at the BOTTOM
    // of the image (Blender's Image.pixels order, where v = 0), straight alpha. Non-finite values are refused.
    Texture(std::string name, const float* pixels, int width, int height, int channels, ColorSpace space);

    const std::string& name() const { return name_; }
    int width() const { return width_; }
    int height() const { return height_; }
    size_t bytes() const { return texels_.size() * sizeof(glm::vec4); }

    // Bilinear lookup with texel centres at (i + 0.5) / width, repeating outside [0, 1), colour clamped to [0, 1].
    glm::vec3 lookup(const glm::vec2& uv) const;

    // Cycles' image lookup at (u, v): texel centres at (i + 0.5) / width; Closest takes the texel under the point,
    // Linear blends four, Cubic sixteen with the cubic B-spline weights. Clip is transparent black outside
    // [0, 1]; the result's alpha is the interpolated alpha.
    glm::vec4 sample(float u, float v, TextureInterpolation interpolation, TextureExtension extension,
                     TextureAlpha alpha) const;

private:
    std::string name_;
    int width_, height_;
    std::vector<glm::vec4> texels_;  // row 0 = bottom (v = 0); straight alpha

    glm::vec4 texel(int x, int y, TextureExtension extension, TextureAlpha alpha) const;
};

// Reads an image file with OpenImageIO (any format it knows: PNG, JPEG, EXR, TIFF, HDR...). Throws InvalidInput
// naming `field` when the file is missing or unreadable, or when this build reads no image files
// (image_files_supported() in image.h: the Blender extension's module, whose textures come as Blender's pixels).
// Defined in src/variants/image_files.cpp or src/variants/no_image_files.cpp.
Texture load_texture(const std::string& name, const std::string& path, ColorSpace space, const std::string& field);

}  // namespace ps
