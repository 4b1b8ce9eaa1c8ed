#include "photonsplat/lights.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "photonsplat/errors.h"
#include "photonsplat/validation.h"

namespace ps {

const char* to_string(LightKind kind) {
    switch (kind) {
        case LightKind::point: return "point";
        case LightKind::sun: return "sun";
        case LightKind::area: return "area";
        case LightKind::spot: return "spot";
    }
    return "?";
}

glm::vec3 Light::area_normal() const { return glm::normalize(glm::cross(axis_u, axis_v)); }

float Light::area() const {
    const float rectangle = glm::length(glm::cross(axis_u, axis_v));
    return ellipse ? 0.25f * 3.14159265358979323846f * rectangle : rectangle;
}

namespace {

// Cycles 3.4's spot edge (kernel light/light.h spot_attenuation): smoothstep over the outer `blend` part of the
// cone, measured in cos θ; a hard edge when blend is 0.
float spot_smoothstep(float cos_theta, float cos_half_angle, float blend) {
    const float t = cos_theta - cos_half_angle;
    if (!(t > 0.0f)) return 0.0f;
    const float s = (1.0f - cos_half_angle) * blend;
    if (s > 0.0f && t < s) {
        const float x = t / s;
        return x * x * (3.0f - 2.0f * x);
    }
    return 1.0f;
}

// ∫ over the cone of the falloff dω / (2π) = ∫_{cos α}^{1} [μ] S(μ) dμ in closed form, with the smoothstep part
// of width s above cos α. Cycles 3.4's μ S(μ): the smoothstep part integrates to s (cos α / 2 + 0.35 s), the rest
// of the cone to (1 − (cos α + s)²) / 2. Cycles 4.x's S(μ) alone: s / 2 (a smoothstep averages 1/2), plus
// 1 − (cos α + s).
float spot_cone_integral(float cos_half_angle, float blend, bool cosine) {
    const float c = cos_half_angle, s = (1.0f - c) * blend;
    if (!cosine) return 1.0f - c - 0.5f * s;
    return s * (0.5f * c + 0.35f * s) + 0.5f * (1.0f - (c + s) * (c + s));
}

// A spot's attenuation at cos θ from its axis, its cone's half angle's cosine given (spot_attenuation, and the
// quadrature of first_hit_falloff, which takes the axis and the cone once for many directions).
float spot_profile(const Light& spot, float cos_theta, float cos_half_angle) {
    const float edge = spot_smoothstep(cos_theta, cos_half_angle, spot.spot_blend);
    return spot.spot_cosine ? cos_theta * edge : edge;
}

}  // namespace

float Light::spot_attenuation(const glm::vec3& outgoing) const {
    return spot_profile(*this, glm::dot(glm::normalize(direction), outgoing), std::cos(0.5f * spot_size));
}

void validate(const Light& light, const std::string& where) {
    require_nonnegative_rgb(light.value, where + ".value");
    // The options that only some kinds have must keep their defaults elsewhere: a set one would be ignored.
    if (light.sphere && light.kind != LightKind::point && light.kind != LightKind::spot)
        throw InvalidInput(where + ".sphere", "is for point and spot lights only");
    if (!light.spot_cosine && light.kind != LightKind::spot)
        throw InvalidInput(where + ".spot_cosine", "is for spot lights only");
    if (!within_world(light.position))
        throw InvalidInput(where + ".position", "must be finite and within ±1e15 on every axis");
    switch (light.kind) {
        case LightKind::point:
            if (!(std::isfinite(light.radius) && light.radius >= 0.0f && light.radius <= kMaxCoordinate))
                throw InvalidInput(where + ".radius", "must be finite and >= 0, got " + std::to_string(light.radius));
            break;
        case LightKind::sun:
            if (!is_finite(light.direction) || glm::length(light.direction) < 1e-12f)
                throw InvalidInput(where + ".direction", "must be finite and non-zero");
            if (!(std::isfinite(light.angle) && light.angle >= 0.0f && light.angle < 3.14159f))
                throw InvalidInput(where + ".angle", "must be in [0, π), got " + std::to_string(light.angle));
            break;
        case LightKind::spot:
            if (!(std::isfinite(light.radius) && light.radius >= 0.0f))
                throw InvalidInput(where + ".radius", "must be finite and >= 0, got " + std::to_string(light.radius));
            if (!is_finite(light.direction) || glm::length(light.direction) < 1e-12f)
                throw InvalidInput(where + ".direction", "must be finite and non-zero");
            if (!(std::isfinite(light.spot_size) && light.spot_size > 0.0f && light.spot_size <= 3.1416f))
                throw InvalidInput(where + ".spot_size", "must be in (0, π], got " + std::to_string(light.spot_size));
            if (!(std::isfinite(light.spot_blend) && light.spot_blend >= 0.0f && light.spot_blend <= 1.0f))
                throw InvalidInput(where + ".spot_blend", "must be in [0, 1], got " + std::to_string(light.spot_blend));
            break;
        case LightKind::area:
            if (!within_world(light.axis_u) || !within_world(light.axis_v))
                throw InvalidInput(where + ".axis_u/axis_v", "must be finite and within ±1e15");
            if (!(light.area() > 0.0f) || !std::isfinite(light.area()))
                throw InvalidInput(where + ".axis_u/axis_v", "span no area (zero size or parallel edges)");
            break;
    }
}

}  // namespace ps

