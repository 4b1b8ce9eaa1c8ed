// Image metrics from Python: psnr, ssim (display luma) and rmse, relmse (linear radiance) of the native core
// (native/include/photonsplat/metrics.h has the definitions).
#include <pybind11/numpy.h>

#include "arrays.h"
#include "bindings.h"
#include "photonsplat/errors.h"
#include "photonsplat/metrics.h"

namespace ps_py {

using namespace pybind11::literals;

namespace {

// (H, W, 3) or (H, W, 4) float image; alpha, when present, is ignored by every metric.
ps::ImageView image_view(const py::array_t<float, py::array::c_style>& a, const std::string& field) {
    if (a.ndim() != 3 || (a.shape(2) != 3 && a.shape(2) != 4) || a.shape(0) < 1 || a.shape(1) < 1)
        throw ps::InvalidInput(field, "must have shape (H, W, 3) or (H, W, 4), got " + shape_of(a));
    return ps::ImageView{a.data(), static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)),
                         static_cast<int>(a.shape(2))};
}

template <double (*metric)(const ps::ImageView&, const ps::ImageView&)>
double compare(const py::object& image_obj, const py::object& reference_obj) {
    const auto image = float_array(image_obj, "image");
    const auto reference = float_array(reference_obj, "reference");
    const ps::ImageView a = image_view(image, "image"), b = image_view(reference, "reference");
    if (image.shape(0) != reference.shape(0) || image.shape(1) != reference.shape(1))
        throw ps::InvalidInput("reference", "shape " + shape_of(reference) + " does not match the image's " +
                                                shape_of(image) + " (height and width must agree)");
    py::gil_scoped_release release;
    return metric(a, b);
}

}  // namespace

void bind_metrics(py::module_& m) {
    m.def("psnr", &compare<ps::psnr>, "image"_a, "reference"_a,
          "PSNR in dB of the display luma (linear -> clamp [0, 1] -> sRGB, then Rec. 709 weights), peak 1. "
          "Identical images give inf. Images (H, W, 3) or (H, W, 4), alpha ignored.");
    m.def("ssim", &compare<ps::ssim>, "image"_a, "reference"_a,
          "Mean SSIM (Wang et al. 2004: 11x11 Gaussian window, sigma 1.5, K1 0.01, K2 0.03) of the display luma, "
          "averaged over the pixels 5 or more from the border, as scikit-image does. Images at least 11x11.");
    m.def("rmse", &compare<ps::rmse>, "image"_a, "reference"_a,
          "Root mean square error of the linear radiance over pixels and RGB channels.");
    m.def("relmse", &compare<ps::relmse>, "image"_a, "reference"_a,
          "Relative MSE of the linear radiance: mean of (a - b)^2 / (b^2 + 0.01) over pixels and RGB, b = reference.");
    m.attr("RELMSE_EPSILON") = ps::kRelMseEpsilon;
}

}  // namespace ps_py
