#include "photonsplat/camera.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>

#include "photonsplat/errors.h"
#include "photonsplat/validation.h"

namespace ps {

namespace {

template <typename Matrix>
bool all_finite(const Matrix& m) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(m[c][r])) return false;
    return true;
}

}  // namespace

Camera::Camera(const glm::dmat4& to_world_input, const glm::mat4& projection, int width, int height)
    : to_world_(to_world_input), world_position_(to_world_input[3]), width_(width), height_(height) {
    // The rotation part is kept in float (a direction needs no more); the position in double.
    const glm::mat4 to_world(to_world_);
    if (width < 1 || height < 1)
        throw InvalidInput("camera.width/height", "must be at least 1×1, got " + std::to_string(width) + "×" +
                                                       std::to_string(height));
    if (!all_finite(to_world_input)) throw InvalidInput("camera.to_world", "contains NaN or infinity");
    if (!all_finite(projection)) throw InvalidInput("camera.projection", "contains NaN or infinity");
    if (std::fabs(glm::determinant(glm::mat3(to_world))) < 1e-12f)
        throw InvalidInput("camera.to_world", "is singular (zero scale?)");
    if (std::fabs(glm::determinant(projection)) < 1e-30f)
        throw InvalidInput("camera.projection", "is singular");
    // Remove any scale: Cycles does the same with the camera object's matrix.
    for (int c = 0; c < 3; ++c) to_world_[c] = glm::vec4(glm::normalize(glm::vec3(to_world_[c])), 0.0f);
    to_world_[3].w = 1.0f;
    const glm::dvec3 p = world_position_;
    const bool position_ok = std::fabs(p.x) <= kMaxCoordinate && std::fabs(p.y) <= kMaxCoordinate &&
                             std::fabs(p.z) <= kMaxCoordinate;
    if (!position_ok || !is_finite(glm::vec3(to_world_[0])) ||
        !is_finite(glm::vec3(to_world_[1])) || !is_finite(glm::vec3(to_world_[2])))
        throw InvalidInput("camera.to_world", "position must be finite and within ±1e15, axes finite and non-zero");
    projection_ = projection;
    inverse_projection_ = glm::inverse(projection);
    forward_ = -glm::vec3(to_world_[2]);

    // An OpenGL projection maps camera-space w = −z (perspective) or w = 1 (orthographic).
    orthographic_ = std::fabs(projection[2][3]) < 1e-6f && std::fabs(projection[3][3] - 1.0f) < 1e-6f;
    if (projection[1][1] == 0.0f) throw InvalidInput("camera.projection", "has no vertical extent");
    half_extent_y_ = 1.0f / std::fabs(projection[1][1]);
    if (orthographic_) {
        // z_ndc = P22·z + P32 = −1 at the near plane.
        near_ = (projection[3][2] + 1.0f) / projection[2][2];
    } else {
        // z_ndc = (P22·z + P32)/(−z) = −1 at z = −near.
        near_ = projection[3][2] / (projection[2][2] - 1.0f);
    }
    // The far plane: z_ndc = +1 at z = −far, by the same two formulas.
    far_ = orthographic_ ? (projection[3][2] - 1.0f) / projection[2][2] : projection[3][2] / (projection[2][2] + 1.0f);
    if (!std::isfinite(far_) || far_ <= 0.0f) far_ = std::numeric_limits<float>::infinity();
    if (!std::isfinite(near_) || (!orthographic_ && near_ <= 0.0f))
        throw InvalidInput("camera.projection", "near clip distance must be positive, got " + std::to_string(near_));
}

ShaderCamera Camera::shader_camera() const {
    glm::mat4 to_world = to_world_;
    to_world[3] = glm::vec4(glm::vec3(world_position_), 1.0f);
    const glm::mat4 world_to_view = glm::inverse(to_world);  // Blender's camera space: looking down −Z
    ShaderCamera c;
    glm::mat4 flip(1.0f);
    flip[2][2] = -1.0f;  // Cycles' camera space looks down +Z
    c.world_to_camera = flip * world_to_view;
    glm::mat4 to_unit(0.5f);  // clip x, y in [−w, w] → [0, w]
    to_unit[2][2] = 1.0f;
    to_unit[3] = glm::vec4(0.5f, 0.5f, 0.0f, 1.0f);
    c.world_to_ndc = to_unit * projection_ * world_to_view;
    c.position = glm::vec3(world_position_);
    c.orthographic = orthographic_;
    c.pixel_spread = 2.0f * half_extent_y_ / static_cast<float>(height_);
    return c;
}

Camera Camera::relative_to(const glm::dvec3& origin) const {
    Camera c = *this;
    c.origin_ = origin;
    c.to_world_[3] = glm::vec4(glm::vec3(world_position_ - origin), 1.0f);
    return c;
}

Ray Camera::generate_ray(float px, float py) const {
    const float x_ndc = 2.0f * px / static_cast<float>(width_) - 1.0f;
    const float y_ndc = 1.0f - 2.0f * py / static_cast<float>(height_);
    glm::vec4 near_point = inverse_projection_ * glm::vec4(x_ndc, y_ndc, -1.0f, 1.0f);
    glm::vec4 far_point = inverse_projection_ * glm::vec4(x_ndc, y_ndc, 1.0f, 1.0f);
    near_point /= near_point.w;
    far_point /= far_point.w;
    // Rays start on the near clip plane, as Cycles clips at clip_start.
    glm::vec3 origin = glm::vec3(to_world_ * glm::vec4(glm::vec3(near_point), 1.0f));
    glm::vec3 direction = glm::mat3(to_world_) * glm::vec3(far_point - near_point);
    return Ray{origin, glm::normalize(direction)};
}

float Camera::far_distance(const Ray& ray) const {
    if (!std::isfinite(far_)) return std::numeric_limits<float>::infinity();
    // Rays start on the near plane; the far plane is (far − near) further along the viewing axis.
    const float along = glm::dot(ray.direction, forward_);
    if (!(along > 1e-12f)) return std::numeric_limits<float>::infinity();
    return std::max(0.0f, (far_ - near_) / along);
}

float Camera::view_depth(const glm::vec3& world_point) const {
    return glm::dot(world_point - position(), forward_);
}

}  // namespace ps
