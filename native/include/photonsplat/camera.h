// A pinhole (perspective) or orthographic camera given the way Blender gives it: camera-to-world matrix and an
// OpenGL-style projection matrix (Object.calc_matrix_camera), so sensor fit, shift and clipping come for free.
// Pixel (x, y) has y = 0 at the TOP row of the image.
//
// The camera's position is kept in double, in world space; its rays and position() are in render space (world
// minus origin(), see scene.h), float. A camera is made with origin 0 (render space = world space);
// relative_to(scene.origin()) gives the same camera in a scene's render space.
#pragma once
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "photonsplat/shader_program.h"

namespace ps {

struct Ray {
    glm::vec3 origin;
    glm::vec3 direction;  // unit
};

class Camera {
public:
    // to_world: camera space (looking down −Z, +Y up) to world, no scale; projection: camera space → clip space.
    Camera(const glm::dmat4& to_world, const glm::mat4& projection, int width, int height);

    // The same camera with rays relative to `origin` (world space); idempotent: relative_to(a).relative_to(a).
    Camera relative_to(const glm::dvec3& origin) const;
    glm::dvec3 origin() const { return origin_; }
    glm::dvec3 world_position() const { return world_position_; }

    int width() const { return width_; }
    int height() const { return height_; }
    bool orthographic() const { return orthographic_; }
    glm::vec3 position() const { return glm::vec3(to_world_[3]); }  // render space
    float near_clip() const { return near_; }
    float far_clip() const { return far_; }   // view depth of the far clip plane (infinity if the projection has none)
    // Perspective: tan of half the vertical field of view; orthographic: half the view height in world units.
    float vertical_half_extent() const { return half_extent_y_; }

    // What shader programs see of the camera (Camera Data, camera and window coordinates), in world space.
    ShaderCamera shader_camera() const;

    // Ray through the point (px, py) of the image plane, in pixel units (pixel centres at +0.5).
    Ray generate_ray(float px, float py) const;
    // Distance along `ray` (a ray of generate_ray) to the far clip plane: Cycles clips camera rays at clip_end.
    float far_distance(const Ray& ray) const;
    // Positive distance of a world point in front of the camera along its viewing axis.
    float view_depth(const glm::vec3& world_point) const;

private:
    glm::mat4 to_world_;  // camera → render space
    glm::dvec3 world_position_;
    glm::dvec3 origin_{0.0};
    glm::mat4 projection_;
    glm::mat4 inverse_projection_;
    glm::vec3 forward_;
    int width_;
    int height_;
    bool orthographic_;
    float near_;
    float far_;
    float half_extent_y_;
};

}  // namespace ps
