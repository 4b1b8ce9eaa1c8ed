// Light sources in radiometric units. The add-on converts Blender/Cycles light settings into these
// (addon/photonsplat/export/lights.py says how), so the core has one unit system and no Cycles quirks.
#pragma once
#include <string>

#include <glm/vec3.hpp>

namespace ps {

enum class LightKind {
    point,  // isotropic intensity I [W/sr]; `radius` > 0 gives it a size for soft shadows (0 = a true point):
            // Cycles 3.4's disc of that radius facing the receiver, or with `sphere` a true sphere (Cycles 4.x
            // with Soft Falloff off); either way of radiance I/(πR²)
    sun,    // distant light, irradiance E [W/m²] on a surface facing it; `angle` = full angular diameter
    area,   // one-sided rectangle (or ellipse) emitting radiance L [W/(sr·m²)] towards normalize(cross(axis_u, axis_v))
    spot,   // a point light (intensity I on the axis, `radius`, `sphere`) restricted to a cone around `direction`:
            // I(θ) = I · cos θ · smoothstep((cos θ − cos(size/2)) / ((1 − cos(size/2))·blend)), Cycles 3.4's falloff,
            // or without the cos θ factor (spot_cosine false), Cycles 4.x's
};

struct Light {
    std::string name;
    LightKind kind = LightKind::point;
    glm::vec3 value{0.0f};       // point: intensity; sun: irradiance; area: radiance (RGB)
    glm::vec3 position{0.0f};    // point: centre; area: centre of the rectangle. In Scene::lights(): render space
    glm::vec3 direction{0.0f, 0.0f, -1.0f};  // sun: direction the light travels; spot: the cone's axis (unit)
    float radius = 0.0f;         // point and spot, >= 0
    // Point and spot: a sphere of `radius` (Cycles 4.x's point and spot lights with Soft Falloff off) instead of
    // the disc of `radius` facing the receiver (Cycles 3.4, and 4.x with Soft Falloff on). A spot's sphere sends
    // each ray its cone's attenuation along that ray's direction.
    bool sphere = false;
    float angle = 0.0f;          // sun only, full angular diameter in radians, in [0, π)
    glm::vec3 axis_u{1.0f, 0.0f, 0.0f};  // area: full edge vectors (object scale included)
    glm::vec3 axis_v{0.0f, 1.0f, 0.0f};
    bool ellipse = false;        // area: the ellipse (disk) inscribed in the rectangle instead of the rectangle
    float spot_size = 0.0f;      // spot: full cone angle in radians, in (0, π]
    float spot_blend = 0.0f;     // spot: softness of the cone's edge, in [0, 1]
    bool spot_cosine = true;     // spot: the falloff has Cycles 3.4's cos θ factor (false: Cycles 4.x's, without)
    // Cycles' "Multiple Importance" (light.cycles.use_multiple_importance_sampling, flag SHADER_USE_MIS). Off: no
    // ray but the camera's meets the light (lights_intersect, light_sample_from_distant_ray skip it), so a BSDF ray
    // after any bounce, a mirror's or sharp glass's included, finds nothing there, and its light samples take their
    // full value, without an MIS weight. Its light therefore reaches nothing through mirrors and sharp glass.
    bool multiple_importance = true;
    // Cycles' "Cast Shadow" (3.4: light.cycles.cast_shadow, 4.x: light.use_shadow; flag SHADER_CAST_SHADOW). Off:
    // its light samples take no shadow ray (shadow_ray_setup: nothing occludes them, not even transparency), so
    // every surface facing it is lit directly; BSDF rays still meet it only where nothing is in the way.
    bool cast_shadow = true;

