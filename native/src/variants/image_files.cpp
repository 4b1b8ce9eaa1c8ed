// Image files through OpenImageIO: write_image and load_texture, in the core built against Debian's libraries (the
// tests, the tools, build/python and build/blender). The extension's core has no_image_files.cpp instead.
#include "photonsplat/image.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "photonsplat/errors.h"
#include "photonsplat/textures.h"

namespace ps {

namespace {

float srgb_encode(float linear) {
    const float x = std::clamp(std::isfinite(linear) ? linear : 0.0f, 0.0f, 1.0f);
    return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

bool is_float_format(const std::string& path) {
    std::string ext = path.substr(path.find_last_of('.') + 1);
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    return ext == "exr" || ext == "hdr" || ext == "tif" || ext == "tiff";
}

}  // namespace

bool image_files_supported() { return true; }

void write_image(const std::string& path, const float* pixels, int width, int height, int channels) {
    if (width < 1 || height < 1 || channels < 1 || channels > 4)
        throw std::invalid_argument("write_image: bad image size for '" + path + "'");
    auto out = OIIO::ImageOutput::create(path);
    if (!out) throw std::runtime_error("write_image: no writer for '" + path + "': " + OIIO::geterror());
    const size_t count = static_cast<size_t>(width) * height * channels;
    if (is_float_format(path)) {
        OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::FLOAT);
        if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, pixels))
            throw std::runtime_error("write_image: cannot write '" + path + "': " + out->geterror());
    } else {
        // Display-referred 8-bit: clamp and sRGB-encode colour, keep alpha linear.
        std::vector<unsigned char> bytes(count);
        for (size_t i = 0; i < count; ++i) {
            const bool alpha = channels == 4 && (i % 4) == 3;
            const float v = alpha ? std::clamp(pixels[i], 0.0f, 1.0f) : srgb_encode(pixels[i]);
            bytes[i] = static_cast<unsigned char>(std::lround(v * 255.0f));
        }
        OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
        if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::UINT8, bytes.data()))
            throw std::runtime_error("write_image: cannot write '" + path + "': " + out->geterror());
    }
    out->close();
}

Texture load_texture(const std::string& name, const std::string& path, ColorSpace space, const std::string& field) {
    using namespace OIIO;
    // Cycles reads straight (unassociated) colour; OIIO would premultiply PNG alpha into the colour otherwise.
    ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    std::unique_ptr<ImageInput> input = ImageInput::open(path, &config);
    if (!input) {
        std::string why = geterror();
        if (why.empty()) why = "cannot open";
        throw InvalidInput(field, "'" + path + "': " + why);
    }
    const ImageSpec& spec = input->spec();
    const int width = spec.width, height = spec.height, channels = std::min(spec.nchannels, 4);
    if (width < 1 || height < 1 || width > kMaxTextureSide || height > kMaxTextureSide || channels < 1)
        throw InvalidInput(field, "'" + path + "': unsupported size " + std::to_string(width) + "×" +
                                      std::to_string(height) + "×" + std::to_string(spec.nchannels));
    std::vector<float> pixels(static_cast<size_t>(width) * height * channels);
    if (!input->read_image(0, 0, 0, channels, TypeDesc::FLOAT, pixels.data())) {
        const std::string why = input->geterror();
        throw InvalidInput(field, "'" + path + "': " + (why.empty() ? "read failed" : why));
    }
    input->close();
    // Files store row 0 at the top; textures keep row 0 at the bottom (v = 0), like Blender.
    const size_t row = static_cast<size_t>(width) * channels;
    for (int y = 0; y < height / 2; ++y)
        std::swap_ranges(pixels.begin() + y * row, pixels.begin() + (y + 1) * row, pixels.begin() + (height - 1 - y) * row);
    return Texture(name, pixels.data(), width, height, channels, space);
}

}  // namespace ps
