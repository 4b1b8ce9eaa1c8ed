#include "photonsplat/photons.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <atomic>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "photonsplat/bump_shadowing.h"
#include "photonsplat/caustic_aim.h"
#include "photonsplat/emission_guide.h"
#include "photonsplat/light_sources.h"
#include "photonsplat/materials.h"
#include "photonsplat/photon_shading_normals.h"
#include "photonsplat/shading.h"
#include "photonsplat/ray_tracer.h"
#include "photonsplat/render_control.h"
#include "photonsplat/rng.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/stats.h"

#include "building_blocks.h"

namespace ps {

namespace {

constexpr float kInvPi = 0.318309886183790671538f;

// Photons are traced in fixed chunks of consecutive indices, and the chunks' photons concatenated in chunk
// order: the photon map is then the same whatever the number of threads.
constexpr uint64_t kChunk = 4096;

// Surfaces one ray passes through: a photon's through surfaces no bounce sees, a shadowless light's line of
// copies (LineRole). Stacked ones beyond this end it.
constexpr int kMaxCrossedSurfaces = 64;

// The origin of a ray going on along its way through the surface at s (s.geometric_normal faces the ray).
glm::vec3 beyond_surface(const SurfacePoint& s) {
    return offset_ray_origin(s.position, -s.geometric_normal, s.rounding_scale);
}

// Sources are chosen in proportion to the luminance of their flux, so photons carry near-equal power.
struct SourceChoice {
    std::vector<float> cdf;
    std::vector<float> probability;
};

SourceChoice choose_sources_by_power(const LightSources& sources) {
    SourceChoice choice;
    double total = 0.0;
    std::vector<double> weights;
    for (size_t i = 0; i < sources.size(); ++i) {
        const double w = std::max(0.0f, luminance(sources.flux(i)));
        weights.push_back(w);
        total += w;
    }
    if (total <= 0.0) return choice;  // nothing emits: no photons
    double running = 0.0;
    for (double w : weights) {
        running += w;
        choice.cdf.push_back(static_cast<float>(running / total));
        choice.probability.push_back(static_cast<float>(w / total));
    }
    choice.cdf.back() = 1.0f;
    return choice;
}

// How a photon's caustic photons (light → specular+ → this hit) are weighed when photons are aimed at mirrors
// and glass (caustic_aim.h). An aimed photon keeps only its caustic photons; an ordinary one weighs its caustic
// photons by the balance heuristic, found at its first specular hit (most photons never make one).
struct CausticWeighting {
    const CausticAim* aim = nullptr;  // null: no aiming, every weight 1
    size_t source = 0;
    bool aimed = false;
};

// The source a photon left (null: none named), for what Cycles keeps of its light where it first meets a mirror
// that reports a density (LightSources::mirror_weight).
struct PhotonSource {
    const LightSources* sources = nullptr;
    size_t index = 0;
};

// What Cycles' Caustics toggles would keep of a photon's light from the surface ahead back to the light, by how
// the camera path reaches that surface (CausticState, photons.h). Camera paths run the other way, so it is kept
// from the light on: at each scatter, a camera path reaching it otherwise sees every part, and labels the scatter
// diffuse with the probability q of ScatterLabel, so that it then reaches the previous surface diffusely; one
// reaching it diffusely sees its diffuse-labelled parts only (their share r of f), and labels it diffuse:
//   kept'[otherwise] = (1 − q)·kept[otherwise] + q·kept[diffusely],   kept'[diffusely] = r·kept[diffusely].
// A mirror or a sharp refraction is q = r = 0, Lambert q = r = 1, transparency leaves both as they were (Cycles'
// transparent bounces keep the path's labels). q is one for all channels, r and what is kept are per channel.
struct CausticKept {
    bool active = false;  // only a Caustics output needs them: else the shares stay 0, at no cost
    glm::vec3 kept[2] = {glm::vec3(1.0f), glm::vec3(1.0f)};
    void scatter(float q, const glm::vec3& r) {
        kept[kReachedOtherwise] = (1.0f - q) * kept[kReachedOtherwise] + q * kept[kReachedDiffusely];
        kept[kReachedDiffusely] = r * kept[kReachedDiffusely];
    }
    void set_shares(Photon& p) const {
        if (!active) return;
        for (int state = 0; state < 2; ++state)
            for (int c = 0; c < 3; ++c)
                p.caustic_share[state][c] = static_cast<uint16_t>(
                    std::lround(std::clamp(1.0f - kept[state][c], 0.0f, 1.0f) * kCausticShareUnit));
    }
};

// What each photon path does besides scattering: its length bound, and whether it keeps its caustic shares.
struct PathOptions {
    int max_bounces = 8;
    bool caustic_shares = false;
};

// The surface as a path leaving it along step sees it: from the other side where step went through.
SurfacePoint seen_by(const SurfacePoint& s, const BsdfSample& step) {
    SurfacePoint seen = s;
    if (step.transmitted) {
        seen.geometric_normal = -s.geometric_normal;
        seen.shading_normal = -s.shading_normal;
        seen.smooth_normal = -s.smooth_normal;
        seen.entering = !s.entering;
    }
    return seen;
}

// A photon's weight across a lobe scatter from s into step.direction, where s's material weighs its closures by
// the view (Glass's Fresnel split, Fresnel and Layer Weight mixes: Material::factors). Cycles evaluates those
// towards its camera path, which is where the photon goes, not where it came from: a light path through rough
// glass holds the Glass split as seen from the direction it leaves in. b is the closures seen from the photon's
// arrival (b.wo), step drawn with density step.pdf; the weight is f(wi = b.wo, wo = step.direction) |cos| / pdf,
// f the closures seen from step.direction, in Cycles' own convention already (no photon_units_across: its η²
// factors are what turning f's arguments round changes). Without it the bottom of a rough glass cylinder seen
// through its side came out 1.16 to 1.58 times as bright as in Cycles (tools/rough_glass_cylinder.py).
glm::vec3 weight_seen_from_exit(const Scene& scene, const SurfacePoint& s, const Bsdf& b, const BsdfSample& step) {
    if (!(step.pdf > 0.0f)) return glm::vec3(0.0f);
    const Bsdf from_exit = shade(scene, seen_by(s, step), step.direction);
    const glm::vec3 f = bsdf_eval(from_exit, b.wo, LobeSet::all, b.sampled_estimate);
    return f * (std::fabs(glm::dot(step.direction, b.n)) / step.pdf);
}

// Whether a photon scatters off s as the camera path arriving from its next direction sees s
// (photon_shading_normals.h): on a smooth-shaded triangle whose normal no program sets (a Bump's or Normal Map's
// normal is tilted against the photon's arrival, as before).
bool scatters_as_seen_from_exit(const SurfacePoint& s) {
    return !s.material->program_normal && shading_normal_tilted(s.smooth_normal, s.geometric_normal);
}

// The share of scatters off such a surface drawn against the triangle (cosine-weighted about n_g), the rest by the
// closures: enough that the band between the two horizons is reached, little enough that narrow lobes stay drawn
// mostly by their own sampler.
constexpr float kHorizonDraw = 0.25f;

// A photon's weight across a reflection by the lobes of s (arrived along b.wo, b seen from there; drawn_from what
// bsdf_sample drew with) into wo, on a surface that scatters_as_seen_from_exit: f (n_c·ω_i)/(n_g·ω_i) (n_g·ω_o) / pdf,
// with f and n_c = exit_normal(s, wo) as the camera path coming along wo shades s, and pdf the mixture of the
// horizon draw and the closures' draw (their density of wo times that of choosing the lobes). Cycles' convention
// already (a reflection: no photon_units_across).
glm::vec3 weight_seen_along_exit_normal(const Scene& scene, const SurfacePoint& s, const Bsdf& b,
                                        const Bsdf& drawn_from, const glm::vec3& wo) {
    const float cos_g = glm::dot(s.geometric_normal, wo);
    if (!(cos_g > 0.0f)) return glm::vec3(0.0f);
    const float pdf = kHorizonDraw * cos_g * kInvPi + (1.0f - kHorizonDraw) * bsdf_sample_pdf(drawn_from, wo);
    if (!(pdf > 0.0f)) return glm::vec3(0.0f);
    SurfacePoint seen = s;
    seen.shading_normal = exit_normal(s, wo);
    const Bsdf from_exit = shade(scene, seen, wo);
    const glm::vec3 f = bsdf_eval(from_exit, b.wo, LobeSet::all, b.sampled_estimate);
    return f * (photon_arrival_ratio(seen.shading_normal, s.geometric_normal, b.wo) * cos_g / pdf);
}

// A photon's weight across Multiscatter GGX glass (or a material holding it) straight from its light. A camera path
// that reaches this glass finds that light two ways, and Cycles 3.4 weighs them by the power heuristic with the
// density the glass reports (mf_glass_pdf): by sampling the light, valued by its own evaluation walk, which is not
// what its sampling walk returns (cycles3_multi_glass_light_value), and by the sampling walk meeting the light. So
// the weight is (w_light f_light_sample + w_walk f_walk)(wi = b.wo, seen from step.direction) |cos| / pdf, both
// seen from where the photon goes, as the camera path sees them (in Cycles' convention already, as in
// weight_seen_from_exit). Seed 30 of the differential scenes: its Multiscatter glass ball's caustic.
glm::vec3 weight_blended_towards_light(const Scene& scene, const SurfacePoint& s, const Bsdf& b, const BsdfSample& step,
                                       const PhotonSource& source) {
    if (!(step.pdf > 0.0f)) return glm::vec3(0.0f);
    const Bsdf from_exit = shade(scene, seen_by(s, step), step.direction);
    const glm::vec3 f_walk = bsdf_eval(from_exit, b.wo, LobeSet::all, MultiScatterEstimate::walk);
    const glm::vec3 f_light = bsdf_eval(from_exit, b.wo, LobeSet::all, MultiScatterEstimate::light_sample);
    const float w_walk = source.sources->mirror_weight(
        source.index, s.position, offset_ray_origin(s.position, s.geometric_normal, s.rounding_scale),
        s.geometric_normal, b.wo, bsdf_sample_pdf(from_exit, b.wo));
    const glm::vec3 f = (1.0f - w_walk) * f_light + w_walk * f_walk;
    return f * (std::fabs(glm::dot(step.direction, b.n)) / step.pdf);
}

// Cycles' bump shadowing term (bump_shadowing.h) on a photon that arrives at s along wi and scatters off its diffuse
// parts: the term of wi, the light's direction, for the normal the camera path going the other way would shade
// with. That normal is tilted by Cycles' ensure_valid_reflection against where that path comes from, the way the
// photon leaves, not against wi as s's is (surface_at tilts it against the photon's arrival). A smooth mesh without
// a program's normal scatters as seen from where the photon leaves (scatters_as_seen_from_exit), whose normal and
// term that scatter takes; taking the term of the arrival's tilt had darkened an 80-face smooth sphere (0.944-1.006
// of Cycles in its blocks, 0.974-1.024 without). Where a program (Bump, Normal Map) makes the normal, that normal
// is the one, tilted against wi as the photon sees it.
float photon_bump_shadowing(const Scene& scene, const SurfacePoint& s, const glm::vec3& wi) {
    if (!s.material->program_normal || !bump_shadowed(s.smooth_normal, s.shading_normal)) return 1.0f;
    return bump_shadowing_term(scene.bump_shadowing(*s.material), s.smooth_normal, s.shading_normal, wi);
}

// A light with Cast Shadow off lights every surface facing it, occluded or not (Cycles takes no shadow ray for its
// samples), and what Cycles' camera paths find of its indirect light starts at such surfaces: a path's next-event
// estimation at a surface behind an occluder still sees it. So each of its photons stands for its light at every
// surface along its emission ray: the ordinary path (`line_first`) scatters at the first surface as usual, and
// one copy of the photon (`line_copy`) starts at each surface beyond it with the full power (no occlusion, no
// transparency on the way: shadow_ray_setup casts nothing). A copy goes on only by the surface's lobes: a light
// reflected by a mirror or sharp glass is found by a BSDF ray, which is occluded as usual, and that is the ordinary
// path's. For the same reason the ordinary path, where transparency lets it reach the next surface still direct,
// leaves that surface's lobes to its copy.
enum class LineRole { ordinary, line_first, line_copy };

// Follows one photon from its emission, appending what it stores to `out`. At each surface the photon is
// stored where the surface has reflection parts a view sample could hold (except where it arrives straight from
// the light, through transparency at most: direct light), then goes on by sampling the whole closure sum (shading.h), with Russian roulette on the weight so
// that surviving photons keep about the power they arrived with. Only delta parts (mirrors, sharp refraction,
// transparency) keep a path a caustic one: light → delta+ → stored.
void trace_path(const Scene& scene, const EmissionSample& emitted, const PhotonSource& source, glm::vec3 power,
                const PathOptions& options, Rng& rng, std::vector<Photon>& out, const CausticWeighting& weighting = {},
                LineRole role = LineRole::ordinary) {
    const RayTracer& tracer = scene.ray_tracer();
    Ray ray{emitted.origin, emitted.direction};
    bool only_specular_so_far = true;
    CausticKept kept;
    kept.active = options.caustic_shares;
    // Until its first scatter other than transparency, what the photon reaches is direct light, which shadow rays
    // (through transparent surfaces too) already count.
    bool direct = true;
    bool after_glossy = false;  // kAfterGlossy
    float caustic_weight = 1.0f;
    // Stores the photon where view samples receive it at s: on a surface that reflects it, and, where it is a
    // caustic one, on a translucent surface, whose far side gathers those (view_samples.h). b: s's closures, or
    // null for a Lambert-only surface.
    const auto store = [&](const SurfacePoint& s, const Bsdf* b) {
        const bool reflected = b == nullptr || bsdf_has(*b, LobeSet::reflection);
        const bool far_side = b != nullptr && only_specular_so_far && s.material->translucent &&
                              translucent_albedo(*b) != glm::vec3(0.0f);
        if (!reflected && !far_side) return;
        const bool inside = b != nullptr && inside_transmitter(s);
        const bool caustic = only_specular_so_far;
        const uint32_t flags = (caustic ? static_cast<uint32_t>(kCaustic) : 0u) |
                               (inside ? static_cast<uint32_t>(kInsidePhoton) : 0u) |
                               (far_side ? static_cast<uint32_t>(kFarSidePhoton) : 0u) |
                               (reflected ? 0u : static_cast<uint32_t>(kFarSideOnly)) |
                               (after_glossy ? static_cast<uint32_t>(kAfterGlossy) : 0u);
        Photon photon{s.position, -ray.direction, s.geometric_normal, caustic ? power * caustic_weight : power, flags,
                      {}};
        kept.set_shares(photon);
        out.push_back(photon);
    };
    int crossings = 0;  // surfaces no bounce sees, passed through
    for (int vertex = 0; vertex <= options.max_bounces; ++vertex) {
        Hit hit;
        if (!tracer.intersect(ray, 0.0f, std::numeric_limits<float>::infinity(), hit, kAllRays)) return;
        // A surface no bounce sees (Object > Visibility > Ray Visibility: diffuse, glossy and transmission off).
        // In Cycles no ray after a bounce meets it, so it passes no light on and hides nothing from the paths
        // beyond it, but its own paths see the rest: the camera finds there the light other surfaces send it. So
        // the photon is stored there (where the camera can see it) and goes on through it unchanged. Straight from
        // the light it is what a shadow ray meets: where the surface casts shadows, nothing lit behind it.
        const uint32_t visible_to = scene.instances()[hit.instance].visibility;
        if (!(visible_to & kIndirectRays)) {
            if (direct && (visible_to & kShadowRays)) return;
            const SurfacePoint s = surface_at(scene, ray, hit, ShaderRay::photon);
            if (!direct && (visible_to & kCameraRays) && (s.material->has_delta || s.material->has_lobes)) {
                if (s.material->lambert_only) {
                    store(s, nullptr);
                } else {
                    const Bsdf b = shade(scene, s, -ray.direction);
                    store(s, &b);
                }
            }
            if (++crossings > kMaxCrossedSurfaces) return;
            ray.origin = beyond_surface(s);
            --vertex;  // not a bounce
            continue;
        }
        const SurfacePoint s = surface_at(scene, ray, hit, ShaderRay::photon);
        if (vertex == 0) power *= first_hit_falloff(emitted, s.position, s.geometric_normal);  // a soft light's disc (lights.h)
        const Material& m = *s.material;
        if (!m.has_delta && !m.has_lobes) return;  // absorbed (black, holdout)
        // A shadowless light's photon still direct beyond transparency: this surface's lobes are its copy's.
        const bool lobes_to_copy = role == LineRole::line_first && direct && vertex > 0;
        if (m.lambert_only) {
            if (lobes_to_copy) return;
            // Most surfaces: stored, then a cosine-weighted bounce with roulette on the albedo (no Bsdf to build).
            if (!direct) store(s, nullptr);
            kept.scatter(1.0f, glm::vec3(1.0f));
            if (weighting.aimed) return;  // an aimed photon stands for caustics only
            only_specular_so_far = false;
            direct = false;
            after_glossy = false;
            // Cycles' bump shadowing term of the light's direction, the photon's arrival (photon_bump_shadowing).
            const float shadowing = photon_bump_shadowing(scene, s, -ray.direction);
            const glm::vec3 albedo = lambert_albedo(scene, s, -ray.direction) * shadowing;
            const float keep = std::min(1.0f, std::max({albedo.x, albedo.y, albedo.z}));
            if (!(keep > 0.0f) || rng.uniform() >= keep) return;
            power *= albedo / keep;
            const float v1 = rng.uniform(), v2 = rng.uniform();
            if (scatters_as_seen_from_exit(s)) {
                // Drawn against the triangle, (n_g·ω_o)/π: f (n_c·ω_i)/(n_g·ω_i) (n_g·ω_o) / pdf is the albedo times
                // the arrival ratio of the normal n_c the camera path coming along ω_o shades with, and Cycles' bump
                // shadowing term of ω_i where n_c is tilted (as shade() gives a view sample there).
                const glm::vec3 direction = sample_cosine_hemisphere(s.geometric_normal, v1, v2);
                if (!(glm::dot(direction, s.geometric_normal) > 0.0f)) return;
                const glm::vec3 nc = exit_normal(s, direction);
                power *= photon_arrival_ratio(nc, s.geometric_normal, -ray.direction);
                if (bump_shadowed(s.smooth_normal, nc))
                    power *= bump_shadowing_term(scene.bump_shadowing(m), s.smooth_normal, nc, -ray.direction);
                ray = Ray{offset_ray_origin(s.position, s.geometric_normal, s.rounding_scale), direction};
                continue;
            }
            const glm::vec3 direction = sample_cosine_hemisphere(s.shading_normal, v1, v2);
            if (!(glm::dot(direction, s.geometric_normal) > 0.0f)) return;  // shading normal pointed below
            power *= shading_normal_ratios(s, -ray.direction, direction);
            ray = Ray{offset_ray_origin(s.position, s.geometric_normal, s.rounding_scale), direction};
            continue;
        }
        Bsdf b = shade(scene, s, -ray.direction);
        // Whichever way it scatters on, light from the photon's own direction (photon_bump_shadowing).
        if (m.program_normal) take_bump_shadowing(b, b.wo);
        // Light that leaves its lamp's first surface is what Cycles finds there by sampling the lamp: a Multiscatter
        // GGX surface passes it on as Cycles' evaluation towards a light sample weighs it (closures.h). Multiscatter
        // GGX glass takes Cycles' blend of that and its walk below (weight_blended_towards_light).
        if (direct && !bsdf_has_multi_ggx_glass(b)) b.sampled_estimate = scene.multiscatter_light_estimate();
        if (!direct) {
            store(s, &b);
            // An aimed photon goes on where this surface also passes light on sharply (glass with a clearcoat, a
            // mirror mixed with diffuse): every caustic photon an ordinary photon stores along its sharp chain is
            // one the balance heuristic shares with the aimed ones, so they must store it too. It stops at its
            // first lobe step below. (Seed 138 of the differential scenes: stopping here lost the floor's caustic
            // behind a clearcoated glass cylinder, the image 0.90 of Cycles.)
        }
        const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        // Where the material weighs its closures by the view, a scatter by its non-delta parts is drawn from all
        // of them (halfway factors: the view it leaves in may weigh in one that b's view leaves out) and weighed
        // as Cycles weighs it, from the direction it leaves in (weight_seen_from_exit). Its delta parts stay b's:
        // a sharp Fresnel split is the same seen from either side.
        const bool view_weighted = m.has_lobes && !m.factors.empty();  // (a sharp Glass has no lobes to draw)
        Bsdf drawn_from = b;
        if (view_weighted) {
            Bsdf halfway = shade_halfway_factors(scene, s, -ray.direction);
            if (m.program_normal) take_bump_shadowing(halfway, halfway.wo);
            drawn_from.lambert = halfway.lambert;
            drawn_from.lobe_count = halfway.lobe_count;
            std::copy(halfway.lobes, halfway.lobes + halfway.lobe_count, drawn_from.lobes);
        }
        // On a smooth mesh the camera path's normal depends on where it comes from (photon_shading_normals.h):
        // a share kHorizonDraw of the scatters draws ω_o against the triangle instead, so that every direction
        // above it, where Cycles' camera paths arrive from, is drawn, and a reflection by the lobes is weighed
        // by the mixture's density (weight_seen_along_exit_normal).
        const bool exit_normals = scatters_as_seen_from_exit(s) && !bsdf_has_multi_ggx_glass(b) &&
                                  bsdf_has(b, LobeSet::reflection);
        BsdfSample step;
        if (exit_normals && rng.uniform() < kHorizonDraw) {
            step.kind = ScatterKind::lobes;
            step.direction = sample_cosine_hemisphere(s.geometric_normal, u1, u2);
        } else {
            step = bsdf_sample(drawn_from, u0, u1, u2);
            if (exit_normals) step.weight /= 1.0f - kHorizonDraw;  // what only this draw reaches
        }
        if (step.kind == ScatterKind::none) return;
        if (step.kind == ScatterKind::lobes && lobes_to_copy) return;
        if (role == LineRole::line_copy && direct && step.kind != ScatterKind::lobes) return;  // the ordinary path's
        // Multiple Importance off: a camera path would find this light through a mirror or sharp glass only by a
        // BSDF ray, which never meets it (Light::multiple_importance): the path carries nothing from here on.
        if (direct && (step.kind == ScatterKind::mirror || step.kind == ScatterKind::refraction) &&
            source.sources != nullptr && !source.sources->found_by_bsdf_rays(source.index))
            return;
        if (step.kind == ScatterKind::lobes) {
            if (kept.active) {
                const ScatterLabel label = scatter_label(b, step.direction);
                kept.scatter(label.diffuse_probability, label.diffuse_value);
            }
        } else if (step.kind != ScatterKind::transparent) {
            kept.scatter(0.0f, glm::vec3(0.0f));  // a mirror or a sharp refraction
        }
        if (step.kind == ScatterKind::lobes) {
            if (weighting.aimed) return;
            only_specular_so_far = false;
        } else if (direct && step.kind != ScatterKind::transparent && weighting.aim && !weighting.aimed) {
            caustic_weight = weighting.aim->ordinary_caustic_weight(weighting.source, emitted);
        }
        // A mirror Cycles 3.x samples as Multiscatter GGX: a camera path finds this light there by a BSDF ray,
        // which Cycles weighs against light sampling by the density the mirror reports (mirror_reported_pdf).
        glm::vec3 step_weight = step.weight;
        if (direct && step.kind == ScatterKind::mirror && source.sources != nullptr && b.mirror_reported_alpha > 0.0f)
            step_weight *= source.sources->mirror_weight(
                source.index, s.position, offset_ray_origin(s.position, s.geometric_normal, s.rounding_scale),
                s.geometric_normal, -ray.direction, mirror_reported_pdf(b));
        const bool blended = direct && step.kind == ScatterKind::lobes && source.sources != nullptr &&
                             scene.multiscatter_light_estimate() == MultiScatterEstimate::light_sample &&
                             bsdf_has_multi_ggx_glass(b);
        const bool along_exit_normal = exit_normals && step.kind == ScatterKind::lobes && !step.transmitted;
        const bool seen_from_exit = blended || along_exit_normal || (view_weighted && step.kind == ScatterKind::lobes);
        if (blended)
            step_weight = weight_blended_towards_light(scene, s, b, step, source);
        else if (along_exit_normal)
            step_weight = weight_seen_along_exit_normal(scene, s, b, drawn_from, step.direction);
        else if (seen_from_exit)
            // A transmission where the horizon draws: only the closures' share (1 − kHorizonDraw) reaches it.
            step_weight = weight_seen_from_exit(scene, s, b, step) / (exit_normals ? 1.0f - kHorizonDraw : 1.0f);
        if (step.kind != ScatterKind::transparent) {
            direct = false;
            after_glossy = step.glossy;
        }
        // Russian roulette on the weight keeps every surviving photon's power near the emitted one (times the
        // units of the refractions it made: 1/ior² inside glass).
        const float keep = std::min(1.0f, std::max({step_weight.x, step_weight.y, step_weight.z}));
        if (!(keep > 0.0f) || rng.uniform() >= keep) return;
        power *= step_weight * ((seen_from_exit ? 1.0f : photon_units_across(b, step)) / keep);
        if (step.kind != ScatterKind::transparent && !along_exit_normal)
            power *= shading_normal_ratios(s, -ray.direction, step.direction);
        if (step.kind == ScatterKind::lobes && !(glm::dot(step.direction, step.transmitted ? -s.geometric_normal
                                                                                            : s.geometric_normal) > 0.0f))
            return;
        const glm::vec3 side = step.transmitted ? -s.geometric_normal : s.geometric_normal;
        ray = Ray{offset_ray_origin(s.position, side, s.rounding_scale), step.direction};
    }
}

// The copies of a shadowless light's photon (LineRole): one from each surface beyond the first along its emission
// ray, up to kMaxCrossedSurfaces of them.
void trace_line_copies(const Scene& scene, const EmissionSample& emitted, const PhotonSource& source,
                       const glm::vec3& power, const PathOptions& options, Rng& rng, std::vector<Photon>& out) {
    const RayTracer& tracer = scene.ray_tracer();
    Ray line{emitted.origin, emitted.direction};
    Hit hit;
    if (!tracer.intersect(line, 0.0f, std::numeric_limits<float>::infinity(), hit, kIndirectRays)) return;
    for (int k = 0; k < kMaxCrossedSurfaces; ++k) {
        line.origin = beyond_surface(surface_at(scene, line, hit, ShaderRay::photon));
        if (!tracer.intersect(line, 0.0f, std::numeric_limits<float>::infinity(), hit, kIndirectRays)) return;
        EmissionSample copy = emitted;
        copy.origin = line.origin;
        trace_path(scene, copy, source, power, options, rng, out, {}, LineRole::line_copy);
    }
}

// One photon of `source`: its emission (redistributed by the source's guide, if any), then its path.
void trace_one_photon(const Scene& scene, const LightSources& sources, size_t source, float source_probability,
                      const EmissionGuide& guide, const CausticAim& aim, const PathOptions& options, Rng& rng,
                      std::vector<Photon>& out) {
    float u1 = rng.uniform(), u2 = rng.uniform();
    const float u3 = rng.uniform(), u4 = rng.uniform(), u5 = rng.uniform();
    // Only a guided source draws the extra number, so unguided photons are the same as they always were.
    const float weight = guide.uniform() ? 1.0f : guide.sample(rng.uniform(), u1, u2);
    const EmissionSample emitted = sources.sample_emission(source, u1, u2, u3, u4, u5);
    CausticWeighting weighting;
    if (aim.active() && aim.aimed_probability(source) > 0.0f) weighting = {&aim, source, false};
    const glm::vec3 power = emitted.power * (weight / source_probability);
    const bool shadowless = !sources.casts_shadow(source);
    trace_path(scene, emitted, PhotonSource{&sources, source}, power, options, rng, out, weighting,
               shadowless ? LineRole::line_first : LineRole::ordinary);
    if (shadowless) trace_line_copies(scene, emitted, PhotonSource{&sources, source}, power, options, rng, out);
}

// One photon aimed at a mirror or glass object (caustic_aim.h): only its caustic photon is kept.
void trace_one_aimed_photon(const Scene& scene, const CausticAim& aim, const std::vector<float>& source_probability,
                            const PathOptions& options, Rng& rng, std::vector<Photon>& out) {
    const size_t source = aim.pick_source(rng.uniform());
    const EmissionSample emitted = aim.sample(source, rng);
    if (!(luminance(emitted.power) > 0.0f)) return;
    trace_path(scene, emitted, PhotonSource{aim.light_sources(), source}, emitted.power / source_probability[source],
               options, rng, out, CausticWeighting{&aim, source, true});
}

// The guide of a sun (emission_guide.h): kPilotsPerCell pilot photons per cell of its (u1, u2) square, each
// cell's usefulness the luminance of the power its pilots stored. The pilots are then thrown away.
constexpr int kPilotsPerCell = 8;

EmissionGuide learn_guide(const Scene& scene, const LightSources& sources, size_t source, int max_bounces,
                          uint64_t seed) {
    std::vector<double> usefulness(EmissionGuide::kCells, 0.0);
    tbb::parallel_for(0, EmissionGuide::kCells, [&](int cell) {
        std::vector<Photon> stored;
        const int x = cell % EmissionGuide::kCellsPerAxis, y = cell / EmissionGuide::kCellsPerAxis;
        for (int k = 0; k < kPilotsPerCell; ++k) {
            const uint64_t index = (uint64_t(source) * EmissionGuide::kCells + uint64_t(cell)) * kPilotsPerCell + uint64_t(k);
            Rng rng(seed, RngDomain::emission_guide, index);
            const float u1 = (float(x) + rng.uniform()) / EmissionGuide::kCellsPerAxis;
            const float u2 = (float(y) + rng.uniform()) / EmissionGuide::kCellsPerAxis;
            const float u3 = rng.uniform(), u4 = rng.uniform(), u5 = rng.uniform();
            const EmissionSample emitted = sources.sample_emission(source, std::min(u1, 0.99999994f),
                                                                   std::min(u2, 0.99999994f), u3, u4, u5);
            trace_path(scene, emitted, PhotonSource{&sources, source}, glm::vec3(1.0f), PathOptions{max_bounces, false},
                       rng, stored);
        }
        double sum = 0.0;
        for (const Photon& p : stored) sum += std::max(0.0f, luminance(p.power));
        usefulness[size_t(cell)] = sum;
    });
    return EmissionGuide::from_usefulness(usefulness);
}

// Photons in Morton order of their position (10 bits an axis over the photons' box), ties by emission order.
// Every splat walks photons in map order: neighbours in the map then meet the same hierarchy nodes, tiles and
// cells, which keeps those in cache (the cluster traversal at 1M photons was bound by cache misses with photons
// in emission order, which is random in space). Deterministic: it depends on the photons only.
void order_photons_spatially(std::vector<Photon>& photons) {
    Box box;
    for (const Photon& p : photons)
        if (std::isfinite(p.position.x) && std::isfinite(p.position.y) && std::isfinite(p.position.z)) box.add(p.position);
    const MortonGrid grid(box);
    std::vector<std::pair<uint32_t, uint32_t>> keyed(photons.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, keyed.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t j = r.begin(); j != r.end(); ++j) {
            const uint32_t key = grid.key(photons[j].position);
            keyed[j] = {key, uint32_t(j)};
        }
    });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    std::vector<Photon> sorted(photons.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, keyed.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t j = r.begin(); j != r.end(); ++j) sorted[j] = photons[keyed[j].second];
    });
    photons.swap(sorted);
}

}  // namespace

