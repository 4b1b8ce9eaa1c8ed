// A surface's closures evaluated at one hit for one outgoing direction: the BSDF every stage uses. Camera paths
// (view_samples.cpp), direct light, photon paths and the reference path tracer call shade() at a hit, then
// evaluate, sample or split what it returns; the splat evaluates a view sample's stored lobes (splat.h).
//
// The closure sum splits three ways:
//   - lambert: the Lambert diffuse closures, summed into one albedo (the common case, evaluated without lobes);
//   - lobes: every other non-delta closure (Oren–Nayar, microfacets, sheen, velvet, translucent, rough
//     refraction), each a Lobe with its weight made concrete here;
//   - delta parts: the sharp reflections (one mirror direction, their Fresnel-weighted sum), the sharp
//     refraction (one direction) and transparency (straight on).
#pragma once
#include <cstdint>

#include <glm/vec3.hpp>

#include "photonsplat/bump_shadowing.h"
#include "photonsplat/closures.h"

namespace ps {

class Scene;
struct SurfacePoint;

constexpr int kMaxLobes = 8;

struct Bsdf {
    glm::vec3 n{0.0f, 0.0f, 1.0f};   // shading normal, on the side of wo (geometric where shading faces away)
    glm::vec3 ng{0.0f, 0.0f, 1.0f};  // geometric normal on the side of wo
    glm::vec3 wo{0.0f, 0.0f, 1.0f};  // unit, away from the surface
    // Cycles' sd->N (SurfacePoint::smooth_normal, on the side of wo): where n is not it (a Bump or Normal Map
    // normal, a tilted one), the diffuse parts take bump_shadowing_term of the light's direction (bump_shadowing.h).
    glm::vec3 smooth_n{0.0f, 0.0f, 1.0f};
    bool bump_shadowed = false;
    BumpShadowing bump_form = BumpShadowing::cycles3;  // which term (Scene::bump_shadowing of the material)
    glm::vec3 lambert{0.0f};         // Σ Lambert weights: f = lambert / π on wo's side
    Lobe lobes[kMaxLobes];
    int lobe_count = 0;
    glm::vec3 mirror{0.0f};          // Σ sharp reflection weights × their Fresnel at n·wo
    float mirror_reported_alpha = 0.0f;  // Closure::reported_alpha of the (first) sharp reflection that has one
    glm::vec3 refraction{0.0f};      // Σ sharp refraction weights
    float refraction_eta = 1.0f;     // n_other / n_this of the (first) sharp refraction
    glm::vec3 transparent{0.0f};     // Σ transparent weights
    // The least weight with which a part is chosen for sampling (choose_defensively); 0: each by its own weight.
    float selection_floor = 0.0f;
    // The estimate of Multiscatter GGX lobes that sampled directions weigh by (closures.h): the walk's, except
    // where a photon leaves its light's first surface, whose light Cycles finds by sampling that light.
    MultiScatterEstimate sampled_estimate = MultiScatterEstimate::walk;

