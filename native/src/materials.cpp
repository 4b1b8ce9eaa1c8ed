#include "photonsplat/materials.h"

#include <algorithm>

#include <cmath>

#include "photonsplat/errors.h"
#include "photonsplat/shading.h"
#include "photonsplat/validation.h"

namespace ps {

const char* to_string(MaterialKind kind) {
    switch (kind) {
        case MaterialKind::diffuse: return "diffuse";
        case MaterialKind::mirror: return "mirror";
        case MaterialKind::glass: return "glass";
        case MaterialKind::glossy: return "glossy";
        case MaterialKind::closures: return "closures";
    }
    return "?";
}

MaterialKind material_kind_from_string(const std::string& name) {
    if (name == "diffuse") return MaterialKind::diffuse;
    if (name == "mirror") return MaterialKind::mirror;
    if (name == "glass") return MaterialKind::glass;
    if (name == "glossy") return MaterialKind::glossy;
    if (name == "closures") return MaterialKind::closures;
    throw InvalidInput("material.kind",
                       "must be 'diffuse', 'mirror', 'glass', 'glossy' or 'closures', got '" + name + "'");
}

void validate(const Material& m, const std::string& where) {
    require_nonnegative_rgb(m.emission, where + ".emission");
    if (m.kind == MaterialKind::closures) {
        if (m.closures.size() > static_cast<size_t>(kMaxClosures))
            throw InvalidInput(where + ".closures", "at most " + std::to_string(kMaxClosures) + " closures, got " +
                                                        std::to_string(m.closures.size()));
        if (m.factors.size() > static_cast<size_t>(kMaxFactors))
            throw InvalidInput(where + ".factors", "at most " + std::to_string(kMaxFactors) + " factors, got " +
                                                       std::to_string(m.factors.size()));
        for (size_t j = 0; j < m.factors.size(); ++j)
            validate(m.factors[j], where + ".factors[" + std::to_string(j) + "]");
        int lobes = 0;
        for (size_t i = 0; i < m.closures.size(); ++i) {
            const Closure& c = m.closures[i];
            validate(c, static_cast<int>(m.factors.size()), where + ".closures[" + std::to_string(i) + "]");
            if (!c.is_delta() && !(c.kind == ClosureKind::diffuse && c.roughness == 0.0f)) ++lobes;
        }
        validate(m.program, static_cast<int>(m.closures.size()), where + ".program");
        // shading.h keeps at most kMaxLobes evaluated lobes a hit (Lambert closures sum into one albedo).
        if (lobes > kMaxLobes)
            throw InvalidInput(where + ".closures", "at most " + std::to_string(kMaxLobes) +
                                                        " non-delta closures other than Lambert diffuse, got " +
                                                        std::to_string(lobes));
        return;
    }
    if (!is_finite(m.color) || m.color.x < 0 || m.color.y < 0 || m.color.z < 0 || m.color.x > 1 || m.color.y > 1 ||
        m.color.z > 1)
        throw InvalidInput(where + ".color", "each channel must be finite and in [0, 1]");
    if (m.kind == MaterialKind::glass && !(std::isfinite(m.ior) && m.ior > 0.0f))
        throw InvalidInput(where + ".ior", "must be finite and > 0, got " + std::to_string(m.ior));
    // Checked for every kind (the default 0.5 is valid), so a bad value never waits for a kind change to bite.
    if (!(std::isfinite(m.roughness) && m.roughness >= 0.0f && m.roughness <= 1.0f))
        throw InvalidInput(where + ".roughness", "must be finite and in [0, 1], got " + std::to_string(m.roughness));
}

void lower_simple_material(Material& m) {
    if (m.kind == MaterialKind::closures) {
        finalize_material(m);
        return;
    }
    m.closures.clear();
    m.factors.clear();
    Closure c;
    c.texture = m.texture;
    // A simple material's texture replaces its colour (the closures' texture multiplies: by 1 here).
    const glm::vec3 color = m.texture >= 0 ? glm::vec3(1.0f) : m.color;
    switch (m.kind) {
        case MaterialKind::diffuse:
            c.kind = ClosureKind::diffuse;
            c.roughness = 0.0f;
            c.color = color;
            m.closures.push_back(c);
            break;
        case MaterialKind::mirror:
        case MaterialKind::glossy: {
            // A metal: Schlick's Fresnel from the tint (the texture replaces the tint), weight 1.
            c.kind = ClosureKind::reflection;
            c.fresnel = FresnelKind::schlick;
            c.color = glm::vec3(1.0f);
            c.specular_color = color;
            c.texture_target = TextureTarget::specular_color;
            const bool sharp = m.kind == MaterialKind::mirror || !(m.roughness > kGlossyMirrorRoughness);
            c.distribution = sharp ? Distribution::sharp : Distribution::ggx;
            c.alpha_x = c.alpha_y = sharp ? 0.0f : m.roughness * m.roughness;
            m.closures.push_back(c);
            break;
        }
        case MaterialKind::glass: {
            // Cycles' Glass: a mirror weighted by the dielectric Fresnel of the view, the refraction by the rest
            // (tinted). The one factor is that Fresnel.
            m.factors.push_back(MixFactor{FactorKind::fresnel, m.ior});
            Closure r;
            r.kind = ClosureKind::reflection;
            r.distribution = Distribution::sharp;
            r.fresnel = FresnelKind::none;
            r.color = glm::vec3(1.0f);
            r.factors_on = 1u;
            m.closures.push_back(r);
            c.kind = ClosureKind::refraction;
            c.distribution = Distribution::sharp;
            c.color = color;
            c.ior = m.ior;
            c.factors_off = 1u;
            m.closures.push_back(c);
            break;
        }
        case MaterialKind::closures: break;
    }
    finalize_material(m);
}

void fold_constant_outputs(Material& m) {
    ShaderProgram& p = m.program;
    if (!p.code.empty()) return;
    const auto vec = [&](int r) { return glm::vec3(p.registers[r], p.registers[r + 1], p.registers[r + 2]); };
    std::vector<ProgramOutput> kept;
    for (const ProgramOutput& o : p.outputs) {
        Closure* c = o.index >= 0 && static_cast<size_t>(o.index) < m.closures.size() ? &m.closures[o.index] : nullptr;
        const float f = p.registers[o.register_];
        switch (o.target) {
            case ProgramTarget::closure_color: c->color = glm::max(vec(o.register_), glm::vec3(0.0f)); break;
            case ProgramTarget::closure_specular_color:
                c->specular_color = glm::clamp(vec(o.register_), 0.0f, 1.0f);
                break;
            case ProgramTarget::closure_roughness: c->roughness = std::clamp(f, 0.0f, 1.0f); break;
            case ProgramTarget::closure_alpha_x: c->alpha_x = std::clamp(f, 0.0f, 1.0f); break;
            case ProgramTarget::closure_alpha_y: c->alpha_y = std::clamp(f, 0.0f, 1.0f); break;
            case ProgramTarget::closure_ior: c->ior = std::max(f, 1e-3f); break;
            case ProgramTarget::emission: m.emission = glm::max(vec(o.register_), glm::vec3(0.0f)); break;
            case ProgramTarget::normal: kept.push_back(o); break;  // a fixed world direction: still per hit
        }
    }
    p.outputs = std::move(kept);
    if (p.outputs.empty()) p = ShaderProgram{};
}

void finalize_material(Material& m) {
    m.has_delta = m.has_lobes = m.directional = m.transmits = m.reflects = m.translucent = m.transparent = false;
    m.anisotropic = m.textured = false;
    m.lambert_only = !m.holdout;
    m.programmed = !m.program.empty();
    m.program_emission = m.program_normal = false;
    // What the program may set, per closure: such an input counts as varying (a colour as non-zero, a roughness
    // or an alpha as rough and anisotropic).
    std::vector<uint32_t> set(m.closures.size(), 0u);
    for (const ProgramOutput& o : m.program.outputs) {
        if (o.target == ProgramTarget::emission) m.program_emission = true;
        if (o.target == ProgramTarget::normal) m.program_normal = true;
        if (o.index >= 0 && static_cast<size_t>(o.index) < set.size() && o.target != ProgramTarget::emission &&
            o.target != ProgramTarget::normal)
            set[o.index] |= 1u << static_cast<int>(o.target);
    }
    for (size_t i = 0; i < m.closures.size(); ++i) {
        Closure c = m.closures[i];
        const auto sets = [&](ProgramTarget t) { return (set[i] & (1u << static_cast<int>(t))) != 0; };
        if (sets(ProgramTarget::closure_color)) c.color = glm::vec3(1.0f);
        if (sets(ProgramTarget::closure_roughness)) c.roughness = 1.0f;
        if (sets(ProgramTarget::closure_alpha_x) != sets(ProgramTarget::closure_alpha_y)) c.alpha_x = c.alpha_y + 0.5f;
        if (sets(ProgramTarget::closure_alpha_x) && sets(ProgramTarget::closure_alpha_y)) c.alpha_x = c.alpha_y + 0.5f;
        if (c.color == glm::vec3(0.0f)) continue;  // weighs nothing anywhere
        if (c.is_delta())
            m.has_delta = true;
        else
            m.has_lobes = true;
        if (!c.is_delta() && !(c.kind == ClosureKind::diffuse && c.roughness == 0.0f)) m.directional = true;
        if (c.transmits()) m.transmits = true;
        if (!c.is_delta() && !c.transmits()) m.reflects = true;
        if (c.kind == ClosureKind::translucent) m.translucent = true;
        if (c.kind == ClosureKind::transparent) m.transparent = true;
        if (!c.is_delta() && c.alpha_x != c.alpha_y &&
            (c.kind == ClosureKind::reflection || c.kind == ClosureKind::refraction))
            m.anisotropic = true;
        if (c.texture >= 0) m.textured = true;
        if (!(c.kind == ClosureKind::diffuse && c.roughness == 0.0f) || c.factors_on != 0 || c.factors_off != 0)
            m.lambert_only = false;
    }
    if (m.programmed) m.textured = true;  // programs read UVs, attributes and the rest of the hit
    if (m.holdout)
        m.has_delta = m.has_lobes = m.directional = m.transmits = m.reflects = m.translucent = m.transparent = false;
}

}  // namespace ps
