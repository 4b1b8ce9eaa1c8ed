// Progressive rendering one iteration at a time, for callers that show the image between iterations (the viewport,
// F12 in Blender): photonsplat.Progressive(scene, camera, settings), then .step() and .image() as often as wanted.
// A whole progressive render in one call is render() with settings.iterations / settings.time_limit.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>

#include "arrays.h"
#include "background.h"
#include "bindings.h"
#include "photonsplat/camera.h"
#include "photonsplat/errors.h"
#include "photonsplat/progressive.h"
#include "photonsplat/scene.h"

namespace ps_py {

using namespace pybind11::literals;

void bind_progressive(py::module_& m) {
    py::class_<ps::ProgressiveRender>(
        m, "Progressive",
        "A progressive render advanced one iteration at a time. Iteration 1 is the one-shot image of render(); every "
        "later iteration traces new photons, jitters the camera rays inside their pixels and shrinks the radius as "
        "r_i^2 = r_(i-1)^2 (i-1+alpha)/i; image() is the running mean. The scene must not be changed while a "
        "Progressive uses it (build a new one instead). Thread-safe: image(), stats() and the properties may be "
        "read from another thread while step() runs; they then describe the iterations completed. Only the film outputs of settings.outputs are averaged.")
        .def(py::init([](const ps::Scene& scene, const ps::Camera& camera, const ps::RenderSettings& settings) {
                 return std::make_unique<ps::ProgressiveRender>(scene, camera, settings);
             }),
             "scene"_a, "camera"_a, "settings"_a = ps::RenderSettings(), py::keep_alive<1, 2>())
        .def(
            "step",
            [](ps::ProgressiveRender& p, const py::object& progress) {
                run_in_background<int>(progress, [&](ps::RenderControl& control) {
                    p.run_iteration(control);
                    return 0;
                });
            },
            "progress"_a = py::none(),
            "Renders one more iteration off the GIL and adds it to the mean; returns None. progress(stage, fraction) "
            "as in render(); returning True cancels the iteration (raises Cancelled, the mean keeps the iterations "
            "before it). "
            "RuntimeError if another thread is running step() on this object.")
        .def(
            "image",
            [](const ps::ProgressiveRender& p) {
                std::vector<float> rgba = p.image();
                const int h = p.height(), w = p.width();
                if (rgba.empty()) rgba.assign(static_cast<size_t>(w) * h * 4, 0.0f);
                return image_array(rgba, h, w, 4);
            },
            "The running mean: float32 (H, W, 4) linear radiance, row 0 at the top; zeros before the first iteration.")
        .def(
            "passes",
            [](const ps::ProgressiveRender& p) {
                if (p.iterations_done() == 0) throw ps::InvalidInput("passes", "no iteration has been rendered yet");
                return pass_images(p.result());
            },
            "The mean of each render pass beyond combined that settings.outputs asks for, as render(passes=True) "
            "gives them ('emission', 'direct', 'indirect', 'normal', 'depth', and 'caustics' with "
            "settings.caustics_pass); normal and depth are of the first iteration (pixel-centred rays), as Cycles "
            "keeps its first sample's.")
        .def("stats", [](const ps::ProgressiveRender& p) { return stats_dict(p.stats()); },
             "Stats summed over the iterations done (seconds, counters), bytes of the last, and values: iterations, "
             "radius (first iteration), final_radius, alpha, time_limit, elapsed, and for an approximate method "
             "exact_iterations / exact_from_iteration (where it gave way to the exact splat).")
        .def_property_readonly("iterations_done", &ps::ProgressiveRender::iterations_done)
        .def_property_readonly("passes_done", &ps::ProgressiveRender::iterations_done, "Deprecated name of iterations_done.")
        .def_property_readonly("radius", &ps::ProgressiveRender::radius,
                               "Radius of the last iteration done (before any: of the first).")
        .def_property_readonly("next_radius", &ps::ProgressiveRender::next_radius)
        .def_property_readonly("elapsed", &ps::ProgressiveRender::elapsed,
                               "Seconds spent choosing the first radius and in completed iterations (time between step() calls is not "
                               "counted).")
        .def_property_readonly("finished", &ps::ProgressiveRender::finished,
                               "settings.iterations are done, or the next iteration would end past settings.time_limit.");
}

}  // namespace ps_py