// ---- sampling ----------------------------------------------------------------------------------------------
#include <limits>

#include "photonsplat/scattering.h"

namespace ps {

namespace {
constexpr float kPi = 3.14159265358979323846f;

// A soft point or spot light shaped as a sphere (Light::sphere) rather than as a disc facing the receiver.
bool is_sphere_light(const Light& light) {
    return (light.kind == LightKind::point || light.kind == LightKind::spot) && light.sphere && light.radius > 0.0f;
}

// 1 − cos of the half angle of the cone that a sphere of radius r subtends at distance d > r, written without
// the cancellation of 1 − √(1 − (r/d)²), which would round a small, far sphere's cone to nothing.
float sphere_cone_one_minus_cos(float r, float d) {
    const float sin2 = (r / d) * (r / d);
    return sin2 / (1.0f + std::sqrt(std::max(0.0f, 1.0f - sin2)));
}

// Uniform direction in the cone around `axis` (unit) whose half angle has 1 − cos = one_minus_cos, drawn as
// 1 − cos θ so that a narrow cone keeps its width in float.
glm::vec3 sample_cone_one_minus_cos(const glm::vec3& axis, float one_minus_cos, float u1, float u2) {
    const float v = u1 * one_minus_cos;  // 1 − cos θ
    const float sin_theta = std::sqrt(std::max(0.0f, v * (2.0f - v))), phi = 2.0f * kPi * u2;
    glm::vec3 b1, b2;
    orthonormal_basis(axis, b1, b2);
    return glm::normalize(sin_theta * std::cos(phi) * b1 + sin_theta * std::sin(phi) * b2 + (1.0f - v) * axis);
}

// Distance along the unit `direction` from x to the surface of the sphere (centre, r): where the ray enters it
// from outside, where it leaves it from inside; negative where the ray misses. The discriminant comes from the
// ray's closest approach to the centre, which stays precise for a small sphere far away (Haines et al., "Precision
// improvements for ray/sphere intersection", Ray Tracing Gems, 2019).
float sphere_hit_distance(const glm::vec3& x, const glm::vec3& direction, const glm::vec3& centre, float r) {
    const glm::vec3 f = x - centre;
    const float b = glm::dot(f, direction);  // the closest approach is at −b along the ray
    const glm::vec3 across = f - b * direction;
    const float h2 = r * r - glm::dot(across, across);
    if (!(h2 >= 0.0f)) return -1.0f;
    const float h = std::sqrt(h2), c = glm::dot(f, f) - r * r;
    if (!(c > 0.0f)) return h - b;       // inside: the far root
    return b < 0.0f ? c / (h - b) : -1.0f;  // outside, ahead: the near root −b − h, without its cancellation
}

// Radiance of a sphere light reaching x along wi (unit, from x towards the light): I/(πR²), and for a spot what
// Cycles 4.5 renders (measured on a white plane under sphere spots, direct light only, within 0.3 %):
// - seen from outside, the cone attenuates each ray along its own direction −wi, so that every point of the
//   sphere sends one direction the same radiance (not along the direction from the centre to x);
// - seen from inside, no cone, but the directions that lead away from the centre's side (wi · (centre − x) ≤ 0)
//   bring only half the radiance. Cycles reaches a point inside its sphere by light samples over the whole
//   hemisphere and by BSDF rays that hit the light, weighted ½ each for a diffuse surface (both densities are
//   cos θ/π); its spot-light intersection is one-sided (the ray must head towards the centre), which every ray
//   from outside does, but from inside it drops the BSDF rays that head away: a diffuse surface there gets
//   E = I/R² (3 + cos β)/4, β between its normal and the direction to the centre (a point light keeps I/R²).
//   For a glossy surface inside a sphere spot Cycles' weights differ; this model keeps the diffuse ones.
glm::vec3 sphere_radiance(const Light& light, const glm::vec3& x, const glm::vec3& wi) {
    glm::vec3 radiance = light.value / (kPi * light.radius * light.radius);
    if (light.kind != LightKind::spot) return radiance;
    const glm::vec3 to_centre = light.position - x;
    if (glm::dot(to_centre, to_centre) > light.radius * light.radius) return radiance * light.spot_attenuation(-wi);
    return glm::dot(wi, to_centre) > 0.0f ? radiance : 0.5f * radiance;
}

// Cycles 3.4's soft point or spot light: a disc of the light's radius facing the receiver, radiance I/(πR²)
// (a spot's times its cone's attenuation along the sampled ray).
LightIncidence sample_disc_incidence(const Light& light, const glm::vec3& x, float u1, float u2) {
    LightIncidence out;
    const glm::vec3 axis = glm::normalize(x - light.position);
    glm::vec3 b1, b2;
    orthonormal_basis(axis, b1, b2);
    const float r = light.radius * std::sqrt(u1), phi = 2.0f * kPi * u2;
    const glm::vec3 p = light.position + r * (std::cos(phi) * b1 + std::sin(phi) * b2);
    const glm::vec3 to_light = p - x;
    const float d2 = glm::dot(to_light, to_light);
    out.distance = std::sqrt(d2);
    out.wi = to_light / out.distance;
    const float cos_light = std::max(0.0f, glm::dot(axis, -out.wi));
    out.value = light.value * (cos_light / d2);
    out.pdf = cos_light > 0.0f ? d2 / (cos_light * kPi * light.radius * light.radius) : 0.0f;
    if (light.kind == LightKind::spot) out.value *= light.spot_attenuation(-out.wi);
    return out;
}

// Solid-angle density of the directions sample_sphere_incidence draws from x: uniform over the cone the sphere
// subtends from outside it, over all directions from inside.
float sphere_direction_pdf(const Light& light, const glm::vec3& x) {
    const glm::vec3 to_centre = light.position - x;
    const float d2 = glm::dot(to_centre, to_centre);
    if (!(d2 > light.radius * light.radius)) return 1.0f / (4.0f * kPi);
    return 1.0f / (2.0f * kPi * sphere_cone_one_minus_cos(light.radius, std::sqrt(d2)));
}

// A sphere light: uniform over the cone it subtends from x outside it; from inside, uniform over all directions
// (finite: the inner wall's radiance over the whole sphere of directions, E = I/R² on any surface inside a point
// light, less inside a spot: sphere_radiance).
LightIncidence sample_sphere_incidence(const Light& light, const glm::vec3& x, float u1, float u2) {
    LightIncidence out;
    const glm::vec3 to_centre = light.position - x;
    const float d2 = glm::dot(to_centre, to_centre);
    if (d2 > light.radius * light.radius) {
        const float d = std::sqrt(d2);
        out.wi = sample_cone_one_minus_cos(to_centre / d, sphere_cone_one_minus_cos(light.radius, d), u1, u2);
    } else {
        out.wi = sample_uniform_sphere(u1, u2);
    }
    out.pdf = sphere_direction_pdf(light, x);
    out.distance = sphere_hit_distance(x, out.wi, light.position, light.radius);
    // A direction at the cone's edge may miss the sphere by rounding: it grazes it at its closest approach.
    if (!(out.distance >= 0.0f)) out.distance = glm::dot(to_centre, out.wi);
    out.value = sphere_radiance(light, x, out.wi) / out.pdf;
    return out;
}

// Where the photon of a soft point or spot light leaving along `direction` starts, given the direction: uniform
// over the disc of the light's radius facing that direction (the rays of one direction leaving a uniformly
// bright sphere, or a disc facing their receivers, cross it uniformly), lifted onto the front of the sphere for a
// spherical emitter. Either way the photon travels the same line; the sphere only moves its start.
glm::vec3 soft_light_origin(const Light& light, const glm::vec3& direction, bool on_sphere, float u3, float u4) {
    glm::vec3 d1, d2;
    orthonormal_basis(direction, d1, d2);
    const float r = std::sqrt(u3), psi = 2.0f * kPi * u4;
    const glm::vec3 across = std::cos(psi) * d1 + std::sin(psi) * d2;  // unit
    if (!on_sphere) return light.position + (light.radius * r) * across;
    return light.position + light.radius * (r * across + std::sqrt(std::max(0.0f, 1.0f - r * r)) * direction);
}

// Marks a soft point or spot light's photon as leaving Cycles' disc facing the receiver (first_hit_falloff).
void mark_facing_disc(const Light& light, EmissionSample& out) {
    if (light.radius > 0.0f && !light.sphere) {
        out.disc_centre = light.position;
        out.disc_radius = light.radius;
        if (light.kind == LightKind::spot) out.disc_spot = &light;
    }
}

// A spot's photons leave in directions drawn in proportion to its hard-edged cone's profile P(μ), μ = cos θ from
// the axis: P = μ with Cycles 3.4's cos θ factor, P = 1 without (Cycles 4.x). The smoothstep edge then scales
// their power, whose mean stays the light's flux.
// ∫ over the hard-edged cone of P dω: π(1 − cos²α), or 2π(1 − cos α).
float spot_profile_integral(const Light& light, float cos_half_angle) {
    const float c = cos_half_angle;
    return light.spot_cosine ? kPi * (1.0f - c * c) : 2.0f * kPi * (1.0f - c);
}

// μ with density ∝ P(μ) on [cos α, 1]: μ² uniform in [cos²α, 1], or μ uniform in [cos α, 1].
float sample_spot_cosine(const Light& light, float cos_half_angle, float u) {
    const float c = cos_half_angle;
    return light.spot_cosine ? std::sqrt(c * c + u * (1.0f - c * c)) : c + u * (1.0f - c);
}

// Flux carried by a spot's photon along μ: intensity I·P(μ)·smoothstep over the density P(μ) / ∫P dω.
glm::vec3 spot_photon_power(const Light& light, float cos_half_angle, float mu) {
    return spot_profile_integral(light, cos_half_angle) * light.value *
           spot_smoothstep(mu, cos_half_angle, light.spot_blend);
}

}  // namespace

// Uniform point on an area light: the rectangle, or the ellipse inscribed in it.
glm::vec3 point_on_area_light(const Light& light, float u1, float u2) {
    if (!light.ellipse) return light.position + (u1 - 0.5f) * light.axis_u + (u2 - 0.5f) * light.axis_v;
    const float r = 0.5f * std::sqrt(u1), phi = 2.0f * kPi * u2;
    return light.position + r * std::cos(phi) * light.axis_u + r * std::sin(phi) * light.axis_v;
}

bool light_is_delta(const Light& light) {
    return ((light.kind == LightKind::point || light.kind == LightKind::spot) && light.radius == 0.0f) ||
           (light.kind == LightKind::sun && light.angle == 0.0f);
}

LightIncidence sample_light_incidence(const Light& light, const glm::vec3& x, float u1, float u2) {
    LightIncidence out;
    switch (light.kind) {
        case LightKind::point:
        case LightKind::spot: {
            if (is_sphere_light(light)) {
                out = sample_sphere_incidence(light, x, u1, u2);
            } else if (light.radius > 0.0f) {
                out = sample_disc_incidence(light, x, u1, u2);
            } else {
                const glm::vec3 to_light = light.position - x;
                const float d2 = glm::dot(to_light, to_light);
                out.distance = std::sqrt(d2);
                out.wi = to_light / out.distance;
                out.value = light.value / d2;
                if (light.kind == LightKind::spot) out.value *= light.spot_attenuation(-out.wi);
            }
            break;
        }
        case LightKind::sun: {
            const glm::vec3 towards_sun = -glm::normalize(light.direction);
            out.wi = light.angle > 0.0f ? sample_uniform_cone(towards_sun, std::cos(0.5f * light.angle), u1, u2)
                                        : towards_sun;
            out.distance = std::numeric_limits<float>::infinity();
            out.value = light.value;
            if (light.angle > 0.0f) out.pdf = 1.0f / (2.0f * kPi * (1.0f - std::cos(0.5f * light.angle)));
            break;
        }
        case LightKind::area: {
            const glm::vec3 p = point_on_area_light(light, u1, u2);
            const glm::vec3 to_light = p - x;
            const float d2 = glm::dot(to_light, to_light);
            out.distance = std::sqrt(d2);
            out.wi = to_light / out.distance;
            const float cos_light = std::max(0.0f, glm::dot(light.area_normal(), -out.wi));
            out.value = light.value * (cos_light * light.area() / d2);
            out.pdf = cos_light > 0.0f ? d2 / (cos_light * light.area()) : 0.0f;
            break;
        }
    }
    if (!(out.distance > 0.0f)) out.value = glm::vec3(0.0f);  // receiver exactly on the light
    return out;
}

LightHit intersect_light(const Light& light, const glm::vec3& x, const glm::vec3& direction) {
    LightHit out;
    switch (light.kind) {
        case LightKind::point:
        case LightKind::spot: {
            if (!(light.radius > 0.0f)) return out;
            if (is_sphere_light(light)) {
                const float t = sphere_hit_distance(x, direction, light.position, light.radius);
                if (!(t > 0.0f)) return out;
                out = {true, t, sphere_radiance(light, x, direction), sphere_direction_pdf(light, x)};
                return out;
            }
            // The disc of sample_light_incidence: centred on the light, facing x, radiance I/(πR²) (a spot's
            // times its cone's attenuation towards x). From x within the light's radius too, as Cycles 3.4's
            // ray_disk_intersect: its light samples reach x from that disc, and its BSDF rays meet it.
            const glm::vec3 from_light = x - light.position;
            const float d = glm::length(from_light);
            if (!(d > 0.0f)) return out;  // x at the centre: no disc faces it
            const glm::vec3 axis = from_light / d;
            const float cos_light = -glm::dot(direction, axis);
            if (!(cos_light > 0.0f)) return out;
            const float t = d / cos_light;
            const glm::vec3 offset = x + t * direction - light.position;
            if (!(glm::dot(offset, offset) < light.radius * light.radius)) return out;
            const float area = kPi * light.radius * light.radius;
            glm::vec3 radiance = light.value / area;
            if (light.kind == LightKind::spot) radiance *= light.spot_attenuation(-direction);
            out = {true, t, radiance, t * t / (cos_light * area)};
            return out;
        }
        case LightKind::sun: {
            if (!(light.angle > 0.0f)) return out;
            const float cos_max = std::cos(0.5f * light.angle);
            if (!(glm::dot(direction, -glm::normalize(light.direction)) >= cos_max)) return out;
            // Uniform radiance over the cone whose irradiance (at normal incidence, small cone) is `value`: the
            // same E/Ω that sample_light_incidence's value = radiance / pdf implies.
            const float solid_angle = 2.0f * kPi * (1.0f - cos_max);
            out = {true, std::numeric_limits<float>::infinity(), light.value / solid_angle, 1.0f / solid_angle};
            return out;
        }
        case LightKind::area: {
            const glm::vec3 n = light.area_normal();
            const float cos_light = -glm::dot(direction, n);  // one-sided: the ray must meet the emitting face
            if (!(cos_light > 0.0f)) return out;
            const float t = glm::dot(light.position - x, n) / glm::dot(direction, n);
            if (!(t > 0.0f) || !std::isfinite(t)) return out;
            // Coordinates of the hit in the edge vectors (a parallelogram in general): q = a·u + b·v.
            const glm::vec3 q = x + t * direction - light.position;
            const float uu = glm::dot(light.axis_u, light.axis_u), vv = glm::dot(light.axis_v, light.axis_v);
            const float uv = glm::dot(light.axis_u, light.axis_v);
            const float qu = glm::dot(q, light.axis_u), qv = glm::dot(q, light.axis_v);
            const float det = uu * vv - uv * uv;
            if (!(det > 0.0f)) return out;
            const float a = (qu * vv - qv * uv) / det, b = (qv * uu - qu * uv) / det;
            const bool inside = light.ellipse ? a * a + b * b <= 0.25f : std::fabs(a) <= 0.5f && std::fabs(b) <= 0.5f;
            if (!inside) return out;
            out = {true, t, light.value, t * t / (cos_light * light.area())};
            return out;
        }
    }
    return out;
}

glm::vec3 light_flux(const Light& light, float scene_radius) {
    switch (light.kind) {
        case LightKind::point: return 4.0f * kPi * light.value;
        case LightKind::sun: return kPi * scene_radius * scene_radius * light.value;
        case LightKind::area: return kPi * light.area() * light.value;
        case LightKind::spot:
            return 2.0f * kPi *
                   spot_cone_integral(std::cos(0.5f * light.spot_size), light.spot_blend, light.spot_cosine) *
                   light.value;
    }
    return glm::vec3(0.0f);
}

EmissionSample sample_light_emission(const Light& light, const glm::vec3& scene_center, float scene_radius,
                                     float u1, float u2, float u3, float u4) {
    EmissionSample out;
    out.power = light_flux(light, scene_radius);
    switch (light.kind) {
        case LightKind::point: {
            if (is_sphere_light(light)) {
                // A spherical emitter: uniform on the surface, cosine-weighted outwards; isotropic from afar.
                const glm::vec3 n = sample_uniform_sphere(u1, u2);
                out.origin = light.position + light.radius * n;
                out.direction = sample_cosine_hemisphere(n, u3, u4);
            } else {
                // Isotropic; a soft light's photon leaves the disc across its direction (soft_light_origin), which
                // reaches the receivers within its radius too (first_hit_falloff).
                out.direction = sample_uniform_sphere(u1, u2);
                out.origin = light.radius > 0.0f ? soft_light_origin(light, out.direction, false, u3, u4)
                                                 : light.position;
            }
            mark_facing_disc(light, out);
            break;
        }
        case LightKind::sun: {
            const glm::vec3 travel = glm::normalize(light.direction);
            out.direction = light.angle > 0.0f ? -sample_uniform_cone(-travel, std::cos(0.5f * light.angle), u3, u4)
                                               : travel;
            // Parallel rays from a disc covering the scene's bounding sphere, placed outside it.
            glm::vec3 b1, b2;
            orthonormal_basis(travel, b1, b2);
            const float r = scene_radius * std::sqrt(u1), phi = 2.0f * kPi * u2;
            out.origin = scene_center - 2.0f * scene_radius * travel + r * (std::cos(phi) * b1 + std::sin(phi) * b2);
            break;
        }
        case LightKind::spot: {
            // μ = cos θ drawn in proportion to the hard-edged cone's profile (spot_profile_integral).
            const glm::vec3 axis = glm::normalize(light.direction);
            const float c = std::cos(0.5f * light.spot_size);
            const float mu = sample_spot_cosine(light, c, u1);
            const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - mu * mu)), phi = 2.0f * kPi * u2;
            glm::vec3 b1, b2;
            orthonormal_basis(axis, b1, b2);
            out.direction = glm::normalize(sin_theta * std::cos(phi) * b1 + sin_theta * std::sin(phi) * b2 + mu * axis);
            out.power = spot_photon_power(light, c, mu);
            out.origin = light.radius > 0.0f ? soft_light_origin(light, out.direction, light.sphere, u3, u4)
                                             : light.position;
            mark_facing_disc(light, out);
            break;
        }
        case LightKind::area: {
            out.origin = point_on_area_light(light, u1, u2);
            out.direction = sample_cosine_hemisphere(light.area_normal(), u3, u4);
            break;
        }
    }
    return out;
}

