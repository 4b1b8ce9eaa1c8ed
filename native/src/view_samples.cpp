#include "photonsplat/view_samples.h"

#include <atomic>
#include <limits>
#include <optional>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "photonsplat/bump_shadowing.h"
#include "photonsplat/direct_light.h"
#include "photonsplat/light_sources.h"
#include "photonsplat/lights.h"
#include "photonsplat/material_program.h"
#include "photonsplat/materials.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/render_control.h"
#include "photonsplat/rng.h"
#include "photonsplat/sample_sequence.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/shading.h"
#include "photonsplat/shadow_terminator.h"
#include "photonsplat/stats.h"

namespace ps {

size_t ViewSamples::bytes() const {
    return samples.capacity() * sizeof(ViewSample) + lobes.capacity() * sizeof(Lobe) +
           terminator.capacity() * sizeof(SampleLift) + transmitted_direct.capacity() * sizeof(glm::vec3) +
           caustic_emission.capacity() * sizeof(glm::vec3) + far_side.capacity() * sizeof(ViewSample) +
           emission.capacity() * sizeof(glm::vec3) +
           alpha.capacity() * sizeof(float) + first_normal.capacity() * sizeof(glm::vec3) +
           first_depth.capacity() * sizeof(float);
}

namespace {

// Where a camera path stands between two vertices: the ray leaving the last one, the product of weights so far,
// the number of bounces behind it, and what the emitters this ray may meet are weighted by.
struct CameraPath {
    Ray ray;
    glm::vec3 throughput;
    int depth;
    uint32_t branch = 0;       // which of its pixel's branches (ViewSample flags)
    bool camera_ray = true;    // still the camera's own ray (only transparency crossed): it does not see lights
    bool split_done = false;   // the pixel's one split (at the first surface with several parts) is behind
    // The ray left a rough transmission, whose own next-event estimation found the emitters this ray may meet.
    bool after_lobe = false;
    // The ray left a mirror that reports this density for it (mirror_reported_pdf, shading.h), from mirror_x: the
    // emitters it meets take mirror_emitter_weight (direct_light.h). 0: a true mirror, or no mirror.
    float mirror_pdf = 0.0f;
    glm::vec3 mirror_x{0.0f};
    // For the Caustics output, as Cycles labels a path's scatters (kCausticSample): the last scatter was a
    // diffuse-labelled one (translucency), and a glossy, mirror or refracting part followed one.
    bool diffuse_last = false;
    bool caustic = false;
    // The last non-delta scatter was translucency, and a mirror or sharp refraction has followed it: the light
    // this ray meets (lights, emission, the world) is the far side's caustic photons' (add_far_side_sample), not
    // the path's.
    bool after_translucency = false;
    bool translucent_then_sharp = false;
};

// What the first surface a pixel's camera ray hits tells its pixel (as Cycles' passes).
struct FirstHit {
    float alpha = 0.0f;
    glm::vec3 normal{0.0f};
    float depth = 0.0f;
};

// Everything a pixel's camera paths need and fill.
struct PixelPaths {
    const Scene& scene;
    const Camera& camera;
    const ViewSampleSettings& settings;
    const LightSources* sources;  // where the scene has rough transmission, delta surfaces or lights with a size
    const DirectLightContext* direct;
    uint32_t pixel;
    Rng& rng;
    std::vector<ViewSample>& found;
    std::vector<Lobe>& found_lobes;
    std::vector<ViewSample>& found_far_side;  // ViewSamples::far_side's
    // The lifts of found's samples that have one (index within found); null unless the scene has an offset.
    std::vector<ViewSamples::SampleLift>* found_terminator;
    glm::vec3& emitted;
    glm::vec3* transmitted_direct;  // null when the scene has no rough transmission
    glm::vec3* caustic_emitted;     // ViewSamples::caustic_emission's; null when transmitted_direct is
    FirstHit& first;
    std::vector<CameraPath> pending;  // branches started at the split, traced after the current path
    uint32_t next_branch = 1;
    uint64_t rays = 0;
    // The camera ray's first hit, traced beforehand with its neighbours' as a packet; used once.
    const Hit* first_hit = nullptr;
    bool first_found = false;
};

// Emitters met by a ray that left a rough transmission were that vertex's next-event estimation's, whose own
// BSDF-sampled probes and light samples cover them, weighted against each other (direct_light.h): 0 here. Met
// through mirrors or sharp glass after translucency, they are the far side's caustic photons': 0. Met after a
// delta bounce otherwise (or by a camera ray), nothing else finds them: 1.
float emitter_weight(const CameraPath& path) { return path.after_lobe || path.translucent_then_sharp ? 0.0f : 1.0f; }

// Light a camera path found along the way (emission, background, a light): the pixel's, and the Caustics
// output's too where the path is a caustic one.
void add_emitted(PixelPaths& p, const CameraPath& path, const glm::vec3& light) {
    p.emitted += light;
    if (path.caustic && p.caustic_emitted != nullptr) *p.caustic_emitted += light;
}

// The view sample of b's reflection parts at surface s, reached by `path` (b null: a lambert_only surface of
// albedo `lambert`, seen along `wo`).
void add_view_sample(PixelPaths& p, const CameraPath& path, const SurfacePoint& s, const Bsdf* b,
                     const glm::vec3& lambert, const glm::vec3& wo, const glm::vec3& weight) {
    ViewSample sample{};
    sample.position = s.position;  // made camera-relative by the caller
    sample.normal = s.geometric_normal;
    sample.shading_normal = b ? b->n : s.shading_normal;
    sample.smooth_normal = s.smooth_normal;
    sample.rounding_scale = s.rounding_scale;
    sample.wo = wo;
    sample.albedo = lambert;
    sample.throughput = weight;
    sample.pixel = p.pixel;
    sample.flags = (path.depth > 0 ? kViaSpecular : 0u) | (std::min<uint32_t>(path.branch, 0xffu) << kBranchShift);
    sample.depth = p.first.depth;
    sample.lobe_begin = static_cast<uint32_t>(p.found_lobes.size());
    sample.lobe_count = 0;
    sample.branched_lobes = 0;
    bool diffuse_part = lambert != glm::vec3(0.0f);
    for (int k = 0; b != nullptr && k < b->lobe_count; ++k) {
        if (is_transmission(b->lobes[k]) || narrow_lobe_branches(b->lobes[k])) continue;
        p.found_lobes.push_back(b->lobes[k]);
        ++sample.lobe_count;
        diffuse_part = diffuse_part || is_diffuse_reflection(b->lobes[k]);
    }
    for (int k = 0; b != nullptr && k < b->lobe_count; ++k) {
        if (!narrow_lobe_branches(b->lobes[k])) continue;
        p.found_lobes.push_back(b->lobes[k]);
        ++sample.branched_lobes;
    }
    if (sample.lobe_count > 0) sample.flags |= kGlossy;
    if (path.depth == 0 && b != nullptr) sample.selection_floor = defensive_floor(*b);
    if (path.caustic || (path.diffuse_last && !diffuse_part)) sample.flags |= kCausticSample;
    else if (path.diffuse_last) sample.flags |= kAfterDiffuseScatter;
    if (inside_transmitter(s)) sample.flags |= kInsideSample;
    if (bump_shadowed(sample.smooth_normal, sample.shading_normal))
        sample.flags |= kBumpShadowed | bump_form_flags(p.scene.bump_shadowing(*s.material));
    p.found.push_back(sample);
    if (p.found_terminator) {
        const TerminatorLift lift = terminator_lift(p.scene, s, s.geometric_normal);
        if (lift.cutoff > 0.0f) p.found_terminator->push_back({static_cast<uint32_t>(p.found.size() - 1), lift});
    }
}

// The far side of translucent surface s, where a camera path scatters through it: a Lambert surface of b's
// translucent albedo facing the other way (translucent_albedo, shading.h), which gathers the caustic photons stored
// on that side (render.cpp). The camera path goes on through the translucency for the rest of the light there
// (and its next-event estimation takes the direct light), but the light it would find through mirrors and sharp
// glass alone, a sun's caustic, it could find only as Cycles does, by meeting the sun: fireflies (seeds 66 and 140
// of the differential scenes). It drops that light (emitter_weight), which the far side's photons carry. Its wo is
// b.wo mirrored through the surface: a Lambert part does not depend on it, and every test of sides then sees it on
// the sample's own.
void add_far_side_sample(PixelPaths& p, const CameraPath& path, const SurfacePoint& s, const Bsdf& b,
                         const glm::vec3& weight) {
    ViewSample sample{};
    sample.position = s.position;  // made camera-relative by the caller
    sample.normal = -b.ng;
    sample.shading_normal = -b.n;
    sample.smooth_normal = -b.smooth_n;
    sample.rounding_scale = s.rounding_scale;
    sample.wo = b.wo - 2.0f * glm::dot(b.wo, b.ng) * b.ng;
    sample.albedo = translucent_albedo(b);
    sample.throughput = weight;
    sample.pixel = p.pixel;
    sample.flags = (path.depth > 0 ? kViaSpecular : 0u) | (std::min<uint32_t>(path.branch, 0xffu) << kBranchShift);
    // The other side of a transmitting surface is another place: inside where the path stands outside.
    if (!inside_transmitter(s)) sample.flags |= kInsideSample;
    if (b.bump_shadowed) sample.flags |= kBumpShadowed | bump_form_flags(b.bump_form);
    sample.depth = p.first.depth;
    p.found_far_side.push_back(sample);
}

// Follows one camera path (and returns when it ends in a view sample, is absorbed, escapes or is dropped),
// adding emission, background and lights seen along the way to p.emitted. At the first surface whose BSDF has
// more than one part (lobes, mirror, refraction, transparency, rough transmission), every part is followed:
// the path ends there in the view sample of the lobes and each other part starts a branch of its own in
// p.pending, weighted by its part; this removes the speckle of glass (the reflected room in some pixels, the
// view through the glass in their neighbours) that a random choice would leave to many passes to average. At
// later surfaces one part is chosen with probability in proportion to its weight.
void trace_camera_path(PixelPaths& p, CameraPath path) {
    const Scene& scene = p.scene;
    const RayTracer& tracer = scene.ray_tracer();
    for (;;) {  // each vertex; `path` becomes the first path going on from it (one bounce deeper)
        const Ray& ray = path.ray;
        Hit hit;
        // The first segment sees what is visible to the camera, up to its far clip; later ones what is visible
        // to indirect rays.
        const bool from_camera = path.depth == 0;
        bool found;
        if (from_camera && p.first_hit != nullptr) {
            found = p.first_found;
            if (found) hit = *p.first_hit;
            p.first_hit = nullptr;
        } else {
            found = tracer.intersect(ray, 0.0f,
                                     from_camera ? p.camera.far_distance(ray) : std::numeric_limits<float>::infinity(),
                                     hit, from_camera ? kCameraRays : kIndirectRays);
        }
        // Lights with a size, seen in mirrors, through glass and rough transmission (Cycles' camera rays do not
        // see lights themselves).
        if (!path.camera_ray && emitter_weight(path) > 0.0f && p.sources != nullptr) {
            for (size_t l = 0; l < p.sources->size(); ++l) {
                const Light* light = p.sources->light(l);
                // Multiple Importance off: Cycles' rays after a bounce never meet the light (Light::multiple_importance).
                if (light == nullptr || !p.sources->mis_with_bsdf_rays(l)) continue;
                const LightHit h = intersect_light(*light, ray.origin, ray.direction);
                if (!h.hit || (found && !(h.distance < hit.t))) continue;
                const float w =
                    path.mirror_pdf > 0.0f
                        ? mirror_emitter_weight(path.mirror_pdf, p.sources->cycles_lamp_pdf(l, path.mirror_x, ray.direction))
                        : 1.0f;
                add_emitted(p, path, path.throughput * h.radiance * w);
            }
        }
        if (!found) {
            // After a rough transmission the world was that vertex's next-event estimation's, by its BSDF probes
            // alone (direct_light.h): not again here; nor after translucency and sharp parts (emitter_weight).
            if (emitter_weight(path) > 0.0f) {
                const ShaderRay kind = path.camera_ray ? ShaderRay::camera : ShaderRay::reflected;
                float w = 1.0f;
                if (path.mirror_pdf > 0.0f && p.sources != nullptr && !p.sources->world().constant() &&
                    !p.sources->world().black())
                    w = mirror_emitter_weight(path.mirror_pdf, p.sources->world().pdf(path.mirror_x,
                                                                                      glm::vec3(0.0f, 0.0f, 1.0f),
                                                                                      ray.direction) *
                                                                   p.sources->cycles_lamp_pick_probability());
                add_emitted(p, path, path.throughput * world_radiance(scene, ray.direction, kind) * w);
            }
            return;
        }
        const SurfacePoint s = surface_at(scene, ray, hit, from_camera ? ShaderRay::camera : ShaderRay::reflected);
        if (from_camera) {
            if (s.material->holdout) return;  // cut out: alpha stays 0, nothing is added
            p.first.alpha = 1.0f;
            p.first.depth = p.camera.view_depth(s.position);
            p.first.normal = s.shading_normal;  // already on the side the camera ray came from
        }
        if (s.material->emission != glm::vec3(0.0f) || s.material->program_emission) {
            float w = emitter_weight(path);
            if (path.mirror_pdf > 0.0f && p.sources != nullptr)
                w *= mirror_emitter_weight(path.mirror_pdf, p.sources->cycles_emissive_pdf(hit.instance, hit.triangle,
                                                                                           path.mirror_x, s.position));
            add_emitted(p, path, path.throughput * emission_at(scene, s, -ray.direction) * w);
        }
        if (s.material->lambert_only) {  // most surfaces: one part, the view sample, without a Bsdf to build
            add_view_sample(p, path, s, nullptr, lambert_albedo(scene, s, -ray.direction), -ray.direction, path.throughput);
            return;
        }
        Bsdf b = shade(scene, s, -ray.direction);
        if (path.depth == 0) choose_defensively(b);  // the camera's first hit (shading.h)

        // The parts and their weights (luminance of what each scatters, roughly), indexed: 0 the reflection parts
        // (the view sample), 1 the rough refraction, 2 the mirror, 3 the sharp refraction, 4 transparency, 5
        // translucency.
        constexpr int kParts = 6;
        float weight[kParts] = {0.0f, 0.0f, luminance(b.mirror), luminance(b.refraction), luminance(b.transparent), 0.0f};
        weight[0] = luminance(b.lambert);
        for (int k = 0; k < b.lobe_count; ++k) {
            const Lobe& lobe = b.lobes[k];
            weight[lobe.kind == ClosureKind::translucent ? 5 : is_transmission(lobe) ? 1 : 0] +=
                lobe_sampling_weight(lobe, b.n, b.wo);
        }
        int parts = 0;
        float total = 0.0f;
        for (float& w : weight) {
            if (!(w > 0.0f) || !std::isfinite(w)) w = 0.0f;
            parts += w > 0.0f ? 1 : 0;
            total += w;
        }
        if (parts == 0) return;  // absorbed
        const bool split = parts > 1 && p.settings.split_at_glass && !path.split_done;
        if (split) path.split_done = true;
        // Which parts go on from here, each with the factor its throughput is divided by (its probability).
        bool take[kParts] = {false, false, false, false, false, false};
        float probability[kParts] = {1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f};
        if (split) {
            for (int k = 0; k < kParts; ++k) take[k] = weight[k] > 0.0f;
        } else if (parts == 1) {
            for (int k = 0; k < kParts; ++k) take[k] = weight[k] > 0.0f;
        } else {
            float pick = p.rng.uniform() * total;
            int chosen = kParts - 1;
            for (int k = 0; k < kParts; ++k) {
                if (weight[k] > 0.0f && pick < weight[k]) {
                    chosen = k;
                    break;
                }
                pick -= weight[k];
            }
            while (!(weight[chosen] > 0.0f)) --chosen;  // rounding at the end of the range
            take[chosen] = true;
            probability[chosen] = weight[chosen] / total;
        }
        const bool can_continue = path.depth < p.settings.max_specular_depth;
        // Paths that go on from this vertex, the first of which continues this loop.
        CameraPath next[kParts];
        int next_count = 0;
        // `same_ray`: transparency, which lets the ray go on as it was (its MIS state, camera-ness and labels
        // kept). `diffuse`: the scatter is one Cycles labels diffuse (translucency).
        const auto go_on = [&](const glm::vec3& direction, const glm::vec3& w, bool transmitted, bool lobe,
                               bool same_ray = false, bool diffuse = false, float mirror_pdf = 0.0f) {
            const glm::vec3 t = path.throughput * w;
            if (!(t.x > 0.0f || t.y > 0.0f || t.z > 0.0f) || !can_continue) return;
            const glm::vec3 side = transmitted ? -s.geometric_normal : s.geometric_normal;
            CameraPath n = path;
            n.depth = path.depth + 1;
            n.ray = Ray{offset_ray_origin(s.position, side, s.rounding_scale), direction};
            n.throughput = t;
            if (!same_ray) {
                n.camera_ray = false;
                n.after_lobe = lobe;
                n.caustic = path.caustic || (path.diffuse_last && !diffuse);
                n.diffuse_last = diffuse;
                // Transparency keeps both (same_ray); a lobe's scatter sets the first anew, a delta keeps it.
                n.after_translucency = lobe ? diffuse : path.after_translucency;
                n.translucent_then_sharp = !lobe && path.after_translucency;
                n.mirror_pdf = mirror_pdf;
                n.mirror_x = s.position;
            }
            next[next_count++] = n;
        };
        if (take[0]) add_view_sample(p, path, s, &b, b.lambert, b.wo, path.throughput / probability[0]);
        const bool sampled_here = take[0];
        // Refraction first, mirror last: a pixel split at glass keeps its refracted path, the reflected one branches.
        if (take[3]) {
            glm::vec3 d;
            if (refraction_direction(b, d)) go_on(d, b.refraction / probability[3], true, false);
        }
        if (take[4]) go_on(-b.wo, b.transparent / probability[4], true, false, true);
        // Rough refraction and translucency: each its own next-event estimation here, then a sampled direction
        // on; translucency also its far side's caustic photons (add_far_side_sample).
        const auto transmit = [&](const Bsdf& part, float part_probability, bool translucency) {
            const glm::vec3 t = path.throughput / part_probability;
            if (p.direct != nullptr && p.transmitted_direct != nullptr) {
                const TerminatorLift lift =
                    p.found_terminator ? terminator_lift(p.scene, s, -s.geometric_normal) : TerminatorLift{};
                const glm::vec3 light = t * direct_light_at(*p.direct, part, s.position, s.rounding_scale,
                                                            LobeSet::transmission, p.rng, p.rays, {}, &lift);
                *p.transmitted_direct += light;
                // Its own light is a caustic one on a caustic path, or where right after translucency this surface
                // refracts (Cycles drops that closure there).
                if ((path.caustic || (path.diffuse_last && !translucency)) && p.caustic_emitted != nullptr)
                    *p.caustic_emitted += light;
            }
            if (translucency) add_far_side_sample(p, path, s, b, t);
            const float u0 = p.rng.uniform(), u1 = p.rng.uniform(), u2 = p.rng.uniform();
            const BsdfSample bs = bsdf_sample_set(part, LobeSet::transmission, u0, u1, u2);
            if (bs.kind == ScatterKind::lobes)
                go_on(bs.direction, bs.weight / part_probability, bs.transmitted, true, false, translucency);
        };
        if (take[1]) transmit(without_translucency(b), probability[1], false);
        if (take[5]) transmit(translucency_of(b), probability[5], true);
        if (take[0] && bsdf_has_branching_clearcoat(b)) {
            // A sharp clearcoat's mirror-like part, as Cycles finds it (shading.h: clearcoat_branches). Its
            // weight is small (a few % but at grazing angles), so the branch is taken with that probability
            // (Russian roulette): a room of clearcoated walls would otherwise trace every pixel's chain of
            // reflections to the depth limit. The lights it would meet are the view sample's direct light's
            // (its BSDF directions draw the clearcoat too), hence a lobe's branch.
            const float u1 = p.rng.uniform(), u2 = p.rng.uniform(), u_keep = p.rng.uniform();
            const BsdfSample cc = sample_clearcoat_branch(b, u1, u2);
            const float keep = std::min(1.0f, std::max({cc.weight.x, cc.weight.y, cc.weight.z}));
            if (cc.kind == ScatterKind::lobes && u_keep < keep)
                go_on(cc.direction, cc.weight / (keep * probability[0]), false, true);
        }
        if (take[0] && bsdf_has_narrow_lobe(b)) {
            // A lobe too narrow for photons (shading.h: narrow_lobe_branches), as a clearcoat's: Russian roulette by
            // its weight, and the lights it meets are the view sample's direct light's.
            const float u0 = p.rng.uniform(), u1 = p.rng.uniform(), u2 = p.rng.uniform(), u_keep = p.rng.uniform();
            const BsdfSample branch = sample_narrow_lobe_branch(b, u0, u1, u2);
            const float keep = std::min(1.0f, std::max({branch.weight.x, branch.weight.y, branch.weight.z}));
            if (branch.kind == ScatterKind::lobes && u_keep < keep)
                go_on(branch.direction, branch.weight / (keep * probability[0]), false, true);
        }
        if (take[2]) {
            // A near-mirror's own light samples (Cycles 3.x's Multiscatter GGX near roughness 0.02): the glow of
            // the lamps it reflects, which its reflection's rays all but drop (mirror_emitter_weight).
            if (b.mirror_reported_alpha > 0.0f && p.direct != nullptr && p.transmitted_direct != nullptr)
                *p.transmitted_direct += path.throughput / probability[2] *
                                         near_mirror_light(*p.direct, b, s.position, s.rounding_scale, p.rng, p.rays);
            go_on(mirror_direction(b), b.mirror / probability[2], false, false, false, false, mirror_reported_pdf(b));
        }
        if (next_count == 0) return;
        // Every sample of a pixel needs its own branch number (its random numbers in later stages).
        if (sampled_here) next[0].branch = p.next_branch++;
        for (int k = 1; k < next_count; ++k) {
            next[k].branch = p.next_branch++;
            p.pending.push_back(next[k]);
        }
        path = next[0];
    }
}

}  // namespace

ViewSamples generate_view_samples(const Scene& scene, const Camera& world_camera, const ViewSampleSettings& settings,
                                  const RenderControl& control, Stats& stats) {
    StageTimer timer(stats, "view_samples");
    // Render space (scene.h); render_iteration has done it already, but this stage is also called on its own.
    const Camera camera = world_camera.relative_to(scene.origin());
    scene.set_shader_camera(world_camera.shader_camera());
    const int width = camera.width(), height = camera.height();
    const size_t pixels = static_cast<size_t>(width) * height;
    ViewSamples out;
    out.width = width;
    out.height = height;
    out.origin = camera.position();
    out.emission.assign(pixels, glm::vec3(0.0f));
    out.alpha.assign(pixels, 0.0f);
    out.first_normal.assign(pixels, glm::vec3(0.0f));
    out.first_depth.assign(pixels, 0.0f);

    // Lights seen along camera paths need the light sources where a path can bounce (delta surfaces, rough
    // transmission); next-event estimation at rough transmissions and near-mirrors (near_mirror_light) needs them
    // too, and a buffer for what it finds.
    bool bounces = false, rough_transmission = false, near_mirrors = false;
    for (const Material& m : scene.materials()) {
        bounces = bounces || m.has_delta || m.transmits;
        rough_transmission = rough_transmission || (m.transmits && m.has_lobes);
        for (const Closure& c : m.closures) near_mirrors = near_mirrors || c.reported_alpha > 0.0f;
    }
    std::optional<LightSources> sources;
    std::optional<DirectLightContext> direct;
    if (bounces) sources.emplace(scene);
    if (rough_transmission || near_mirrors) {
        out.transmitted_direct.assign(pixels, glm::vec3(0.0f));
        out.caustic_emission.assign(pixels, glm::vec3(0.0f));
        direct.emplace(DirectLightContext{scene, *sources, settings.samples_per_light, scene_has_transparency(scene)});
    }
    const LightSources* sources_ptr = sources ? &*sources : nullptr;
    const DirectLightContext* direct_ptr = direct ? &*direct : nullptr;

    // Each band of rows collects its samples (one or more a pixel) and their lobes in pixel order; the bands are
    // joined in order, so the result does not depend on which thread traced which band.
    constexpr int kBandRows = 8;
    const int bands = (height + kBandRows - 1) / kBandRows;
    std::vector<std::vector<ViewSample>> band_samples(static_cast<size_t>(bands));
    std::vector<std::vector<Lobe>> band_lobes(static_cast<size_t>(bands));
    std::vector<std::vector<ViewSample>> band_far_side(static_cast<size_t>(bands));
    const bool lifts = scene.any_terminator_offset();
    std::vector<std::vector<ViewSamples::SampleLift>> band_lifts(lifts ? static_cast<size_t>(bands) : 0);
    std::atomic<uint64_t> extra_rays{0};
    const RayTracer& tracer = scene.ray_tracer();  // built once, before the threads need it
    std::atomic<bool> cancelled{false};
    std::atomic<uint64_t> rows_done{0};
    tbb::parallel_for(tbb::blocked_range<int>(0, bands), [&](const tbb::blocked_range<int>& range) {
        for (int band = range.begin(); band < range.end(); ++band) {
            if (cancelled.load(std::memory_order_relaxed) || control.cancel_requested()) {
                cancelled = true;
                return;
            }
            // Collected here (a band's worth of memory per thread), then copied to a vector of exactly their size.
            std::vector<ViewSample> found;
            std::vector<Lobe> found_lobes;
            std::vector<ViewSamples::SampleLift> found_lifts;
            std::vector<ViewSample> found_far_side;
            uint64_t rays = 0;
            const int y_end = std::min(height, (band + 1) * kBandRows);
            found.reserve(static_cast<size_t>(y_end - band * kBandRows) * static_cast<size_t>(width));
            for (int y = band * kBandRows; y < y_end; ++y) {
                // The row's camera rays go in packets of side-by-side pixels, whose first hits are traced together.
                for (int x0 = 0; x0 < width; x0 += RayTracer::kPacketRays) {
                    const int count = std::min(RayTracer::kPacketRays, width - x0);
                    Ray camera_rays[RayTracer::kPacketRays];
                    float t_min[RayTracer::kPacketRays], t_max[RayTracer::kPacketRays];
                    Hit first_hits[RayTracer::kPacketRays];
                    bool first_found[RayTracer::kPacketRays];
                    for (int k = 0; k < count; ++k) {
                        const size_t pixel = static_cast<size_t>(y) * width + x0 + k;
                        float jx = 0.5f, jy = 0.5f;
                        if (settings.jitter)
                            SampleSequence::pixel_point(settings.sequence_seed, pixel,
                                                        settings.pass > 0 ? settings.pass - 1 : 0, jx, jy);
                        camera_rays[k] =
                            camera.generate_ray(static_cast<float>(x0 + k) + jx, static_cast<float>(y) + jy);
                        t_min[k] = 0.0f;
                        t_max[k] = camera.far_distance(camera_rays[k]);
                    }
                    tracer.intersect(camera_rays, t_min, t_max, count, kCameraRays, first_hits, first_found);
                    for (int k = 0; k < count; ++k) {
                        const size_t pixel = static_cast<size_t>(y) * width + x0 + k;
                        Rng rng(settings.seed, RngDomain::camera, pixel);
                        const CameraPath start{camera_rays[k], glm::vec3(1.0f), 0};
                        FirstHit first;
                        const size_t before = found.size(), before_far_side = found_far_side.size();
                        PixelPaths paths{scene, camera, settings, sources_ptr, direct_ptr, static_cast<uint32_t>(pixel),
                                         rng, found, found_lobes, found_far_side, lifts ? &found_lifts : nullptr,
                                         out.emission[pixel],
                                         out.transmitted_direct.empty() ? nullptr : &out.transmitted_direct[pixel],
                                         out.caustic_emission.empty() ? nullptr : &out.caustic_emission[pixel],
                                         first, {}, 1, 0, &first_hits[k], first_found[k]};
                        trace_camera_path(paths, start);
                        while (!paths.pending.empty()) {
                            const CameraPath branch = paths.pending.front();
                            paths.pending.erase(paths.pending.begin());
                            trace_camera_path(paths, branch);
                        }
                        rays += paths.rays;
                        for (size_t j = before; j < found.size(); ++j) found[j].position -= out.origin;
                        for (size_t j = before_far_side; j < found_far_side.size(); ++j)
                            found_far_side[j].position -= out.origin;
                        out.alpha[pixel] = first.alpha;
                        out.first_normal[pixel] = first.normal;
                        out.first_depth[pixel] = first.depth;
                    }
                }
            }
            band_samples[static_cast<size_t>(band)].assign(found.begin(), found.end());
            band_lobes[static_cast<size_t>(band)] = std::move(found_lobes);
            if (lifts) band_lifts[static_cast<size_t>(band)] = std::move(found_lifts);
            band_far_side[static_cast<size_t>(band)].assign(found_far_side.begin(), found_far_side.end());
            extra_rays += rays;
            control.advance(rows_done += static_cast<uint64_t>(y_end - band * kBandRows),
                            static_cast<uint64_t>(height));
        }
    });
    control.check();

    size_t count = 0, lobe_count = 0;
    for (size_t band = 0; band < band_samples.size(); ++band) {
        count += band_samples[band].size();
        lobe_count += band_lobes[band].size();
    }
    out.samples.reserve(count);
    out.lobes.reserve(lobe_count);
    size_t lift_count = 0, far_side_count = 0;
    for (const auto& band : band_lifts) lift_count += band.size();
    for (const auto& band : band_far_side) far_side_count += band.size();
    out.terminator.reserve(lift_count);
    out.far_side.reserve(far_side_count);
    for (size_t band = 0; band < band_samples.size(); ++band) {
        const uint32_t offset = static_cast<uint32_t>(out.lobes.size());
        const uint32_t first_sample = static_cast<uint32_t>(out.samples.size());
        for (ViewSample& sample : band_samples[band]) sample.lobe_begin += offset;
        out.samples.insert(out.samples.end(), band_samples[band].begin(), band_samples[band].end());
        out.lobes.insert(out.lobes.end(), band_lobes[band].begin(), band_lobes[band].end());
        if (lifts) {
            for (ViewSamples::SampleLift lift : band_lifts[band]) {
                lift.sample += first_sample;
                out.terminator.push_back(lift);
            }
            std::vector<ViewSamples::SampleLift>().swap(band_lifts[band]);
        }
        out.far_side.insert(out.far_side.end(), band_far_side[band].begin(), band_far_side[band].end());
        std::vector<ViewSample>().swap(band_samples[band]);
        std::vector<Lobe>().swap(band_lobes[band]);
        std::vector<ViewSample>().swap(band_far_side[band]);
    }
    if (extra_rays.load() > 0) stats.counters["shadow_rays"] += static_cast<double>(extra_rays.load());
    stats.counters["view_samples"] += static_cast<double>(count);
    stats.bytes["view_samples"] = static_cast<double>(out.bytes());
    return out;
}

}  // namespace ps
