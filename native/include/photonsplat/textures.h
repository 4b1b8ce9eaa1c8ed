// Image textures for a material's base colour, looked up at the surface's UV like Cycles' Image Texture node
// with its defaults (Linear interpolation, Repeat extension). Texels are stored as linear RGB in [0, 1]: an
// sRGB-encoded image is decoded once on load, so lookups never convert. Alpha is dropped (Cycles' Color output
// of a straight-alpha image does not depend on it).
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace ps {

enum class ColorSpace {
    srgb,    // 8-bit photos and paintings: decoded with the sRGB transfer curve
    linear,  // scene-linear data (EXR, HDR) and non-colour data: used as stored
};
ColorSpace color_space_from_string(const std::string& name);  // "sRGB" | "linear"; throws InvalidInput

constexpr int kMaxTextureSide = 65536;  // texels per side, at most

class Texture {
public:
    // `pixels`: height × width × channels floats (1, 3 or 4 channels), row 0 at the BOTTOM of the image
    // (Blender's Image.pixels order, where v = 0). Non-finite values are refused; colours are clamped to [0, 1]
    // after decoding because they are used as reflectances.
    Texture(std::string name, const float* pixels, int width, int height, int channels, ColorSpace space);

    const std::string& name() const { return name_; }
    int width() const { return width_; }
    int height() const { return height_; }
    size_t bytes() const { return texels_.size() * sizeof(glm::vec3); }

    // Bilinear lookup with texel centres at (i + 0.5) / width, repeating outside [0, 1).
    glm::vec3 lookup(const glm::vec2& uv) const;

private:
    std::string name_;
    int width_, height_;
    std::vector<glm::vec3> texels_;  // row 0 = bottom (v = 0)

    const glm::vec3& texel(int x, int y) const;
};

// Reads an image file with OpenImageIO (any format it knows: PNG, JPEG, EXR, TIFF, HDR...). Throws InvalidInput
// naming `field` when the file is missing or unreadable, or when this build reads no image files
// (image_files_supported() in image.h: the Blender extension's module, whose textures come as Blender's pixels).
// Defined in src/variants/image_files.cpp or src/variants/no_image_files.cpp.
Texture load_texture(const std::string& name, const std::string& path, ColorSpace space, const std::string& field);

}  // namespace ps
