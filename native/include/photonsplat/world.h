// The world: what a ray that leaves the scene sees, and the world as a light source (Cycles' background light,
// kernel/light/background.h).
//
// A world is either a constant radiance (Scene::set_background) or a node program evaluated per direction
// (Scene::set_world_program), as Cycles evaluates the world's shader for a ray that escapes: P = the ray's
// direction, N = Ng = I = -direction, generated and object coordinates = the direction.
//
// As a light, a constant world without portals is sampled cosine-weighted about the receiving surface (that is
// the Lambert part's own density). A programmed world is baked once into an equirectangular map (averaged over
// 2 x 2 points per cell, so a sun smaller than a cell still weighs what it covers) whose piecewise-constant
// distribution (environment_map.h) importance-samples directions; the radiance itself is always the program's
// along the sampled direction, so the map only decides where rays go, never what they carry. Portals (Cycles'
// area lights marked as portals) and a Nishita sky's sun disc (a uniform cone) are sampled beside the map, with
// Cycles 3.4's method weights (portal 1, sun 4, map 1); a portal by a uniform point on its rectangle, its
// density the mean over the portals a direction passes through.
//
// Photons: along a direction drawn from the map (a sun in the sky sends most of the photons, from its own
// direction), from a disc perpendicular to it: half of them from the disc covering the scene's bounding sphere,
// half from the one covering what the camera sees (a large ground plane would take most photons far from the
// view), each weighted by the mixture's density. With portals most of them start on a portal instead, into the
// room (if nothing outside blocks the way to the sky), and the disc photons that would enter through a portal
// are dropped, so that no path counts twice and light through openings without a portal still arrives.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "photonsplat/environment_map.h"
#include "photonsplat/lights.h"
#include "photonsplat/scattering.h"

namespace ps {

class Scene;

// A rectangle the world's light enters through: corner + s·edge_u + t·edge_v for s, t in [0, 1]. Light passes
// it travelling along normalize(cross(edge_u, edge_v)). World space.
struct Portal {
    std::string name;
    glm::dvec3 corner{0.0};
    glm::vec3 edge_u{0.0f}, edge_v{0.0f};
};

// The world's radiance arriving along -direction, i.e. seen by a ray travelling along `direction` (unit) after
// it left the scene; `ray` is what kind of ray it is (Light Path). Finite and >= 0.
glm::vec3 world_radiance(const Scene& scene, const glm::vec3& direction, ShaderRay ray);

// The world as a light source, built from a scene's world by Scene::world_light (once per change of the
// world). Immutable: safe to use from every thread.
class WorldLight {
public:
    explicit WorldLight(const Scene& scene);

    bool black() const { return black_; }            // nothing to light with
    bool constant() const { return constant_; }      // a constant world without portals: cosine-weighted
    const EnvironmentDistribution* map() const { return map_.get(); }  // nullptr for a constant world

    // ∫ L dω over the sphere (RGB) [W m⁻² sr⁻¹ × sr]: the flux through a disc of area A facing every way is A × this.
    glm::vec3 radiance_integral() const { return integral_; }

    // Flux [W] the world sends into a sphere of radius R (no portals), or through the portals.
    glm::vec3 flux(float scene_radius) const;

    // A direction towards the world from x (render space), whose surface has geometric normal n (facing the
    // side light must arrive on). pdf: solid angle; value: radiance / pdf (constant world: radiance π / cos).
    LightIncidence sample_incidence(const glm::vec3& x, const glm::vec3& n, float u1, float u2, float u3) const;
    // The density with which sample_incidence draws wi from x (for MIS of BSDF rays that escape). The constant
    // world's needs n; the others ignore it.
    float pdf(const glm::vec3& x, const glm::vec3& n, const glm::vec3& wi) const;

    // A photon: from a disc covering the sphere (center, radius), or from a portal. Power: flux / probability.
    // A programmed world places the photon with u1, u2 (on the disc or the portal; what an EmissionGuide
    // redistributes) and draws its direction from the map with u3, u4; a constant one draws the direction
    // uniformly with u1, u2 and the disc point with u3, u4.
    // focus (radius > 0): the sphere around what the camera sees; half of the disc photons are sent through it.
    EmissionSample sample_emission(const glm::vec3& center, float radius, const glm::vec3& focus_center,
                                   float focus_radius, float u1, float u2, float u3, float u4, float u5) const;

private:
    const Scene& scene_;
    bool black_ = true;
    bool constant_ = true;
    glm::vec3 background_{0.0f};
    std::unique_ptr<EnvironmentDistribution> map_;
    glm::vec3 integral_{0.0f};
    // Portals in render space.
    struct Rect {
        glm::vec3 corner, edge_u, edge_v, normal;  // normal: the way light passes
        float area;
        glm::vec3 flux;  // through it, from the map
    };
    std::vector<Rect> portals_;
    std::vector<float> portal_cdf_;  // by flux, for photons
    glm::vec3 portal_flux_{0.0f};

    // A Nishita sky's sun disc (its own sampling, as Cycles' background sun).
    bool has_sun_ = false;
    glm::vec3 sun_axis_{0.0f, 0.0f, 1.0f};
    float sun_half_angle_ = 0.0f;
    double sun_one_minus_cos_ = 0.0;
    float sun_photon_share_ = 0.0f;  // of the world's photons, by the disc's share of ∫ L dω

    // The light-sampling methods' probabilities at a point: portals, sun, map (Cycles 3.4's weights 1, 4, 1).
    struct Methods {
        float portal = 0.0f, sun = 0.0f, map = 0.0f;
    };
    Methods methods(int possible_portals) const;
    float sun_pdf(const glm::vec3& wi) const;
    float map_pdf(const glm::vec3& wi) const;
    float portal_pdf(const glm::vec3& x, const glm::vec3& wi, int& possible) const;
    int possible_portals(const glm::vec3& x) const;
};

}  // namespace ps