    glm::vec3 area_normal() const;  // unit normal of the emitting side of an area light
    float area() const;             // area light surface area (π/4 of the rectangle's for an ellipse)
    // Spot only: the falloff factor [cos θ ·] smoothstep(...) for a unit direction leaving the light (0 outside).
    float spot_attenuation(const glm::vec3& outgoing) const;
};

const char* to_string(LightKind kind);

// Light arriving at a point from one sampled point of a light (for shadow rays).
// Reflected radiance estimate = f_r · value · max(0, n·wi), with a shadow ray of length `distance` towards wi.
// A sphere light is sampled uniformly over the cone it subtends. From inside the sphere (a receiver within
// `radius` of its centre) it is sampled uniformly over all directions, each meeting the inner wall at radiance
// I/(πR²) with no spot cone applied, as Cycles 4.x does there: finite, E = I/R² on any surface inside a point
// light. Inside a spot, as Cycles 4.5 renders a diffuse surface there, the directions leading away from the
// centre's side bring half that: E = I/R² (3 + cos β)/4, β between the normal and the direction to the centre.
struct LightIncidence {
    glm::vec3 wi;      // unit, from the receiving point towards the light
    float distance;    // to the sampled light point (infinity for a sun)
    glm::vec3 value;   // incident radiance × geometry / pdf (irradiance per unit cos θ)
    float pdf = 0.0f;  // solid-angle density of having drawn wi (for MIS); 0 for a delta light
};
LightIncidence sample_light_incidence(const Light& light, const glm::vec3& x, float u1, float u2);
bool light_is_delta(const Light& light);  // a point of radius 0 or a 0° sun: one shadow ray is exact

// Where a ray from x along `direction` (unit) meets the light's emitting shape AS sample_light_incidence(x)
// samples it (a point light's disc facing x or its sphere, a sun's cone, an area light's front face), for a
// path tracer whose BSDF-sampled rays may hit lights (multiple importance sampling). pdf is the density
// sample_light_incidence has of drawing that direction from x. A delta light is never hit.
struct LightHit {
    bool hit = false;
    float distance = 0.0f;       // along the ray; infinity for a sun
    glm::vec3 radiance{0.0f};    // emitted towards x
    float pdf = 0.0f;            // solid angle
};
LightHit intersect_light(const Light& light, const glm::vec3& x, const glm::vec3& direction);

// Total flux [W] the light sends into the scene; a sun's is what crosses the scene's bounding sphere.
glm::vec3 light_flux(const Light& light, float scene_radius);

// An emitted photon's starting ray, sampled in proportion to the light's emission (so every photon of a
// light carries the same power: light_flux / photons of that light).
struct EmissionSample {
    glm::vec3 origin;
    glm::vec3 direction;
    glm::vec3 power;  // flux carried by this sample (before dividing by the probability of its source)
    // A soft point or spot light lit as the disc facing its receiver (not `sphere`): its centre and radius, for
    // first_hit_falloff. disc_radius 0: any other light.
    glm::vec3 disc_centre{0.0f};
    float disc_radius = 0.0f;
    const Light* disc_spot = nullptr;  // the spot whose disc it is (its cone weighs each direction), else null
};
EmissionSample sample_light_emission(const Light& light, const glm::vec3& scene_center, float scene_radius,
                                     float u1, float u2, float u3, float u4);

// What an emitted photon's power keeps at its first hit x, on a surface of normal `normal` (either side). The disc
// of radius R that Cycles 3.4 (and 4.x with Soft Falloff on) turns towards each receiver, of radiance L = I/(πR²),
// lights x with L times the projected solid angle of that disc above x's horizon: I cos θ/(d² + R²) where the
// disc lies wholly above it (d from x to its centre), not the I cos θ/d² of a point. Photons leave the disc across
// their direction (a sphere's silhouette from outside it; from within the radius, every direction on the centre's
// side), of the same radiance, so they take the ratio of the two projected solid angles: d²/(d² + R²) from afar,
// less where a disc crosses x's horizon or x lies within the radius. A spot's cone weighs each direction of both
// (by quadrature within two radii of the light, where the two differ most). 1 for every other light. Found by the
// differential scenes: seed 150 (a room under two soft point lights of radius 0.15 and 0.21 was 5 % too bright
// with Lambert walls, exact with radius 0) and seed 15 (a point light of radius 0.86, 0.38 under a ceiling: the
// ceiling within its radius got no photons from the sphere they then left, the bounced light 7 % short).
float first_hit_falloff(const EmissionSample& emitted, const glm::vec3& x, const glm::vec3& normal);

// The same emission with the direction chosen by the caller (photons aimed at mirrors and glass,
// caustic_aim.h). Point, spot and area lights only. Their photons leave an anchor: the centre of a point or
// spot light, or for an area light the point emission_anchor(u1, u2) draws exactly as sample_light_emission
// does. Given the direction, the origin is distributed as in sample_light_emission (a uniform offset on the
// disc of a soft light facing that direction, lifted onto the sphere's front for a spherical emitter), so the
// two samplings differ in their direction density alone.
bool light_can_aim(const Light& light);  // point, spot, area
glm::vec3 emission_anchor(const Light& light, float u1, float u2);
// Solid-angle density with which sample_light_emission draws `direction` (unit) leaving `anchor`; 0 where the
// light sends nothing.
float emission_direction_pdf(const Light& light, const glm::vec3& anchor, const glm::vec3& direction);
// A photon leaving `anchor` along `direction`: power = emitted intensity / emission_direction_pdf, the power
// sample_light_emission would give that direction (0 where the light sends nothing). u3, u4 place a soft
// light's origin.
EmissionSample emission_along(const Light& light, const glm::vec3& anchor, const glm::vec3& direction, float u3,
                              float u4);
void validate(const Light& light, const std::string& where);

}  // namespace ps
