#pragma once
// Multiscatter GGX glass (Cycles 3.x's Glass BSDF of that distribution, Distribution::multi_ggx_glass).
//
// Cycles renders it as a random walk on a GGX microsurface (Heitz et al. 2016; its mf_sample and mf_eval for
// glass): each microfacet reflects with the dielectric Fresnel of its own normal or refracts, and the Glass colour
// multiplies every scattering after the first. Light leaves on the side it arrived from or on the other. The core
// evaluates the first scattering as Cycles' mf_eval does (closures.cpp), and gives the light of the later ones to
// a cosine lobe on each side, the shape Cycles' own density assumes for it (mf_glass_pdf). How much light that is
// comes from running the walk itself, once per η: a table per roughness and cos θ_o of what it returns on each
// side after one, two, and three or more scatterings (glass_multiscatter.cpp). docs/closures.md has the
// measurements.
#include <cstdint>

#include <glm/vec3.hpp>

namespace ps {

// The albedos of the walk for a view of cos θ_o, per unit of the closure's weight: of its first scattering (white:
// the Glass colour is in the weight) and of its later ones (each multiplied by the tint), on each side.
// multiple_* also holds what the walk's first scattering returns beyond multi_ggx_glass_single's integral (up to
// 17 % of it at roughness 0.8 and cos θ_o 0.3, where Cycles' two disagree; within 0.3 % up to roughness 0.5).
struct GlassMultiscatterAlbedo {
    float single_reflect = 0.0f, single_transmit = 0.0f;
    glm::vec3 multiple_reflect{0.0f}, multiple_transmit{0.0f};
};

// eta: n_other / n_this seen from wo's side (> 0, finite); alpha: the isotropic GGX α (roughness²) in [0, 1];
// cos_o: n·wo in (0, 1]; tint: the Glass colour, in [0, 1]. Thread-safe; the first call for an η builds its
// table (a fraction of a second), later calls only read it.
GlassMultiscatterAlbedo glass_multiscatter_albedo(float eta, float alpha, float cos_o, const glm::vec3& tint);

// The first scattering of the walk towards wi, seen from wo (local frame: n = +z, wo.z > 0; wi.z > 0 reflected,
// < 0 transmitted), white, as Cycles' mf_eval evaluates it: the dielectric Fresnel of the microfacet normal and the
// height-correlated masking of uniform heights; transmitted, with η² (what the walk returns). Its density under
// visible-normal sampling from wo goes to *pdf (may be null).
float multi_ggx_glass_single(float eta, float alpha, const glm::vec3& wi, const glm::vec3& wo, float* pdf);

// Cycles 3.4's own value of its Multiscatter GGX Glass towards a light sample (its mf_eval for glass), which is not
// what its walk returns: where Cycles meets a light from such glass it weighs this against the walk by the power
// heuristic, with mf_glass_pdf as the walk's density (cycles3_multi_glass_pdf), so its image holds both. f (no
// cosine) towards wi, seen from wo (local frame, wo.z > 0; wi.z < 0 transmitted), per unit of the closure's weight,
// the tint once per scattering after the first. Its first scattering is analytic; the later ones come from `walks`
// walks of its own, keyed by `key` (the same key, the same value). As Cycles': the η² of a transmission is left out,
// and a transmission whose wi is the more grazing is evaluated turned round with the same η.
glm::vec3 cycles3_multi_glass_light_value(float eta, float alpha, const glm::vec3& tint, const glm::vec3& wi,
                                          const glm::vec3& wo, int walks, uint64_t key);
// The density Cycles 3.4 reports for that glass's direction wi seen from wo (mf_glass_pdf): both sides together
// (Fresnel of the half vector between them), used only to weigh light samples against its directions.
float cycles3_multi_glass_pdf(float eta, float alpha, const glm::vec3& wi, const glm::vec3& wo);

// Cycles 3.x's random numbers for the walks of one shading point (kernel/sample/lcg.h): a 32-bit LCG seeded by
// lcg_init(rng_hash + rng_offset + sample * scramble), where rng_offset grows by 16 per surface a path meets. So the
// walks of one path at successive vertices run on the same numbers shifted by constants (the k-th by 16 a^k mod
// 2^32, a the LCG's multiplier): Cycles' Multiscatter glass is not independent from one vertex to the next. Through
// a slab of roughness 0.45 seen at cos 0.3, a path that meets both faces leaves through the bottom with 0.49 of the
// light on Cycles' numbers and 0.34 on independent ones, in a narrow band of directions where independent walks
// spread it. The reference runs a lone Multiscatter Glass on these numbers (reference/path_tracer.cpp).
class CyclesLcg {
public:
    // At the vertex of a camera path that met `vertex` surfaces before (transparent ones counted, as Cycles counts
    // them in rng_offset); `path` stands for rng_hash + sample * scramble, uniform over paths.
    static CyclesLcg at_vertex(uint32_t path, int vertex);
    float uniform();  // lcg_step_float: in [0, 1]

private:
    uint32_t state_ = 0;
};
// cycles3_multi_glass_light_value with one walk on `lcg`, as Cycles' light sample runs it (before the bounce's).
glm::vec3 cycles3_multi_glass_light_value(float eta, float alpha, const glm::vec3& tint, const glm::vec3& wi,
                                          const glm::vec3& wo, CyclesLcg& lcg);
// Cycles 3.x's sampling walk from wo (local frame, wo.z > 0) on `lcg` (its mf_sample for glass): the direction it
// leaves along in wi, and its weight per unit of the closure's weight (the tint once per scattering after the
// first); 0 where the walk does not leave within Cycles' ten scatterings. mf_glass_pdf (cycles3_multi_glass_pdf) is
// the density Cycles reports for it.
glm::vec3 cycles3_multi_glass_walk_sample(float eta, float alpha, const glm::vec3& tint, const glm::vec3& wo,
                                          CyclesLcg& lcg, glm::vec3& wi);

// The walk's energies for white glass (tint 1) at one (eta, alpha, cos_o), by side and by the number of
// scatterings, estimated with `walks` walks (the table's own numbers: tests compare them with Cycles').
struct GlassWalkEnergy {
    float reflect[3] = {0.0f, 0.0f, 0.0f};   // after 1, 2, and 3 or more scatterings (up to Cycles' 10)
    float transmit[3] = {0.0f, 0.0f, 0.0f};
};
GlassWalkEnergy glass_walk_energy(float eta, float alpha, float cos_o, int walks, unsigned seed = 1);

}  // namespace ps
