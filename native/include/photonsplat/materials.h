// The few BSDFs the core supports. The add-on maps Blender's shader nodes onto these; anything else is
// approximated there (and said so), never interpreted here.
#pragma once
#include <cstdint>
#include <string>

#include <glm/vec3.hpp>

namespace ps {

enum class MaterialKind {
    diffuse,  // Lambertian, BRDF = color / π
    mirror,   // perfect specular reflection, Fresnel-Schlick with F0 = color (metal tint)
    glass,    // smooth dielectric: Fresnel reflection, refraction tinted by color, total internal reflection
    glossy,   // GGX microfacet reflection (brdf.h), Fresnel-Schlick with F0 = color, α = roughness²; a perfect
              // mirror when roughness <= kGlossyMirrorRoughness
};

// Blender roughness at or below which a glossy surface is rendered as a perfect mirror (α <= 0.0025: visually
// sharp in Cycles, and Cycles users expect such a surface to focus caustics).
constexpr float kGlossyMirrorRoughness = 0.05f;

struct Material {
    std::string name;
    MaterialKind kind = MaterialKind::diffuse;
    glm::vec3 color{0.8f};     // diffuse albedo, mirror/glossy F0 tint, or glass transmission tint; each in [0, 1]
    float ior = 1.45f;         // glass only; > 0
    glm::vec3 emission{0.0f};  // emitted radiance W/(sr·m²), from both faces (Cycles' Emission convention)
    float roughness = 0.5f;    // glossy only: Blender roughness in [0, 1]; the GGX α is its square
    int32_t texture = -1;      // index into Scene::textures() whose lookup at the hit's UV replaces `color`; -1: none
    bool holdout = false;      // Cycles' Holdout: cut out of the image (alpha 0, black) where the camera sees it,
                               // an absorbing black surface for every other ray

    // A glossy surface rough enough to be a lobe: a non-specular hit (view sample, stored photon).
    bool is_glossy() const { return kind == MaterialKind::glossy && roughness > kGlossyMirrorRoughness; }
    // Mirror, glass and near-smooth glossy: followed by scatter_specular, never a view sample or a photon.
    bool is_specular() const { return kind != MaterialKind::diffuse && !is_glossy(); }
    float glossy_alpha() const { return roughness * roughness; }
};

const char* to_string(MaterialKind kind);
MaterialKind material_kind_from_string(const std::string& name);  // throws InvalidInput

// Validates one material; `where` names it in error messages.
void validate(const Material& m, const std::string& where);

}  // namespace ps
