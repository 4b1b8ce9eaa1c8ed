// One frame, the whole pipeline: view samples → direct light → cluster hierarchy → photons → splat → image.
#pragma once
#include <cstdint>
#include <vector>

#include "photonsplat/camera.h"
#include "photonsplat/film.h"
#include "photonsplat/kernel_radius.h"
#include "photonsplat/render_control.h"
#include "photonsplat/settings.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"

namespace ps {

class Scene;


struct RenderResult {
    Film film;  // the outputs the settings asked for (requested_outputs); linear radiance, row 0 = TOP
    // The iteration's splat was a kernel estimate per view sample (splatter.h); false when an approximate method
    // used its own blocks. A progressive render counts these iterations.
    bool kernel_estimate = true;
    Stats stats;

    int width() const { return film.width(); }
    int height() const { return film.height(); }
    // The combined image, height × width × 4: emission + direct + indirect, and alpha.
    const std::vector<float>& rgba() const { return film[FilmOutput::combined]; }
};

// Which iteration of a progressive render is being rendered, and with what radius. Iteration 0 keeps
// settings.seed and pixel-centred camera rays, so a one-iteration render is the paper's one-shot image; later
// iterations draw from their own random streams (iteration_seed) and jitter each camera ray inside its pixel.
struct IterationParams {
    uint32_t index = 0;
    float radius = 0.0f;  // > 0: the kernel radius of this iteration
};
uint64_t iteration_seed(uint64_t seed, uint32_t iteration);  // = seed for iteration 0

// The radius of iteration 0: settings.radius, or when that is 0 default_radius, except for a progressive render
// that the boundary correction does not cover (switched off, or an approximate method, whose estimates it does
// not rescale): automatic_radius (kernel_radius.h, which depends on what the camera sees).
float first_radius(const Scene& scene, const Camera& camera, const RenderSettings& settings);

// One iteration of the pipeline (the whole of a one-shot render). Throws InvalidInput, Cancelled.
RenderResult render_iteration(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                              const IterationParams& iteration, RenderControl& control);

// What the settings ask for: one iteration (settings.iterations == 1: render_iteration of iteration 0), or a
// progressive render (progressive.h) stopped by settings.iterations, settings.time_limit or a cancel. A cancel
// before the first iteration is done throws Cancelled; a cancel after it returns the mean of the iterations done,
// with stats.values["cancelled"] = 1. Throws InvalidInput for bad settings. The memory check of a frame is
// memory_budget.h's check_frame_memory.
RenderResult render(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                    RenderControl& control);

}  // namespace ps