PhotonMap trace_photons(const Scene& scene, const PhotonSettings& settings, const RenderControl& control,
                        Stats& stats) {
    StageTimer timer(stats, "photon_trace");
    PhotonMap map;
    map.emitted = settings.count;
    LightSources sources(scene);
    sources.set_focus(settings.focus_center, settings.focus_radius);
    const SourceChoice choice = choose_sources_by_power(sources);
    if (choice.cdf.empty() || settings.count == 0 || scene.triangle_count() == 0) return map;

    scene.ray_tracer();
    std::vector<EmissionGuide> guides(sources.size());
    if (settings.guide) {
        for (size_t i = 0; i < sources.size(); ++i)
            if (sources.emits_from_disc(i) && choice.probability[i] > 0.0f) {
                guides[i] = learn_guide(scene, sources, i, settings.max_bounces, settings.seed);
                stats.counters["guided_light_sources"] += guides[i].uniform() ? 0.0 : 1.0;
            }
        control.check();
    }
    const CausticAim aim(scene, sources, choice.probability, settings.aimed_fraction);
    map.aimed = aim.active() ? static_cast<uint64_t>(std::llround(double(settings.aimed_fraction) * double(settings.count))) : 0;
    // Ordinary photons take indices [0, count), aimed ones [count, count + aimed): each index its own stream.
    const uint64_t paths = settings.count + map.aimed;
    const PathOptions options{settings.max_bounces, settings.caustic_shares};
    const uint64_t chunks = (paths + kChunk - 1) / kChunk;
    std::vector<std::vector<Photon>> per_chunk(chunks);
    std::atomic<bool> cancelled{false};
    std::atomic<uint64_t> chunks_done{0};
    tbb::parallel_for(uint64_t{0}, chunks, [&](uint64_t chunk) {
        if (cancelled.load(std::memory_order_relaxed) || control.cancel_requested()) {
            cancelled = true;
            return;
        }
        const uint64_t end = std::min(paths, (chunk + 1) * kChunk);
        for (uint64_t index = chunk * kChunk; index < end; ++index) {
            Rng rng(settings.seed, RngDomain::photon, index);
            if (index >= settings.count) {
                trace_one_aimed_photon(scene, aim, choice.probability, options, rng, per_chunk[chunk]);
                continue;
            }
            const float u = rng.uniform();
            const size_t l = static_cast<size_t>(std::upper_bound(choice.cdf.begin(), choice.cdf.end(), u) - choice.cdf.begin());
            const size_t which = std::min(l, choice.cdf.size() - 1);
            trace_one_photon(scene, sources, which, choice.probability[which], guides[which], aim, options, rng,
                             per_chunk[chunk]);
        }
        control.advance(++chunks_done, chunks);
    });
    control.check();

    size_t total = 0;
    for (const auto& c : per_chunk) total += c.size();
    map.photons.reserve(total);
    for (auto& c : per_chunk) {
        map.photons.insert(map.photons.end(), c.begin(), c.end());
        std::vector<Photon>().swap(c);
    }
    {
        StageTimer sort_timer(stats, "photon_sort");
        order_photons_spatially(map.photons);
    }
    size_t caustic = 0;
    for (const Photon& p : map.photons) caustic += (p.flags & kCaustic) ? 1 : 0;
    stats.counters["photons_emitted"] += static_cast<double>(map.emitted);
    if (map.aimed > 0) stats.counters["aimed_photons_emitted"] += static_cast<double>(map.aimed);
    stats.counters["photons_stored"] += static_cast<double>(map.photons.size());
    stats.counters["caustic_photons_stored"] += static_cast<double>(caustic);
    stats.bytes["photon_map"] = static_cast<double>(map.bytes());
    return map;
}

}  // namespace ps
