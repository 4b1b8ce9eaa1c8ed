// A material: a weighted sum of closures (closures.h), as Cycles' shader nodes build one, plus its emission and
// whether it is a holdout. The add-on lowers Blender's shader nodes to closures (export/materials.py), and the
// nodes that drive their inputs to a shader program (shader_program.h) that sets those inputs at each hit. For scripts and tests a material may instead name one of four simple kinds, which
// lower_simple_material turns into closures when the material is added to a scene.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "photonsplat/closures.h"
#include "photonsplat/shader_program.h"

namespace ps {

enum class MaterialKind {
    diffuse,  // Lambertian, BRDF = color / π
    mirror,   // perfect specular reflection, Fresnel-Schlick with F0 = color (metal tint)
    glass,    // smooth dielectric: Fresnel reflection, refraction tinted by color, total internal reflection
    glossy,   // GGX microfacet reflection (brdf.h), Fresnel-Schlick with F0 = color, α = roughness²; a perfect
              // mirror when roughness <= kGlossyMirrorRoughness
    closures, // the closures listed in Material::closures, as exported
};

// Blender roughness at or below which a microfacet closure is rendered as a perfect mirror or refraction (α <=
// 0.0025: visually sharp in Cycles, and Cycles users expect such a surface to focus caustics). The add-on turns
// such closures into Distribution::sharp; the simple "glossy" kind does it here.
constexpr float kGlossyMirrorRoughness = 0.05f;

struct Material {
    std::string name;
    MaterialKind kind = MaterialKind::diffuse;
    // The simple kinds' inputs (kind != closures), emission and holdout for every kind:
    glm::vec3 color{0.8f};     // diffuse albedo, mirror/glossy F0 tint, or glass transmission tint; each in [0, 1]
    float ior = 1.45f;         // glass only; > 0
    glm::vec3 emission{0.0f};  // emitted radiance W/(sr·m²), from both faces (Cycles' Emission convention)
    float roughness = 0.5f;    // glossy only: Blender roughness in [0, 1]; the GGX α is its square
    int32_t texture = -1;      // index into Scene::textures() whose lookup at the hit's UV replaces `color`; -1: none
    bool holdout = false;      // Cycles' Holdout: cut out of the image (alpha 0, black) where the camera sees it,
                               // an absorbing black surface for every other ray
    bool bump_map_correction = true;  // Blender 4.x's material setting: its bump shadowing term softens (bump_shadowing.h)
    // kind == closures, or filled by lower_simple_material:
    std::vector<Closure> closures;   // at most kMaxClosures
    std::vector<MixFactor> factors;  // at most kMaxFactors
    // Sets closure inputs, the emission and the shading normal at each hit (its outputs override the constants
    // above). Scene::add_material folds what is constant into the closures; empty: nothing varies.
    ShaderProgram program;

    // Derived from the closures by finalize_material (Scene::add_material calls it):
    bool has_delta = false;        // a sharp reflection, sharp refraction or transparent closure
    bool has_lobes = false;        // a non-delta closure: the surface holds view samples and stores photons
    bool directional = false;      // a non-delta closure other than Lambert diffuse: the BRDF depends on directions
    bool transmits = false;        // a closure sends light to the other side
    bool reflects = false;         // a non-delta closure scatters light back to the side it came from: photons
                                   // arriving on that side are stored here
    bool translucent = false;      // a translucent closure: caustic photons arriving on either side are stored
                                   // here, for the far sides of camera paths through it (ViewSamples::far_side)
    bool transparent = false;      // a transparent closure: shadow rays pass through, attenuated
    bool anisotropic = false;      // a microfacet closure with alpha_x != alpha_y: hits need a tangent
    bool textured = false;         // a closure reads a texture: hits need their UV
    bool lambert_only = false;     // only Lambert closures without factors: the stages take their albedo directly
    bool programmed = false;       // a program runs at each hit (program not empty after folding)
    bool program_emission = false; // ... and sets the emission
    bool program_normal = false;   // ... and the shading normal (surface_at applies it)

    // Only delta closures: every path that reaches the surface goes on (no view sample, no photon stored).
    bool is_specular() const { return has_delta && !has_lobes; }
};

constexpr int kMaxClosures = 16;

const char* to_string(MaterialKind kind);
MaterialKind material_kind_from_string(const std::string& name);  // throws InvalidInput

// Validates one material; `where` names it in error messages.
void validate(const Material& m, const std::string& where);

// Fills m.closures and m.factors from a simple kind (diffuse, mirror, glass, glossy); then finalize_material.
void lower_simple_material(Material& m);
// The derived flags above, from m.closures and the program's outputs.
void finalize_material(Material& m);
// After finalize_program: moves outputs that read constant registers into the closures and the emission, and
// empties a program left with nothing to do.
void fold_constant_outputs(Material& m);

}  // namespace ps
