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
    }
    return "?";
}

glm::vec3 Light::area_normal() const { return glm::normalize(glm::cross(axis_u, axis_v)); }

float Light::area() const { return glm::length(glm::cross(axis_u, axis_v)); }

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

bool light_is_delta(const Light& light) {
    return (light.kind == LightKind::point && light.radius == 0.0f) || (light.kind == LightKind::sun && light.angle == 0.0f);
}

LightIncidence sample_light_incidence(const Light& light, const glm::vec3& x, float u1, float u2) {
    LightIncidence out;
    switch (light.kind) {
        case LightKind::point: {
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
            } else {
                const float d2 = glm::dot(to_light, to_light);
                out.distance = std::sqrt(d2);
                out.wi = to_light / out.distance;
                out.value = light.value / d2;
            }
            break;
        }
        case LightKind::sun: {
            const glm::vec3 towards_sun = -glm::normalize(light.direction);
            out.wi = light.angle > 0.0f ? sample_uniform_cone(towards_sun, std::cos(0.5f * light.angle), u1, u2)
                                        : towards_sun;
            out.distance = std::numeric_limits<float>::infinity();
            out.value = light.value;
            break;
        }
        case LightKind::area: {
            const glm::vec3 p = light.position + (u1 - 0.5f) * light.axis_u + (u2 - 0.5f) * light.axis_v;
            const glm::vec3 to_light = p - x;
            const float d2 = glm::dot(to_light, to_light);
            out.distance = std::sqrt(d2);
            out.wi = to_light / out.distance;
            const float cos_light = std::max(0.0f, glm::dot(light.area_normal(), -out.wi));
            out.value = light.value * (cos_light * light.area() / d2);
            break;
        }
    }
    if (!(out.distance > 0.0f)) out.value = glm::vec3(0.0f);  // receiver exactly on the light
    return out;
}

glm::vec3 light_flux(const Light& light, float scene_radius) {
    switch (light.kind) {
        case LightKind::point: return 4.0f * kPi * light.value;
        case LightKind::sun: return kPi * scene_radius * scene_radius * light.value;
        case LightKind::area: return kPi * light.area() * light.value;
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
        case LightKind::area: {
            out.origin = light.position + (u1 - 0.5f) * light.axis_u + (u2 - 0.5f) * light.axis_v;
            out.direction = sample_cosine_hemisphere(light.area_normal(), u3, u4);
            break;
        }
    }
    return out;
}

}  // namespace ps
