// Image files from Python: write_image for tests, tools and scripts that save what render() returned.
#include <pybind11/numpy.h>

#include "arrays.h"
#include "bindings.h"
#include "photonsplat/errors.h"
#include "photonsplat/image.h"

namespace ps_py {

using namespace pybind11::literals;

void bind_images(py::module_& m) {
    m.def(
        "write_image",
        [](const std::string& path, const py::object& image_obj) {
            auto image = float_array(image_obj, "image");
            if (image.ndim() != 3 || image.shape(2) < 1 || image.shape(2) > 4)
                throw ps::InvalidInput("image", "must have shape (H, W, C) with C in 1..4, got " + shape_of(image));
            const int h = static_cast<int>(image.shape(0)), w = static_cast<int>(image.shape(1));
            const int c = static_cast<int>(image.shape(2));
            py::gil_scoped_release release;
            ps::write_image(path, image.data(), w, h, c);
        },
        "path"_a, "image"_a,
        "Writes (H, W, C) linear floats: EXR as is, PNG/JPEG clamped and sRGB-encoded. Raises RuntimeError in a "
        "build without image files (IMAGE_FILES is False: the Blender extension's).");
}

}  // namespace ps_py
