// Image files: writing with OpenImageIO: EXR keeps linear float radiance; PNG/JPEG get the sRGB transfer curve
// after clamping to [0, 1] (a plain "Standard" view, no tone mapping). Reading is load_texture (textures.h).
//
// OpenImageIO is linked only into the build against Debian's libraries (src/variants/image_files.cpp). The Blender
// extension's module is built without it (src/variants/no_image_files.cpp): Debian's OpenImageIO brings some 250
// shared libraries with it, and inside Blender every image reaches the core as Blender's own pixels anyway.
#pragma once
#include <string>

namespace ps {

// True when this build reads and writes image files (OpenImageIO linked in); false in the extension's module.
bool image_files_supported();

// pixels: height × width × channels floats, row 0 = top. Throws std::runtime_error naming the path on failure,
// and in a build without image files.
void write_image(const std::string& path, const float* pixels, int width, int height, int channels);

}  // namespace ps
