// Everything that emits light, as direct light and photon tracing see it: the scene's lights, the emissive
// surfaces (all triangles of all instances whose material has emission, as one source: Cycles' "mesh lights") and the
// world (world.h: a constant, or a node program importance-sampled through its map and portals). Built per render
// stage from the scene (the world's map is the scene's, built once per change), so a scene without emission pays
// nothing for it.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "photonsplat/lights.h"
#include "photonsplat/world.h"

namespace ps {

class Scene;

class LightSources {
public:
    explicit LightSources(const Scene& scene);

    size_t size() const { return sources_.size(); }
    const std::string& name(size_t i) const { return sources_[i].name; }
    glm::vec3 flux(size_t i) const { return sources_[i].flux; }  // [W] sent into the scene
    bool is_delta(size_t i) const;                                // one shadow ray is exact
    bool is_world(size_t i) const { return sources_[i].kind == Kind::world; }
    // The world as a light (never null); constant(): sampled cosine-weighted, the Lambert part's own density.
    const WorldLight& world() const { return *world_; }
    const Light* light(size_t i) const { return sources_[i].light; }          // nullptr unless a scene light
    // Whether rays other than the camera's (BSDF rays, photon-side mirror chains) meet source i: false for a light
    // with Multiple Importance off (Light::multiple_importance), whose light samples then take weight 1.
    bool found_by_bsdf_rays(size_t i) const { return sources_[i].light == nullptr || sources_[i].light->multiple_importance; }
    // Whether a BSDF ray can meet source i, so that its light samples share with such rays by MIS: it has a size
    // (not is_delta) and Multiple Importance on. Where not, its light samples take weight 1.
    bool mis_with_bsdf_rays(size_t i) const { return !is_delta(i) && found_by_bsdf_rays(i); }
    // Whether source i's light samples take a shadow ray: false for a light with Cast Shadow off.
    bool casts_shadow(size_t i) const { return sources_[i].light == nullptr || sources_[i].light->cast_shadow; }

    // Solid-angle density with which sample_incidence of the emissive surfaces draws the point y of
    // `triangle` of `instance` from x (0 when it does not emit): for MIS of BSDF rays that hit emitters.
    float emissive_pdf(uint32_t instance, uint32_t triangle, const glm::vec3& x, const glm::vec3& y) const;

    // Cycles 3.x's density of drawing, from x, the point its ray along wi meets on scene light i (y on the
    // emissive `triangle` of `instance`), Cycles' pick of the light included. Only where Cycles' estimate depends
    // on it (mirror_emitter_weight); a light's own sampling here has densities of its own. A rectangular area
    // light: Cycles samples its solid angle (1 / the solid angle it spans from x); an ellipse, a disc, a sphere
    // or a sun: as intersect_light's. An emissive triangle: Cycles picks emissive triangles by area alone, and
    // samples a triangle by solid angle where its longest edge is longer than x's distance to its plane, by area
    // elsewhere (triangle_light_pdf). 0 where Cycles would not draw it.
    float cycles_lamp_pdf(size_t i, const glm::vec3& x, const glm::vec3& wi) const;
    float cycles_emissive_pdf(uint32_t instance, uint32_t triangle, const glm::vec3& x, const glm::vec3& y) const;

    // What Cycles 3.x keeps of source i's light reaching x along -wi, where x is a mirror that reports density
    // `mirror_pdf` for wi (mirror_reported_pdf, shading.h; n: its geometric normal on wi's side, `origin` x
    // offset for a ray along wi): its BSDF ray meets the source with mirror_emitter_weight (direct_light.h)
    // against the source's light-sampling density from x, Cycles' pick of it included; a delta light, which no
    // BSDF ray meets, keeps nothing, nor does a light with Multiple Importance off (found_by_bsdf_rays), whatever
    // the mirror. 1 for mirror_pdf 0 (a true mirror). For a photon's first scatter.
    float mirror_weight(size_t i, const glm::vec3& x, const glm::vec3& origin, const glm::vec3& n,
                        const glm::vec3& wi, float mirror_pdf) const;

