// The few BSDFs the core supports. The add-on maps Blender's shader nodes onto these; anything else is
// approximated there (and said so), never interpreted here.
#pragma once
#include <string>

#include <glm/vec3.hpp>

namespace ps {

enum class MaterialKind {
    diffuse,  // Lambertian, BRDF = color / π
    mirror,   // perfect specular reflection, Fresnel-Schlick with F0 = color (metal tint)
    glass,    // smooth dielectric: Fresnel reflection, refraction tinted by color, total internal reflection
};

struct Material {
    std::string name;
    MaterialKind kind = MaterialKind::diffuse;
    glm::vec3 color{0.8f};     // diffuse albedo, mirror F0 tint, or glass transmission tint; each in [0, 1]
    float ior = 1.45f;         // glass only; > 0
    glm::vec3 emission{0.0f};  // emitted radiance W/(sr·m²), from both faces (Cycles' Emission convention)

    bool is_specular() const { return kind != MaterialKind::diffuse; }
};

const char* to_string(MaterialKind kind);
MaterialKind material_kind_from_string(const std::string& name);  // throws InvalidInput

// Validates one material; `where` names it in error messages.
void validate(const Material& m, const std::string& where);

}  // namespace ps
