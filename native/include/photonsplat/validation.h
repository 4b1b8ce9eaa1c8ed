// Small checks shared by everything that validates input on entry (materials, lights, scene, settings).
#pragma once
#include <cmath>
#include <string>

#include <glm/vec3.hpp>

#include "photonsplat/errors.h"

namespace ps {

inline bool is_finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// The largest world coordinate (and light size) the core accepts. Embree rejects, with an assertion that aborts
// the process, rays whose origin or direction exceeds 1.8e18 (found by fuzzing); floats have lost all sub-metre
// precision long before 1e15 anyway.
constexpr float kMaxCoordinate = 1e15f;
inline bool within_world(const glm::vec3& v) {
    return is_finite(v) && std::fabs(v.x) <= kMaxCoordinate && std::fabs(v.y) <= kMaxCoordinate &&
           std::fabs(v.z) <= kMaxCoordinate;
}

// The largest emitted value (radiance, intensity, irradiance) accepted: the sun's radiance is ~2e7. Larger finite
// values overflowed float in the direct light (found by fuzzing: a background of 3e38 gave infinite pixels).
constexpr float kMaxEmission = 1e10f;

// Colours, radiances, intensities: every channel finite, >= 0 and <= kMaxEmission.
inline void require_nonnegative_rgb(const glm::vec3& v, const std::string& field) {
    if (!is_finite(v) || v.x < 0.0f || v.y < 0.0f || v.z < 0.0f || v.x > kMaxEmission || v.y > kMaxEmission ||
        v.z > kMaxEmission)
        throw InvalidInput(field, "each channel must be finite, >= 0 and <= 1e10");
}

}  // namespace ps
