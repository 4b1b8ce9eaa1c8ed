#include "photonsplat/progressive.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "photonsplat/errors.h"
#include "photonsplat/memory_budget.h"
#include "photonsplat/render_control.h"
#include "photonsplat/scene.h"
#include "photonsplat/splatter.h"

namespace ps {

namespace {

// Clears, on every exit, the flag that keeps two iterations from running at once on one object.
struct RunningFlag {
    explicit RunningFlag(std::atomic<bool>& flag) : flag_(flag) {
        if (flag_.exchange(true)) throw std::runtime_error("a progressive iteration is already running on this render");
    }
    ~RunningFlag() { flag_.store(false); }
    std::atomic<bool>& flag_;
};

}  // namespace

ProgressiveRender::ProgressiveRender(const Scene& scene, const Camera& camera, const RenderSettings& settings)
    : scene_(scene), camera_(camera.relative_to(scene.origin())), settings_(settings) {
    validate(settings_);
    scene_.set_shader_camera(camera.shader_camera());
    check_frame_memory(scene_, camera_, settings_, FilmAccumulator::bytes_per_pixel(requested_outputs(settings_)));
    film_ = FilmAccumulator(camera_.width(), camera_.height(), requested_outputs(settings_));
    exact_method_ = splat_method_info(settings_.method).exact;
    // Choosing the automatic radius traces rays (kernel_radius.h): it is part of the render's time.
    const auto started = std::chrono::steady_clock::now();
    first_radius_ = first_radius(scene_, camera_, settings_);
    elapsed_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    last_radius_ = first_radius_;
    radius_sq_ = static_cast<double>(first_radius_) * first_radius_;
}

void ProgressiveRender::run_iteration(RenderControl& control) {
    RunningFlag running(running_);
    uint32_t index;
    float radius;
    double elapsed;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        index = iterations_done_;
        radius = static_cast<float>(std::sqrt(radius_sq_));
        elapsed = elapsed_;
    }
    // Progress: this iteration's share of the whole, by count or by time, whichever is further along.
    double start = 0.0, end = 1.0;
    std::string prefix = "iteration " + std::to_string(index + 1);
    if (settings_.iterations > 0) {
        start = static_cast<double>(index) / settings_.iterations;
        end = static_cast<double>(index + 1) / settings_.iterations;
        prefix += "/" + std::to_string(settings_.iterations);
    }
    if (settings_.time_limit > 0.0 && index > 0) {
        const double per_iteration = elapsed / index;
        if (elapsed / settings_.time_limit > start) {
            start = elapsed / settings_.time_limit;
            end = (elapsed + per_iteration) / settings_.time_limit;
        }
    }
    control.set_span(std::min(start, 1.0), std::min(end, 1.0), prefix + ": ");

    const auto began = std::chrono::steady_clock::now();
    IterationParams iteration;
    iteration.index = index;
    iteration.radius = radius;
    RenderResult r = render_iteration(scene_, camera_, settings_, iteration, control);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();

    std::lock_guard<std::mutex> lock(mutex_);
    film_.add(r.film);
    if (r.kernel_estimate) {
        ++kernel_estimate_iterations_;
        if (first_kernel_estimate_iteration_ == 0) first_kernel_estimate_iteration_ = index + 1;
    }
    stats_.merge(r.stats);
    ++iterations_done_;
    elapsed_ += seconds;
    last_radius_ = radius;
    // Knaus & Zwicker, 1-based: r_{i+1}² = r_i²·(i + α)/(i + 1), i = the iterations now done.
    const double i = static_cast<double>(iterations_done_);
    radius_sq_ *= (i + static_cast<double>(settings_.alpha)) / (i + 1.0);
}

bool ProgressiveRender::finished() const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (iterations_done_ == 0) return false;
    if (settings_.iterations > 0 && iterations_done_ >= settings_.iterations) return true;
    if (settings_.time_limit > 0.0) {
        const double per_iteration = elapsed_ / iterations_done_;
        if (elapsed_ + per_iteration > settings_.time_limit) return true;
    }
    return false;
}

uint32_t ProgressiveRender::iterations_done() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return iterations_done_;
}

float ProgressiveRender::radius() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return last_radius_;
}

float ProgressiveRender::next_radius() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return static_cast<float>(std::sqrt(radius_sq_));
}

double ProgressiveRender::elapsed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return elapsed_;
}

Stats ProgressiveRender::stats() const {
    std::lock_guard<std::mutex> lock(mutex_);
    Stats s = stats_;
    s.values["iterations"] = iterations_done_;
    s.values["radius"] = first_radius_;
    s.values["final_radius"] = last_radius_;
    s.values["alpha"] = settings_.alpha;
    s.values["time_limit"] = settings_.time_limit;
    s.values["elapsed"] = elapsed_;
    s.values["photons"] = static_cast<double>(settings_.photons);
    if (!exact_method_) {  // how often the approximate method's own estimate gave way to the exact splat
        s.values["exact_iterations"] = kernel_estimate_iterations_;
        s.values["exact_from_iteration"] = first_kernel_estimate_iteration_;
    }
    s.bytes["progressive_sums"] = static_cast<double>(film_.bytes());
    return s;
}

std::vector<float> ProgressiveRender::image() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return film_.mean(FilmOutput::combined);
}

RenderResult ProgressiveRender::result() const {
    RenderResult r;
    r.stats = stats();
    std::lock_guard<std::mutex> lock(mutex_);
    r.film = film_.mean();
    return r;
}

RenderResult render_progressive(const Scene& scene, const Camera& camera, const RenderSettings& settings,
                                RenderControl& control) {
    ProgressiveRender progressive(scene, camera, settings);
    while (!progressive.finished()) {
        try {
            control.check();
            progressive.run_iteration(control);
        } catch (const Cancelled&) {
            // Nothing to show yet: the caller learns it was cancelled. Else the iterations done are a valid image.
            if (progressive.iterations_done() == 0) throw;
            RenderResult r = progressive.result();
            r.stats.values["cancelled"] = 1.0;
            control.set_span(0.0, 1.0, "");
            control.begin_stage("cancelled", 1.0, 1.0);
            return r;
        }
    }
    control.set_span(0.0, 1.0, "");
    control.begin_stage("done", 1.0, 1.0);
    return progressive.result();
}

}  // namespace ps
