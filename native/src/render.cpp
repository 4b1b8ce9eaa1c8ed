#include "photonsplat/render.h"

#include <cmath>
#include <string>

#include <glm/geometric.hpp>
#include <tbb/task_arena.h>

#include "photonsplat/direct_light.h"
#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/kernel_coverage.h"
#include "photonsplat/memory_budget.h"
#include "photonsplat/photons.h"
#include "photonsplat/progressive.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/scene.h"
#include "photonsplat/view_samples.h"

namespace ps {

uint64_t iteration_seed(uint64_t seed, uint32_t pass) {
    if (pass == 0) return seed;
    // SplitMix64 of (seed, pass): passes draw from unrelated streams, and pass 0 keeps the user's seed.
    uint64_t z = seed ^ (0xD1B54A32D192ED03ull * (static_cast<uint64_t>(pass) + 1));
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

float first_radius(const Scene& scene, const Camera& camera, const RenderSettings& settings) {
    if (settings.radius > 0.0f) return settings.radius;
    // A single pass keeps all of its photon noise, which a smaller radius would raise: it stays at the noise
    // limit (on the atrium's one-shot 200k image half the radius lowers SSIM 0.655 -> 0.614). The boundary
    // correction removes the bias a smaller radius would trade that noise for (on the atrium a progressive
    // render with it reaches SSIM 0.9 in 20 passes from default_radius, 38 from the automatic radius). Only a
    // progressive render without it weighs the boundary bias against the noise its passes average away.
    // directional's approximate passes are not corrected (render_iteration), so it keeps the automatic radius.
    const bool corrected = settings.boundary_correction && settings.method != SplatMethod::directional;
    if (settings.iterations == 1 || corrected) return default_radius(scene, settings.photons);
    return automatic_radius(scene, camera, settings.photons);
}

RenderResult render_iteration(const Scene& scene, const Camera& world_camera, const RenderSettings& settings,
                         const IterationParams& pass, RenderControl& control) {
    validate(settings);
    const Camera camera = world_camera.relative_to(scene.origin());  // every stage works in render space
    RenderResult result;
    const int width = camera.width(), height = camera.height();
    const size_t pixels = static_cast<size_t>(width) * height;
    Stats& stats = result.stats;
    // Every large structure is predicted before it is allocated: a frame that cannot fit is refused here.
    MemoryBudget budget(settings.memory_budget, stats);
    reserve_frame(budget, scene, camera, settings);
    const float radius = pass.radius;
    const uint64_t seed = iteration_seed(settings.seed, pass.index);
    stats.values["radius"] = radius;
    stats.values["photons"] = static_cast<double>(settings.photons);
    stats.values["width"] = width;
    stats.values["height"] = height;
    stats.counters["triangles"] = static_cast<double>(scene.triangle_count());
    stats.counters["dropped_triangles"] = static_cast<double>(scene.dropped_triangles());
    stats.counters["lights"] = static_cast<double>(scene.lights().size());

    tbb::task_arena arena(settings.threads > 0 ? settings.threads : tbb::task_arena::automatic);
    arena.execute([&] {
        StageTimer total(stats, "total");
        control.begin_stage("scene", 0.0, 0.02);
        {
            StageTimer t(stats, "scene_build");
            stats.bytes["embree_scene"] = static_cast<double>(scene.ray_tracer().bytes());
        }
        control.check();

        control.begin_stage("view samples", 0.02, 0.15);
        ViewSampleSettings view_settings;
        view_settings.seed = seed;
        view_settings.jitter = pass.index > 0;
        view_settings.max_specular_depth = settings.max_bounces;
        const ViewSamples samples = generate_view_samples(scene, camera, view_settings, control, stats);
        reserve_split_samples(budget, settings, pixels, samples.samples.size());

        control.begin_stage("direct light", 0.15, 0.35);
        DirectLightSettings direct_settings;
        direct_settings.seed = seed;
        direct_settings.samples_per_light = settings.direct_samples;
        const std::vector<glm::vec3> direct = compute_direct_light(scene, samples, direct_settings, control, stats);
        stats.bytes["direct_light"] = static_cast<double>(direct.capacity() * sizeof(glm::vec3));

        control.begin_stage("photons", 0.35, 0.45);
        PhotonSettings photon_settings;
        photon_settings.count = settings.photons;
        photon_settings.max_bounces = settings.max_bounces;
        photon_settings.seed = seed;
        photon_settings.guide = settings.guide_photons;
        photon_settings.aimed_fraction = settings.aimed_photons;
        const PhotonMap photons = trace_photons(scene, photon_settings, control, stats);

        SplatParams params;
        params.radius = radius;
        params.cos_normal_tolerance = std::cos(settings.normal_tolerance * 3.14159265358979f / 180.0f);
        params.plane_distance_factor = settings.plane_distance;
        params.emitted = std::max<uint64_t>(photons.emitted, 1);
        params.kernel = settings.kernel;
        params.directional_level = settings.directional_level;
        // The caustics pass splats the caustic photons a second time, alone, over the same view samples and
        // hierarchy: exact (the same estimate restricted to those photons), and free when the pass is off.
        PhotonMap caustic_photons;
        if (settings.caustics_pass) {
            caustic_photons.emitted = photons.emitted;
            for (const Photon& p : photons.photons)
                if (p.flags & kCaustic) caustic_photons.photons.push_back(p);
        }
        const double splat_end = settings.caustics_pass ? 0.9 : 0.98;
        std::vector<glm::vec3> indirect, caustic;
        const std::string splat_stage = std::string("splat (") + to_string(settings.method) + ")";
        switch (settings.method) {
            case SplatMethod::brute:
            case SplatMethod::tiled:
            case SplatMethod::gather: {
                auto splat = [&](const PhotonMap& map) {
                    if (settings.method == SplatMethod::brute) return splat_brute(samples, map, params, control, stats);
                    if (settings.method == SplatMethod::tiled)
                        return splat_tiled(samples, camera, map, params, control, stats);
                    return splat_gather(samples, map, params, control, stats);
                };
                params.max_pairs_in_memory = fit_pair_cap(
                    budget, settings.method, predict_splat_memory(settings.method, samples.samples.size(),
                                                                  photons.photons.size(), nullptr, camera,
                                                                  settings.kernel, arena.max_concurrency()));
                control.begin_stage(splat_stage, 0.45, splat_end);
                StageTimer t(stats, "splat");
                indirect = splat(photons);
                if (settings.caustics_pass) {
                    control.begin_stage("caustics pass", splat_end, 0.98);
                    caustic = splat(caustic_photons);
                }
                break;
            }
            case SplatMethod::cluster:
            case SplatMethod::cluster_cone:
            case SplatMethod::directional: {
                control.begin_stage("cluster hierarchy", 0.45, 0.5);
                ClusterHierarchy hierarchy;
                {
                    StageTimer t(stats, "hierarchy_build");
                    ClusterBuildOptions build_options;
                    build_options.normal_cones = settings.method == SplatMethod::cluster_cone;
                    build_options.leaf_summaries = settings.method == SplatMethod::directional;
                    hierarchy = build_cluster_hierarchy(samples, ClusterKeyParams::from_camera(camera), build_options);
                }
                stats.bytes["hierarchy"] = static_cast<double>(hierarchy.bytes());
                if (!hierarchy.leaf_summaries.empty())
                    stats.bytes["leaf_summaries"] = static_cast<double>(hierarchy.summary_bytes());
                stats.counters["hierarchy_nodes"] = static_cast<double>(hierarchy.nodes.size());
                stats.counters["hierarchy_leaves"] = static_cast<double>(hierarchy.leaves.size());
                control.check();
                // Progressive passes: an explicit directional level would keep its blocks however small r gets, so
                // once the leaves outgrow the radius the automatic rule takes over, and it splats exactly.
                if (settings.method == SplatMethod::directional && pass.index > 0 && params.directional_level >= 0 &&
                    directional_leaves_exceed_radius(hierarchy, radius))
                    params.directional_level = -1;
                auto splat = [&](const PhotonMap& map) {
                    if (settings.method == SplatMethod::cluster)
                        return splat_cluster(hierarchy, samples, map, params, control, stats);
                    if (settings.method == SplatMethod::cluster_cone)
                        return splat_cluster_cone(hierarchy, samples, map, params, control, stats);
                    return splat_directional(hierarchy, samples, map, params, control, stats);
                };
                params.max_pairs_in_memory = fit_pair_cap(
                    budget, settings.method, predict_splat_memory(settings.method, samples.samples.size(),
                                                                  photons.photons.size(), &hierarchy, camera,
                                                                  settings.kernel, arena.max_concurrency()));
                control.begin_stage(splat_stage, 0.5, splat_end);
                StageTimer t(stats, "splat");
                indirect = splat(photons);
                if (settings.caustics_pass) {
                    control.begin_stage("caustics pass", splat_end, 0.98);
                    caustic = splat(caustic_photons);
                }
                break;
            }
        }
        control.check();
        // directional's blocks gather photons from around whole clusters, not a kernel ball per sample, so the
        // correction is only for its exact fallback (applied to the blocks it lowered directional's SSIM on the
        // atrium at 5 s from 0.916 to 0.899).
        const bool kernel_estimate = settings.method != SplatMethod::directional ||
                                     stats.values["directional_exact_fallback"] == 1.0;
        if (settings.boundary_correction && kernel_estimate && !photons.photons.empty()) {
            StageTimer t(stats, "kernel_coverage");
            const std::vector<float> coverage = kernel_coverage(scene, samples, params, seed, control, stats);
            for (size_t i = 0; i < coverage.size(); ++i) {
                indirect[i] /= coverage[i];
                if (settings.caustics_pass) caustic[i] /= coverage[i];
            }
        }
        stats.bytes["indirect_light"] = static_cast<double>(indirect.capacity() * sizeof(glm::vec3));

        control.begin_stage("image", 0.98, 1.0);
        StageTimer t(stats, "image");
        result.width = width;
        result.height = height;
        result.rgba.assign(pixels * 4, 0.0f);
        result.emission.assign(pixels * 3, 0.0f);
        result.direct.assign(pixels * 3, 0.0f);
        result.indirect.assign(pixels * 3, 0.0f);
        if (settings.caustics_pass) result.caustics.assign(pixels * 3, 0.0f);
        result.normal.assign(pixels * 3, 0.0f);
        result.depth.assign(pixels, RenderResult::kNoDepth);
        for (size_t p = 0; p < pixels; ++p) {
            // With film transparency a camera ray that escapes straight to the world shows nothing (Cycles):
            // the background seen through glass or in mirrors stays.
            const bool escaped = samples.alpha[p] == 0.0f;
            if (!(settings.transparent && escaped))
                for (int c = 0; c < 3; ++c) result.emission[3 * p + c] = samples.emission[p][c];
            if (!escaped) {
                for (int c = 0; c < 3; ++c) result.normal[3 * p + c] = samples.first_normal[p][c];
                result.depth[p] = samples.first_depth[p];
            }
        }
        for (size_t i = 0; i < samples.samples.size(); ++i) {
            const size_t p = samples.samples[i].pixel;
            for (int c = 0; c < 3; ++c) {  // a pixel's samples add up (view_samples.h)
                result.direct[3 * p + c] += direct[i][c];
                result.indirect[3 * p + c] += indirect[i][c];
                if (settings.caustics_pass) result.caustics[3 * p + c] += caustic[i][c];
            }
        }
        for (size_t p = 0; p < pixels; ++p) {
            for (int c = 0; c < 3; ++c)
                result.rgba[4 * p + c] = result.emission[3 * p + c] + result.direct[3 * p + c] + result.indirect[3 * p + c];
            result.rgba[4 * p + 3] = settings.transparent ? samples.alpha[p] : 1.0f;
        }
        // Validation bounds every input, but products of extreme ones (1e10 W over a 1e15 m scene) can still leave
        // float's range: say so rather than hand back a frame with infinities in it.
        size_t overflowed = 0;
        for (float v : result.rgba) overflowed += std::isfinite(v) ? 0 : 1;
        if (overflowed > 0)
            throw InvalidInput("scene", std::to_string(overflowed) + " pixel values overflowed the float range; lower "
                                        "light strengths, emission or the background, or the scene's size");
        stats.bytes["image"] = static_cast<double>((result.rgba.size() + 3 * result.emission.size() + result.caustics.size() +
                                                    result.normal.size() + result.depth.size()) * sizeof(float));
    });
    control.begin_stage("done", 1.0, 1.0);
    return result;
}

RenderResult render(const Scene& scene, const Camera& camera, const RenderSettings& settings, RenderControl& control) {
    validate(settings);
    if (settings.iterations != 1) return render_progressive(scene, camera, settings, control);
    IterationParams pass;
    pass.radius = first_radius(scene, camera, settings);
    RenderResult result = render_iteration(scene, camera, settings, pass, control);
    result.stats.values["passes"] = 1.0;
    return result;
}

}  // namespace ps
