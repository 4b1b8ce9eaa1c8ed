#include "photonsplat/render.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "photonsplat/direct_light.h"
#include "photonsplat/errors.h"
#include "photonsplat/hierarchy.h"
#include "photonsplat/kernel_coverage.h"
#include "photonsplat/memory_budget.h"
#include "photonsplat/photon_density.h"
#include "photonsplat/photons.h"
#include "photonsplat/progressive.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/scene.h"
#include "photonsplat/splatter.h"
#include "photonsplat/view_samples.h"

namespace ps {

uint64_t iteration_seed(uint64_t seed, uint32_t iteration) {
    if (iteration == 0) return seed;
    // SplitMix64 of (seed, iteration): iterations draw from unrelated streams, and iteration 0 keeps the user's seed.
    uint64_t z = seed ^ (0xD1B54A32D192ED03ull * (static_cast<uint64_t>(iteration) + 1));
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

float first_radius(const Scene& scene, const Camera& camera, const RenderSettings& settings) {
    if (settings.radius > 0.0f) return settings.radius;
    // A single iteration keeps all of its photon noise, which a smaller radius would raise: it stays at the noise
    // limit. The boundary correction removes the bias a smaller radius would trade that noise for, so only a
    // progressive render without it weighs the boundary bias against the noise its iterations average away
    // (docs/results/README.md, "Automatic radius" and "Boundary correction", has the measurements). An
    // approximate method's estimates are not corrected, so it keeps the automatic radius.
    const bool corrected = settings.boundary_correction && splat_method_info(settings.method).exact;
    if (settings.iterations == 1 || corrected) return default_radius(scene, settings.photons);
    return automatic_radius(scene, camera, settings.photons);
}

namespace {

// The photons' side of the splat test, from the settings and this iteration's radius.
SplatParams splat_params(const RenderSettings& settings, float radius, uint64_t emitted) {
    SplatParams params;
    params.radius = radius;
    params.cos_normal_tolerance = std::cos(settings.normal_tolerance * 3.14159265358979f / 180.0f);
    params.plane_distance_factor = settings.plane_distance;
    params.emitted = std::max<uint64_t>(emitted, 1);
    params.kernel = settings.kernel;
    return params;
}

// Stage 3: the view-sample cluster hierarchy, for the methods that splat onto one.
std::optional<ClusterHierarchy> build_hierarchy(const Splatter& splatter, const ViewSamples& samples,
                                                const Camera& camera, RenderControl& control, Stats& stats) {
    const std::optional<ClusterBuildOptions> options = splatter.hierarchy_options();
    if (!options) return std::nullopt;
    control.begin_stage("cluster hierarchy", 0.45, 0.5);
    std::optional<ClusterHierarchy> hierarchy;
    {
        StageTimer t(stats, "hierarchy_build");
        hierarchy = build_cluster_hierarchy(samples, ClusterKeyParams::from_camera(camera), *options);
    }
    stats.bytes["hierarchy"] = static_cast<double>(hierarchy->bytes());
    if (!hierarchy->leaf_summaries.empty()) stats.bytes["leaf_summaries"] = static_cast<double>(hierarchy->summary_bytes());
    stats.counters["hierarchy_nodes"] = static_cast<double>(hierarchy->nodes.size());
    stats.counters["hierarchy_leaves"] = static_cast<double>(hierarchy->leaves.size());
    control.check();
    return hierarchy;
}

// The photons a caustics output splats again, over the same view samples and hierarchy, each with the share of
// its power that Cycles' Caustics toggles remove when the camera path reaches the surface that stores it in
// `state` (photons.h). The output is what those toggles change: the splat of kReachedOtherwise's photons with the
// share of each sample's BRDF that Cycles would not label diffuse (its camera path then reaches the photon's
// previous surface otherwise), plus that of kReachedDiffusely's with the diffuse-labelled share (LabelShare).
PhotonMap caustic_photons_of(const PhotonMap& photons, CausticState state) {
    PhotonMap caustic;
    caustic.emitted = photons.emitted;
    for (const Photon& p : photons.photons) {
        const glm::vec3 share = caustic_share(p, state);
        if (share == glm::vec3(0.0f)) continue;
        caustic.photons.push_back(p);
        caustic.photons.back().power *= share;
    }
    return caustic;
}

// The Caustics output's light per view sample: the two splats above, and where samples reached right after
// translucency have parts Cycles drops there, a third: every photon's light through those parts.
SplatEstimate splat_caustics(const Splatter& splatter, const SplatFrame& frame, const PhotonMap& photons,
                             SplatParams params, RenderControl& control, Stats& stats) {
    params.label_share = LabelShare::other;
    SplatEstimate caustic =
        splatter.splat(frame, caustic_photons_of(photons, kReachedOtherwise), params, control, stats);
    const auto add = [&caustic](const SplatEstimate& e) {
        for (size_t i = 0; i < caustic.radiance.size(); ++i) caustic.radiance[i] += e.radiance[i];
        caustic.kernel_estimate = caustic.kernel_estimate && e.kernel_estimate;
    };
    params.label_share = LabelShare::diffuse;
    add(splatter.splat(frame, caustic_photons_of(photons, kReachedDiffusely), params, control, stats));
    const auto& samples = frame.samples.samples;
    if (std::any_of(samples.begin(), samples.end(), has_dropped_parts)) {
        params.label_share = LabelShare::other_parts;
        add(splatter.splat(frame, photons, params, control, stats));
    }
    return caustic;
}

// Stage 6½: divides each sample's splatted light by the part of its kernel on a like-facing surface
// (kernel_coverage.h). Only kernel estimates are rescaled.
// With `lit_only`, only the samples that received some of that light are measured (kernel_coverage.h).
void correct_boundaries(const Scene& scene, const ViewSamples& samples, const SplatParams& params, uint64_t seed,
                        std::vector<std::vector<glm::vec3>*> lights, bool lit_only, RenderControl& control,
                        Stats& stats) {
    StageTimer t(stats, "kernel_coverage");
    std::vector<uint8_t> lit;
    if (lit_only) {
        lit.assign(samples.samples.size(), 0);
        for (const std::vector<glm::vec3>* light : lights)
            for (size_t i = 0; i < lit.size(); ++i) lit[i] |= (*light)[i] != glm::vec3(0.0f) ? 1 : 0;
    }
    const std::vector<float> coverage =
        kernel_coverage(scene, samples, params, seed, control, stats, lit_only ? &lit : nullptr);
    for (std::vector<glm::vec3>* light : lights)
        for (size_t i = 0; i < coverage.size(); ++i) (*light)[i] /= coverage[i];
}

// The light splatted onto the view samples: all of it, and what the Caustics output takes (empty without it).
struct SplatLight {
    std::vector<glm::vec3> indirect, caustic;
    bool kernel_estimate = true;  // every level's was a kernel estimate (splatter.h)
};

// Stages 5–6½ for the photons of one radius: the splat (and the caustic splat), then the boundary correction of
// kernel estimates at that radius (of the samples they lit alone, for a radius level's few photons; `level` 0 is
// the iteration's radius). Adds to `light`.
// Its progress runs from `begin` to `end`: the caustic splat takes the last tenth.
void splat_one_radius(const Scene& scene, const Splatter& splatter, const SplatFrame& frame, const PhotonMap& photons,
                      const SplatParams& params, int level, bool caustics_output, const RenderSettings& settings,
                      uint64_t seed, double begin, double end, SplatLight& light, RenderControl& control,
                      Stats& stats) {
    SplatEstimate indirect, caustic;
    {
        StageTimer t(stats, "splat");
        const double middle = caustics_output ? end - 0.1 * (end - begin) : end;
        const std::string name = std::string("splat (") + to_string(settings.method) + ")";
        const std::string radius = level > 0 ? ", radius / " + std::to_string(1 << level) : "";
        control.begin_stage(name + radius, begin, middle);
        indirect = splatter.splat(frame, photons, params, control, stats);
        if (caustics_output) {
            control.begin_stage("caustic splat" + radius, middle, end);
            caustic = splat_caustics(splatter, frame, photons, params, control, stats);
        }
    }
    control.check();
    light.kernel_estimate = light.kernel_estimate && indirect.kernel_estimate;
    if (settings.boundary_correction && indirect.kernel_estimate && !photons.photons.empty()) {
        std::vector<std::vector<glm::vec3>*> lights = {&indirect.radiance};
        if (caustics_output) lights.push_back(&caustic.radiance);
        correct_boundaries(scene, frame.samples, params, seed, lights, level > 0, control, stats);
    }
    const auto add = [](std::vector<glm::vec3>& sum, std::vector<glm::vec3>&& part) {
        if (sum.empty()) {
            sum = std::move(part);
            return;
        }
        for (size_t i = 0; i < sum.size(); ++i) sum[i] += part[i];
    };
    add(light.indirect, std::move(indirect.radiance));
    if (caustics_output) add(light.caustic, std::move(caustic.radiance));
}

// Stage 4½: the photons of the smaller radii (photon_density.h) moved out of `photons` into one map per level
// 1, 2, … (empty where none or where the settings keep one radius); `photons` keeps the ordinary level's. Their
// memory, and each level's light while it is splatted, is reserved before the splat's pair cap is fitted.
std::vector<PhotonMap> split_radius_levels(PhotonMap& photons, float radius, size_t samples, bool caustics_output,
                                           const RenderSettings& settings, MemoryBudget& budget, Stats& stats) {
    std::vector<PhotonMap> dense;
    if (!settings.adaptive_radius || photons.photons.empty()) return dense;
    StageTimer t(stats, "radius_levels");
    budget.reserve("radius_levels", predict_radius_level_bytes(photons.photons.size()), "photons");
    const RadiusLevels levels = photon_radius_levels(photons, radius, stats);
    for (int k = 1; k < kRadiusLevels; ++k)
        stats.counters["photons_radius_level_" + std::to_string(k)] += double(levels.count[k]);
    const size_t moved = photons.photons.size() - levels.count[0];
    if (moved > 0) {
        // (and the mask of the samples a level lit, whose coverage its correction measures)
        budget.reserve("radius_level_photons",
                       double(moved) * sizeof(Photon) +
                           (caustics_output ? 2.0 : 1.0) * predict_per_sample_light_bytes(samples) + double(samples),
                       "photons");
        for (int k = 1; k < kRadiusLevels; ++k) {
            dense.emplace_back();
            dense.back().emitted = photons.emitted;
            dense.back().aimed = photons.aimed;
            dense.back().photons.reserve(levels.count[k]);
        }
        size_t kept = 0;  // the ordinary ones compacted in place, in their (Morton) order
        for (size_t i = 0; i < photons.photons.size(); ++i) {
            if (levels.level[i] == 0) photons.photons[kept++] = photons.photons[i];
            else dense[levels.level[i] - 1].photons.push_back(photons.photons[i]);
        }
        photons.photons.resize(kept);
        double bytes = 0.0;
        for (const PhotonMap& m : dense) bytes += double(m.bytes());
        stats.bytes["radius_level_photons"] = bytes;
    }
    budget.release("radius_levels");
    return dense;
}

// Stages 5–6½: the ordinary photons splatted with the iteration's radius, then each level's with its own.
// Without levels, exactly the one splat of the iteration's radius.
SplatLight splat_levels(const Scene& scene, const Splatter& splatter, const SplatFrame& frame, const PhotonMap& photons,
                        const std::vector<PhotonMap>& dense, const SplatParams& params, bool caustics_output,
                        const RenderSettings& settings, uint64_t seed, double begin, double end,
                        RenderControl& control, Stats& stats) {
    // The progress from `begin` to `end`, shared by the splats in proportion to their photons.
    double total = double(photons.photons.size());
    for (const PhotonMap& m : dense) total += double(m.photons.size());
    const auto share = [&](const PhotonMap& m) { return total > 0.0 ? (end - begin) * m.photons.size() / total : 0.0; };
    SplatLight light;
    double at = dense.empty() ? end : begin + share(photons);
    splat_one_radius(scene, splatter, frame, photons, params, 0, caustics_output, settings, seed, begin, at, light,
                     control, stats);
    for (size_t k = 0; k < dense.size(); ++k) {
        if (dense[k].photons.empty()) continue;
        SplatParams level = params;
        level.radius = level_radius(params.radius, static_cast<int>(k) + 1);
        const double from = at;
        at = std::min(end, at + share(dense[k]));
        splat_one_radius(scene, splatter, frame, dense[k], level, static_cast<int>(k) + 1, caustics_output, settings,
                         seed, from, at, light, control, stats);
    }
    return light;
}

// The photons the view samples' splat takes: all but those stored for the far sides of translucent surfaces
// alone (kFarSideOnly, photons.h), taken out of the map in place.
void keep_reflected_photons(PhotonMap& photons) {
    std::vector<Photon>& v = photons.photons;
    v.erase(std::remove_if(v.begin(), v.end(), [](const Photon& p) { return (p.flags & kFarSideOnly) != 0; }),
            v.end());
}

// The light of the far sides of translucent surfaces (ViewSamples::far_side): the caustic photons stored on them
// (kFarSidePhoton), gathered from a hashed grid (splat/gather.cpp) whatever the settings' method, exact like the
// splat of the view samples, with the same radius and boundary correction. Empty where no camera path scattered
// through translucency. Its structures are reserved in the budget as one, "far_side_gather".
std::vector<glm::vec3> gather_far_sides(const Scene& scene, const ViewSamples& samples, const Camera& camera,
                                        int threads, const PhotonMap& photons, const RenderSettings& settings,
                                        const SplatParams& params, uint64_t seed, MemoryBudget& budget,
                                        RenderControl& control, Stats& stats) {
    if (samples.far_side.empty()) return {};
    StageTimer timer(stats, "far_side_gather");
    size_t count = 0;
    for (const Photon& p : photons.photons) count += (p.flags & kFarSidePhoton) != 0 ? 1 : 0;
    RenderSettings gather_settings = settings;
    gather_settings.method = SplatMethod::gather;
    const std::unique_ptr<Splatter> gather = make_splatter(gather_settings);
    ViewSamples sides;
    sides.width = samples.width;
    sides.height = samples.height;
    sides.origin = samples.origin;
    const size_t n = samples.far_side.size();
    const SplatFrame frame{sides, camera, nullptr, 0, threads};
    double predicted = double(count) * sizeof(Photon) + double(n) * (sizeof(ViewSample) + sizeof(glm::vec3)) +
                       predict_kernel_coverage_bytes(n) + double(samples.width) * samples.height * sizeof(uint32_t);
    for (const auto& [structure, bytes] : gather->predict_memory(frame, count, params).fixed) predicted += bytes;
    budget.reserve("far_side_gather", predicted, "resolution");
    sides.samples = samples.far_side;
    PhotonMap caustic;
    caustic.emitted = photons.emitted;
    caustic.aimed = photons.aimed;
    caustic.photons.reserve(count);
    for (const Photon& p : photons.photons)
        if (p.flags & kFarSidePhoton) caustic.photons.push_back(p);
    Stats own;  // the gather's counters and bytes, apart from the splat's of the same names
    SplatEstimate light = gather->splat(frame, caustic, params, control, own);
    if (settings.boundary_correction && !caustic.photons.empty()) {
        const std::vector<float> coverage = kernel_coverage(scene, sides, params, seed, control, own);
        for (size_t i = 0; i < n; ++i) light.radiance[i] /= coverage[i];
    }
    double measured = double(caustic.photons.capacity()) * sizeof(Photon) +
                      double(sides.samples.capacity()) * sizeof(ViewSample) +
                      double(light.radiance.capacity()) * sizeof(glm::vec3);
    for (const auto& [structure, bytes] : own.bytes) measured += bytes;
    stats.bytes["far_side_gather"] = measured;
    stats.counters["far_side_samples"] += double(n);
    stats.counters["far_side_photons"] += double(count);
    return std::move(light.radiance);
}

// Runs body(first, last) over [0, pixels) in blocks, in parallel.
template <typename Body>
void for_pixel_blocks(size_t pixels, const Body& body) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels, 16384),
                      [&](const tbb::blocked_range<size_t>& r) { body(r.begin(), r.end()); });
}

