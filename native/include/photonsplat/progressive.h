// Progressive, consistent splatting (beyond the paper): iterations of the whole pipeline, each with new photons,
// camera rays jittered inside their pixels and a smaller radius, averaged into a running mean that converges to
// the exact answer (Knaus & Zwicker 2011, "Progressive photon mapping: a probabilistic approach").
//
// Iteration i (1-based) splats with r_i² = r_{i−1}²·(i−1+α)/i, r_1 = the one-shot radius. Its noise grows as
// 1/r_i² ∝ i^(1−α) while its blur (bias ∝ r_i²) shrinks as i^(α−1); the mean of N iterations then has variance
// ∝ N^(−α) and bias ∝ N^(α−1), both → 0, balanced at α = 2/3: mean squared error ∝ N^(−2/3). Direct light and
// emission are re-estimated every iteration (new shadow rays, jittered pixels) and averaged the same way.
//
// Iteration 1 is exactly render_iteration of iteration 0: the user's seed, pixel-centred rays, the one-shot
// radius; so a progressive render stopped after one iteration is the paper's one-shot image, bit for bit.
//
// An approximate method may give way to the exact splat as the radius shrinks (directional does once its leaf
// clusters are more than 2r across, whatever level was asked for: else the mean would converge to the blocky
// image of a fixed level); the iterations' SplatEstimate says when, and stats.values count it.
//
// The film's running sums (film.h) hold only the outputs the settings ask for, in double.
#pragma once
#include <atomic>
#include <cstdint>
#include <mutex>
#include <vector>

#include "photonsplat/camera.h"
#include "photonsplat/film.h"
#include "photonsplat/render.h"

namespace ps {

class Scene;

class ProgressiveRender {
public:
    // Validates settings (InvalidInput) and refuses frames whose buffers and running sums would not fit in
    // memory. The scene must outlive this object and must not change while it is used.
    ProgressiveRender(const Scene& scene, const Camera& camera, const RenderSettings& settings);

    // Renders the next iteration and adds it to the mean. Throws Cancelled when control asks to stop, leaving the
    // mean as it was; std::runtime_error when another thread is already running an iteration on this object.
    void run_iteration(RenderControl& control);

    // settings.iterations are done, or (time_limit > 0) the next iteration, predicted to take the mean iteration
    // time so far, would end past time_limit. False before the first iteration.
    bool finished() const;

    int width() const { return camera_.width(); }
    int height() const { return camera_.height(); }
    uint32_t iterations_done() const;
    float radius() const;       // the radius of the last iteration done (before any: of the first)
    float next_radius() const;  // the radius the next iteration will use
    double elapsed() const;     // seconds spent choosing the first radius and in completed iterations (not between)

    // The mean of the iterations done (the film's outputs), with their stats summed (seconds, counters) and the
    // progressive values: "iterations", "radius" (first iteration), "final_radius", "alpha", "time_limit",
    // "elapsed", and for an approximate method "exact_iterations", "exact_from_iteration" (1-based, 0 = none).
    // Safe to call from another thread while an iteration runs: it returns the mean without that iteration.
    // Empty (width 0) before the first iteration.
    RenderResult result() const;
    // Only the mean combined image, height × width × 4 (cheaper than result()); empty before the first iteration.
    std::vector<float> image() const;
    Stats stats() const;

private:
    const Scene& scene_;
    Camera camera_;
    RenderSettings settings_;
    std::atomic<bool> running_{false};

    bool exact_method_;          // the registry's word on settings.method (splatter.h)

    mutable std::mutex mutex_;  // guards everything below
    uint32_t iterations_done_ = 0;
    double radius_sq_;          // of the next iteration
    float last_radius_;
    float first_radius_;
    double elapsed_ = 0.0;
    // Iterations whose splat was a kernel estimate, and the first of them (1-based, 0 = none): for an approximate
    // method, where it gave way to the exact splat.
    uint32_t kernel_estimate_iterations_ = 0, first_kernel_estimate_iteration_ = 0;
    FilmAccumulator film_;      // the running sums of the requested outputs
    Stats stats_;
};

// A whole progressive render: iterations until finished(), or a cancel (see render() in render.h).
RenderResult render_progressive(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                                RenderControl& control);

}  // namespace ps
