// render_reference from Python: the converged reference image (native/include/photonsplat/reference.h), run off
// the GIL with progress and cancel like render().
#include <pybind11/numpy.h>

#include "arrays.h"
#include "background.h"
#include "bindings.h"
#include "photonsplat/camera.h"
#include "photonsplat/errors.h"
#include "photonsplat/reference.h"
#include "photonsplat/scene.h"

namespace ps_py {

using namespace pybind11::literals;

namespace {

// Python ints of any size: refuse negatives and out-of-range values with the field's name before narrowing.
int64_t checked_int(const py::object& obj, const std::string& field) {
    if (!py::isinstance<py::int_>(obj) || py::isinstance<py::bool_>(obj))
        throw ps::InvalidInput(field, "must be an integer, got " + py::repr(obj).cast<std::string>());
    try {
        return obj.cast<int64_t>();
    } catch (const py::cast_error&) {
        throw ps::InvalidInput(field, "is out of range: " + py::repr(obj).cast<std::string>());
    }
}

py::tuple render_reference(const ps::Scene& scene, const ps::Camera& camera, const py::object& samples,
                           const py::object& seed, const py::object& threads, const py::object& max_bounces,
                           const py::object& caustic_photons, double time_limit, const py::object& progress) {
    ps::ReferenceSettings s;
    const int64_t n = checked_int(samples, "samples"), b = checked_int(max_bounces, "max_bounces");
    const int64_t t = checked_int(threads, "threads"), sd = checked_int(seed, "seed");
    const int64_t photons = checked_int(caustic_photons, "caustic_photons");
    if (n < 1 || n > (1 << 24)) throw ps::InvalidInput("samples", "must be in [1, 16777216], got " + std::to_string(n));
    if (b < 0 || b > 1000) throw ps::InvalidInput("max_bounces", "must be in [0, 1000], got " + std::to_string(b));
    if (t < 0 || t > 4096) throw ps::InvalidInput("threads", "must be in [0, 4096] (0 = all cores), got " + std::to_string(t));
    if (sd < 0) throw ps::InvalidInput("seed", "must be >= 0, got " + std::to_string(sd));
    if (photons < 0) throw ps::InvalidInput("caustic_photons", "must be >= 0, got " + std::to_string(photons));
    s.samples = static_cast<int>(n);
    s.max_bounces = static_cast<int>(b);
    s.threads = static_cast<int>(t);
    s.seed = static_cast<uint64_t>(sd);
    s.caustic_photons = static_cast<uint64_t>(photons);
    s.time_limit = time_limit;
    ps::validate(s);
    const ps::ReferenceResult r = run_in_background<ps::ReferenceResult>(
        progress, [&](ps::RenderControl& control) { return ps::render_reference(scene, camera, s, control); });
    return py::make_tuple(image_array(r.rgba, r.height, r.width, 4), stats_dict(r.stats));
}

}  // namespace

void bind_reference(py::module_& m) {
    const ps::ReferenceSettings defaults;
    m.def("render_reference", &render_reference, "scene"_a, "camera"_a, "samples"_a = defaults.samples,
          "seed"_a = defaults.seed, "threads"_a = defaults.threads, "max_bounces"_a = defaults.max_bounces,
          "caustic_photons"_a = defaults.caustic_photons, "time_limit"_a = defaults.time_limit,
          "progress"_a = py::none(),
          "Renders a converged reference: path tracing with next-event estimation and MIS, plus progressive photon "
          "mapping of the caustics of point lights and suns (L S+ D paths). One camera path per pixel per pass; "
          "`samples` passes, each tracing `caustic_photons` photon paths (0 = pure path tracing). Stops early at "
          "`time_limit` seconds (0 = none, at least one pass). Returns (image float32 (H, W, 4), stats dict); "
          "stats['values']['samples'] is the number of passes done. progress(stage, fraction) as in render().");
}

}  // namespace ps_py
