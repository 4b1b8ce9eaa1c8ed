// Closures: the BSDFs of Cycles 3.4 as the core renders them. A material is a weighted sum of closures
// (materials.h), as Cycles' shader nodes make one; this header holds one closure's definition (what the add-on
// exports) and its evaluated form at a hit (a Lobe), with the three things every stage needs of a lobe: its
// value for a pair of directions, a sampled direction, and the density of that sampling.
//
// The definitions to match are Cycles 3.4's kernel (closure/bsdf_*.h, svm/svm_closure.h): formulas, Fresnel
// terms, how a node's inputs become a closure's parameters. docs/closures.md lists each closure with its source
// and what differs.
//
// Conventions: every direction is a unit vector pointing AWAY from the surface; `n` is the shading normal on the
// side `wo` arrives from (the viewer's side for camera paths, the light's side for photons' reversed view). A
// lobe's value f excludes the cosine: the scattered radiance is ∫ f(wi, wo) L(wi) |n·wi| dwi. Transmission lobes
// are non-zero only for wi on the other side of the surface (n·wi < 0), reflection lobes only on the same side.
#pragma once
#include <cstdint>
#include <string>

#include <glm/vec3.hpp>

namespace ps {

enum class ClosureKind : uint8_t {
    diffuse,             // Diffuse BSDF: Lambert (roughness 0) or Cycles' Oren–Nayar (σ = roughness)
    principled_diffuse,  // Principled v1's diffuse: Burley's, with its retro-reflection (roughness)
    translucent,         // Translucent BSDF: Lambertian transmission to the other side
    reflection,          // microfacet reflection (distribution, α, fresnel); Distribution::sharp: a mirror
    refraction,          // microfacet refraction through `ior` (no Fresnel inside: Glass splits its weight, see
                         // MixFactor); Distribution::sharp: perfect refraction
    transparent,         // Transparent BSDF: light goes straight through, tinted by the weight
    sheen,               // Principled v1's sheen: weight · (1 − |wi·h|)^5 / π-free form of Cycles' bsdf_principled_sheen
    velvet,              // Velvet BSDF (Ashikhmin's velvet, σ = roughness)
};
constexpr int kClosureKindCount = 8;

enum class Distribution : uint8_t {
    sharp,      // a delta: perfect mirror or perfect refraction
    ggx,        // GGX with separable Smith G (Cycles 3.4's single-scatter GGX)
    beckmann,   // Beckmann with Smith G (Cycles' rational approximation)
    multi_ggx,  // Cycles' multiscatter GGX: GGX plus the energy its single scattering loses (closures.cpp says how)
    gtr1,       // Principled v1's clearcoat: GTR1 distribution, GGX masking with α = 0.25 (Cycles' clearcoat)
    multi_ggx_glass,  // Cycles 3.x's Multiscatter GGX Glass, on the side of a reflection closure or of a
                      // refraction one (glass_multiscatter.h): the whole Glass is the two, unweighted by Fresnel;
                      // specular_color is the Glass colour its later scatterings multiply by
};

enum class FresnelKind : uint8_t {
    none,        // the weight alone (Glossy BSDF, Cycles' Glass halves, refraction)
    principled,  // Principled v1: specular_color + (1 − specular_color) · (F(ior, wi·h) − F0) / (1 − F0),
                 // F the dielectric Fresnel, F0 = F(ior, 1): Cycles' interpolate_fresnel_color
    dielectric,  // F(ior, wi·h) times the weight (clearcoat: ior 1.5)
    schlick,     // specular_color + (1 − specular_color)(1 − wi·h)^5: the core's simple "mirror" and "glossy"
                 // kinds, and Principled v2's metal (F82 with a white edge tint)
};

// A Mix Shader or Glass factor that depends on the viewing direction, evaluated once per hit with the shading
// normal and wo (Cycles evaluates Fresnel and Layer Weight nodes the same way, at the shading point).
enum class FactorKind : uint8_t {
    fresnel,        // Fresnel node / Glass split: F_dielectric(n·wo, η), η = value from the front, 1/value behind
    layer_fresnel,  // Layer Weight's Fresnel output, value = Blend
    layer_facing,   // Layer Weight's Facing output, value = Blend
};
struct MixFactor {
    FactorKind kind = FactorKind::fresnel;
    float value = 1.45f;
};
constexpr int kMaxFactors = 16;

// Where a closure's image texture (Scene::textures) applies: the weight (colour), or the Fresnel colour.
enum class TextureTarget : uint8_t { color, specular_color };

// One closure of a material, as exported.
struct Closure {
    ClosureKind kind = ClosureKind::diffuse;
    Distribution distribution = Distribution::ggx;  // reflection and refraction only
    FresnelKind fresnel = FresnelKind::none;        // reflection only
    TextureTarget texture_target = TextureTarget::color;
    glm::vec3 color{0.8f};           // the weight: colour × every constant Mix/Add factor above it; >= 0
    glm::vec3 specular_color{0.0f};  // principled / schlick Fresnel's colour at normal incidence, in [0, 1]; for
                                     // multi_ggx without Fresnel: the tint of each bounce after the first (Cycles'
                                     // Glossy colour; 0: single scattering only)
    float roughness = 0.0f;          // diffuse (Oren–Nayar σ), principled_diffuse, velvet (σ): in [0, 1]
    float alpha_x = 0.0f, alpha_y = 0.0f;  // reflection / refraction: α along the tangent and the bitangent
                                           // (isotropic: equal; Blender roughness², as Cycles squares it)
    float ior = 1.45f;               // refraction; fresnel principled / dielectric: > 0
    // A sharp reflection that Cycles 3.x renders as Multiscatter GGX of this α (its roughness at most 0.05, and
    // α² >= 1e-7, where Cycles would take it for a mirror itself): a mirror here, but the density Cycles reports
    // for its directions is not a mirror's (cycles3_multiscatter_mirror_pdf), and it weighs the emitters the
    // reflection meets against Cycles' light sampling by it. 0: a mirror Cycles takes for one.
    float reported_alpha = 0.0f;
    int32_t texture = -1;            // Scene::textures index multiplying the target at the hit's UV; -1: none
    uint32_t factors_on = 0;         // bit j: the weight is multiplied by Material::factors[j] at the hit
    uint32_t factors_off = 0;        // bit j: ... by 1 − Material::factors[j]