namespace {

// The projected solid angle (∫ cos⁺ dω over the horizon of a surface) of the cone of directions within α of a
// direction θ from the surface's normal: π sin²α cos θ where the cone lies wholly above the horizon, 0 wholly below,
// and where the horizon cuts it, the clipped cap's closed form (Snyder's sphere form factor with the horizon): with
// x = cot α and y = −x cot θ, (cos θ acos y − x sin θ √(1 − y²)) sin²α + atan(sin θ √(1 − y²) / x). A disc facing
// the receiver is such a cone, and so is a sphere's silhouette.
float cone_projected_solid_angle(float cos_theta, float sin2_alpha) {
    if (sin2_alpha >= 1.0f) return 0.5f * kPi * (1.0f + cos_theta);  // the half of all directions about u
    if (cos_theta * cos_theta > sin2_alpha) return kPi * sin2_alpha * std::max(cos_theta, 0.0f);
    const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
    const float x = std::sqrt(1.0f / sin2_alpha - 1.0f);
    const float y = std::clamp(-x * cos_theta / sin_theta, -1.0f, 1.0f);
    const float s = sin_theta * std::sqrt(std::max(0.0f, 1.0f - y * y));
    return std::max(0.0f, (cos_theta * std::acos(y) - x * s) * sin2_alpha + std::atan2(s, x));
}

// The same for a spot's two cones about u at once, each direction weighed by the spot's attenuation along the
// light's travel (−ω): Cycles' disc within cos_cycles of u, the photons' directions within cos_photons (wider). One
// midpoint rule in (cos β, φ), uniform in solid angle, whose rings meet at the inner cone's edge, so that the two
// sums share their points and most of their error.
void spot_cones_projected_solid_angles(const Light& spot, float cos_cycles, float cos_photons, const glm::vec3& u,
                                       const glm::vec3& n, float& cycles, float& photons) {
    constexpr int kInnerRings = 6, kOuterRings = 4, kSectors = 16;
    glm::vec3 b1, b2;
    orthonormal_basis(u, b1, b2);
    const glm::vec3 axis = glm::normalize(spot.direction);
    const float cos_half_angle = std::cos(0.5f * spot.spot_size);
    // The sectors' directions about u, once: the rings differ only in how far they lean from it.
    glm::vec3 across[kSectors];
    for (int j = 0; j < kSectors; ++j) {
        const float phi = 2.0f * kPi * (j + 0.5f) / kSectors;
        across[j] = std::cos(phi) * b1 + std::sin(phi) * b2;
    }
    const auto ring = [&](float cos_beta) {
        const float sin_beta = std::sqrt(std::max(0.0f, 1.0f - cos_beta * cos_beta));
        float sum = 0.0f;
        for (int j = 0; j < kSectors; ++j) {
            const glm::vec3 w = cos_beta * u + sin_beta * across[j];
            const float cosine = glm::dot(w, n);
            if (!(cosine > 0.0f)) continue;
            sum += cosine * spot_profile(spot, -glm::dot(axis, w), cos_half_angle);  // spot_attenuation(−w)
        }
        return sum * 2.0f * kPi / kSectors;
    };
    float inner = 0.0f, outer = 0.0f;
    for (int i = 0; i < kInnerRings; ++i) inner += ring(cos_cycles + (1.0f - cos_cycles) * (i + 0.5f) / kInnerRings);
    for (int i = 0; i < kOuterRings; ++i)
        outer += ring(cos_photons + (cos_cycles - cos_photons) * (i + 0.5f) / kOuterRings);
    cycles = inner * (1.0f - cos_cycles) / kInnerRings;
    photons = cycles + outer * (cos_cycles - cos_photons) / kOuterRings;
}

}  // namespace

