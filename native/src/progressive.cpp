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

namespace ps {

namespace {

// Per pixel: the double sums of rgba (4) and of the emission, direct, indirect and caustics components (3 each),
// and pass 0's normal and depth.
constexpr double kSumBytesPerPixel = 16 * sizeof(double) + 4 * sizeof(float);

void add_to(std::vector<double>& sum, const std::vector<float>& pass) {
    for (size_t i = 0; i < sum.size(); ++i) sum[i] += static_cast<double>(pass[i]);
}

std::vector<float> mean_of(const std::vector<double>& sum, uint32_t passes) {
    std::vector<float> mean(sum.size());
    const double n = static_cast<double>(passes);
    for (size_t i = 0; i < sum.size(); ++i) mean[i] = static_cast<float>(sum[i] / n);
    return mean;
}

// Clears, on every exit, the flag that keeps two passes from running at once on one object.
struct RunningFlag {
    explicit RunningFlag(std::atomic<bool>& flag) : flag_(flag) {
        if (flag_.exchange(true)) throw std::runtime_error("a progressive pass is already running on this render");
    }
    ~RunningFlag() { flag_.store(false); }
    std::atomic<bool>& flag_;
};

}  // namespace

ProgressiveRender::ProgressiveRender(const Scene& scene, const Camera& camera, const RenderSettings& settings)
    : scene_(scene), camera_(camera.relative_to(scene.origin())), settings_(settings) {
    validate(settings_);
    check_frame_memory(scene_, camera_, settings_, kSumBytesPerPixel);
    pixels_ = static_cast<size_t>(camera_.width()) * camera_.height();
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
    // Progress: this pass's share of the whole, by pass count or by time, whichever is further along.
    double start = 0.0, end = 1.0;
    std::string prefix = "pass " + std::to_string(index + 1);
    if (settings_.iterations > 0) {
        start = static_cast<double>(index) / settings_.iterations;
        end = static_cast<double>(index + 1) / settings_.iterations;
        prefix += "/" + std::to_string(settings_.iterations);
    }
    if (settings_.time_limit > 0.0 && index > 0) {
        const double per_pass = elapsed / index;
        if (elapsed / settings_.time_limit > start) {
            start = elapsed / settings_.time_limit;
            end = (elapsed + per_pass) / settings_.time_limit;
        }
    }
    control.set_span(std::min(start, 1.0), std::min(end, 1.0), prefix + ": ");

    const auto began = std::chrono::steady_clock::now();
    IterationParams pass;
    pass.index = index;
    pass.radius = radius;
    RenderResult r = render_iteration(scene_, camera_, settings_, pass, control);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();

    std::lock_guard<std::mutex> lock(mutex_);
    if (iterations_done_ == 0) {
        rgba_sum_.assign(pixels_ * 4, 0.0);
        emission_sum_.assign(pixels_ * 3, 0.0);
        direct_sum_.assign(pixels_ * 3, 0.0);
        indirect_sum_.assign(pixels_ * 3, 0.0);
        if (settings_.caustics_pass) caustics_sum_.assign(pixels_ * 3, 0.0);
        normal_ = std::move(r.normal);
        depth_ = std::move(r.depth);
    }
    add_to(rgba_sum_, r.rgba);
    add_to(emission_sum_, r.emission);
    add_to(direct_sum_, r.direct);
    add_to(indirect_sum_, r.indirect);
    if (settings_.caustics_pass) add_to(caustics_sum_, r.caustics);
    const auto fallback = r.stats.values.find("directional_exact_fallback");
    if (settings_.method == SplatMethod::directional && fallback != r.stats.values.end() && fallback->second > 0.0) {
        ++directional_exact_passes_;
        if (directional_exact_from_pass_ == 0) directional_exact_from_pass_ = index + 1;
    }
    stats_.merge(r.stats);
    ++iterations_done_;
    elapsed_ += seconds;
    last_radius_ = radius;
    // Knaus & Zwicker, 1-based: r_{i+1}² = r_i²·(i + α)/(i + 1), i = the passes now done.
    const double i = static_cast<double>(iterations_done_);
    radius_sq_ *= (i + static_cast<double>(settings_.alpha)) / (i + 1.0);
}

bool ProgressiveRender::finished() const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (iterations_done_ == 0) return false;
    if (settings_.iterations > 0 && iterations_done_ >= settings_.iterations) return true;
    if (settings_.time_limit > 0.0) {
        const double per_pass = elapsed_ / iterations_done_;
        if (elapsed_ + per_pass > settings_.time_limit) return true;
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
    s.values["passes"] = iterations_done_;
    s.values["radius"] = first_radius_;
    s.values["final_radius"] = last_radius_;
    s.values["alpha"] = settings_.alpha;
    s.values["time_limit"] = settings_.time_limit;
    s.values["elapsed"] = elapsed_;
    s.values["photons"] = static_cast<double>(settings_.photons);
    if (settings_.method == SplatMethod::directional) {
        s.values["directional_exact_passes"] = directional_exact_passes_;
        s.values["directional_exact_from_pass"] = directional_exact_from_pass_;
    }
    s.bytes["progressive_sums"] =
        static_cast<double>((rgba_sum_.size() + emission_sum_.size() + direct_sum_.size() + indirect_sum_.size() +
                             caustics_sum_.size()) * sizeof(double) + (normal_.size() + depth_.size()) * sizeof(float));
    return s;
}

std::vector<float> ProgressiveRender::image() const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (iterations_done_ == 0) return {};
    return mean_of(rgba_sum_, iterations_done_);
}

RenderResult ProgressiveRender::result() const {
    RenderResult r;
    r.stats = stats();
    std::lock_guard<std::mutex> lock(mutex_);
    if (iterations_done_ == 0) return r;
    r.width = camera_.width();
    r.height = camera_.height();
    r.rgba = mean_of(rgba_sum_, iterations_done_);
    r.emission = mean_of(emission_sum_, iterations_done_);
    r.direct = mean_of(direct_sum_, iterations_done_);
    r.indirect = mean_of(indirect_sum_, iterations_done_);
    if (settings_.caustics_pass) r.caustics = mean_of(caustics_sum_, iterations_done_);
    r.normal = normal_;
    r.depth = depth_;
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
            // Nothing to show yet: the caller learns it was cancelled. Else the passes done are a valid image.
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
