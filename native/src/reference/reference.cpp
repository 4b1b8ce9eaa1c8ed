// The reference renderer's driver: passes of (caustic photons → one camera path per pixel), averaged in
// double; threads, progress, cancel and the time limit. The estimators are in path_tracer.cpp and
// caustic_photons.cpp; reference.h explains how they split path space.
#include "photonsplat/reference.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "caustic_photons.h"
#include "path_tracer.h"
#include "photonsplat/direct_light.h"
#include "photonsplat/errors.h"
#include "photonsplat/light_sources.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/render.h"
#include "photonsplat/rng.h"
#include "photonsplat/sample_sequence.h"
#include "photonsplat/scene.h"

namespace ps {

namespace {

constexpr double kAlpha = 2.0 / 3.0;                  // Knaus & Zwicker's radius-reduction parameter
constexpr int kMaxSamples = 1 << 24;
constexpr uint64_t kMaxCausticPhotons = 100'000'000;  // per pass; ~5 GB of photons if every one were stored

template <typename T>
void require(bool ok, const std::string& field, const std::string& what, T value) {
    if (!ok) throw InvalidInput(field, what + ", got " + std::to_string(value));
}

}  // namespace

void validate(const ReferenceSettings& s) {
    require(s.samples >= 1 && s.samples <= kMaxSamples, "samples", "must be in [1, " + std::to_string(kMaxSamples) + "]",
            s.samples);
    require(s.max_bounces >= 0 && s.max_bounces <= 1000, "max_bounces", "must be in [0, 1000]", s.max_bounces);
    require(s.threads >= 0 && s.threads <= 4096, "threads", "must be in [0, 4096] (0 = all cores)", s.threads);
    require(s.caustic_photons <= kMaxCausticPhotons, "caustic_photons",
            "must be at most " + std::to_string(kMaxCausticPhotons) + " per pass", s.caustic_photons);
    require(std::isfinite(s.caustic_radius) && s.caustic_radius >= 0.0f, "caustic_radius",
            "must be finite and >= 0 (0 = automatic)", s.caustic_radius);
    require(std::isfinite(s.time_limit) && s.time_limit >= 0.0, "time_limit", "must be finite and >= 0 (0 = none)",
            s.time_limit);
}

float default_caustic_radius(const Scene& scene, uint64_t photons_per_pass) {
    return 0.5f * default_radius(scene, photons_per_pass);
}

ReferenceResult render_reference(const Scene& scene, const Camera& world_camera, const ReferenceSettings& settings,
                                 RenderControl& control) {
    validate(settings);
    const Camera camera = world_camera.relative_to(scene.origin());  // paths are traced in render space
    scene.set_shader_camera(world_camera.shader_camera());
    const int width = camera.width(), height = camera.height();
    const size_t pixels = static_cast<size_t>(width) * height;
    {
        // Refuse, before allocating, a frame whose buffers would take more than half of the machine's memory.
        const double bytes = static_cast<double>(pixels) * (3 * sizeof(double) + 4 * sizeof(float));
        const double memory = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
        if (memory > 0.0 && bytes > 0.5 * memory)
            throw InvalidInput("resolution", std::to_string(width) + "×" + std::to_string(height) +
                                                 " needs more than half of this machine's memory; lower it");
    }
    ReferenceResult result;
    Stats& stats = result.stats;
    const auto started = std::chrono::steady_clock::now();
    const float first_radius = settings.caustic_radius > 0.0f ? settings.caustic_radius
                                                              : default_caustic_radius(scene, settings.caustic_photons);
    stats.values["samples_requested"] = settings.samples;
    stats.values["caustic_photons"] = static_cast<double>(settings.caustic_photons);
    stats.values["caustic_radius_first"] = first_radius;
    stats.values["max_bounces"] = settings.max_bounces;
    stats.values["width"] = width;
    stats.values["height"] = height;

    std::vector<glm::dvec3> sum(pixels, glm::dvec3(0.0));
    int passes = 0;
    double radius2 = static_cast<double>(first_radius) * first_radius;
    tbb::task_arena arena(settings.threads > 0 ? settings.threads : tbb::task_arena::automatic);
    arena.execute([&] {
        StageTimer total(stats, "total");
        control.begin_stage("scene", 0.0, 0.0);
        report_scene(scene, stats);
        const LightSources sources(scene);
        PathTracerContext context{scene, sources, nullptr, {}, settings.max_bounces, scene_has_transparency(scene),
                                  scene.any_terminator_offset()};
        bool photon_sources = false;
        for (size_t l = 0; l < sources.size(); ++l) {
            const bool photons = settings.caustic_photons > 0 && caustics_by_photons(sources, l);
            context.photon_caustics.push_back(photons ? 1 : 0);
            photon_sources = photon_sources || photons;
        }
        control.begin_stage("reference", 0.0, 1.0);
        tbb::enumerable_thread_specific<PathCounters> counters;
        for (int pass = 0; pass < settings.samples; ++pass) {
            control.check();
            // Knaus & Zwicker: r_i² = r_{i−1}² (i − 1 + α) / i for pass i >= 2 (1-based).
            if (pass > 0) radius2 *= (pass + kAlpha) / (pass + 1.0);
            std::unique_ptr<CausticPhotonMap> caustics;
            if (photon_sources) {
                StageTimer t(stats, "caustic_photons");
                std::vector<Photon> photons =
                    trace_caustic_photons(scene, sources, settings.caustic_photons, settings.max_bounces, settings.seed,
                                          static_cast<uint64_t>(pass), control, stats);
                caustics = std::make_unique<CausticPhotonMap>(std::move(photons), settings.caustic_photons,
                                                              static_cast<float>(std::sqrt(radius2)), camera.position());
            }
            context.caustics = caustics.get();
            {
                StageTimer t(stats, "paths");
                tbb::parallel_for(tbb::blocked_range<int>(0, height, 4), [&](const tbb::blocked_range<int>& rows) {
                    if (control.cancel_requested()) return;
                    PathCounters& local = counters.local();
                    for (int y = rows.begin(); y < rows.end(); ++y)
                        for (int x = 0; x < width; ++x) {
                            const size_t pixel = static_cast<size_t>(y) * width + x;
                            Rng rng(settings.seed, RngDomain::reference_path, static_cast<uint64_t>(pass) * pixels + pixel);
                            // A box filter over the pixel, its passes placed by one low-discrepancy sequence as
                            // Cycles places a pixel's samples: a glint covering part of a pixel (a sun in a smooth
                            // floor) converges far sooner than with independent positions (differential seed 121:
                            // its four pixels 0.81 of Cycles at 2 x 512 samples so, 0.99 along the sequence).
                            float jx = 0.5f, jy = 0.5f;
                            SampleSequence::pixel_point(settings.seed, pixel, static_cast<uint32_t>(pass), jx, jy);
                            const glm::vec3 l = trace_reference_path(context, camera.generate_ray(x + jx, y + jy), rng, local);
                            // A non-finite sample (degenerate geometry) would poison the pixel for good: drop and count it.
                            if (std::isfinite(l.x) && std::isfinite(l.y) && std::isfinite(l.z))
                                sum[pixel] += glm::dvec3(l);
                            else
                                ++local.non_finite;
                        }
                });
            }
            control.check();
            ++passes;
            const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
            const bool out_of_time = settings.time_limit > 0.0 && elapsed >= settings.time_limit;
            if (settings.time_limit > 0.0)
                control.advance(static_cast<uint64_t>(1000.0 * std::max(static_cast<double>(passes) / settings.samples,
                                                                        elapsed / settings.time_limit)),
                                1000);
            else
                control.advance(static_cast<uint64_t>(passes), static_cast<uint64_t>(settings.samples));
            if (out_of_time) break;
        }
        PathCounters all;
        for (const PathCounters& c : counters) {
            all.rays += c.rays;
            all.shadow_rays += c.shadow_rays;
            all.non_finite += c.non_finite;
        }
        stats.counters["non_finite_samples"] = static_cast<double>(all.non_finite);
        stats.counters["rays"] = static_cast<double>(all.rays);
        stats.counters["shadow_rays"] = static_cast<double>(all.shadow_rays);
        stats.counters["camera_paths"] = static_cast<double>(pixels) * passes;
    });
    stats.values["samples"] = passes;
    stats.values["caustic_radius_last"] = std::sqrt(radius2);
    result.width = width;
    result.height = height;
    result.rgba.assign(pixels * 4, 1.0f);
    for (size_t p = 0; p < pixels; ++p)
        for (int c = 0; c < 3; ++c) result.rgba[4 * p + c] = static_cast<float>(sum[p][c] / passes);
    control.begin_stage("done", 1.0, 1.0);
    return result;
}

}  // namespace ps
