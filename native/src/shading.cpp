#include "photonsplat/shading.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "photonsplat/bump_shadowing.h"
#include "photonsplat/material_program.h"
#include "photonsplat/materials.h"
#include "photonsplat/scattering.h"
#include "photonsplat/scene.h"
#include "photonsplat/textures.h"

namespace ps {

namespace {

constexpr float kInvPi = 0.318309886183790671538f;

// Below this cosine between the shading normal and the viewer, a directional closure shades with the geometric
// normal: interpolation tilts shading normals away from the viewer at silhouettes of smooth meshes, where a lobe
// would see wo below its surface and reflect nothing (black rims).
constexpr float kMinShadingCosine = 1e-3f;

bool is_zero(const glm::vec3& v) { return v.x <= 0.0f && v.y <= 0.0f && v.z <= 0.0f; }

// Reflection-side f of the Lambert sum and the lobes; wi on wo's side of the geometric normal. The diffuse parts
// (takes_bump_shadowing) are multiplied by `diffuse_term`.
glm::vec3 reflection_value(const glm::vec3& lambert, const Lobe* lobes, int count, const glm::vec3& n,
                           const glm::vec3& wi, const glm::vec3& wo,
                           MultiScatterEstimate estimate = MultiScatterEstimate::walk, float diffuse_term = 1.0f) {
    glm::vec3 diffuse = glm::dot(wi, n) > 0.0f ? lambert * kInvPi : glm::vec3(0.0f);
    glm::vec3 f(0.0f);
    for (int k = 0; k < count; ++k) {
        if (is_transmission(lobes[k])) continue;
        (takes_bump_shadowing(lobes[k]) ? diffuse : f) += lobe_eval(lobes[k], n, wi, wo, estimate).f;
    }
    return f + diffuse * diffuse_term;
}

bool in_set(const Lobe& l, LobeSet set) {
    if (set == LobeSet::all) return true;
    return is_transmission(l) == (set == LobeSet::transmission);
}

// The lobe-sampling strategy of a set: Lambert (outside the transmission set) and each lobe, chosen in
// proportion to these weights.
struct LobeChoice {
    LobeSet set = LobeSet::all;
    float lambert = 0.0f;
    float lobe[kMaxLobes] = {};
    float total = 0.0f;
};

// A part's selection weight raised to the floor where the part is there at all.
float at_least(float weight, bool present, float floor) { return present ? std::max(weight, floor) : weight; }
// The same for a part of weight `part` (Lambert, mirror, refraction, transparency): the mean of its channels, as
// Cycles weighs its closures for sampling (closure/alloc.h).
float selection_weight(const glm::vec3& part, float floor) {
    return at_least(std::max(0.0f, (part.x + part.y + part.z) * (1.0f / 3.0f)), !is_zero(part), floor);
}

// The delta parts' summed selection weight (bsdf_sample), each raised to `floor`.
float delta_sampling_weight(const Bsdf& b, float floor) {
    return selection_weight(b.mirror, floor) + selection_weight(b.refraction, floor) +
           selection_weight(b.transparent, floor);
}

LobeChoice lobe_choice(const Bsdf& b, LobeSet set) {
    LobeChoice c;
    const float floor = b.selection_floor;
    c.set = set;
    if (set != LobeSet::transmission) c.lambert = selection_weight(b.lambert, floor);
    c.total = c.lambert;
    for (int k = 0; k < b.lobe_count; ++k) {
        if (!in_set(b.lobes[k], set)) continue;
        c.lobe[k] = std::max(0.0f, lobe_sampling_weight(b.lobes[k], b.n, b.wo));
        if (!std::isfinite(c.lobe[k])) c.lobe[k] = 0.0f;
        c.lobe[k] = at_least(c.lobe[k], !is_zero(b.lobes[k].weight), floor);
        c.total += c.lobe[k];
    }
    return c;
}

// The density of wi under the choice: the one its samplers draw with, or (`reported`) the one Cycles reports for
// its closures where it weighs light samples against them (lobe_reported_pdf: Multiscatter GGX glass's closure
// picked by its own weight and reporting mf_glass_pdf).
float choice_pdf(const Bsdf& b, const LobeChoice& c, const glm::vec3& wi, bool reported = false) {
    if (!(c.total > 0.0f)) return 0.0f;
    float pdf = c.lambert > 0.0f ? c.lambert * std::max(0.0f, glm::dot(wi, b.n)) * kInvPi : 0.0f;
    for (int k = 0; k < b.lobe_count; ++k) {
        if (!(c.lobe[k] > 0.0f)) continue;
        const Lobe& l = b.lobes[k];
        if (reported && l.distribution == Distribution::multi_ggx_glass)
            pdf += std::fabs((l.weight.x + l.weight.y + l.weight.z) * (1.0f / 3.0f)) *
                   lobe_reported_pdf(l, b.n, wi, b.wo);
        else
            pdf += c.lobe[k] * (reported ? lobe_reported_pdf(l, b.n, wi, b.wo) : lobe_eval(l, b.n, wi, b.wo).pdf);
    }
    return pdf / c.total;
}

BsdfSample sample_choice(const Bsdf& b, const LobeChoice& c, float u0, float u1, float u2) {
    BsdfSample out;
    if (!(c.total > 0.0f)) return out;
    // Pick Lambert or a lobe by u0, then place the direction with u1, u2.
    float pick = u0 * c.total;
    glm::vec3 wi(0.0f);
    bool picked = false, glossy = false;
    if (c.lambert > 0.0f) {
        if (pick < c.lambert) {
            wi = sample_cosine_hemisphere(b.n, u1, u2);
            picked = true;
        }
        pick -= c.lambert;
    }
    int last = -1;
    for (int k = 0; k < b.lobe_count; ++k)
        if (c.lobe[k] > 0.0f) last = k;
    for (int k = 0; k < b.lobe_count && !picked; ++k) {
        if (!(c.lobe[k] > 0.0f)) continue;
        if (pick < c.lobe[k] || k == last) {
            const LobeSample s = lobe_sample(b.lobes[k], b.n, b.wo, u1, u2);
            if (!(s.pdf > 0.0f)) return out;
            wi = s.direction;
            picked = true;
            glossy = b.lobes[k].kind == ClosureKind::reflection || b.lobes[k].kind == ClosureKind::refraction;
        }
        pick -= c.lobe[k];
    }
    if (!picked) return out;
    const float pdf = choice_pdf(b, c, wi);
    if (!(pdf > 0.0f) || !std::isfinite(pdf)) return out;
    const glm::vec3 f = bsdf_eval(b, wi, c.set, b.sampled_estimate);
    const glm::vec3 weight = f * (std::fabs(glm::dot(wi, b.n)) / pdf);
    if (is_zero(weight) || !std::isfinite(weight.x + weight.y + weight.z)) return out;
    out.kind = ScatterKind::lobes;
    out.direction = wi;
    out.weight = weight;
    out.pdf = pdf;
    out.mis_pdf = bsdf_has_multi_ggx_glass(b) ? choice_pdf(b, c, wi, true) : pdf;
    out.transmitted = glm::dot(wi, b.ng) < 0.0f;
    out.glossy = glossy;
    return out;
}

}  // namespace

namespace {

// Σ of the closures' weights, textured: a lambert_only material's albedo.
glm::vec3 albedo_of(const Scene& scene, const SurfacePoint& surface, const Closure* closures, size_t count) {
    glm::vec3 albedo(0.0f);
    for (size_t i = 0; i < count; ++i) {
        const Closure& c = closures[i];
        glm::vec3 weight = c.color;
        if (c.texture >= 0 && c.texture_target == TextureTarget::color)
            weight *= scene.textures()[static_cast<size_t>(c.texture)].lookup(surface.uv);
        albedo += weight;
    }
    return albedo;
}

}  // namespace

glm::vec3 lambert_albedo(const Scene& scene, const SurfacePoint& surface, const glm::vec3& wo) {
    const Material& m = *surface.material;
    if (!m.programmed) return albedo_of(scene, surface, m.closures.data(), m.closures.size());
    // The program's values in place of the constants; a closure's texture still multiplies, as in shade().
    ProgrammedMaterial programmed;
    run_material_program(scene, surface, wo, programmed);
    return albedo_of(scene, surface, programmed.closures, static_cast<size_t>(programmed.closure_count));
}

namespace {

// shade() for a given list of closures: the material's own, or those its program set at this hit.
Bsdf shade_closures(const Scene& scene, const SurfacePoint& surface, const glm::vec3& wo, const Closure* closures,
                    size_t closure_count, bool view_factors = true) {
    Bsdf b;
    const Material& m = *surface.material;
    b.ng = surface.geometric_normal;
    b.wo = wo;
    b.n = surface.shading_normal;
    if (m.directional && !(glm::dot(b.n, wo) > kMinShadingCosine)) b.n = b.ng;
    b.smooth_n = surface.smooth_normal;
    b.bump_shadowed = bump_shadowed(b.smooth_n, b.n);
    b.bump_form = scene.bump_shadowing(m);
    if (m.holdout) return b;  // absorbs everything

    // The view-dependent factors, once per hit (Cycles evaluates Fresnel and Layer Weight at the shading point).
    float factor[kMaxFactors];
    // Fresnel and Layer Weight read Cycles' sd->N, untilted (a program's normal where it makes one).
    const glm::vec3& factor_normal = m.program_normal ? surface.shading_normal : surface.smooth_normal;
    const float cos_no = std::clamp(glm::dot(factor_normal, wo), 0.0f, 1.0f);
    for (size_t j = 0; j < m.factors.size(); ++j)
        factor[j] = view_factors ? evaluate_factor(m.factors[j], cos_no, !surface.entering) : 0.5f;

    for (size_t ci = 0; ci < closure_count; ++ci) {
        const Closure& c = closures[ci];
        glm::vec3 weight = c.color;
        for (size_t j = 0; j < m.factors.size(); ++j) {
            if (c.factors_on & (1u << j)) weight *= factor[j];
            if (c.factors_off & (1u << j)) weight *= 1.0f - factor[j];
        }
        glm::vec3 specular_color = c.specular_color;
        if (c.texture >= 0) {
            const glm::vec3 texel = scene.textures()[static_cast<size_t>(c.texture)].lookup(surface.uv);
            if (c.texture_target == TextureTarget::color)
                weight *= texel;
            else
                specular_color *= texel;
        }
        if (is_zero(weight)) continue;
        // Refraction indices are relative to the side the ray came from: into the material from the front.
        const float eta = surface.entering ? c.ior : 1.0f / c.ior;
        if (c.kind == ClosureKind::transparent) {
            b.transparent += weight;
            continue;
        }
        if (c.is_delta()) {
            if (c.kind == ClosureKind::reflection) {
                b.mirror += weight * sharp_reflection_fresnel(c.fresnel, specular_color, c.ior,
                                                              std::clamp(glm::dot(b.n, wo), 0.0f, 1.0f));
                if (b.mirror_reported_alpha == 0.0f) b.mirror_reported_alpha = c.reported_alpha;
            } else {
                if (is_zero(b.refraction)) b.refraction_eta = eta;
                b.refraction += weight;
            }
            continue;
        }
        if (c.kind == ClosureKind::diffuse && c.roughness == 0.0f) {
            b.lambert += weight;
            continue;
        }
        Lobe l;
        l.kind = c.kind;
        l.distribution = c.distribution;
        l.fresnel = c.fresnel;
        l.weight = weight;
        l.specular_color = specular_color;
        l.roughness = c.roughness;
        l.alpha_x = c.alpha_x;
        l.alpha_y = c.alpha_y;
        // A refraction's η, and a Multiscatter GGX Glass's on either side, are seen from the side the ray came from.
        l.eta = c.kind == ClosureKind::refraction || c.distribution == Distribution::multi_ggx_glass ? eta : c.ior;
        l.tangent = surface.tangent;
        if (b.lobe_count < kMaxLobes) {
            b.lobes[b.lobe_count++] = l;
        } else {
            // Never for a validated material (at most kMaxLobes non-Lambert closures); kept finite regardless.
            b.lobes[kMaxLobes - 1].weight += l.weight;
        }
    }
    return b;
}

}  // namespace

Bsdf shade(const Scene& scene, const SurfacePoint& surface, const glm::vec3& wo) {
    const Material& m = *surface.material;
    if (!m.programmed) return shade_closures(scene, surface, wo, m.closures.data(), m.closures.size());
    // The program's values replace the constants (a closure's texture shortcut and the factors still apply).
    ProgrammedMaterial programmed;
    run_material_program(scene, surface, wo, programmed);
    return shade_closures(scene, surface, wo, programmed.closures, static_cast<size_t>(programmed.closure_count));
}

Bsdf shade_halfway_factors(const Scene& scene, const SurfacePoint& surface, const glm::vec3& wo) {
    const Material& m = *surface.material;
    if (!m.programmed) return shade_closures(scene, surface, wo, m.closures.data(), m.closures.size(), false);
    ProgrammedMaterial programmed;
    run_material_program(scene, surface, wo, programmed);
    return shade_closures(scene, surface, wo, programmed.closures, static_cast<size_t>(programmed.closure_count),
                          false);
}

bool is_transmission(const Lobe& l) { return l.kind == ClosureKind::translucent || l.kind == ClosureKind::refraction; }

glm::vec3 translucent_albedo(const Bsdf& b) {
    glm::vec3 albedo(0.0f);
    for (int k = 0; k < b.lobe_count; ++k)
        if (b.lobes[k].kind == ClosureKind::translucent) albedo += b.lobes[k].weight;
    return albedo;
}

namespace {

Bsdf lobes_where(const Bsdf& b, bool translucent) {
    Bsdf out = b;
    out.lobe_count = 0;
    for (int k = 0; k < b.lobe_count; ++k)
        if ((b.lobes[k].kind == ClosureKind::translucent) == translucent) out.lobes[out.lobe_count++] = b.lobes[k];
    if (translucent) out.lambert = out.mirror = out.refraction = out.transparent = glm::vec3(0.0f);
    return out;
}

}  // namespace

Bsdf translucency_of(const Bsdf& b) { return lobes_where(b, true); }
Bsdf without_translucency(const Bsdf& b) { return lobes_where(b, false); }

bool is_diffuse_reflection(const Lobe& l) {
    return l.kind == ClosureKind::diffuse || l.kind == ClosureKind::principled_diffuse || l.kind == ClosureKind::sheen ||
           l.kind == ClosureKind::velvet;
}

bool takes_bump_shadowing(const Lobe& l) {
    return l.kind == ClosureKind::diffuse || l.kind == ClosureKind::principled_diffuse || l.kind == ClosureKind::sheen ||
           l.kind == ClosureKind::translucent;
}

float bump_shadowing_of(const Bsdf& b, const glm::vec3& wi) {
    return b.bump_shadowed ? bump_shadowing_term(b.bump_form, b.smooth_n, b.n, wi) : 1.0f;
}

void take_bump_shadowing(Bsdf& b, const glm::vec3& wi) {
    if (!b.bump_shadowed) return;
    const float term = bump_shadowing_term(b.bump_form, b.smooth_n, b.n, wi);
    b.lambert *= term;
    for (int k = 0; k < b.lobe_count; ++k)
        if (takes_bump_shadowing(b.lobes[k])) b.lobes[k].weight *= term;
    b.bump_shadowed = false;
}

namespace {

// The set's parts for wi on the reflection side (`above`) or the transmission side of the surface.
glm::vec3 eval_on_side(const Bsdf& b, const glm::vec3& wi, LobeSet set, MultiScatterEstimate estimate, bool above) {
    if (above && set == LobeSet::transmission) return glm::vec3(0.0f);
    if (!above && set == LobeSet::reflection) return glm::vec3(0.0f);
    const float diffuse_term = bump_shadowing_of(b, wi);
    if (above) return reflection_value(b.lambert, b.lobes, b.lobe_count, b.n, wi, b.wo, estimate, diffuse_term);
    glm::vec3 f(0.0f);
    for (int k = 0; k < b.lobe_count; ++k)
        if (is_transmission(b.lobes[k]))
            f += lobe_eval(b.lobes[k], b.n, wi, b.wo, estimate).f *
                 (takes_bump_shadowing(b.lobes[k]) ? diffuse_term : 1.0f);
    return f;
}

}  // namespace

glm::vec3 bsdf_eval(const Bsdf& b, const glm::vec3& wi, LobeSet set, MultiScatterEstimate estimate) {
    return eval_on_side(b, wi, set, estimate, glm::dot(wi, b.ng) > 0.0f);
}

glm::vec3 bsdf_eval_shading_side(const Bsdf& b, const glm::vec3& wi, LobeSet set, MultiScatterEstimate estimate) {
    return eval_on_side(b, wi, set, estimate, glm::dot(wi, b.n) > 0.0f);
}

glm::vec3 bsdf_eval_reflection(const glm::vec3& lambert, const Lobe* lobes, int lobe_count, const glm::vec3& n,
                               const glm::vec3& wi, const glm::vec3& wo) {
    return reflection_value(lambert, lobes, lobe_count, n, wi, wo);
}

bool labelled_diffuse(const Lobe& l) { return is_diffuse_reflection(l) || l.kind == ClosureKind::translucent; }

namespace {

// Σ w_j p_j(wi) over the parts (all, and the diffuse-labelled ones), and f(wi) likewise, for ScatterLabel and
// LabelShare. `lambert` counts only for wi above n; lobes only on their own side (reflection or transmission).
// `drawn`: Σ w_j times the density part j's sampler really draws wi with, which differs from the one it reports
// (in `picked`) only for a clearcoat.
struct LabelSums {
    float picked = 0.0f, picked_diffuse = 0.0f, drawn = 0.0f;
    glm::vec3 f{0.0f}, f_diffuse{0.0f};
    void add(const glm::vec3& value, float weight_times_pdf, bool diffuse, float weight_times_drawn_pdf) {
        f += value;
        picked += weight_times_pdf;
        drawn += weight_times_drawn_pdf;
        if (diffuse) {
            f_diffuse += value;
            picked_diffuse += weight_times_pdf;
        }
    }
    float diffuse_probability() const { return picked > 0.0f ? picked_diffuse / picked : 0.0f; }
};

// A lobe's sampling weight as Cycles picks among its closures, raised to the defensive floor.
float part_weight(const Lobe& lobe, const glm::vec3& n, const glm::vec3& wo, float floor) {
    const float w = lobe_sampling_weight(lobe, n, wo);
    return at_least(std::isfinite(w) ? std::max(w, 0.0f) : 0.0f, !is_zero(lobe.weight), floor);
}

LabelSums label_sums(const glm::vec3& lambert, const Lobe* lobes, int count, const glm::vec3& n, const glm::vec3& wi,
                     const glm::vec3& wo, float floor, bool reflection_side, float diffuse_term) {
    LabelSums sums;
    const float cos_i = glm::dot(wi, n);
    if (reflection_side && cos_i > 0.0f && !is_zero(lambert)) {
        const float w = selection_weight(lambert, floor) * cos_i * kInvPi;
        sums.add(lambert * (kInvPi * diffuse_term), w, true, w);
    }
    for (int k = 0; k < count; ++k) {
        if (is_transmission(lobes[k]) == reflection_side) continue;
        const LobeValue v = lobe_eval(lobes[k], n, wi, wo);
        const float w = part_weight(lobes[k], n, wo, floor);
        // A clearcoat's own sampler: its branch's where it branches (clearcoat_branches), not the splat's.
        const float drawn = lobes[k].distribution != Distribution::gtr1 ? v.pdf
                            : clearcoat_branches(lobes[k])         ? 0.0f
                                                                   : lobe_sampler_pdf(lobes[k], n, wi, wo);
        sums.add(v.f * (takes_bump_shadowing(lobes[k]) ? diffuse_term : 1.0f), w * v.pdf, labelled_diffuse(lobes[k]),
                 w * drawn);
    }
    return sums;
}

}  // namespace

glm::vec3 bsdf_eval_reflection(const glm::vec3& lambert, const Lobe* lobes, int lobe_count, const glm::vec3& n,
                               const glm::vec3& wi, const glm::vec3& wo, LabelShare share, float selection_floor,
                               float diffuse_term) {
    bool clearcoat = false;
    for (int k = 0; k < lobe_count; ++k) clearcoat = clearcoat || lobes[k].distribution == Distribution::gtr1;
    if (share == LabelShare::whole && !clearcoat)
        return reflection_value(lambert, lobes, lobe_count, n, wi, wo, MultiScatterEstimate::walk, diffuse_term);
    const LabelSums sums = label_sums(lambert, lobes, lobe_count, n, wi, wo, selection_floor, true, diffuse_term);
    if (share == LabelShare::diffuse_parts) return sums.f_diffuse;
    // Cycles' camera path draws wi with density Σ w_j p_j^drawn and weighs it by f / Σ w_j p_j^reported: it converges
    // to f Σ w p^drawn / Σ w p^reported, which is f but where a clearcoat's two densities differ (bsdf_has_clearcoat).
    // Of that, the share it labels diffuse is f Σ_diffuse w p / Σ w p^reported.
    const glm::vec3 whole = sums.picked > 0.0f ? sums.f * (sums.drawn / sums.picked) : sums.f;
    if (share == LabelShare::other_parts) return glm::max(whole - sums.f_diffuse, glm::vec3(0.0f));
    if (!(sums.picked > 0.0f)) return share == LabelShare::diffuse ? glm::vec3(0.0f) : sums.f;
    switch (share) {
        case LabelShare::whole: return whole;
        case LabelShare::diffuse: return sums.f * (sums.picked_diffuse / sums.picked);
        default: break;
    }
    return sums.f * (std::max(0.0f, sums.drawn - sums.picked_diffuse) / sums.picked);
}

bool clearcoat_branches(const Lobe& lobe) {
    return lobe.kind == ClosureKind::reflection && lobe.distribution == Distribution::gtr1 &&
           std::max(lobe.alpha_x, lobe.alpha_y) <= 0.01f;
}

bool bsdf_has_branching_clearcoat(const Bsdf& b) {
    for (int k = 0; k < b.lobe_count; ++k)
        if (clearcoat_branches(b.lobes[k])) return true;
    return false;
}

BsdfSample sample_clearcoat_branch(const Bsdf& b, float u1, float u2) {
    BsdfSample out;
    int clearcoat = -1;
    for (int k = 0; k < b.lobe_count && clearcoat < 0; ++k)
        if (clearcoat_branches(b.lobes[k])) clearcoat = k;
    if (clearcoat < 0) return out;
    const LobeSample s = lobe_sample(b.lobes[clearcoat], b.n, b.wo, u1, u2);
    if (!(s.pdf > 0.0f) || !(glm::dot(s.direction, b.ng) > 0.0f)) return out;
    const LabelSums sums =
        label_sums(b.lambert, b.lobes, b.lobe_count, b.n, s.direction, b.wo, b.selection_floor, true,
                   bump_shadowing_of(b, s.direction));
    if (!(sums.picked > 0.0f)) return out;
    const float w = part_weight(b.lobes[clearcoat], b.n, b.wo, b.selection_floor);
    const glm::vec3 weight = sums.f * (std::fabs(glm::dot(s.direction, b.n)) * w / sums.picked);
    if (!std::isfinite(weight.x + weight.y + weight.z) || is_zero(weight)) return out;
    out.kind = ScatterKind::lobes;
    out.glossy = true;
    out.direction = s.direction;
    out.weight = glm::max(weight, glm::vec3(0.0f));
    return out;
}

bool narrow_lobe_branches(const Lobe& lobe) {
    constexpr float kNarrowAlpha = 0.04f;
    return lobe.kind == ClosureKind::reflection && lobe.distribution != Distribution::gtr1 &&
           std::max(lobe.alpha_x, lobe.alpha_y) <= kNarrowAlpha;
}

bool bsdf_has_narrow_lobe(const Bsdf& b) {
    for (int k = 0; k < b.lobe_count; ++k)
        if (narrow_lobe_branches(b.lobes[k])) return true;
    return false;
}

BsdfSample sample_narrow_lobe_branch(const Bsdf& b, float u0, float u1, float u2) {
    BsdfSample out;
    float weights[kMaxLobes] = {}, total = 0.0f;
    for (int k = 0; k < b.lobe_count; ++k) {
        if (!narrow_lobe_branches(b.lobes[k])) continue;
        const float w = lobe_sampling_weight(b.lobes[k], b.n, b.wo);
        weights[k] = std::isfinite(w) ? std::max(w, 0.0f) : 0.0f;
        total += weights[k];
    }
    if (!(total > 0.0f)) return out;
    int chosen = -1;
    float pick = u0 * total;
    for (int k = 0; k < b.lobe_count; ++k) {
        if (!(weights[k] > 0.0f)) continue;
        chosen = k;
        if (pick < weights[k]) break;
        pick -= weights[k];
    }
    const LobeSample s = lobe_sample(b.lobes[chosen], b.n, b.wo, u1, u2);
    if (!(s.pdf > 0.0f) || !(glm::dot(s.direction, b.ng) > 0.0f)) return out;
    const glm::vec3 weight = s.f * (std::fabs(glm::dot(s.direction, b.n)) * total / (s.pdf * weights[chosen]));
    if (!std::isfinite(weight.x + weight.y + weight.z) || is_zero(weight)) return out;
    out.kind = ScatterKind::lobes;
    out.glossy = true;
    out.direction = s.direction;
    out.weight = glm::max(weight, glm::vec3(0.0f));
    out.pdf = out.mis_pdf = s.pdf * weights[chosen] / total;
    return out;
}

ScatterLabel scatter_label(const Bsdf& b, const glm::vec3& wi) {
    const LabelSums sums =
        label_sums(b.lambert, b.lobes, b.lobe_count, b.n, wi, b.wo, b.selection_floor, glm::dot(wi, b.ng) > 0.0f,
                   bump_shadowing_of(b, wi));
    ScatterLabel label;
    label.diffuse_probability = sums.diffuse_probability();
    for (int c = 0; c < 3; ++c)
        label.diffuse_value[c] = sums.f[c] > 0.0f ? std::clamp(sums.f_diffuse[c] / sums.f[c], 0.0f, 1.0f) : 0.0f;
    return label;
}

float bsdf_pdf(const Bsdf& b, const glm::vec3& wi, LobeSet set) { return choice_pdf(b, lobe_choice(b, set), wi, true); }

bool bsdf_has(const Bsdf& b, LobeSet set) {
    if (set != LobeSet::transmission && !is_zero(b.lambert)) return true;
    for (int k = 0; k < b.lobe_count; ++k)
        if (in_set(b.lobes[k], set)) return true;
    return false;
}

bool bsdf_has_clearcoat(const Bsdf& b) {
    for (int k = 0; k < b.lobe_count; ++k)
        if (b.lobes[k].distribution == Distribution::gtr1) return true;
    return false;
}

float defensive_floor(const Bsdf& b) {
    // 1/8 of the parts' summed weights, as Cycles sums its closures'.
    float sum = selection_weight(b.lambert, 0.0f) + delta_sampling_weight(b, 0.0f);
    for (int k = 0; k < b.lobe_count; ++k) {
        const float w = lobe_sampling_weight(b.lobes[k], b.n, b.wo);
        if (std::isfinite(w)) sum += std::max(w, 0.0f);
    }
    return 0.125f * sum;
}

bool bsdf_has_multi_ggx_glass(const Bsdf& b) {
    for (int k = 0; k < b.lobe_count; ++k)
        if (b.lobes[k].distribution == Distribution::multi_ggx_glass) return true;
    return false;
}

const Lobe* lone_multi_ggx_glass(const Bsdf& b, float side_z) {
    if (b.lobe_count != 2 || !is_zero(b.lambert) || !is_zero(b.mirror) || !is_zero(b.refraction) ||
        !is_zero(b.transparent))
        return nullptr;
    const Lobe& l0 = b.lobes[0];
    const Lobe& l1 = b.lobes[1];
    if (l0.distribution != Distribution::multi_ggx_glass || l1.distribution != Distribution::multi_ggx_glass ||
        l0.kind == l1.kind || l0.eta != l1.eta || l0.alpha_x != l1.alpha_x || l0.weight != l1.weight ||
        l0.specular_color != l1.specular_color)
        return nullptr;
    const bool reflect = side_z > 0.0f;
    return (l0.kind == ClosureKind::reflection) == reflect ? &l0 : &l1;
}

bool bsdf_weighs_by_cycles_pick(const Bsdf& b) { return bsdf_has_clearcoat(b) || bsdf_has_multi_ggx_glass(b); }

void choose_defensively(Bsdf& b) { b.selection_floor = bsdf_has_clearcoat(b) ? defensive_floor(b) : 0.0f; }

BsdfSample bsdf_sample_set(const Bsdf& b, LobeSet set, float u0, float u1, float u2) {
    return sample_choice(b, lobe_choice(b, set), u0, u1, u2);
}

float mirror_reported_pdf(const Bsdf& b) {
    return b.mirror_reported_alpha > 0.0f ? cycles3_multiscatter_mirror_pdf(b.mirror_reported_alpha, glm::dot(b.n, b.wo))
                                          : 0.0f;
}

glm::vec3 mirror_direction(const Bsdf& b) {
    const float c = glm::dot(b.wo, b.n);
    return glm::normalize(2.0f * c * b.n - b.wo);
}

bool refraction_direction(const Bsdf& b, glm::vec3& direction) {
    // Snell's law about the shading normal; eta = n_other / n_this.
    const float cos_i = std::clamp(glm::dot(b.wo, b.n), 0.0f, 1.0f);
    const float inv_eta = 1.0f / b.refraction_eta;
    const float sin2_t = inv_eta * inv_eta * std::max(0.0f, 1.0f - cos_i * cos_i);
    if (!(sin2_t < 1.0f)) return false;  // total internal reflection
    const float cos_t = std::sqrt(1.0f - sin2_t);
    direction = glm::normalize(-inv_eta * b.wo + (inv_eta * cos_i - cos_t) * b.n);
    return true;
}

float bsdf_sample_pdf(const Bsdf& b, const glm::vec3& wi) {
    const LobeChoice lobes = lobe_choice(b, LobeSet::all);
    const float total = lobes.total + delta_sampling_weight(b, b.selection_floor);
    if (!(lobes.total > 0.0f) || !(total > 0.0f)) return 0.0f;
    return choice_pdf(b, lobes, wi, true) * (lobes.total / total);
}

float photon_units_across(const Bsdf& b, const BsdfSample& s) {
    if (s.kind == ScatterKind::refraction) return 1.0f / (b.refraction_eta * b.refraction_eta);
    if (s.kind != ScatterKind::lobes || !s.transmitted) return 1.0f;
    float refracted = 0.0f, total = 0.0f;
    for (int k = 0; k < b.lobe_count; ++k) {
        if (!is_transmission(b.lobes[k])) continue;
        const float f = luminance(lobe_eval(b.lobes[k], b.n, s.direction, b.wo).f);
        if (!(f > 0.0f)) continue;
        total += f;
        refracted += b.lobes[k].kind == ClosureKind::refraction ? f / (b.lobes[k].eta * b.lobes[k].eta) : f;
    }
    return total > 0.0f ? refracted / total : 1.0f;
}

BsdfSample bsdf_sample(const Bsdf& b, float u0, float u1, float u2) {
    const LobeChoice lobes = lobe_choice(b, LobeSet::all);
    const float floor = b.selection_floor;
    const float w_mirror = selection_weight(b.mirror, floor), w_refraction = selection_weight(b.refraction, floor),
                w_transparent = selection_weight(b.transparent, floor);
    const float total = lobes.total + w_mirror + w_refraction + w_transparent;
    BsdfSample out;
    if (!(total > 0.0f) || !std::isfinite(total)) return out;
    float pick = u0 * total;
    if (pick < lobes.total) {
        // Rescale u0 into [0, 1) for the lobe choice, then weigh by the probability of having chosen the lobes.
        BsdfSample s = sample_choice(b, lobes, std::min(pick / lobes.total, 0x1.fffffep-1f), u1, u2);
        s.weight *= total / lobes.total;
        s.pdf *= lobes.total / total;
        s.mis_pdf *= lobes.total / total;
        return s;
    }
    pick -= lobes.total;
    if (pick < w_mirror || (w_refraction <= 0.0f && w_transparent <= 0.0f)) {
        if (!(w_mirror > 0.0f)) return out;
        out.kind = ScatterKind::mirror;
        out.glossy = true;
        out.direction = mirror_direction(b);
        out.weight = b.mirror * (total / w_mirror);
        return out;
    }
    pick -= w_mirror;
    if (pick < w_refraction || w_transparent <= 0.0f) {
        if (!(w_refraction > 0.0f) || !refraction_direction(b, out.direction)) return out;
        out.kind = ScatterKind::refraction;
        out.glossy = true;
        out.weight = b.refraction * (total / w_refraction);
        out.transmitted = true;
        return out;
    }
    out.kind = ScatterKind::transparent;
    out.direction = -b.wo;
    out.weight = b.transparent * (total / w_transparent);
    out.transmitted = true;
    return out;
}

}  // namespace ps