    bool is_delta() const {
        return kind == ClosureKind::transparent ||
               ((kind == ClosureKind::reflection || kind == ClosureKind::refraction) &&
                distribution == Distribution::sharp);
    }
    bool transmits() const {  // scatters light to the other side of the surface
        return kind == ClosureKind::translucent || kind == ClosureKind::refraction || kind == ClosureKind::transparent;
    }
};

const char* to_string(ClosureKind kind);
ClosureKind closure_kind_from_string(const std::string& name);  // throws InvalidInput
const char* to_string(Distribution d);
Distribution distribution_from_string(const std::string& name);
const char* to_string(FresnelKind f);
FresnelKind fresnel_kind_from_string(const std::string& name);
const char* to_string(FactorKind f);
FactorKind factor_kind_from_string(const std::string& name);
const char* to_string(TextureTarget t);
TextureTarget texture_target_from_string(const std::string& name);

// Checks one closure (finite, ranges above, factor bits below `factor_count`); `where` names it.
void validate(const Closure& c, int factor_count, const std::string& where);
void validate(const MixFactor& f, const std::string& where);

// A factor's value in [0, 1] at a hit: `cos_no` = n·wo (> 0 on the side the ray came from), `backfacing` when the
// ray hit the back face of the triangle (Cycles flips η there).
float evaluate_factor(const MixFactor& f, float cos_no, bool backfacing);

// The unpolarised Fresnel reflectance of a smooth dielectric interface (Cycles' fresnel_dielectric_cos): `cos_i`
// the cosine on the incident side, `eta` = n_transmitted / n_incident. 1 under total internal reflection.
float fresnel_dielectric_cos(float cos_i, float eta);

// A non-delta closure at one hit: its weight made concrete (texture, factors) and its refraction index turned to
// the side the ray came from.
struct Lobe {
    ClosureKind kind = ClosureKind::diffuse;
    Distribution distribution = Distribution::ggx;
    FresnelKind fresnel = FresnelKind::none;
    glm::vec3 weight{0.0f};          // Closure::color × texture × factors at this hit
    glm::vec3 specular_color{0.0f};  // textured where the closure says so
    float roughness = 0.0f;
    float alpha_x = 0.0f, alpha_y = 0.0f;
    float eta = 1.0f;                // refraction: n_other_side / n_this_side (the side n faces); fresnel: the ior
    glm::vec3 tangent{0.0f};         // anisotropic reflection (alpha_x != alpha_y): unit, ⟂ n; else unused
};

// f(wi, wo) of one lobe (no cosine, no delta part), and the density with which lobe_sample would pick wi.
struct LobeValue {
    glm::vec3 f{0.0f};
    float pdf = 0.0f;
};
// Which of Cycles' estimates of a lobe an evaluation follows. A direction Cycles draws from a Multiscatter GGX lobe
// comes with the weight of its random walk on the microsurface (mf_sample): light that leaves after k extra bounces
// keeps the colour (or the Fresnel colour) of each once. Towards a light sample Cycles 3.x evaluates the lobe by
// another walk (mf_eval), which applies each extra bounce's colour twice; 4.x values it there as drawn. And towards
// a light sample every Cycles values a GGX or Beckmann refraction at any pair of directions, even one that no
// microfacet refracts into the other, which it never draws (eval_refraction). Every other lobe is the same in all.
enum class MultiScatterEstimate : uint8_t {
    walk,                  // where Cycles' path samples the lobe: camera paths' indirect light, photons' bounces
    light_sample,          // where Cycles 3.x samples a light (or the world's map) instead: direct light
    light_sample_as_walk,  // where Cycles 4.x samples a light: Multiscatter GGX valued as drawn
};
LobeValue lobe_eval(const Lobe& lobe, const glm::vec3& n, const glm::vec3& wi, const glm::vec3& wo,
                    MultiScatterEstimate estimate = MultiScatterEstimate::walk);
// The density with which lobe_sample really draws wi: lobe_eval's pdf, except for the clearcoat, whose sampler (GGX
// visible normals of its α) is not the density it reports (GTR1's), as in Cycles.
float lobe_sampler_pdf(const Lobe& lobe, const glm::vec3& n, const glm::vec3& wi, const glm::vec3& wo);
// The density Cycles reports for wi where it weighs a light sample against its own BSDF directions (MIS): lobe_eval's
// pdf, except for Multiscatter GGX glass, whose closure reports mf_glass_pdf over both its sides
// (cycles3_multi_glass_pdf, glass_multiscatter.h) where the lobe draws from its own model, and for a GGX or Beckmann
// refraction, which reports a density also where no microfacet joins wi and wo (eval_refraction). Per unit of the
// lobe's weight's sampling weight (sampling_weight_of(lobe.weight)) for such glass, as Cycles picks its one closure.
float lobe_reported_pdf(const Lobe& lobe, const glm::vec3& n, const glm::vec3& wi, const glm::vec3& wo);

struct LobeSample {
    glm::vec3 direction{0.0f};  // wi, unit
    glm::vec3 f{0.0f};          // lobe_eval's f at wi
    float pdf = 0.0f;           // of wi (solid angle); 0: the sample failed and the path ends
};
// Draws wi for wo from the lobe's own distribution (visible normals for microfacets). u1, u2 in [0, 1).
LobeSample lobe_sample(const Lobe& lobe, const glm::vec3& n, const glm::vec3& wo, float u1, float u2);

// The density Cycles 3.x reports for the mirror direction of a Multiscatter GGX lobe of (isotropic) α, seen at
// cos θ = n·wo (mf_ggx_pdf at h = n): its single scattering's D is clamped to α² / max(π α⁴, 1e-7), which for
// α < 0.0133 is far below a mirror's (α = 0.0004, roughness 0.02: 1.6 for 1 / (π α²) = 2e6), so its sampled
// directions meet lights with almost no MIS weight, and its light samples see almost nothing (mf_eval's D is the
// same). Cycles 3.4 thus shows almost none of a light's reflection in such a surface (4.x fixed it).
float cycles3_multiscatter_mirror_pdf(float alpha, float cos_o);
// That lobe towards any wi (n: the normal, unit wi and wo): the f (white, no cosine) its light samples evaluate,
// the single scattering with the clamped D and the height-correlated G2 (its multiple scattering is nothing at
// such α), and the density its sampled directions report for wi (mf_ggx_pdf).
struct Cycles3MirrorValue {
    float f = 0.0f;
    float pdf = 0.0f;
};
Cycles3MirrorValue cycles3_multiscatter_mirror_eval(float alpha, const glm::vec3& n, const glm::vec3& wi,
                                                    const glm::vec3& wo);

// The lobe's weight in choosing which part to sample, as Cycles weighs the closure (the mean of its weight's
// channels, a Fresnel closure's times the mean of its Fresnel colour at wo): never in an estimate's value, but
// where Cycles' own estimate depends on its choice (a clearcoat's, the labels its Caustics toggles go by), ours
// follows it.
float lobe_sampling_weight(const Lobe& lobe, const glm::vec3& n, const glm::vec3& wo);

// Cycles' ensure_valid_reflection (closure/bsdf_util.h): a shading normal n (unit) tilted towards the geometric
// normal ng just enough that the mirror direction of i (unit, towards the viewer) leaves the surface at least as
// steeply as min(0.9 ng·i, 0.01); ng where no such tilt exists. Cycles applies it to every bumped or
// normal-mapped closure normal.
glm::vec3 ensure_valid_reflection(const glm::vec3& ng, const glm::vec3& i, const glm::vec3& n);

// The Fresnel colour of a sharp reflection closure at cos θ = n·wo (delta lobes have no lobe_eval).
glm::vec3 sharp_reflection_fresnel(FresnelKind fresnel, const glm::vec3& specular_color, float ior, float cos_no);

}  // namespace ps
