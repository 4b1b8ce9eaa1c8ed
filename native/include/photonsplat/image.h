// Writing images with OpenImageIO: EXR keeps linear float radiance; PNG/JPEG get the sRGB transfer curve
// after clamping to [0, 1] (a plain "Standard" view, no tone mapping).
#pragma once
#include <string>

namespace ps {

// pixels: height × width × channels floats, row 0 = top. Throws std::runtime_error naming the path on failure.
void write_image(const std::string& path, const float* pixels, int width, int height, int channels);

}  // namespace ps
