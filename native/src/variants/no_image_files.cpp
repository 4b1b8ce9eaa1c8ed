// The core without image files, for the Blender extension's module: no OpenImageIO (whose Debian build brings some 250
// shared libraries with it). Inside Blender nothing is lost: Blender reads every image format itself and the add-on
// hands the core its pixels (export/textures.py asks IMAGE_FILES), and Blender writes the render results.
#include "photonsplat/image.h"

#include <stdexcept>

#include "photonsplat/errors.h"
#include "photonsplat/textures.h"

namespace ps {

namespace {

const char* const kWhy = "this build of Photon Splat reads and writes no image files (it is the Blender extension's, "
                         "built without OpenImageIO)";

}  // namespace

bool image_files_supported() { return false; }

void write_image(const std::string& path, const float*, int, int, int) {
    throw std::runtime_error("write_image: cannot write '" + path + "': " + kWhy +
                             "; save images with Blender (bpy.data.images) instead");
}

Texture load_texture(const std::string&, const std::string& path, ColorSpace, const std::string& field) {
    throw InvalidInput(field, "'" + path + "': " + kWhy + "; pass the image's pixels instead");
}

}  // namespace ps