    // The probability that Cycles 3.4 picks source i for a shading point's one light sample: its light
    // distribution splits its picks evenly over the lamps (a world it importance-samples counts as one), and gives
    // emissive triangles half of them where there are lamps too. We sample every source at every point, so our
    // own MIS weights need none of this; Cycles' weights include it, which changes what Cycles converges to where
    // a BSDF's sampling density is not what it reports (the clearcoat: bsdf_has_clearcoat, shading.h).
    float cycles_pick_probability(size_t i) const {
        return sources_[i].kind == Kind::emissive_surfaces ? emissive_pick_ : lamp_pick_;
    }
    float cycles_lamp_pick_probability() const { return lamp_pick_; }  // a scene light or a programmed world
    // The density of wi from x that Cycles 3.4 weighs source i by against a BSDF's directions, its pick included,
    // where `own` is our sampler's (no pick): a lamp's by cycles_lamp_pdf (a rectangle's by its solid angle, as
    // Cycles samples it), any other source's `own` times Cycles' pick. For the MIS weights that must be Cycles' own
    // (bsdf_weighs_by_cycles_pick, shading.h).
    float cycles_mis_density(size_t i, const glm::vec3& x, const glm::vec3& wi, float own) const {
        return sources_[i].kind == Kind::light ? cycles_lamp_pdf(i, x, wi) : own * cycles_pick_probability(i);
    }
    float cycles_emissive_pick_probability() const { return emissive_pick_; }

    // A sun or a programmed world: its photons start on a disc covering the scene (or on a portal), placed by
    // sample_emission's u1, u2 (an area-preserving map), which an EmissionGuide may redistribute.
    bool emits_from_disc(size_t i) const {
        if (sources_[i].kind == Kind::world) return !world_->constant();
        return sources_[i].kind == Kind::light && sources_[i].light->kind == LightKind::sun;
    }

    // For a shadow ray from x, whose surface has geometric normal n (facing the viewer). u1..u3 in [0, 1).
    // The returned pdf is the solid-angle density of wi (0 for a delta light); a constant world is sampled
    // cosine-weighted about n, a programmed one by its map (and portals).
    LightIncidence sample_incidence(size_t i, const glm::vec3& x, const glm::vec3& n, float u1, float u2,
                                    float u3) const;
    // What the camera sees (a sphere, render space): a programmed world sends half of its disc photons through
    // it (world.h). Radius 0: none.
    void set_focus(const glm::vec3& center, float radius) {
        focus_center_ = center;
        focus_radius_ = radius;
    }
    // A photon's starting ray and power. u1..u5 in [0, 1).
    EmissionSample sample_emission(size_t i, float u1, float u2, float u3, float u4, float u5) const;

private:
    enum class Kind { light, emissive_surfaces, world };
    struct Source {
        Kind kind;
        std::string name;
        glm::vec3 flux;
        const Light* light = nullptr;
    };
    const Scene& scene_;
    std::shared_ptr<const WorldLight> world_;
    glm::vec3 center_;
    float radius_;  // of the scene's bounding sphere
    glm::vec3 focus_center_{0.0f};
    float focus_radius_ = 0.0f;
    std::vector<Source> sources_;
    float lamp_pick_ = 1.0f, emissive_pick_ = 1.0f;  // cycles_pick_probability
    // Emissive triangles of every instance (an instanced emissive mesh lights the scene once per copy), chosen
    // in proportion to world-space area × luminance of their emission.
    struct Emitter {
        uint32_t instance, triangle;
    };
    std::vector<Emitter> emitters_;
    double emissive_area_ = 0.0;  // Σ the emitters' areas (Cycles' pdf_triangles)
    std::vector<float> emitter_cdf_;
    std::vector<float> emitter_probability_;

    size_t pick_emitter(float u) const;
    std::vector<glm::vec3> emitter_emission_;  // radiance of each emitter (a program's: at its centroid)
    glm::vec3 emission_of(size_t emitter) const;
};

}  // namespace ps
