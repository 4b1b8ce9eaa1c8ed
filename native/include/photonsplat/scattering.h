// What happens where a ray meets a surface, shared by camera paths (view samples) and photon paths, so both
// see the same geometry, normals and specular interfaces.
#pragma once
#include <glm/vec3.hpp>

#include "photonsplat/camera.h"

namespace ps {

class Scene;
struct Hit;
struct Material;

struct SurfacePoint {
    glm::vec3 position;
    glm::vec3 geometric_normal;  // unit, facing the side the ray came from
    glm::vec3 shading_normal;    // unit, interpolated, on the same side as geometric_normal
    bool entering;               // the ray hit the front face (the triangle's winding normal faced the ray)
    const Material* material;
    glm::vec3 color;             // the material's colour here: its texture at the hit's UV, else Material::color
    float rounding_scale;        // Instance::rounding_scale of the surface hit, for offset_ray_origin
};

// Resolves a hit (instance + triangle + barycentrics) to a world-space surface point: position, normals
// (through the instance's normal matrix), UV and the material's textured colour. The one place where hits
// become surfaces, for camera paths, shadow-ray origins and photon paths alike.
SurfacePoint surface_at(const Scene& scene, const Ray& ray, const Hit& hit);

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

// One stochastic step through a mirror or glass interface (a glossy material at or below
// kGlossyMirrorRoughness counts as a mirror here). `direction` is the travel direction of the ray.
// The tint is surface.color (the material's colour, textured). The branch (reflect or refract) is chosen with probability equal to its Fresnel weight, so the returned
// weight is the tint only: photon powers and path throughputs stay near equal.
struct SpecularStep {
    glm::vec3 direction;
    glm::vec3 weight;
    bool transmitted;
};
SpecularStep scatter_specular(const Material& material, const SurfacePoint& surface, const glm::vec3& direction,
                              float u);

// Both branches of a glass surface at once, for camera paths that follow each (view_samples.cpp): the reflected
// one weighted by the Fresnel reflectance F, the refracted one by (1 − F) × tint, so their weighted sum is what
// scatter_specular returns on average. `both` is false where only one branch exists (total internal reflection,
// or a mirror): then `reflected` holds scatter_specular's single step and `transmitted` is unused.
struct SpecularSplit {
    SpecularStep reflected;
    SpecularStep transmitted;
    bool both;
};
SpecularSplit split_specular(const Material& material, const SurfacePoint& surface, const glm::vec3& direction);

// One step off a glossy surface (Material::is_glossy()): the new direction importance-samples the GGX lobe
// (brdf.h) around the shading normal (the geometric one where the shading normal faces away from the arriving
// ray) for the arriving `direction` (travel direction of the ray), which holds for photons as well as for
// camera paths since the lobe is reciprocal. `weight` = f_r cos θ / pdf <= 1; `valid` is false when the sampled
// direction leaves below the shading or the geometric surface (the path ends: single-scattering GGX loses
// that light, as its white furnace integral < 1 says).
struct GlossyStep {
    glm::vec3 direction;
    glm::vec3 weight;
    bool valid;
};
GlossyStep scatter_glossy(const Material& material, const SurfacePoint& surface, const glm::vec3& direction,
                          float u1, float u2);

float luminance(const glm::vec3& rgb);

}  // namespace ps
