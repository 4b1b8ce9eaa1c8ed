#include "photonsplat/lights.h"

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

// ∫ over the cone of cos θ · smoothstep dω / (2π) = ∫_{cos α}^{1} μ S(μ) dμ, in closed form: the smoothstep part
// (width s above cos α) integrates to s (cos α / 2 + 0.35 s), the rest of the cone to (1 − (cos α + s)²) / 2.
float spot_cone_integral(float cos_half_angle, float blend) {
    const float c = cos_half_angle, s = (1.0f - c) * blend;
    return s * (0.5f * c + 0.35f * s) + 0.5f * (1.0f - (c + s) * (c + s));
}

}  // namespace

float Light::spot_attenuation(const glm::vec3& outgoing) const {
    const float cos_theta = glm::dot(glm::normalize(direction), outgoing);
    return cos_theta * spot_smoothstep(cos_theta, std::cos(0.5f * spot_size), spot_blend);
}

void validate(const Light& light, const std::string& where) {
    require_nonnegative_rgb(light.value, where + ".value");
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
}

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
            glm::vec3 to_light = light.position - x;
            if (light.radius > 0.0f) {
                // A disc of the light's radius facing the receiver, radiance I/(πR²): what Cycles 3.4 does.
                const glm::vec3 axis = glm::normalize(-to_light);
                glm::vec3 b1, b2;
                orthonormal_basis(axis, b1, b2);
                const float r = light.radius * std::sqrt(u1), phi = 2.0f * kPi * u2;
                const glm::vec3 p = light.position + r * (std::cos(phi) * b1 + std::sin(phi) * b2);
                to_light = p - x;
                const float d2 = glm::dot(to_light, to_light);
                out.distance = std::sqrt(d2);
                out.wi = to_light / out.distance;
                const float cos_light = std::max(0.0f, glm::dot(axis, -out.wi));
                out.value = light.value * (cos_light / d2);
                out.pdf = cos_light > 0.0f ? d2 / (cos_light * kPi * light.radius * light.radius) : 0.0f;
            } else {
                const float d2 = glm::dot(to_light, to_light);
                out.distance = std::sqrt(d2);
                out.wi = to_light / out.distance;
                out.value = light.value / d2;
            }
            if (light.kind == LightKind::spot) out.value *= light.spot_attenuation(-out.wi);
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
            // The disc of sample_light_incidence: centred on the light, facing x, radiance I/(πR²) (a spot's
            // times its cone's attenuation towards x).
            const glm::vec3 from_light = x - light.position;
            const float d = glm::length(from_light);
            if (!(d > light.radius)) return out;  // x inside the light: it samples no disc either
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
            if (!(std::fabs(a) <= 0.5f && std::fabs(b) <= 0.5f)) return out;
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
            return 2.0f * kPi * spot_cone_integral(std::cos(0.5f * light.spot_size), light.spot_blend) * light.value;
    }
    return glm::vec3(0.0f);
}

EmissionSample sample_light_emission(const Light& light, const glm::vec3& scene_center, float scene_radius,
                                     float u1, float u2, float u3, float u4) {
    EmissionSample out;
    out.power = light_flux(light, scene_radius);
    switch (light.kind) {
        case LightKind::point: {
            if (light.radius > 0.0f) {
                // A spherical emitter: uniform on the surface, cosine-weighted outwards; isotropic from afar.
                const glm::vec3 n = sample_uniform_sphere(u1, u2);
                out.origin = light.position + light.radius * n;
                out.direction = sample_cosine_hemisphere(n, u3, u4);
            } else {
                out.origin = light.position;
                out.direction = sample_uniform_sphere(u1, u2);
            }
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
            // cos θ distributed ∝ cos θ over the cone (μ² uniform in [cos²α, 1]): the hard-edged cone's intensity
            // profile exactly; the smoothstep edge then scales the power, whose mean stays the light's flux.
            const glm::vec3 axis = glm::normalize(light.direction);
            const float c = std::cos(0.5f * light.spot_size);
            const float mu = std::sqrt(c * c + u1 * (1.0f - c * c));
            const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - mu * mu)), phi = 2.0f * kPi * u2;
            glm::vec3 b1, b2;
            orthonormal_basis(axis, b1, b2);
            out.direction = glm::normalize(sin_theta * std::cos(phi) * b1 + sin_theta * std::sin(phi) * b2 + mu * axis);
            out.power = kPi * (1.0f - c * c) * light.value * (spot_smoothstep(mu, c, light.spot_blend));
            out.origin = light.position;
            if (light.radius > 0.0f) {
                // The emitting disk of a soft spot faces the receiver: offset across the direction of travel.
                glm::vec3 d1, d2;
                orthonormal_basis(out.direction, d1, d2);
                const float r = light.radius * std::sqrt(u3), psi = 2.0f * kPi * u4;
                out.origin += r * (std::cos(psi) * d1 + std::sin(psi) * d2);
            }
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
            return mu >= c && c < 1.0f ? mu / (kPi * (1.0f - c * c)) : 0.0f;
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
            if (light.radius > 0.0f) {
                // Rays of one direction leaving a uniformly bright sphere cross the disc facing that direction
                // uniformly: start where such a ray leaves the sphere's front.
                glm::vec3 d1, d2;
                orthonormal_basis(direction, d1, d2);
                const float r = std::sqrt(u3), psi = 2.0f * kPi * u4;
                const glm::vec3 across = r * (std::cos(psi) * d1 + std::sin(psi) * d2);
                out.origin = anchor + light.radius * (across + std::sqrt(std::max(0.0f, 1.0f - r * r)) * direction);
            }
            break;
        }
        case LightKind::spot: {
            const float c = std::cos(0.5f * light.spot_size);
            const float mu = glm::dot(direction, glm::normalize(light.direction));
            if (!(mu >= c)) break;
            out.power = kPi * (1.0f - c * c) * light.value * spot_smoothstep(mu, c, light.spot_blend);
            if (light.radius > 0.0f) {
                glm::vec3 d1, d2;
                orthonormal_basis(direction, d1, d2);
                const float r = light.radius * std::sqrt(u3), psi = 2.0f * kPi * u4;
                out.origin += r * (std::cos(psi) * d1 + std::sin(psi) * d2);
            }
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
