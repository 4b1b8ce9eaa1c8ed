// A material's shader program at one hit: the shading point as the program's nodes see it (ShaderGlobals), and
// what the program sets there (closure inputs, emission, normal). shade() (shading.h), surface_at
// (scattering.h) and the emission reads of every stage go through here; a material without a program never
// does.
#pragma once
#include <glm/vec3.hpp>

#include "photonsplat/closures.h"
#include "photonsplat/materials.h"
#include "photonsplat/scattering.h"
#include "photonsplat/shader_program.h"

namespace ps {

class Scene;

// The shading point of `s` seen from `wo` (unit, away from the surface).
ShaderGlobals shader_globals(const Scene& scene, const SurfacePoint& s, const glm::vec3& wo);

// The material's inputs at a hit after its program ran: its closures with the program's values in place
// (sanitised: colours >= 0, roughness and alphas in [0, 1], ior > 0), its emission and, where set, its normal.
struct ProgrammedMaterial {
    Closure closures[kMaxClosures];
    int closure_count = 0;
    glm::vec3 emission{0.0f};
    bool has_normal = false;
    glm::vec3 normal{0.0f};  // unit, on the side of the geometric normal
};
void run_material_program(const Scene& scene, const SurfacePoint& s, const glm::vec3& wo, ProgrammedMaterial& out);

// The emitted radiance of the surface towards wo: the material's constant, or its program's.
glm::vec3 emission_at(const Scene& scene, const SurfacePoint& s, const glm::vec3& wo);

// The shading normal a program's Bump / Normal Map makes at s (s.smooth_normal where it makes none).
glm::vec3 program_normal(const Scene& scene, const SurfacePoint& s, const glm::vec3& wo);

// A point on a triangle as a surface seen from the front (for sampling an emissive triangle's program).
SurfacePoint surface_on_triangle(const Scene& scene, uint32_t instance, uint32_t triangle, float u, float v);

}  // namespace ps