// A per-sample light summed into its pixels (a pixel's samples add up: view_samples.h), 3 floats a pixel. The
// samples come in pixel order, so a block of pixels owns one range of samples: blocks are summed in parallel,
// each pixel's samples in their order (the same bits as one thread).
std::vector<float> pixel_sums(const ViewSamples& samples, const std::vector<glm::vec3>& light, size_t pixels) {
    std::vector<float> image(pixels * 3, 0.0f);
    const std::vector<ViewSample>& v = samples.samples;
    const auto first_of = [&](size_t pixel) {
        const auto before = [&](const ViewSample& s) { return s.pixel < pixel; };
        return std::partition_point(v.begin(), v.end(), before) - v.begin();
    };
    for_pixel_blocks(pixels, [&](size_t first, size_t last) {
        for (size_t i = size_t(first_of(first)), end = size_t(first_of(last)); i < end; ++i) {
            const size_t p = v[i].pixel;
            for (int c = 0; c < 3; ++c) image[3 * p + c] += light[i][c];
        }
    });
    return image;
}

// Stage 7: the film's outputs from the view samples and the light at them.
Film develop_film(const ViewSamples& samples, const std::vector<glm::vec3>& direct,
                  const std::vector<glm::vec3>& indirect, const std::vector<glm::vec3>* caustics,
                  const std::vector<glm::vec3>& far_sides, const RenderSettings& settings, Stats& stats) {
    const size_t pixels = static_cast<size_t>(samples.width) * samples.height;
    Film film(samples.width, samples.height, requested_outputs(settings));
    std::vector<float> emission(pixels * 3, 0.0f);
    for_pixel_blocks(pixels, [&](size_t first, size_t last) {
        for (size_t p = first; p < last; ++p) {
            // With film transparency a camera ray that escapes straight to the world shows nothing (Cycles): the
            // background seen through glass or in mirrors stays.
            const bool escaped = samples.alpha[p] == 0.0f;
            if (!(settings.transparent && escaped))
                for (int c = 0; c < 3; ++c) emission[3 * p + c] = samples.emission[p][c];
            if (escaped) continue;
            if (film.has(FilmOutput::normal))
                for (int c = 0; c < 3; ++c) film[FilmOutput::normal][3 * p + c] = samples.first_normal[p][c];
            if (film.has(FilmOutput::depth)) film[FilmOutput::depth][p] = samples.first_depth[p];
        }
    });
    std::vector<float> direct_image = pixel_sums(samples, direct, pixels);
    // Direct light that reached the camera through rough transmission (view_samples.h) is direct light too.
    if (!samples.transmitted_direct.empty())
        for (size_t p = 0; p < pixels; ++p)
            for (int c = 0; c < 3; ++c) direct_image[3 * p + c] += samples.transmitted_direct[p][c];
    std::vector<float> indirect_image = pixel_sums(samples, indirect, pixels);
    // The far sides' caustic light (gather_far_sides), in pixel order.
    const auto add_far_sides = [&](std::vector<float>& image) {
        for (size_t i = 0; i < far_sides.size(); ++i)
            for (int c = 0; c < 3; ++c) image[3 * samples.far_side[i].pixel + c] += far_sides[i][c];
    };
    add_far_sides(indirect_image);
    std::vector<float>& rgba = film[FilmOutput::combined];
    for_pixel_blocks(pixels, [&](size_t first, size_t last) {
        for (size_t p = first; p < last; ++p) {
            for (int c = 0; c < 3; ++c)
                rgba[4 * p + c] = emission[3 * p + c] + direct_image[3 * p + c] + indirect_image[3 * p + c];
            rgba[4 * p + 3] = settings.transparent ? samples.alpha[p] : 1.0f;
        }
    });
    if (film.has(FilmOutput::emission)) film[FilmOutput::emission] = std::move(emission);
    if (film.has(FilmOutput::direct)) film[FilmOutput::direct] = std::move(direct_image);
    if (film.has(FilmOutput::indirect)) film[FilmOutput::indirect] = std::move(indirect_image);
    if (caustics && film.has(FilmOutput::caustics)) {
        // The caustic photons' light, but all of a kCausticSample's (view_samples.h), and what camera paths found
        // beyond translucency and a glossy part.
        std::vector<float> image = pixel_sums(samples, *caustics, pixels);
        for (size_t i = 0; i < samples.samples.size(); ++i) {
            const ViewSample& s = samples.samples[i];
            if (!(s.flags & kCausticSample)) continue;
            const glm::vec3 rest = direct[i] + indirect[i] - (*caustics)[i];
            for (int c = 0; c < 3; ++c) image[3 * s.pixel + c] += rest[c];
        }
        for (size_t p = 0; p < samples.caustic_emission.size(); ++p)
            for (int c = 0; c < 3; ++c) image[3 * p + c] += samples.caustic_emission[p][c];
        // Cycles' Caustics toggles remove it whole: it reached a diffuse-labelled scatter (translucency) through
        // mirrors and sharp glass alone.
        add_far_sides(image);
        film[FilmOutput::caustics] = std::move(image);
    }
    // The film, and the images combined was summed from that it does not keep.
    stats.bytes["image"] =
        double(film.bytes() + (emission.size() + direct_image.size() + indirect_image.size()) * sizeof(float));
    return film;
}