float first_hit_falloff(const EmissionSample& emitted, const glm::vec3& x, const glm::vec3& normal) {
    if (!(emitted.disc_radius > 0.0f)) return 1.0f;
    const glm::vec3 to_centre = emitted.disc_centre - x;
    const float d2 = glm::dot(to_centre, to_centre), r2 = emitted.disc_radius * emitted.disc_radius;
    const float nn = glm::dot(normal, normal);
    if (!(d2 > 0.0f) || !(nn > 0.0f)) return 0.0f;
    const float d = std::sqrt(d2);
    const glm::vec3 u = to_centre / d;
    // The side of the surface the photon arrives on.
    const glm::vec3 n = (glm::dot(normal, emitted.direction) > 0.0f ? -normal : normal) / std::sqrt(nn);
    // Both emitters are of the light's radiance: the ratio of what each shows the receiver is the ratio of light.
    // Cycles' disc is the cone of directions within atan(R/d) of the centre; the photons', within asin(R/d), or
    // the centre's half of all directions from within the radius.
    if (emitted.disc_spot != nullptr && d2 < 4.0f * r2) {
        float cycles, photons;
        spot_cones_projected_solid_angles(*emitted.disc_spot, d / std::sqrt(d2 + r2),
                                          d2 > r2 ? std::sqrt(1.0f - r2 / d2) : 0.0f, u, n, cycles, photons);
        return photons > 0.0f ? std::min(1.0f, cycles / photons) : 0.0f;
    }
    const float cos_theta = glm::dot(u, n);
    const float cycles = cone_projected_solid_angle(cos_theta, r2 / (d2 + r2));
    const float photons = cone_projected_solid_angle(cos_theta, d2 > r2 ? r2 / d2 : 1.0f);
    if (!(photons > 0.0f)) return 0.0f;
    return std::min(1.0f, cycles / photons);
}

