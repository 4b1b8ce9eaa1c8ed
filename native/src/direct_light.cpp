#include "photonsplat/direct_light.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/lights.h"
#include "photonsplat/material_program.h"
#include "photonsplat/materials.h"
#include "photonsplat/light_sources.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/render_control.h"
#include "photonsplat/rng.h"
#include "photonsplat/sample_sequence.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/splat.h"
#include "photonsplat/stats.h"
#include "photonsplat/view_samples.h"

namespace ps {

namespace {

// A light's samples at a view sample are stratified over the (u1, u2) square its sampling maps to a point or a
// direction: a √n × √n jittered grid when n is a square (the default 4: 2 × 2), else n strips along u1. Each
// sample stays uniform within its cell and the cells are equal, so the estimate keeps its expectation; what
// changes is that the n samples cover the light (or the sky's hemisphere) evenly instead of clumping, which
// lowers the noise of partly hidden lights: soft shadows, the sky seen through an opening.
struct StrataGrid {
    int columns = 1, rows = 1;
    void place(int k, float& u1, float& u2) const {
        if (columns * rows == 1) return;
        constexpr float kBelowOne = 0x1.fffffep-1f;  // (cell + u) / cells may round up to 1 otherwise
        u1 = std::min((static_cast<float>(k % columns) + u1) / static_cast<float>(columns), kBelowOne);
        u2 = std::min((static_cast<float>(k / columns) + u2) / static_cast<float>(rows), kBelowOne);
    }
};

StrataGrid strata_grid(int n) {
    const int side = static_cast<int>(std::lround(std::sqrt(static_cast<double>(n))));
    if (side * side == n) return {side, side};
    return {n, 1};
}

constexpr float kInvPi = 0.318309886183790671538f;

bool is_black(const glm::vec3& v) { return v.x <= 0.0f && v.y <= 0.0f && v.z <= 0.0f; }

// The view sample's stored reflection parts as a BSDF (the transmission parts went on along the camera path),
// written into `b` (reused from sample to sample: its lobes are only written where the sample has them).
void bsdf_of(const ViewSample& s, const std::vector<Lobe>& lobes, Bsdf& b) {
    b.n = s.shading_normal;
    b.ng = s.normal;
    b.wo = s.wo;
    b.smooth_n = s.smooth_normal;
    b.bump_shadowed = (s.flags & kBumpShadowed) != 0;
    b.bump_form = bump_form_of(s.flags);
    b.lambert = s.albedo;
    // The splat's lobes and the narrow ones after them (view_samples.h): direct light takes them all.
    b.lobe_count = static_cast<int>(std::min<uint32_t>(uint32_t(s.lobe_count) + s.branched_lobes, kMaxLobes));
    for (int k = 0; k < b.lobe_count; ++k) b.lobes[k] = lobes[s.lobe_begin + static_cast<uint32_t>(k)];
    b.selection_floor = 0.0f;
    if (!(s.flags & kViaSpecular)) choose_defensively(b);  // the camera's first hit; its reflection parts only
}

}  // namespace

// A programmed world's light samples per view sample, in units of direct_samples (see direct_light_at).
constexpr int kWorldSampleFactor = 2;
// Transparent surfaces a shadow ray or a BSDF probe passes before it counts as blocked.
constexpr int kMaxCrossings = 64;

float power_heuristic(float chosen, float other) {
    if (!(other > 0.0f)) return 1.0f;
    const float a = chosen * chosen, b = other * other;
    return std::isfinite(a + b) ? a / (a + b) : (chosen >= other ? 1.0f : 0.0f);
}

float mirror_emitter_weight(float mirror_pdf, float light_pdf) {
    return mirror_pdf > 0.0f ? power_heuristic(mirror_pdf, light_pdf) : 1.0f;
}

bool scene_has_transparency(const Scene& scene) {
    for (const Material& m : scene.materials())
        if (m.transparent) return true;
    return false;
}

ShadowSegment shadow_segment(const glm::vec3& x, const glm::vec3& origin, const LightIncidence& in) {
    constexpr float kShortOfLight = 1e-4f;
    ShadowSegment out{Ray{origin, in.wi}, in.distance * (1.0f - kShortOfLight)};
    if (!std::isfinite(in.distance)) return out;
    const glm::vec3 to_light = (x + in.distance * in.wi) - origin;
    const float d = glm::length(to_light);
    if (!(d > 0.0f) || !std::isfinite(d)) return out;
    out.ray.direction = to_light / d;
    out.t_max = d * (1.0f - kShortOfLight);
    return out;
}

glm::vec3 shadow_transmittance(const Scene& scene, const Ray& ray, float t_max, bool transparency) {
    const RayTracer& tracer = scene.ray_tracer();
    if (!transparency) return tracer.occluded(ray, 0.0f, t_max, kShadowRays) ? glm::vec3(0.0f) : glm::vec3(1.0f);
    // Step through the surfaces on the way, multiplying their transparent weights (Cycles' transparent shadows,
    // up to its default of 8 transparent bounces... we allow more: the loop ends at the first opaque surface).
    glm::vec3 transmittance(1.0f);
    Ray r = ray;
    float remaining = t_max;
    for (int k = 0; k < kMaxCrossings; ++k) {
        Hit hit;
        if (!tracer.intersect(r, 0.0f, remaining, hit, kShadowRays)) return transmittance;
        if (!scene.materials()[scene.meshes()[scene.instances()[hit.instance].mesh].materials[hit.triangle]].transparent)
            return glm::vec3(0.0f);
        const SurfacePoint s = surface_at(scene, r, hit, ShaderRay::shadow);
        const Bsdf b = shade(scene, s, -r.direction);
        transmittance *= glm::min(b.transparent, glm::vec3(1.0f));
        if (is_black(transmittance)) return glm::vec3(0.0f);
        remaining -= hit.t;
        r.origin = offset_ray_origin(s.position, -s.geometric_normal, s.rounding_scale);
        if (!(remaining > 0.0f)) return transmittance;
    }
    return glm::vec3(0.0f);
}

glm::vec3 near_mirror_light(const DirectLightContext& c, const Bsdf& b, const glm::vec3& x, float rounding_scale,
                            Rng& rng, uint64_t& rays) {
    const float alpha = b.mirror_reported_alpha;
    if (!(alpha > 0.0f) || is_black(b.mirror)) return glm::vec3(0.0f);
    const LightSources& sources = c.sources;
    const RayTracer& tracer = c.scene.ray_tracer();
    const glm::vec3 origin = offset_ray_origin(x, b.ng, rounding_scale);
    glm::vec3 sum(0.0f);
    for (size_t l = 0; l < sources.size(); ++l) {
        if (sources.light(l) == nullptr) continue;  // lamps only
        const bool delta = sources.is_delta(l);
        const int n = delta ? 1 : std::max(1, c.samples_per_light);
        const StrataGrid grid = strata_grid(n);
        glm::vec3 light_sum(0.0f);
        for (int k = 0; k < n; ++k) {
            float u1 = rng.uniform(), u2 = rng.uniform();
            const float u3 = rng.uniform();
            grid.place(k, u1, u2);
            const LightIncidence in = sources.sample_incidence(l, x, b.ng, u1, u2, u3);
            if (!(glm::dot(in.wi, b.ng) > 0.0f) || is_black(in.value)) continue;
            const Cycles3MirrorValue v = cycles3_multiscatter_mirror_eval(alpha, b.n, in.wi, b.wo);
            if (!(v.f > 0.0f)) continue;
            const float w = !sources.mis_with_bsdf_rays(l)
                                ? 1.0f
                                : power_heuristic(sources.cycles_lamp_pdf(l, x, in.wi), v.pdf);
            const float scale = v.f * glm::dot(in.wi, b.n) * w;
            if (!(scale > 0.0f) || !std::isfinite(scale)) continue;
            ++rays;
            const ShadowSegment segment = shadow_segment(x, origin, in);
            const glm::vec3 t = !sources.casts_shadow(l) ? glm::vec3(1.0f)  // Cast Shadow off
                                : c.transparency ? shadow_transmittance(c.scene, segment.ray, segment.t_max, true)
                                                 : (tracer.occluded(segment.ray, 0.0f, segment.t_max, kShadowRays)
                                                        ? glm::vec3(0.0f)
                                                        : glm::vec3(1.0f));
            light_sum += in.value * t * scale;
        }
        sum += light_sum / static_cast<float>(n);
    }
    return b.mirror * sum;
}

glm::vec3 direct_light_at(const DirectLightContext& c, const Bsdf& b, const glm::vec3& x, float rounding_scale,
                          LobeSet set, Rng& rng, uint64_t& rays, const DirectLightSequences& sequences,
                          const TerminatorLift* terminator) {
    const Scene& scene = c.scene;
    const LightSources& sources = c.sources;
    const int samples_per_light = c.samples_per_light;
    const bool transparency = c.transparency;
    const bool transmission = set == LobeSet::transmission;
    const glm::vec3 side = transmission ? -b.ng : b.ng;  // light must arrive on this side of the surface
    const bool mis = transmission || b.directional();
    const glm::vec3 origin = offset_ray_origin(x, side, rounding_scale);
    const RayTracer& tracer = scene.ray_tracer();
    // Where b holds a clearcoat or Multiscatter GGX glass, a light's density in the MIS weights is the one Cycles
    // gives it, its pick included (bsdf_weighs_by_cycles_pick, shading.h; LightSources::cycles_mis_density).
    const bool cycles_weights = bsdf_weighs_by_cycles_pick(b);
    const auto mis_pick = [cycles_weights](float cycles_pick) { return cycles_weights ? cycles_pick : 1.0f; };
    glm::vec3 sum(0.0f);
    bool any_area = false;
    const bool world_constant = sources.world().constant();
    bool world_sampled = false;  // a programmed world among the sources: its BSDF directions always run
    for (size_t l = 0; l < sources.size(); ++l) world_sampled = world_sampled || (sources.is_world(l) && !world_constant);
    // BSDF directions: as many as light samples where the BSDF has lobes (a highlight is theirs to find); on a
    // Lambert surface only a programmed world needs them, for what its map under-weights, and one does: the map
    // takes nearly all of a Lambert surface's light.
    const int probes = mis ? std::max(1, samples_per_light) : 1;
    // A programmed world takes twice the light samples of a light: its map is what most surfaces see (an HDRI's
    // sun, sky and ground at once) and a sample costs less than the photons' share of an iteration.
    const int world_samples = kWorldSampleFactor * std::max(1, samples_per_light);
    for (size_t l = 0; l < sources.size(); ++l) {
        const bool delta = sources.is_delta(l);
        any_area = any_area || !delta;
        const int n = delta ? 1 : (sources.is_world(l) && !world_constant ? world_samples : samples_per_light);
        const StrataGrid grid = strata_grid(n);
        glm::vec3 light_sum(0.0f);
        const bool sequenced = sequences.light != nullptr && sources.is_world(l) && !world_constant;
        // Each sample's direction, value and weight first, then their shadow rays, summed in the samples' order as
        // one by one. Towards a lamp (from one point to one small region) they are coherent and go as a packet:
        // the atrium's direct light (sun and sky) took 0.9 of the time so. The sky's directions spread over the
        // hemisphere, where a packet took 1.2 times as long as single rays: those go one by one.
        const bool coherent = !sources.is_world(l);
        Ray shadow[RayTracer::kPacketRays];
        float t_min[RayTracer::kPacketRays], t_max[RayTracer::kPacketRays];
        glm::vec3 value[RayTracer::kPacketRays];
        float scale[RayTracer::kPacketRays];
        int pending = 0;
        // A light with Cast Shadow off takes no shadow ray (Light::cast_shadow): every sample counts.
        const bool shadowed = sources.casts_shadow(l);
        // Multiple Importance off: the BSDF directions below never meet the light, so its samples take weight 1.
        const bool light_mis = sources.mis_with_bsdf_rays(l);
        const auto trace_pending = [&] {
            if (!shadowed) {
                for (int j = 0; j < pending; ++j) light_sum += value[j] * scale[j];
            } else if (transparency) {
                for (int j = 0; j < pending; ++j) {
                    const glm::vec3 t = shadow_transmittance(scene, shadow[j], t_max[j], true);
                    if (!is_black(t)) light_sum += value[j] * t * scale[j];
                }
            } else if (!coherent) {
                for (int j = 0; j < pending; ++j)
                    if (!tracer.occluded(shadow[j], t_min[j], t_max[j], kShadowRays)) light_sum += value[j] * scale[j];
            } else {
                bool blocked[RayTracer::kPacketRays];
                tracer.occluded(shadow, t_min, t_max, pending, kShadowRays, blocked);
                for (int j = 0; j < pending; ++j)
                    if (!blocked[j]) light_sum += value[j] * scale[j];
            }
            pending = 0;
        };
        for (int k = 0; k < n; ++k) {
            float u1 = rng.uniform(), u2 = rng.uniform();
            float u3 = rng.uniform();
            if (sequenced)
                sequences.light->point(sequences.iteration * uint32_t(n) + uint32_t(k), u1, u2, u3);
            else
                grid.place(k, u1, u2);
            const LightIncidence in = sources.sample_incidence(l, x, side, u1, u2, u3);
            if (is_black(in.value)) continue;
            // Under the triangle's horizon but above the shading normal's, Cycles traces a light sample from the
            // smooth surface where its object has a terminator offset (shadow_terminator.h), else drops it.
            const bool below = !(glm::dot(in.wi, side) > 0.0f);
            if (below && !(terminator != nullptr && terminator_reaches_below(*terminator, b.n, side, in.wi))) continue;
            const float cos_shading = std::fabs(glm::dot(in.wi, b.n));
            // The shading normal only weights the light; on the reflection side it must agree with the geometric.
            if (!transmission && !(glm::dot(in.wi, b.n) > 0.0f)) continue;
            // The constant world is sampled cosine-weighted, which is the Lambert part's own sampling: light
            // samples take that part (weight 1), the BSDF's directions below take the lobes (weight 1). A
            // programmed world is sampled by its map: the whole BSDF, weighted against the BSDF's directions.
            const bool world = sources.is_world(l) && world_constant;
            const bool weighted = (mis || sources.is_world(l)) && !world;
            const glm::vec3 f = below      ? bsdf_eval_shading_side(b, in.wi, set, scene.multiscatter_light_estimate())
                                : weighted ? bsdf_eval(b, in.wi, set, scene.multiscatter_light_estimate())
                                           : (transmission ? glm::vec3(0.0f) : b.lambert * (kInvPi * bump_shadowing_of(b, in.wi)));
            if (is_black(f)) continue;
            ++rays;
            // The BSDF takes `probes` directions against this light's n: the power heuristic over the counts.
            const float p_light = cycles_weights ? sources.cycles_mis_density(l, x, in.wi, in.pdf) : in.pdf;
            const float p_bsdf = (!light_mis || !weighted) ? 0.0f : bsdf_pdf(b, in.wi, set);
            const float w = (!light_mis || !weighted) ? 1.0f
                            : probes == n        ? power_heuristic(p_light, p_bsdf)
                                                 : power_heuristic(float(n) * p_light, float(probes) * p_bsdf);
            const ShadowSegment segment =
                terminator == nullptr
                    ? shadow_segment(x, origin, in)
                    : shadow_segment(x, offset_ray_origin(terminator_origin(x, *terminator, b.n, side, in.wi), side,
                                                          rounding_scale), in);
            shadow[pending] = segment.ray;
            t_min[pending] = 0.0f;
            t_max[pending] = segment.t_max;
            value[pending] = f * in.value;
            scale[pending] = cos_shading * w;
            if (++pending == RayTracer::kPacketRays) trace_pending();
        }
        trace_pending();
        sum += light_sum / static_cast<float>(n);
    }
    if (!((mis && any_area) || world_sampled)) return sum;

    // The BSDF's own directions, each adding the first emitter it meets, weighted against light sampling.
    const int m = probes;
    glm::vec3 bsdf_sum(0.0f);
    const StrataGrid probe_grid = strata_grid(m);
    for (int k = 0; k < m; ++k) {
        float u0 = rng.uniform();
        float u1 = rng.uniform(), u2 = rng.uniform();
        if (world_sampled && sequences.bsdf != nullptr)
            sequences.bsdf->point(sequences.iteration * uint32_t(m) + uint32_t(k), u1, u2, u0);
        else
            probe_grid.place(k, u1, u2);
        const BsdfSample bs = bsdf_sample_set(b, set, u0, u1, u2);
        if (bs.kind != ScatterKind::lobes || !(glm::dot(bs.direction, side) > 0.0f)) continue;
        ++rays;
        // The probe goes on through transparent surfaces as a shadow ray does (shadow_transmittance), each
        // segment with the transparency left after the crossings before it: a light or emitter met beyond a
        // transparent surface is the one light sampling found through it, and without this its BSDF share was
        // lost (a glossy floor under an area light behind a clear sheet: 0.55 of the same without the sheet).
        Ray ray{origin, bs.direction};
        glm::vec3 through(1.0f);  // transparency of the crossings so far
        float travelled = 0.0f;   // from origin to ray.origin
        Hit hit;
        bool found = false;
        for (int crossing = 0;; ++crossing) {
            found = tracer.intersect(ray, 0.0f, std::numeric_limits<float>::infinity(), hit, kIndirectRays);
            for (size_t l = 0; l < sources.size() && mis; ++l) {
                const Light* light = sources.light(l);
                if (!light || !sources.mis_with_bsdf_rays(l)) continue;
                const LightHit h = intersect_light(*light, x, bs.direction);
                if (!h.hit || !(h.distance >= travelled) || (found && !(h.distance < travelled + hit.t))) continue;
                const float p_light = cycles_weights ? sources.cycles_mis_density(l, x, bs.direction, h.pdf) : h.pdf;
                bsdf_sum += bs.weight * through * h.radiance * power_heuristic(bs.mis_pdf, p_light);
            }
            if (!found) break;
            const Material& material =
                scene.materials()[scene.meshes()[scene.instances()[hit.instance].mesh].materials[hit.triangle]];
            if (mis && (!is_black(material.emission) || material.program_emission) && !material.holdout) {
                const glm::vec3 y = ray.origin + hit.t * ray.direction;
                const float p_light = sources.emissive_pdf(hit.instance, hit.triangle, x, y) *
                                      mis_pick(sources.cycles_emissive_pick_probability());
                if (p_light > 0.0f) {
                    const glm::vec3 emitted = material.program_emission
                                                  ? emission_at(scene, surface_at(scene, ray, hit), -ray.direction)
                                                  : material.emission;
                    bsdf_sum += bs.weight * through * emitted * power_heuristic(bs.mis_pdf, p_light);
                }
            }
            if (!transparency || !material.transparent || crossing + 1 == kMaxCrossings) break;
            const SurfacePoint s = surface_at(scene, ray, hit, ShaderRay::shadow);
            through *= glm::min(shade(scene, s, -ray.direction).transparent, glm::vec3(1.0f));
            if (is_black(through)) break;
            travelled += hit.t;
            ray.origin = offset_ray_origin(s.position, -s.geometric_normal, s.rounding_scale);
            ++rays;
        }
        if (found) continue;  // an opaque surface, or the crossings' limit
        if (world_sampled) {
            // A programmed world: whatever the BSDF sampled, weighted against the world's map (and portals).
            const float p_light = sources.world().pdf(x, side, bs.direction) *
                                  mis_pick(sources.cycles_lamp_pick_probability());
            const float w = power_heuristic(float(m) * bs.mis_pdf, float(world_samples) * p_light);
            bsdf_sum += bs.weight * through * world_radiance(scene, bs.direction, ShaderRay::reflected) * w;
        } else {
            // The world: the lobes' part only (light sampling took Lambert's), f_lobes·cos / pdf.
            glm::vec3 lobes_weight = bs.weight;
            if (!transmission) {
                const float cos_n = glm::dot(bs.direction, b.n);
                if (cos_n > 0.0f)
                    lobes_weight -= b.lambert * (kInvPi * bump_shadowing_of(b, bs.direction) * cos_n / bs.pdf);
                lobes_weight = glm::max(lobes_weight, glm::vec3(0.0f));
            }
            for (size_t l = 0; l < sources.size(); ++l)
                if (sources.is_world(l)) bsdf_sum += lobes_weight * through * scene.background();
        }
    }
    return sum + bsdf_sum / static_cast<float>(m);
}

namespace {

// Direct light at every view sample through the parts `parts(sample, b)` leaves in b, the sample's BSDF (false:
// none, the sample keeps 0), throughput included; numbers from `domain`. `progress`: the call is its stage's own.
template <typename Parts>
std::vector<glm::vec3> direct_light_through(const Scene& scene, const ViewSamples& samples,
                                            const DirectLightSettings& settings, const RenderControl& control,
                                            Stats& stats, RngDomain domain, bool progress, const Parts& parts) {
    StageTimer timer(stats, "direct_light");
    std::vector<glm::vec3> out(samples.samples.size(), glm::vec3(0.0f));
    const LightSources sources(scene);
    if (sources.size() == 0 || samples.samples.empty()) return out;
    const DirectLightContext context{scene, sources, settings.samples_per_light, scene_has_transparency(scene)};
    bool world_sampled = false;  // a programmed world: its samples follow each view sample's sequence
    for (size_t l = 0; l < sources.size(); ++l) world_sampled = world_sampled || (sources.is_world(l) && !sources.world().constant());
    std::atomic<bool> cancelled{false};
    std::atomic<uint64_t> shadow_rays{0};
    std::atomic<uint64_t> samples_done{0};

    tbb::parallel_for(tbb::blocked_range<size_t>(0, samples.samples.size(), 4096), [&](const tbb::blocked_range<size_t>& range) {
        if (cancelled.load(std::memory_order_relaxed) || control.cancel_requested()) {
            cancelled = true;
            return;
        }
        uint64_t rays = 0;
        Bsdf b;
        auto lift = std::lower_bound(samples.terminator.begin(), samples.terminator.end(), range.begin(),
                                     [](const ViewSamples::SampleLift& l, size_t i) { return l.sample < i; });
        for (size_t i = range.begin(); i < range.end(); ++i) {
            const ViewSample& s = samples.samples[i];
            bsdf_of(s, samples.lobes, b);
            if (!parts(s, b)) continue;
            // Each sample of a pixel (one per branch of its camera path) draws its own numbers.
            const uint64_t key = uint64_t(s.pixel) + (uint64_t(branch_of(s.flags)) << 32);
            Rng rng(settings.seed, domain, key);
            DirectLightSequences sequences;
            std::optional<SampleSequence> light_points, bsdf_points;
            if (world_sampled) {
                light_points.emplace(settings.sequence_seed, key, SampleSequence::kLightStream);
                bsdf_points.emplace(settings.sequence_seed, key, SampleSequence::kBsdfStream);
                sequences = {&*light_points, &*bsdf_points, settings.iteration};
            }
            // The samples' lifts are in index order: step along them with i.
            while (lift != samples.terminator.end() && lift->sample < i) ++lift;
            const TerminatorLift* terminator =
                lift != samples.terminator.end() && lift->sample == i ? &lift->lift : nullptr;
            out[i] = s.throughput * direct_light_at(context, b, s.position + samples.origin, s.rounding_scale,
                                                    LobeSet::reflection, rng, rays, sequences, terminator);
        }
        shadow_rays += rays;
        if (progress) control.advance(samples_done += range.size(), samples.samples.size());
    });
    control.check();
    stats.counters["shadow_rays"] += static_cast<double>(shadow_rays.load());
    return out;
}

}  // namespace

std::vector<glm::vec3> compute_direct_light(const Scene& scene, const ViewSamples& samples,
                                            const DirectLightSettings& settings, const RenderControl& control,
                                            Stats& stats) {
    return direct_light_through(scene, samples, settings, control, stats, RngDomain::direct_light, true,
                                [](const ViewSample&, Bsdf&) { return true; });
}

std::vector<glm::vec3> compute_dropped_direct_light(const Scene& scene, const ViewSamples& samples,
                                                    const DirectLightSettings& settings, const RenderControl& control,
                                                    Stats& stats) {
    if (std::none_of(samples.samples.begin(), samples.samples.end(), has_dropped_parts)) return {};
    // The parts Cycles drops there: all but the diffuse-labelled ones.
    const auto dropped = [](const ViewSample& s, Bsdf& b) {
        if (!has_dropped_parts(s)) return false;
        b.lambert = glm::vec3(0.0f);
        int kept = 0;
        for (int k = 0; k < b.lobe_count; ++k)
            if (!labelled_diffuse(b.lobes[k])) b.lobes[kept++] = b.lobes[k];
        b.lobe_count = kept;
        return kept > 0;
    };
    return direct_light_through(scene, samples, settings, control, stats, RngDomain::dropped_direct, false, dropped);
}

}  // namespace ps