// The sphere around the view samples and the far sides of translucency (render space), where photons are useful
// (radius 0 without samples).
void view_sample_sphere(const ViewSamples& samples, glm::vec3& center, float& radius) {
    radius = 0.0f;
    if (samples.samples.empty() && samples.far_side.empty()) return;
    glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
    for (const std::vector<ViewSample>* list : {&samples.samples, &samples.far_side})
        for (const ViewSample& s : *list) {
            lo = glm::min(lo, s.position);
            hi = glm::max(hi, s.position);
        }
    center = samples.origin + 0.5f * (lo + hi);
    radius = 0.5f * glm::length(hi - lo);
    if (!std::isfinite(radius) || !std::isfinite(center.x + center.y + center.z)) radius = 0.0f;
}

}  // namespace

RenderResult render_iteration(const Scene& scene, const Camera& world_camera, const RenderSettings& settings,
                              const IterationParams& iteration, RenderControl& control) {
    validate(settings);
    const Camera camera = world_camera.relative_to(scene.origin());  // every stage works in render space
    scene.set_shader_camera(world_camera.shader_camera());
    const std::unique_ptr<Splatter> splatter = make_splatter(settings);
    RenderResult result;
    const size_t pixels = static_cast<size_t>(camera.width()) * camera.height();
    Stats& stats = result.stats;
    // Every large structure is predicted before it is allocated: a frame that cannot fit is refused here.
    MemoryBudget budget(settings.memory_budget, stats);
    reserve_frame(budget, scene, camera, settings);
    const uint64_t seed = iteration_seed(settings.seed, iteration.index);
    stats.values["radius"] = iteration.radius;
    stats.values["photons"] = static_cast<double>(settings.photons);
    stats.values["width"] = camera.width();
    stats.values["height"] = camera.height();

    tbb::task_arena arena(settings.threads > 0 ? settings.threads : tbb::task_arena::automatic);
    arena.execute([&] {
        StageTimer total(stats, "total");
        control.begin_stage("scene", 0.0, 0.02);
        report_scene(scene, stats);
        control.check();

        // 1. View samples: camera paths to their first diffuse or glossy hit.
        control.begin_stage("view samples", 0.02, 0.15);
        ViewSampleSettings view_settings;
        view_settings.seed = seed;
        view_settings.jitter = iteration.index > 0;
        view_settings.sequence_seed = settings.seed;
        view_settings.pass = iteration.index;
        view_settings.max_specular_depth = settings.max_bounces;
        view_settings.samples_per_light = settings.direct_samples;
        const ViewSamples samples = generate_view_samples(scene, camera, view_settings, control, stats);
        reserve_split_samples(budget, settings, pixels, samples.samples.size(), samples.lobes.size(),
                              !samples.transmitted_direct.empty(), samples.terminator.size(), samples.far_side.size());

        // 2. Direct light at the view samples.
        control.begin_stage("direct light", 0.15, 0.35);
        DirectLightSettings direct_settings;
        direct_settings.seed = seed;
        direct_settings.samples_per_light = settings.direct_samples;
        direct_settings.sequence_seed = settings.seed;
        direct_settings.iteration = iteration.index;
        const std::vector<glm::vec3> direct = compute_direct_light(scene, samples, direct_settings, control, stats);
        const bool caustics_output = contains(requested_outputs(settings), FilmOutput::caustics);
        // The Caustics output takes whole what reaches samples after translucency by the parts Cycles drops there.
        const std::vector<glm::vec3> dropped_direct =
            caustics_output ? compute_dropped_direct_light(scene, samples, direct_settings, control, stats)
                            : std::vector<glm::vec3>();
        stats.bytes["direct_light"] =
            static_cast<double>((direct.capacity() + dropped_direct.capacity()) * sizeof(glm::vec3));

        // 4. Photons (before the hierarchy, whose memory is reserved already, so that the splat's is known).
        control.begin_stage("photons", 0.35, 0.45);
        PhotonSettings photon_settings;
        photon_settings.count = settings.photons;
        photon_settings.max_bounces = settings.max_bounces;
        photon_settings.seed = seed;
        photon_settings.guide = settings.guide_photons;
        photon_settings.aimed_fraction = settings.aimed_photons;
        photon_settings.caustic_shares = caustics_output;
        view_sample_sphere(samples, photon_settings.focus_center, photon_settings.focus_radius);
        PhotonMap photons = trace_photons(scene, photon_settings, control, stats);
        // The far sides of translucent surfaces take their caustic photons first; the rest of the pipeline the
        // photons the view samples receive.
        const std::vector<glm::vec3> far_sides =
            gather_far_sides(scene, samples, camera, arena.max_concurrency(), photons, settings,
                             splat_params(settings, iteration.radius, photons.emitted), seed, budget, control, stats);
        keep_reflected_photons(photons);
        // 4½. Photons that gather densely after glossy or sharp parts take a smaller radius (photon_density.h).
        const size_t photon_count = photons.photons.size();  // the splat's pairs are bounded for all of them
        const std::vector<PhotonMap> dense = split_radius_levels(photons, iteration.radius, samples.samples.size(),
                                                                 caustics_output, settings, budget, stats);

        // 3. The cluster hierarchy, if the method splats onto one.
        const std::optional<ClusterHierarchy> hierarchy = build_hierarchy(*splatter, samples, camera, control, stats);

        // 5–6½. Splat, each radius level with its own radius and boundary correction.
        SplatFrame frame{samples, camera, hierarchy ? &*hierarchy : nullptr, iteration.index, arena.max_concurrency()};
        SplatParams params = splat_params(settings, iteration.radius, photons.emitted);
        params.max_pairs_in_memory =
            fit_pair_cap(budget, splatter->predict_memory(frame, photon_count, params));
        SplatLight light = splat_levels(scene, *splatter, frame, photons, dense, params, caustics_output, settings,
                                        seed, hierarchy ? 0.5 : 0.45, 0.98, control, stats);
        result.kernel_estimate = light.kernel_estimate;
        for (size_t i = 0; i < dropped_direct.size(); ++i) light.caustic[i] += dropped_direct[i];
        stats.bytes["indirect_light"] = static_cast<double>(light.indirect.capacity() * sizeof(glm::vec3));

        // 7. The film.
        control.begin_stage("image", 0.98, 1.0);
        StageTimer t(stats, "image");
        result.film = develop_film(samples, direct, light.indirect, caustics_output ? &light.caustic : nullptr,
                                   far_sides, settings, stats);
        // Validation bounds every input, but products of extreme ones (1e10 W over a 1e15 m scene) can still leave
        // float's range: say so rather than hand back a frame with infinities in it.
        size_t overflowed = 0;
        for (float v : result.rgba()) overflowed += std::isfinite(v) ? 0 : 1;
        if (overflowed > 0)
            throw InvalidInput("scene", std::to_string(overflowed) + " pixel values overflowed the float range; lower "
                                        "light strengths, emission or the background, or the scene's size");
    });
    control.begin_stage("done", 1.0, 1.0);
    return result;
}

RenderResult render(const Scene& scene, const Camera& camera, const RenderSettings& settings, RenderControl& control) {
    validate(settings);
    if (settings.iterations != 1) return render_progressive(scene, camera, settings, control);
    IterationParams iteration;
    iteration.radius = first_radius(scene, camera, settings);
    RenderResult result = render_iteration(scene, camera, settings, iteration, control);
    result.stats.values["iterations"] = 1.0;
    return result;
}

}  // namespace ps
