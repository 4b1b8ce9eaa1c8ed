// Where a ray meets a surface, shared by camera paths (view samples), shadow rays and photon paths, so all see
// the same geometry and normals; what the surface then does to light is shading.h's.
#pragma once
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "photonsplat/camera.h"

namespace ps {

class Scene;
struct Hit;
struct Material;

// The kind of ray that found a surface, as Light Path nodes see it.
enum class ShaderRay : uint8_t { camera, reflected, shadow, photon };

struct SurfacePoint {
    glm::vec3 position;
    glm::vec3 geometric_normal;  // unit, facing the side the ray came from
    glm::vec3 shading_normal;    // unit, the closures' normal: the interpolated one (or a program's), tilted as
                                 // Cycles 3.x tilts it where the view's mirror image would fall below the triangle
                                 // (ensure_valid_reflection); on the same side as geometric_normal
    bool entering;               // the ray hit the front face (the triangle's winding normal faced the ray)
    const Material* material;
    glm::vec2 uv;                // the mesh's UV here (0 without UVs), where the material's textures are looked up
    glm::vec3 tangent;           // for anisotropic materials only: unit, ⟂ shading normal, radial about the object's
                                 // Z axis (Cycles' default tangent); 0 otherwise
    float rounding_scale;        // Instance::rounding_scale of the surface hit, for offset_ray_origin
    // For shader programs (material_program.h):
    uint32_t instance = 0, triangle = 0;
    glm::vec2 bary{0.0f};        // the hit's barycentrics (u, v of the 2nd and 3rd corners)
    float distance = 0.0f;       // along the ray that found it
    glm::vec3 smooth_normal{0.0f};  // the interpolated normal (Cycles' sd->N), untilted, before a program's Bump or
                                    // Normal Map: what Fresnel, Layer Weight and the programs read; on the side of
                                    // geometric_normal
    ShaderRay ray_kind = ShaderRay::camera;  // what arrived, for Light Path nodes
};

// Resolves a hit (instance + triangle + barycentrics) to a world-space surface point: position, normals
// (through the instance's normal matrix, then a program's Bump or Normal Map), UV. The one place where hits
// become surfaces, for camera paths, shadow-ray origins and photon paths alike.
// `kind`: what the ray is, for Light Path nodes.
SurfacePoint surface_at(const Scene& scene, const Ray& ray, const Hit& hit, ShaderRay kind = ShaderRay::camera);

// Whether the hit lies on the inside of a transmitting surface (its back face: inside rough glass, behind a
// translucent pane), where photons and view samples are kept apart from those outside (kInsidePhoton,
// kInsideSample): rough glass stores photons on its inner walls, and a kernel reaching through the wall would
// splat them onto the floor just below it.
bool inside_transmitter(const SurfacePoint& s);

// A ray origin just off the surface on the side of `normal`, robust at any scale (the integer-ulp offset of
// Wächter & Binder, Ray Tracing Gems ch. 6), so rays neither re-hit their surface nor tunnel through thin walls.
// The offset is 256 ulps of each coordinate of p, or 8 ulps of `rounding_scale` where that is larger: a mesh
// whose object-space vertices are large (far from their object's origin) gives hit points rounded at that size
// even where the render-space p is small (scene.h), and the ray must start beyond that rounding.
glm::vec3 offset_ray_origin(const glm::vec3& p, const glm::vec3& normal, float rounding_scale = 0.0f);

// Orthonormal basis around a unit vector (Duff et al. 2017).
void orthonormal_basis(const glm::vec3& n, glm::vec3& b1, glm::vec3& b2);

glm::vec3 sample_cosine_hemisphere(const glm::vec3& n, float u1, float u2);  // pdf = cos θ / π
glm::vec3 sample_uniform_sphere(float u1, float u2);
glm::vec3 sample_uniform_cone(const glm::vec3& axis, float cos_max, float u1, float u2);

float luminance(const glm::vec3& rgb);

}  // namespace ps