    bool has_lobes() const { return lobe_count > 0 || lambert != glm::vec3(0.0f); }
    bool directional() const { return lobe_count > 0; }  // the value depends on directions beyond Lambert's
    bool has_delta() const {
        return mirror != glm::vec3(0.0f) || refraction != glm::vec3(0.0f) || transparent != glm::vec3(0.0f);
    }
};

// The BSDF of `surface` (its material, textures at its UV) seen from `wo` (unit, away from the surface, on the
// side of surface.geometric_normal). Lobes beyond kMaxLobes are merged into the last (never in practice: the
// add-on refuses materials with more non-delta closures than that).
Bsdf shade(const Scene& scene, const SurfacePoint& surface, const glm::vec3& wo);
// shade() with every view-dependent factor (Material::factors: Glass's Fresnel split, Fresnel and Layer Weight
// mixes) at one half: every closure the factors could weigh in from some view is there. Photons draw their
// scatter from it where the view they are shaded from is not the one Cycles weighs by (photons.cpp).
Bsdf shade_halfway_factors(const Scene& scene, const SurfacePoint& surface, const glm::vec3& wo);

// The density Cycles reports for the mirror's direction where its sharp reflection is a Cycles 3.x Multiscatter
// GGX (Closure::reported_alpha), 0 for a true mirror: an emitter its reflection meets weighs
// power_heuristic(this, the emitter's light-sampling density) (mirror_emitter_weight, direct_light.h).
float mirror_reported_pdf(const Bsdf& b);

// Which non-delta parts a strategy covers: all of them, the reflection side (Lambert and every lobe that is not a
// transmission), or the transmission lobes (translucent, rough refraction).
enum class LobeSet : uint8_t { all, reflection, transmission };

// The albedo of a lambert_only material at the hit seen from wo (Σ of its closures' weights, textured or set by
// its program): what shade() would put in Bsdf::lambert, without the rest of it.
glm::vec3 lambert_albedo(const Scene& scene, const SurfacePoint& surface, const glm::vec3& wo);

// Σ f of the set's non-delta parts for wi (no cosine). Reflection parts count only for wi on wo's side of the
// geometric normal, transmission parts only on the other (light leaking under the shading normal must not count).
// `estimate`: light_sample where wi is a light's sample (closures.h).
glm::vec3 bsdf_eval(const Bsdf& b, const glm::vec3& wi, LobeSet set = LobeSet::all,
                    MultiScatterEstimate estimate = MultiScatterEstimate::walk);
// bsdf_eval with the sides told by the shading normal instead of the geometric one: for a light sample that
// Cycles traces from under the triangle's horizon (shadow_terminator.h), where it evaluates the closures by the
// shading normal alone.
glm::vec3 bsdf_eval_shading_side(const Bsdf& b, const glm::vec3& wi, LobeSet set,
                                 MultiScatterEstimate estimate = MultiScatterEstimate::walk);
// The density of wi under bsdf_sample_set(b, set) that a light sample is weighed against (solid angle): the one
// it draws with, except for Multiscatter GGX glass (BsdfSample::mis_pdf).
float bsdf_pdf(const Bsdf& b, const glm::vec3& wi, LobeSet set = LobeSet::all);
// Only the reflection side of bsdf_eval, from a view sample's stored parts: what it receives from photons (splat.h).
glm::vec3 bsdf_eval_reflection(const glm::vec3& lambert, const Lobe* lobes, int lobe_count, const glm::vec3& n,
                               const glm::vec3& wi, const glm::vec3& wo);
// The share of f a Caustics output takes from a view sample (splat.h): all of it, or the part of its photons' light
// that Cycles' camera paths would label diffuse at this surface (by picking a diffuse-labelled part to sample wi:
// Lambert, Oren–Nayar, Principled diffuse, sheen, velvet, translucency), or the rest. Cycles picks a part in
// proportion to its sampling weight w_j, draws wi from its density p_j and weighs the result by the sum of every
// part's f over Σ w_j p_j(wi), so the diffuse-labelled share of f(wi) is Σ_diffuse w_j p_j(wi) / Σ_all w_j p_j(wi).
// selection_floor is Cycles' defensive floor at the camera's first hit (choose_defensively; 0 elsewhere).
// Where the camera path reaches the surface right after a diffuse-labelled scatter, Cycles' toggles drop every part
// but the diffuse-labelled ones instead: `diffuse_parts` is the f of those parts alone, `other_parts` the rest of f
// (the whole's, clearcoat's estimate included, less the diffuse parts').
enum class LabelShare : uint8_t { whole, diffuse, other, diffuse_parts, other_parts };
// `diffuse_term`: what the diffuse parts are multiplied by for this wi (bump_shadowing_term, 1 where none applies).
glm::vec3 bsdf_eval_reflection(const glm::vec3& lambert, const Lobe* lobes, int lobe_count, const glm::vec3& n,
                               const glm::vec3& wi, const glm::vec3& wo, LabelShare share, float selection_floor,
                               float diffuse_term = 1.0f);
bool bsdf_has(const Bsdf& b, LobeSet set);  // the set has a part with weight here
// How Cycles would label a photon's scatter from b (its wo, towards where the photon came from) into wi, sampled
// among b's non-delta parts: the probability that its camera path, going the other way, labels it diffuse (the
// share above, with the densities of the photon's own direction: for Lambert and visible-normal microfacets the
// ratio of the two is the same but for the masking term), and the diffuse-labelled parts' share of f(wi) per
// channel, which is what is left of the scatter where Cycles' Caustics toggles drop the other parts. (Cycles
// weighs closures by one number each, so the label's probability is one for all channels; the share is not: a red
// Principled wall's diffuse part keeps most of the red, its specular part much of the rest.)
struct ScatterLabel {
    float diffuse_probability = 1.0f;
    glm::vec3 diffuse_value{1.0f};
};
ScatterLabel scatter_label(const Bsdf& b, const glm::vec3& wi);
// Cycles' defensive floor for b at the camera's first hit: 1/8 of its parts' summed sampling weights.
float defensive_floor(const Bsdf& b);
// Whether b holds a clearcoat (a GTR1 lobe). Cycles samples its clearcoat by GGX's visible normals but reports
// GTR1's density for them, so what it converges to there depends on how it samples, and we follow it there:
//   - the MIS weights take the light's density as Cycles gives it, the probability that Cycles picks that light
//     included (LightSources::cycles_mis_density; differential seed 153: a 0.001 W lamp added far away took 2.9 %
//     off a clearcoat's highlight in Cycles). Elsewhere the light's own density is the better one, every light
//     being sampled at each point;
//   - choose_defensively at the camera's first hit.
bool bsdf_has_clearcoat(const Bsdf& b);
// Whether b holds a Multiscatter GGX glass lobe, whose light samples and MIS density are Cycles' own
// (cycles3_multi_glass_light_value, lobe_reported_pdf).
bool bsdf_has_multi_ggx_glass(const Bsdf& b);
// The lobe on wi's side of b where b is one Multiscatter GGX Glass alone (its two lobes of one η, α and weight,
// nothing else): Cycles' one closure, sampled and valued as its own walks (CyclesLcg); otherwise nullptr. side_z:
// wi's cosine with b.n (> 0 the reflection lobe, < 0 the refraction lobe).
const Lobe* lone_multi_ggx_glass(const Bsdf& b, float side_z);
// Whether what Cycles converges to at b depends on its MIS weights, so that they take the light's density times
// Cycles' pick of that light: a clearcoat (above), or a Multiscatter GGX glass, whose light samples Cycles values by
// an evaluation its walk does not agree with (cycles3_multi_glass_light_value, glass_multiscatter.h).
bool bsdf_weighs_by_cycles_pick(const Bsdf& b);
// Where Cycles picks the clearcoat, it draws wi from GGX's visible normals and weighs it by f / Σ w_j p_j with the
// clearcoat's p_j GTR1's: a sharp clearcoat (α ≤ 0.01: the default Clearcoat Roughness 0.03 is α 0.0009) so
// reflects its surroundings as a mirror does, with the whole of its Fresnel weight, where GTR1 itself would put
// half of that into a wide tail. Photons cannot resolve a lobe that narrow, so the camera path follows that part
// as a branch of its own (view_samples.cpp), with sample_clearcoat_branch's direction and weight, and a view
// sample's splat (bsdf_eval_reflection) takes what Cycles finds by picking its other parts:
// f Σ_{j≠clearcoat} w_j p_j / Σ_j w_j p_j. Without it rooms of clearcoated walls came out 1–2 % brighter than
// Cycles (differential seeds 89, 99, 102). A rougher clearcoat stays in the splat, with its own sampler's density.
bool clearcoat_branches(const Lobe& lobe);
bool bsdf_has_branching_clearcoat(const Bsdf& b);
// A reflection lobe other than the clearcoat too narrow for photons to resolve (α ≤ 0.04, roughness 0.2 for GGX):
// a view sample's splat weighs each photon by the lobe at the photon's own direction, which for a lobe this narrow
// is next to nothing for nearly every photon and hundreds to thousands of times the average for the few within it
// (seeds of the generated scenes: 38, a metal cylinder of roughness 0.06, had pixels at 0.04 and 12 times Cycles'
// after 16 s; 198, a Beckmann cylinder of roughness 0.146, α 0.021, its block at 0.30 and 0.62 of Cycles after 4
// and 16 s, until the bound went from α 0.01 to 0.04). The camera path follows such a lobe as a branch of its own
// (view_samples.cpp, sample_narrow_lobe_branch), the view sample's splat leaves it out, and its direct light keeps
// it (light samples and the BSDF's directions, which draw it too).
bool narrow_lobe_branches(const Lobe& lobe);
bool bsdf_has_narrow_lobe(const Bsdf& b);
// The camera's first hit (no transparency or specular part before it), where Cycles samples "defensively": each
// closure is chosen with at least 1/8 of the closures' summed sampling weights. That changes only the noise,
// except with a clearcoat, so b's selection_floor is set only where it holds one (a clearcoat over metal under a
// constant world was 1.055 of Cycles without it). Call once b's parts are all there.
void choose_defensively(Bsdf& b);
bool is_transmission(const Lobe& lobe);
// Translucency is Lambert's reflection turned to the other side: f = weight / π for wi on the far side of n, and
// 0 on wo's. Camera paths take it as a part of its own (view_samples.h): its caustic light is gathered from the
// photons stored on the other side, as by a Lambert surface of this albedo facing that way.
glm::vec3 translucent_albedo(const Bsdf& b);
// b's translucent lobes alone, and b without them (its rough refraction and the rest).
Bsdf translucency_of(const Bsdf& b);
Bsdf without_translucency(const Bsdf& b);
// A part Cycles labels a diffuse reflection (Oren–Nayar, Principled diffuse, sheen, velvet), as against a microfacet
// one: its Light Path flags and Caustics toggles go by that label.
bool is_diffuse_reflection(const Lobe& lobe);
// A part Cycles labels diffuse when it samples from it (its Light Path flags and Caustics toggles go by it):
// a diffuse reflection or translucency.
bool labelled_diffuse(const Lobe& lobe);
// The parts Cycles gives its bump shadowing term (bump_shadowing.h): Lambert, and lobes of these kinds.
bool takes_bump_shadowing(const Lobe& lobe);
// What b's diffuse parts are multiplied by for light from wi: bump_shadowing_term where b is bump-shadowed, else 1.
float bump_shadowing_of(const Bsdf& b, const glm::vec3& wi);
// b seen by light arriving along wi (a photon's arrival, b.wo where b was shaded from the photon's side): its
// diffuse parts' weights multiplied by their term for wi once, for every direction the light scatters on in, and
// b no longer bump-shadowed.
void take_bump_shadowing(Bsdf& b, const glm::vec3& wi);

// What a path does next at this surface.
enum class ScatterKind : uint8_t { none, lobes, mirror, refraction, transparent };
struct BsdfSample {
    ScatterKind kind = ScatterKind::none;  // none: absorbed (the path ends)
    glm::vec3 direction{0.0f};
    glm::vec3 weight{0.0f};  // f |cos| / pdf for lobes; delta weight / choice probability for the rest
    float pdf = 0.0f;        // lobes only: the density direction was drawn with (weight's); 0 for delta parts
    float mis_pdf = 0.0f;    // the density Cycles reports for it, which a light it meets is weighed against (MIS):
                             // pdf, except where Multiscatter GGX glass reports its own (lobe_reported_pdf)
    bool transmitted = false;  // the direction leaves on the other side (offset the next ray there)
    // A microfacet lobe, the mirror or the refraction was chosen: what Cycles labels glossy or transmission (its
    // Caustics toggles), as against diffuse, translucent, sheen, velvet and transparency.
    bool glossy = false;
};
// Samples the whole closure sum: a part chosen in proportion to its sampling weight (the delta parts' luminance,
// the lobes' lobe_sampling_weight), then a direction. u0 chooses, u1 and u2 place. Non-delta samples carry
// the density of their direction (the lobes' density times the probability of choosing the lobes), and the one
// Cycles reports for it (mis_pdf), which bsdf_sample_pdf gives for any direction.
BsdfSample bsdf_sample(const Bsdf& b, float u0, float u1, float u2);
float bsdf_sample_pdf(const Bsdf& b, const glm::vec3& wi);
// The same over one set of non-delta parts only.
BsdfSample bsdf_sample_set(const Bsdf& b, LobeSet set, float u0, float u1, float u2);
// The branch of b's sharp clearcoat (clearcoat_branches): wi drawn from the clearcoat's sampler (u1, u2), weight
// f(wi) |n·wi| w_clearcoat / Σ_j w_j p_j(wi), kind lobes and glossy (Cycles labels it glossy); kind none where
// the draw fails or leaves below the surface.
BsdfSample sample_clearcoat_branch(const Bsdf& b, float u1, float u2);
// One of b's narrow lobes (narrow_lobe_branches), picked by its sampling weight, and a direction drawn from it
// above the surface, with weight f·cos / (pdf · pick). kind none where b has none or the draw failed.
BsdfSample sample_narrow_lobe_branch(const Bsdf& b, float u0, float u1, float u2);

// What a photon's power is multiplied by across the scatter `s` drew from `b`, so that photon estimates come out
// in Cycles' units of radiance. Physical radiance changes by eta² = (n_t / n_i)² across a refraction; Cycles'
// paths carry it across as (1 − F) times itself, in and out alike, so the radiance a camera path finds beyond a
// refraction is the physical one over eta². A photon that refracts takes 1/eta² (a closed glass object's inside
// photons 1/ior², those that leave it 1 again, a thin glass pane's back face 1 for what never crossed it). A
// transmitted direction shared by rough refraction and translucency takes the refraction's share of f only.
float photon_units_across(const Bsdf& b, const BsdfSample& s);

// The delta directions at this surface (the refraction's only when it exists: none under total internal
// reflection, where its weight has gone to the mirror by Fresnel already).
glm::vec3 mirror_direction(const Bsdf& b);
bool refraction_direction(const Bsdf& b, glm::vec3& direction);

}  // namespace ps
