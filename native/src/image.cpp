#include "photonsplat/image.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include <OpenImageIO/imageio.h>

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

}  // namespace ps
