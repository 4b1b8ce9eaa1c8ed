#include "photonsplat/materials.h"

#include <cmath>

#include "photonsplat/errors.h"
#include "photonsplat/validation.h"

namespace ps {

const char* to_string(MaterialKind kind) {
    switch (kind) {
        case MaterialKind::diffuse: return "diffuse";
        case MaterialKind::mirror: return "mirror";
        case MaterialKind::glass: return "glass";
        case MaterialKind::glossy: return "glossy";
    }
    return "?";
}

MaterialKind material_kind_from_string(const std::string& name) {
    if (name == "diffuse") return MaterialKind::diffuse;
    if (name == "mirror") return MaterialKind::mirror;
    if (name == "glass") return MaterialKind::glass;
    if (name == "glossy") return MaterialKind::glossy;
    throw InvalidInput("material.kind", "must be 'diffuse', 'mirror', 'glass' or 'glossy', got '" + name + "'");
}

void validate(const Material& m, const std::string& where) {
    if (!is_finite(m.color) || m.color.x < 0 || m.color.y < 0 || m.color.z < 0 || m.color.x > 1 || m.color.y > 1 ||
        m.color.z > 1)
        throw InvalidInput(where + ".color", "each channel must be finite and in [0, 1]");
    require_nonnegative_rgb(m.emission, where + ".emission");
    if (m.kind == MaterialKind::glass && !(std::isfinite(m.ior) && m.ior > 0.0f))
        throw InvalidInput(where + ".ior", "must be finite and > 0, got " + std::to_string(m.ior));
    // Checked for every kind (the default 0.5 is valid), so a bad value never waits for a kind change to bite.
    if (!(std::isfinite(m.roughness) && m.roughness >= 0.0f && m.roughness <= 1.0f))
        throw InvalidInput(where + ".roughness", "must be finite and in [0, 1], got " + std::to_string(m.roughness));
}

}  // namespace ps