bool light_can_aim(const Light& light) {
    return light.kind == LightKind::point || light.kind == LightKind::spot || light.kind == LightKind::area;
}

glm::vec3 emission_anchor(const Light& light, float u1, float u2) {
    return light.kind == LightKind::area ? point_on_area_light(light, u1, u2) : light.position;
}

float emission_direction_pdf(const Light& light, const glm::vec3& /*anchor*/, const glm::vec3& direction) {
    switch (light.kind) {
        case LightKind::point:
            // Uniform on the sphere; for a spherical emitter too (uniform point, cosine-weighted direction
            // integrates to 1/(4π) over the points that face it).
            return 1.0f / (4.0f * kPi);
        case LightKind::spot: {
            const float c = std::cos(0.5f * light.spot_size);
            const float mu = glm::dot(direction, glm::normalize(light.direction));
            if (!(mu >= c && c < 1.0f)) return 0.0f;
            return (light.spot_cosine ? mu : 1.0f) / spot_profile_integral(light, c);
        }
        case LightKind::area: return std::max(0.0f, glm::dot(direction, light.area_normal())) / kPi;
        case LightKind::sun: return 0.0f;
    }
    return 0.0f;
}

EmissionSample emission_along(const Light& light, const glm::vec3& anchor, const glm::vec3& direction, float u3,
                              float u4) {
    EmissionSample out;
    out.direction = direction;
    out.origin = anchor;
    out.power = glm::vec3(0.0f);
    switch (light.kind) {
        case LightKind::point: {
            out.power = light_flux(light, 0.0f);
            if (light.radius > 0.0f) out.origin = soft_light_origin(light, direction, light.sphere, u3, u4);
            mark_facing_disc(light, out);
            break;
        }
        case LightKind::spot: {
            const float c = std::cos(0.5f * light.spot_size);
            const float mu = glm::dot(direction, glm::normalize(light.direction));
            if (!(mu >= c)) break;
            out.power = spot_photon_power(light, c, mu);
            if (light.radius > 0.0f) out.origin = soft_light_origin(light, direction, light.sphere, u3, u4);
            mark_facing_disc(light, out);
            break;
        }
        case LightKind::area:
            if (glm::dot(direction, light.area_normal()) > 0.0f) out.power = light_flux(light, 0.0f);
            break;
        case LightKind::sun: break;
    }
    return out;
}

}  // namespace ps
