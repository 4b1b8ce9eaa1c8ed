"""Blender materials -> the core's closures: a material is a weighted sum of closures, as Cycles builds one.

We read the node tree Cycles would render (get_output_node('CYCLES')) and lower the shader plugged into the
Surface input to the list of closures that Cycles 3.4's svm/svm_closure.h allocates for it, with the same
weights and parameters (closures.h lists the kinds the core renders):

  Principled BSDF v1   principled_diffuse (Base Color, blended towards Subsurface Color by Subsurface), sheen,
                       the specular reflection (fresnel "principled": cspec0 and the IOR from Specular),
                       transmission as reflection + refraction split by a Fresnel factor, clearcoat (GTR1,
                       dielectric 1.5, weight 0.25 x Clearcoat), Alpha as a transparent closure.
  Principled BSDF v2   the same kinds, approximately (its energy-conserving layering is not; notes say what)
  Diffuse              diffuse (Oren-Nayar sigma = Roughness)
  Glossy, Anisotropic  reflection without Fresnel (distribution from the node, anisotropic alphas as Cycles)
  Metallic (4.3+)      reflection with Schlick's Fresnel from Base Color (or a conductor's normal reflectance)
  Glass                reflection + refraction split by a Fresnel factor of its IOR
  Refraction           refraction only
  Translucent, Transparent, Velvet, Emission, Holdout   their closures (holdout: the whole material)
  Mix, Add Shader      the two lists, weighted by Fac (a constant or a program value), or by a view-dependent
                       factor when Fac comes from a Fresnel or Layer Weight node of constant IOR / Blend
                       (evaluated by the core for each direction)
  node groups          followed inside, and back out through their Group Input sockets

Microfacet closures with Blender roughness <= ROUGHNESS_SHARP are exported as distribution "sharp" (a perfect
mirror or refraction, which the core follows to focus caustics): Cycles' alpha = r^2 is then below 0.0025.

Inputs driven by nodes. An Image Texture node with its default settings plugged straight into a colour stays a
closure texture the core looks up at the hit's UV (export/textures.py). Any other node graph driving a closure input,
a Mix Shader's Fac, an Emission or a Normal input is compiled into the material's node program
(export/shader_program.py: a ProgramBuilder per material), which the core runs at each hit: every closure input is
then a Value, a constant or a register. The lowering's own arithmetic (the Principled formulas, a Mix Shader's factor
scaling its closures' weights, Glass's Fresnel split) folds constants and emits ops otherwise; a register that a
closure ends up with becomes a program output (closure_color, closure_specular_color, closure_roughness,
closure_alpha_x, closure_alpha_y, closure_ior; emission; normal). A material whose inputs are all constant has no
program and comes out as before programs. A microfacet closure whose roughness is programmed stays a GGX or Beckmann
lobe (never 'sharp'). One shading normal per material: the first Normal input driven by nodes (Bump, Normal Map...)
is every closure's, with a note when another closure's Normal input names another. A Mix Shader's Fac from a Fresnel or Layer Weight node of constant
IOR/Blend stays a view-dependent factor of the closures (MixFactor, evaluated by the core for each direction).

Without node programs in the core (an older _core without shader_ops()), driven inputs take the socket's unconnected
value with a note, as before. Each material's notes list only what is still approximated; the sync (export/sync.py)
reports them and the material panel shows them.
"""

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .. import compat
from . import textures
from . import shader_program as sp
from .shader_program import is_const, is_reg, positive

# Blender roughness at or below which a microfacet closure is a perfect mirror or refraction (the core's
# kGlossyMirrorRoughness).
ROUGHNESS_SHARP = 0.05

# Cycles renders objects without a material with a plain grey diffuse surface; so do we.
DEFAULT_COLOR = (0.8, 0.8, 0.8)
DEFAULT_MATERIAL_NAME = "Photon Splat default"

BLACK = (0.0, 0.0, 0.0)
WHITE = (1.0, 1.0, 1.0)

# The core's limits (closures.h, materials.h).
MAX_CLOSURES = 16
MAX_FACTORS = 16
MAX_DIRECTIONAL = 8        # non-delta closures other than Lambert diffuse

# Cycles drops closures whose weight is below this (CLOSURE_WEIGHT_CUTOFF).
WEIGHT_CUTOFF = 1e-5

# Rec. 709 luminance, Cycles' linear_rgb_to_gray for the default scene-linear space (Principled sheen tint).
_LUMINANCE = (0.2126729, 0.7151522, 0.0721750)


@dataclass
class Closure:
    """One closure as the core's add_material(closures=[...]) takes it. Factors are (kind, value) keys here; the
    material turns them into indices. `texture` is a textures.TextureRef (the sync makes it an index)."""
    kind: str
    color: tuple = DEFAULT_COLOR
    distribution: str = "ggx"
    fresnel: str = "none"
    specular_color: tuple = BLACK
    roughness: float = 0.0
    alpha_x: float = 0.0
    alpha_y: float = 0.0
    ior: float = 1.45
    reported_alpha: float = 0.0  # a sharp reflection Cycles 3.x renders as Multiscatter GGX of this alpha (core's)
    texture: object = None
    texture_target: str = "color"
    factors_on: tuple = ()
    factors_off: tuple = ()
    label: str = ""            # what it is, for describe(): "diffuse", "specular", "clearcoat"...

    def is_delta(self):
        return self.kind == "transparent" or (self.kind in ("reflection", "refraction")
                                              and self.distribution == "sharp")

    def is_lambert(self):
        return self.kind == "diffuse" and is_const(self.roughness) and self.roughness == 0.0

    def weight(self):
        """The largest channel of the weight; 1 for a programmed one (unknown before the hit)."""
        return max(self.color) if is_const(self.color) else 1.0

    def merge_key(self):
        """Closures equal but for their colour add up to one."""
        texture = None if self.texture is None else self.texture.key
        return (self.kind, self.distribution, self.fresnel, self.specular_color, self.roughness, self.alpha_x,
                self.alpha_y, self.ior, self.reported_alpha, texture, self.texture_target,
                tuple(sorted(self.factors_on)), tuple(sorted(self.factors_off)))


@dataclass
class Shader:
    """What a shader socket contributes: closures, emitted radiance and holdout weight, as Cycles sums them."""
    closures: list = field(default_factory=list)
    emission: tuple = BLACK
    holdout: float = 0.0
    summary: str = ""          # how describe() names it: "principled", "glass, IOR 1.50"...

    def scaled(self, w, b=None):
        """Every weight times `w` (a Value; `b` the ProgramBuilder when it is a register)."""
        return Shader([replace(c, color=sp.mul(b, c.color, w)) for c in self.closures],
                      sp.mul(b, self.emission, w), sp.mul(b, self.holdout, w), self.summary)


@dataclass
class MaterialSpec:
    """One material as the core's add_material() takes it, plus the notes gathered while converting it."""
    name: str
    closures: list = field(default_factory=list)
    factors: list = field(default_factory=list)      # (kind, value) keys, in index order
    emission: tuple = BLACK
    notes: list = field(default_factory=list)
    holdout: bool = False          # Holdout shader or holdout object: cut out of the image
    summary: str = "diffuse"
    program: object = None         # shader_program.ProgramBuilder, or None (no node programs in the core)
    normal: object = None          # the shading normal's Reg (a Normal input driven by nodes), or None
    bump_map_correction: bool = True  # Blender 4.x's setting: softens Cycles 4.x's bump shadowing term

    kind = "closures"

    @property
    def emits(self):
        """Whether the material may emit light (a programmed emission may)."""
        return positive(self.emission, 0.0)

    @property
    def uses_program(self):
        """Whether add_material gets a program: some closure input, the emission or the normal is a register."""
        return bool(self._program_outputs())

    @property
    def attributes(self):
        """Mesh attribute names the program reads (the mesh export exports only those)."""
        return list(self.program.attributes) if self.uses_program else []

    @property
    def uses_uvs(self):
        """Whether the core may read the render UV map for it: an image on a closure, or any node program (UV
        reads, Normal Map tangents); a plain material needs none, so its meshes export no UVs."""
        return self.uses_program or any(c.texture is not None for c in self.closures)

    @property
    def uses_texspace(self):
        return self.uses_program and self.program.uses_texspace

    @property
    def uses_object_info(self):
        return self.uses_program and self.program.uses_object_info

    def _program_outputs(self):
        """(target, closure index, Reg) of every register the closures, the emission and the normal hold."""
        outputs = []
        for j, c in enumerate(self.closures):
            for target, value in _closure_targets(c):
                if is_reg(value):
                    outputs.append((target, j, value))
        if is_reg(self.emission):
            outputs.append(("emission", 0, self.emission))
        if self.normal is not None:
            outputs.append(("normal", 0, self.normal))
        return outputs

    @property
    def textures(self):
        """The TextureRefs the closures use, once each."""
        found = {}
        for c in self.closures:
            if c.texture is not None:
                found.setdefault(c.texture.key, c.texture)
        return list(found.values())

    def closure_dicts(self, texture_index=None):
        """The closures as the binding takes them; `texture_index(TextureRef)` gives a core texture index."""
        index = {key: j for j, key in enumerate(self.factors)}
        result = []
        for c in self.closures:
            # A programmed input gets a placeholder here; the program sets it at each hit.
            d = dict(kind=c.kind, color=_placeholder(c.color, WHITE))
            if c.kind in ("reflection", "refraction"):
                d.update(distribution=c.distribution, alpha_x=_placeholder(c.alpha_x, 0.25),
                         alpha_y=_placeholder(c.alpha_y, 0.25), ior=_placeholder(c.ior, 1.45))
            if c.kind == "reflection":
                d["fresnel"] = c.fresnel
                if c.reported_alpha > 0.0:
                    d["reported_alpha"] = c.reported_alpha
            if _reads_specular_color(c):
                d["specular_color"] = _placeholder(c.specular_color, (0.5, 0.5, 0.5))
            if c.kind in ("diffuse", "principled_diffuse", "velvet"):
                d["roughness"] = _placeholder(c.roughness, 0.5)
            if c.texture is not None:
                texture = -1 if texture_index is None else int(texture_index(c.texture))
                if texture >= 0:
                    d["texture"] = texture
                    d["texture_target"] = c.texture_target
                elif c.texture_target == "color" and is_const(c.color):   # unreadable image: its fallback grey
                    d["color"] = tuple(w * g for w, g in zip(c.color, DEFAULT_COLOR))
                elif c.texture_target == "color":
                    pass                         # a programmed weight: the image's grey is not applied
                else:
                    d["specular_color"] = DEFAULT_COLOR
            if c.factors_on:
                d["factors_on"] = sorted(index[k] for k in c.factors_on)
            if c.factors_off:
                d["factors_off"] = sorted(index[k] for k in c.factors_off)
            result.append(d)
        return result

    def core_arguments(self, texture_index=None, attribute_id=None):
        """Keyword arguments for core Scene.add_material(); `texture_index` maps a TextureRef to the core's
        texture index (without it, textured closures get -1: no texture), `attribute_id` a mesh attribute name to
        the core's attribute id (the core Scene's attribute_id). `program` only when there is one."""
        arguments = dict(name=self.name, kind="closures", closures=self.closure_dicts(texture_index),
                         factors=[dict(kind=k, value=float(v)) for k, v in self.factors],
                         emission=_placeholder(self.emission, BLACK))
        outputs = self._program_outputs()
        if outputs:
            arguments["program"] = self.program.encode(outputs, texture_index, attribute_id)
        if self.holdout:
            arguments["holdout"] = True
        if not self.bump_map_correction:
            arguments["bump_map_correction"] = False
        return arguments

    @property
    def program_textures(self):
        """The TextureRefs the program's image ops read, once each."""
        if not self.uses_program:
            return []
        found = {}
        for _, params, _, _ in self.program.instructions:
            for p in params:
                if isinstance(p, sp.TextureParam):
                    found.setdefault(p.reference.key, p.reference)
        return list(found.values())

    @property
    def no_surface(self):
        return not self.closures

    def describe(self):
        """Short human description, e.g. for the material panel: 'principled: diffuse + specular'."""
        if self.holdout:
            return "holdout"
        labels = list(dict.fromkeys(c.label or c.kind for c in self.closures))
        text = self.summary
        if labels and labels != [self.summary]:
            text += ": " + " + ".join(labels)
        if not self.closures:
            text = "black" if self.summary in ("", "diffuse") else self.summary
        if self.emits:
            text += ", emitting"
        for reference in self.textures + self.program_textures:
            text += f", image '{reference.image.name}'"
        if self.uses_program:
            text += f", node program ({len(self.program.instructions)} ops)"
        return text


def _placeholder(value, default):
    """A closure input as the binding takes it: a constant as is, a register's placeholder `default`."""
    if is_reg(value):
        return tuple(default) if isinstance(default, tuple) else float(default)
    return tuple(float(c) for c in value) if isinstance(value, tuple) else float(value)


def _reads_specular_color(c):
    """Whether the core reads the closure's specular colour: the Fresnel's colour at normal incidence, or for a
    Multiscatter GGX without Fresnel (Glossy) and a Multiscatter Glass's extra light the tint of its bounces after
    the first, without which the core's lobe has no multiple scattering at all."""
    if c.distribution == "multi_ggx_glass":
        return True
    return c.kind == "reflection" and (c.fresnel in ("principled", "schlick") or c.distribution == "multi_ggx")


def _closure_targets(c):
    """(program target, Value) of the inputs of closure `c` that the core reads."""
    targets = [("closure_color", c.color)]
    if c.kind in ("reflection", "refraction"):
        targets += [("closure_alpha_x", c.alpha_x), ("closure_alpha_y", c.alpha_y), ("closure_ior", c.ior)]
    if _reads_specular_color(c):
        targets.append(("closure_specular_color", c.specular_color))
    if c.kind in ("diffuse", "principled_diffuse", "velvet"):
        targets.append(("closure_roughness", c.roughness))
    return targets


def default_material():
    return MaterialSpec(name=DEFAULT_MATERIAL_NAME, closures=[Closure("diffuse", DEFAULT_COLOR, label="diffuse")])


def holdout_material():
    """What objects marked as holdout render with, whatever their own materials."""
    return MaterialSpec(name="Photon Splat holdout", holdout=True, summary="holdout")


def convert_material(material):
    """Map a Blender material (or None) to a MaterialSpec. Never raises for odd node setups."""
    if material is None:
        return default_material()
    spec = _convert_material(material)
    spec.bump_map_correction = compat.bump_map_correction(material)
    return spec


def _convert_material(material):
    name = material.name_full
    notes = []

    if not compat.uses_nodes(material):
        # Without nodes Cycles shades the material as a diffuse surface of its viewport colour.
        color = _clamped_color(_color(material.diffuse_color), notes)
        shader = Shader([Closure("diffuse", color, label="diffuse")], summary="diffuse")
        return _finish(name, shader, notes)

    output = material.node_tree.get_output_node('CYCLES')
    if output is None:
        notes.append("no Material Output node, rendered as default grey diffuse")
        shader = Shader([Closure("diffuse", DEFAULT_COLOR, label="diffuse")], summary="diffuse")
        return _finish(name, shader, notes)

    notes = _Notes(sp.op_table())
    if notes.program is not None:
        notes.program.material_index = int(getattr(material, "pass_index", 0))
    try:
        shader = _convert_socket(output.inputs["Surface"], (), notes)
        _check_displacement(output, notes)
        return _finish(name, shader, notes)
    except RecursionError:
        notes = _Notes(None, ["node tree too deeply nested: rendered as default grey diffuse"])
        shader = Shader([Closure("diffuse", DEFAULT_COLOR, label="diffuse")], summary="diffuse")
    except Exception as error:   # noqa: BLE001 -- a node setup the compiler did not foresee: never fail a render
        if notes.program is None:
            raise
        failure = f"node program not compiled ({type(error).__name__}: {error}): driven inputs use their values"
        notes = _Notes(None, [failure])
        shader = _convert_socket(output.inputs["Surface"], (), notes)
    return _finish(name, shader, notes)


class _Notes(list):
    """One material's notes, carrying what the conversion shares: its ProgramBuilder (None without node programs in
    the core) and the shading normal found so far."""

    def __init__(self, ops, lines=()):
        super().__init__(lines)
        self.program = sp.ProgramBuilder(ops, self) if ops else None
        self.normal = None


def _program(notes):
    """The ProgramBuilder of the material being converted, or None (plain note lists: the world, lights)."""
    return getattr(notes, "program", None)


def _check_displacement(output, notes):
    socket = output.inputs.get("Displacement")
    if socket is not None and source_node(socket) is not None:
        notes.append("Displacement output ignored")


# --- the finished material ------------------------------------------------------------------------------------

def _finish(name, shader, notes):
    """The closures checked against what the core accepts: finite, in range, merged, within its limits."""
    b = _program(notes)
    closures = []
    for c in shader.closures:
        c = _sanitised(c, notes)
        if positive(c.color, WEIGHT_CUTOFF):
            closures.append(c)
    # Equal closures add up (a Mix of two diffuse shaders is one diffuse closure).
    merged = {}
    for c in closures:
        key = c.merge_key()
        if key in merged:
            kept = merged[key]
            merged[key] = replace(kept, color=sp.add(b, kept.color, c.color))
        else:
            merged[key] = c
    closures = list(merged.values())
    closures = _within_limits(closures, notes)

    # Factors: the ones used, at most MAX_FACTORS; the rest evaluated at normal incidence.
    factors = []
    for c in closures:
        for key in (*c.factors_on, *c.factors_off):
            if key not in factors:
                factors.append(key)
    if len(factors) > MAX_FACTORS:
        dropped = set(factors[MAX_FACTORS:])
        notes.append(f"more than {MAX_FACTORS} view-dependent mix factors: {len(dropped)} evaluated at normal "
                     "incidence")
        closures = [_freeze_factors(c, dropped, b) for c in closures]
        factors = factors[:MAX_FACTORS]

    emission = shader.emission
    if is_const(emission):
        emission = tuple(max(e, 0.0) if math.isfinite(e) else 0.0 for e in emission)
    holdout = False
    if is_reg(shader.holdout):
        notes.append("holdout weighted by nodes rendered as no holdout")
    elif shader.holdout > WEIGHT_CUTOFF:
        holdout = shader.holdout >= 0.5
        if shader.holdout < 1.0 - 1e-6:
            notes.append(f"partial holdout (weight {shader.holdout:.2f}) rendered as "
                         + ("a full holdout" if holdout else "no holdout"))
    if holdout:
        closures = []
    if not closures:
        # Nothing reflects: a black surface (Cycles renders an unconnected Surface black).
        closures = [Closure("diffuse", BLACK, label="black")]
    # (A Bump node compiles its height three times: a note from there comes once.)
    return MaterialSpec(name=name, closures=closures, factors=factors, emission=emission,
                        notes=list(dict.fromkeys(notes)),
                        holdout=holdout, summary=shader.summary or "black", program=b,
                        normal=None if holdout else getattr(notes, "normal", None))


def _sanitised(c, notes):
    """Constant inputs made finite and in range (programmed ones are the core's to keep in range)."""
    def finite(value, default):
        return float(value) if math.isfinite(value) else default

    def each(value, fix):
        if is_reg(value):
            return value
        return tuple(fix(v) for v in value) if isinstance(value, tuple) else fix(value)
    return replace(c, color=each(c.color, lambda v: max(finite(v, 0.0), 0.0)),
                   specular_color=each(c.specular_color, lambda v: _clamp01(finite(v, 0.0))),
                   roughness=each(c.roughness, lambda v: _clamp01(finite(v, 0.0))),
                   alpha_x=each(c.alpha_x, lambda v: _clamp01(finite(v, 0.0))),
                   alpha_y=each(c.alpha_y, lambda v: _clamp01(finite(v, 0.0))),
                   ior=each(c.ior, lambda v: max(finite(v, 1.45), 1e-5)))


def _directional(c):
    return not c.is_delta() and not c.is_lambert()


def _within_limits(closures, notes):
    """At most MAX_CLOSURES closures and MAX_DIRECTIONAL directional ones: the lightest go, with a note."""
    directional = sorted((c for c in closures if _directional(c)), key=Closure.weight, reverse=True)
    if len(directional) > MAX_DIRECTIONAL:
        dropped = directional[MAX_DIRECTIONAL:]
        notes.append(f"{len(dropped)} lightest of {len(directional)} directional closures dropped (the core "
                     f"takes {MAX_DIRECTIONAL})")
        closures = [c for c in closures if not any(c is d for d in dropped)]
    if len(closures) > MAX_CLOSURES:
        ordered = sorted(closures, key=Closure.weight, reverse=True)
        notes.append(f"{len(closures) - MAX_CLOSURES} lightest of {len(closures)} closures dropped (the core "
                     f"takes {MAX_CLOSURES})")
        keep = ordered[:MAX_CLOSURES]
        closures = [c for c in closures if any(c is k for k in keep)]
    return closures


def _freeze_factors(c, dropped, b=None):
    w = 1.0
    for key in c.factors_on:
        if key in dropped:
            w *= _factor_at_normal_incidence(key)
    for key in c.factors_off:
        if key in dropped:
            w *= 1.0 - _factor_at_normal_incidence(key)
    return replace(c, color=sp.mul(b, c.color, w), factors_on=tuple(k for k in c.factors_on if k not in dropped),
                   factors_off=tuple(k for k in c.factors_off if k not in dropped))


# --- shader nodes ---------------------------------------------------------------------------------------------

def _convert_socket(socket, stack, notes):
    """The Shader a shader input socket receives (nothing when unconnected)."""
    out, _, stack = follow(socket, stack)
    if out is None:
        return Shader()
    node = out.node
    converter = _SHADERS.get(node.bl_idname)
    if converter is not None:
        return converter(node, stack, notes)
    return _unsupported_shader(node, stack, notes)


def _principled(node, stack, notes):
    _shading_normal(node, stack, notes)
    if compat.principled_input("specular") is None:
        return _principled_v2(node, stack, notes)
    return _principled_v1(node, stack, notes)


def _principled_v1(node, stack, notes):
    """Principled BSDF v1 (Blender 3.x), as Cycles 3.4's svm_closure.h lowers CLOSURE_BSDF_PRINCIPLED_ID."""
    b = _program(notes)
    inputs = _Inputs(node, stack, notes)
    base, texture = inputs.color_or_texture("Base Color")
    metallic = sp.clamp01(b, inputs.number("Metallic"))
    subsurface = sp.clamp01(b, inputs.number("Subsurface"))
    specular = sp.clamp_min(b, inputs.number("Specular", 0.5), 0.0)
    roughness = sp.clamp01(b, inputs.number("Roughness", 0.5))
    specular_tint = sp.clamp01(b, inputs.number("Specular Tint"))
    anisotropic = sp.clamp01(b, inputs.number("Anisotropic"))
    sheen = sp.clamp_min(b, inputs.number("Sheen"), 0.0)
    sheen_tint = sp.clamp01(b, inputs.number("Sheen Tint", 0.5))
    clearcoat = sp.clamp_min(b, inputs.number("Clearcoat"), 0.0)
    clearcoat_roughness = sp.clamp01(b, inputs.number("Clearcoat Roughness", 0.03))
    eta = sp.clamp_min(b, inputs.number("IOR", 1.45), 1e-5)
    transmission = sp.clamp01(b, inputs.number("Transmission"))
    transmission_roughness = sp.clamp01(b, inputs.number("Transmission Roughness"))
    rotation = inputs.number("Anisotropic Rotation")
    distribution = getattr(node, "distribution", "GGX")
    if texture is not None and b is not None and (
            positive(subsurface, WEIGHT_CUTOFF) or positive(specular_tint, 0.0)
            or (positive(sheen, WEIGHT_CUTOFF) and positive(sheen_tint, 0.0))
            or (is_reg(metallic) or 0.0 < metallic < 1.0)):
        # The image enters the formulas (a blend, a hue, a partly metallic colour): compiled into the program
        # rather than multiplying closures as a closure texture.
        base, texture = inputs.color("Base Color"), None

    diffuse_weight = sp.mul(b, sp.one_minus(b, metallic), sp.one_minus(b, transmission))
    final_transmission = sp.mul(b, transmission, sp.one_minus(b, metallic))
    specular_weight = sp.one_minus(b, final_transmission)
    closures = []

    # Diffuse: Burley's, of Base Color blended towards Subsurface Color (Cycles' subsurface albedo).
    color = base
    if positive(subsurface, WEIGHT_CUTOFF):
        color = sp.lerp(b, base, inputs.color("Subsurface Color"), subsurface)
        notes.append("subsurface rendered as diffuse")
        if texture is not None:
            notes.append(f"image '{texture.image.name}' rendered without its blend towards Subsurface Color")
    if positive(diffuse_weight, WEIGHT_CUTOFF):
        closures.append(_textured(Closure("principled_diffuse", sp.mul(b, color, diffuse_weight),
                                          roughness=roughness, label="diffuse"), texture, diffuse_weight, b))

    # Sheen: white blended towards the base colour's hue by Sheen Tint.
    if positive(diffuse_weight, WEIGHT_CUTOFF) and positive(sheen, WEIGHT_CUTOFF):
        tint = _hue(b, base, _LUMINANCE)
        sheen_color = sp.lerp(b, WHITE, tint, sheen_tint)
        closures.append(Closure("sheen", sp.mul(b, sheen_color, sp.mul(b, sheen, diffuse_weight)), label="sheen"))
        if texture is not None and positive(sheen_tint, 0.0):
            notes.append("sheen tinted by the image's fallback colour, not the image")

    # Specular reflection: cspec0 mixes the tinted 0.08 x Specular with Base Color by Metallic.
    alpha_x, alpha_y = _principled_alphas(b, roughness, anisotropic)
    if positive(specular_weight, WEIGHT_CUTOFF) and (positive(specular, WEIGHT_CUTOFF)
                                                     or positive(metallic, WEIGHT_CUTOFF)):
        tint = _hue(b, base, (0.3, 0.6, 0.1))
        tinted = sp.lerp(b, WHITE, tint, specular_tint)
        cspec0 = sp.add(b, sp.mul(b, sp.mul(b, sp.mul(b, specular, 0.08), tinted), sp.one_minus(b, metallic)),
                        sp.mul(b, base, metallic))
        ior = sp.sub(b, sp.divide(b, 2.0, sp.one_minus(b, sp.sqrt(b, sp.minimum(b, sp.mul(b, 0.08, specular),
                                                                                   0.999999)))), 1.0)
        smooth = is_const(roughness) and roughness <= 0.075
        dist = "ggx" if distribution == "GGX" or smooth else "multi_ggx"
        c = _microfacet("reflection", _rgb(b, specular_weight), roughness, alpha_x, alpha_y, dist,
                        fresnel="principled", specular_color=cspec0, ior=ior, label="specular")
        if texture is not None and is_const(metallic) and metallic >= 1.0:
            c = replace(c, texture=texture, texture_target="specular_color")
        elif texture is not None and positive(metallic, 0.0):
            notes.append(f"image '{texture.image.name}' not applied to the partly metallic specular colour")
        closures.append(c)
        if is_reg(anisotropic) or alpha_x != alpha_y:
            _note_rotation(notes, rotation, node.inputs["Tangent"].is_linked)

    # Transmission: Fresnel-weighted reflection and (1 - Fresnel)-weighted refraction of Base Color.
    if positive(final_transmission, WEIGHT_CUTOFF):
        cspec0 = sp.add(b, sp.mul(b, base, specular_tint), sp.one_minus(b, specular_tint))
        if distribution == "GGX" or (is_const(roughness) and roughness <= ROUGHNESS_SHARP):
            refraction_roughness = (sp.one_minus(b, sp.mul(b, sp.one_minus(b, roughness),
                                                           sp.one_minus(b, transmission_roughness)))
                                    if distribution == "GGX" else roughness)
        else:
            refraction_roughness = roughness
            notes.append("multiscatter GGX glass rendered as single-scatter GGX reflection and refraction")
        on, off = _fresnel_split(b, notes, eta)
        r2 = sp.square(b, roughness)
        reflection = _microfacet("reflection", _rgb(b, final_transmission), roughness, r2, r2, "ggx",
                                 fresnel="principled", specular_color=cspec0, ior=eta, label="glass reflection")
        closures.append(on(reflection))
        t2 = sp.square(b, refraction_roughness)
        refraction = _microfacet("refraction", sp.mul(b, base, final_transmission), refraction_roughness, t2, t2,
                                 "ggx", ior=eta, label="refraction")
        closures.append(_textured(off(refraction), texture, final_transmission, b))

    # Clearcoat: GTR1, dielectric Fresnel of index 1.5, weighted 0.25 x Clearcoat in Cycles' eval.
    if positive(clearcoat, WEIGHT_CUTOFF):
        a = sp.square(b, clearcoat_roughness)
        closures.append(Closure("reflection", _rgb(b, sp.mul(b, 0.25, clearcoat)), distribution="gtr1",
                                fresnel="dielectric", alpha_x=a, alpha_y=a, ior=1.5, label="clearcoat"))
        if node.inputs["Clearcoat Normal"].is_linked:
            notes.append("clearcoat normal map ignored (the Normal input's used)")

    emission = sp.mul(b, inputs.color("Emission"), inputs.number("Emission Strength", 1.0))
    return _with_alpha(Shader(closures, emission, summary="principled"), inputs.number("Alpha", 1.0), notes)


def _principled_v2(node, stack, notes):
    """Principled BSDF v2 (Blender 4.x): the same closure kinds, its layering approximated."""
    b = _program(notes)
    role = compat.principled_input
    inputs = _Inputs(node, stack, notes)
    base, texture = inputs.color_or_texture(role("base_color"))
    metallic = sp.clamp01(b, inputs.number(role("metallic")))
    roughness = sp.clamp01(b, inputs.number(role("roughness"), 0.5))
    eta = sp.clamp_min(b, inputs.number(role("ior"), 1.5), 1e-5)
    transmission = sp.clamp01(b, inputs.number(role("transmission")))
    subsurface = sp.clamp01(b, inputs.number(role("subsurface")))
    level = sp.clamp_min(b, inputs.number(role("specular_ior_level"), 0.5), 0.0)
    specular_tint = sp.clamp01(b, inputs.color(role("specular_tint")))
    anisotropic = sp.clamp01(b, inputs.number(role("anisotropic")))
    rotation = inputs.number("Anisotropic Rotation")
    coat = sp.clamp01(b, inputs.number(role("coat")))
    sheen = sp.clamp_min(b, inputs.number(role("sheen")), 0.0)
    diffuse_roughness = sp.clamp01(b, inputs.optional_number(role("diffuse_roughness")))
    distribution = getattr(node, "distribution", "GGX")
    dist = "ggx" if distribution == "GGX" else "multi_ggx"
    if positive(inputs.optional_number(role("thin_film")), 0.0):
        notes.append("thin film ignored")

    closures = []
    alpha_x, alpha_y = _principled_alphas(b, roughness, anisotropic)
    # Coat on top of everything: a dielectric GGX reflection; what lies below loses what it reflects.
    below = 1.0
    if positive(coat, WEIGHT_CUTOFF):
        coat_ior = sp.clamp_min(b, inputs.number("Coat IOR", 1.5), 1.0)
        coat_roughness = sp.clamp01(b, inputs.number(role("coat_roughness"), 0.03))
        c2 = sp.square(b, coat_roughness)
        closures.append(_microfacet("reflection", _rgb(b, coat), coat_roughness, c2, c2, "ggx",
                                    fresnel="dielectric", ior=coat_ior, label="coat"))
        below = sp.one_minus(b, sp.mul(b, coat, _f0(b, coat_ior)))
        tint = sp.clamp01(b, inputs.color(role("coat_tint")))
        if _is_tinted(tint):
            notes.append("Coat Tint applied at normal incidence only")
        below_tint = sp.lerp(b, WHITE, tint, coat)
        notes.append("coat layering approximated (layers below dimmed by the coat's normal reflectance)")
        if "Coat Normal" in node.inputs and node.inputs["Coat Normal"].is_linked:
            notes.append("coat normal map ignored (the Normal input's used)")
    else:
        below_tint = WHITE

    def under(weight_rgb):
        return sp.mul(b, sp.mul(b, weight_rgb, below), below_tint)

    # Metal: Schlick's Fresnel from Base Color (F82 with a white edge tint).
    if positive(metallic, WEIGHT_CUTOFF):
        c = _microfacet("reflection", under(_rgb(b, metallic)), roughness, alpha_x, alpha_y, dist,
                        fresnel="schlick", specular_color=sp.clamp01(b, base), label="metal")
        if texture is not None:
            c = replace(c, texture=texture, texture_target="specular_color")
        closures.append(c)
        if _is_tinted(specular_tint):
            notes.append("Specular Tint of the metal ignored (F82 edge tint rendered white)")

    # The dielectric specular: F0 of the IOR scaled by 2 x Specular IOR Level, tinted by Specular Tint.
    f0 = sp.minimum(b, sp.mul(b, sp.mul(b, _f0(b, eta), 2.0), level), 0.999)
    root = sp.sqrt(b, f0)
    specular_ior = sp.divide(b, sp.add(b, 1.0, root), sp.one_minus(b, root))
    dielectric = sp.one_minus(b, metallic)
    glass = sp.mul(b, dielectric, transmission)
    opaque = sp.mul(b, dielectric, sp.one_minus(b, transmission))
    if positive(opaque, WEIGHT_CUTOFF) and positive(f0, 0.0):
        closures.append(_microfacet("reflection", under(_rgb(b, opaque)), roughness, alpha_x, alpha_y, dist,
                                    fresnel="principled", specular_color=sp.mul(b, specular_tint, f0),
                                    ior=specular_ior, label="specular"))
    if positive(glass, WEIGHT_CUTOFF):
        if dist != "ggx" and _is_rough(roughness):
            notes.append("multiscatter GGX glass rendered as single-scatter GGX reflection and refraction")
        on, off = _fresnel_split(b, notes, eta)
        r2 = sp.square(b, roughness)
        closures.append(on(_microfacet("reflection", under(_rgb(b, glass)), roughness, r2, r2, "ggx",
                                       fresnel="schlick", specular_color=specular_tint, label="glass reflection")))
        refraction = _microfacet("refraction", under(sp.mul(b, base, glass)), roughness, r2, r2, "ggx", ior=eta,
                                 label="refraction")
        closures.append(_textured(off(refraction), texture, sp.mul(b, glass, below), b))

    # Sheen over the diffuse base: velvet of Sheen Roughness.
    if positive(opaque, WEIGHT_CUTOFF) and positive(sheen, WEIGHT_CUTOFF):
        sheen_tint = sp.clamp01(b, inputs.color(role("sheen_tint")))
        sheen_roughness = sp.clamp01(b, inputs.number("Sheen Roughness", 0.5))
        closures.append(Closure("velvet", under(sp.mul(b, sheen_tint, sp.mul(b, sheen, opaque))),
                                roughness=sheen_roughness, label="sheen"))
        notes.append("microfibre sheen rendered as velvet")

    # Diffuse base under the dielectric specular: dimmed by its normal reflectance.
    if positive(opaque, WEIGHT_CUTOFF):
        if positive(subsurface, WEIGHT_CUTOFF):
            notes.append("subsurface rendered as diffuse")
        dimmed = sp.mul(b, opaque, sp.one_minus(b, sp.mul(b, f0, sp.max_component(b, specular_tint))))
        weight = sp.mul(b, sp.mul(b, opaque, below),
                        sp.one_minus(b, sp.mul(b, f0, sp.max_component(b, specular_tint))))
        c = Closure("diffuse", under(sp.mul(b, base, dimmed)), roughness=diffuse_roughness, label="diffuse")
        closures.append(_textured(c, texture, weight, b))
        if positive(f0, 0.0):
            notes.append("energy-conserving layering approximated (diffuse dimmed by the specular's normal "
                         "reflectance)")
    if (is_reg(anisotropic) or alpha_x != alpha_y) and (positive(metallic, WEIGHT_CUTOFF)
                                                         or positive(opaque, WEIGHT_CUTOFF)):
        _note_rotation(notes, rotation, node.inputs["Tangent"].is_linked)

    emission = sp.mul(b, inputs.color(role("emission_color")), inputs.number(role("emission_strength"), 0.0))
    return _with_alpha(Shader(closures, emission, summary="principled"), inputs.number(role("alpha"), 1.0), notes)


def _shading_normal(node, stack, notes):
    """A shader node's Normal input driven by nodes: the material's shading normal (one per material; a program
    output). Without node programs it is ignored, with a note."""
    socket = node.inputs.get("Normal")
    if socket is None or not socket.is_linked:
        return
    b = _program(notes)
    if b is None:
        notes.append("normal/bump map ignored")
        return
    out, _, _ = follow(socket, stack)
    if out is None:
        return
    normal = b.value_of(socket, stack)
    if is_const(normal):
        normal = b.constant(normal)
    if notes.normal is None:
        notes.normal = normal
    elif notes.normal != normal:
        notes.append(f"{node.bl_label}'s own Normal input ignored (one shading normal per material: the first "
                     "one used)")


def _rgb(b, weight):
    """A scalar weight as an RGB weight."""
    return sp.as_vector(b, weight) if is_reg(weight) else (weight,) * 3


def _fresnel_split(b, notes, eta):
    """Two closure transforms (reflected part, refracted part) splitting by a dielectric Fresnel factor of `eta`: a
    view-dependent factor for a constant IOR, a fresnel op weighting the two otherwise."""
    if is_const(eta):
        key = ("fresnel", eta)
        return (lambda c: replace(c, factors_on=c.factors_on + (key,)),
                lambda c: replace(c, factors_off=c.factors_off + (key,)))
    normal = notes.normal
    if normal is None:   # the shading point's own normal, at the point itself (bump offset 0, width 1)
        normal = b.emit("geometry", [0, -1, -1, sp.float_bits(1.0)], [])[1]
    f = b.emit("fresnel", [], [eta, normal])[0]
    rest = sp.one_minus(b, f)
    return (lambda c: replace(c, color=sp.mul(b, c.color, f)),
            lambda c: replace(c, color=sp.mul(b, c.color, rest)))


def _principled_alphas(b, roughness, anisotropic):
    """Cycles' Principled anisotropy: aspect = sqrt(1 - 0.9 anisotropic), alphas r^2 / aspect and r^2 x aspect."""
    if is_const(roughness) and is_const(anisotropic):
        aspect = math.sqrt(max(1.0 - anisotropic * 0.9, 1e-6))
        r2 = roughness * roughness
        return min(r2 / aspect, 1.0), r2 * aspect
    aspect = sp.sqrt(b, sp.clamp_min(b, sp.sub(b, 1.0, sp.mul(b, anisotropic, 0.9)), 1e-6))
    r2 = sp.square(b, roughness)
    return sp.minimum(b, sp.divide(b, r2, aspect), 1.0), sp.mul(b, r2, aspect)


def _with_alpha(shader, alpha, notes):
    """Alpha < 1: a transparent closure of weight 1 - alpha over the shader scaled by alpha (Cycles' mix)."""
    b = _program(notes)
    alpha = sp.clamp01(b, alpha)
    if is_const(alpha) and alpha >= 1.0:
        return shader
    result = shader.scaled(alpha, b)
    result.closures.append(Closure("transparent", _rgb(b, sp.one_minus(b, alpha)), label="transparent"))
    return result


def _textured(closure, texture, weight, b=None):
    """`closure` with `texture` multiplying its colour: the colour is then the scalar weight."""
    if texture is None:
        return closure
    return replace(closure, texture=texture, texture_target="color", color=_rgb(b, weight))


def _microfacet(kind, color, roughness, alpha_x, alpha_y, distribution, fresnel="none", specular_color=BLACK,
                ior=1.45, label=""):
    """A reflection or refraction closure; sharp when the Blender roughness is at most ROUGHNESS_SHARP (never when
    the roughness is programmed)."""
    reported_alpha = 0.0
    if distribution == "sharp" or not _is_rough(roughness):
        reported_alpha = _cycles3_multiscatter_mirror_alpha(kind, distribution, alpha_x, alpha_y)
        distribution, alpha_x, alpha_y = "sharp", 0.0, 0.0
    return Closure(kind, _tuple(color), distribution=distribution, fresnel=fresnel,
                   specular_color=_tuple(specular_color), alpha_x=alpha_x, alpha_y=alpha_y, ior=ior,
                   reported_alpha=reported_alpha, label=label)


def _cycles3_multiscatter_mirror_alpha(kind, distribution, alpha_x, alpha_y):
    """The alpha a sharp reflection keeps where Cycles 3.x renders it as Multiscatter GGX (a Glossy or Anisotropic
    BSDF of roughness at most ROUGHNESS_SHARP): Cycles takes it for a mirror only below alpha_x alpha_y = 1e-7, and
    above that the density it reports for the mirror's direction (its D clamped) all but drops the lights the
    reflection meets (the core's Closure::reported_alpha). 0: a mirror to Cycles too, or Cycles 4.x (fixed)."""
    if (kind != "reflection" or distribution != "multi_ggx" or compat.MULTISCATTER_LIGHT_ESTIMATE != "light_sample"
            or is_reg(alpha_x) or is_reg(alpha_y)):
        return 0.0
    product = float(np.float32(alpha_x)) * float(np.float32(alpha_y))
    return math.sqrt(product) if product >= 1e-7 else 0.0


def _tuple(value):
    return value if is_reg(value) else tuple(value)


def _is_rough(roughness):
    """roughness > ROUGHNESS_SHARP as the core decides it, in float32: Blender stores 0.05 as 0.0500000007. A
    programmed roughness is rough."""
    if is_reg(roughness):
        return True
    return bool(np.float32(roughness) > np.float32(ROUGHNESS_SHARP))


# Blender's distribution names -> the core's; Ashikhmin-Shirley has no counterpart (GGX, noted).
_DISTRIBUTIONS = {"SHARP": "sharp", "GGX": "ggx", "BECKMANN": "beckmann", "MULTI_GGX": "multi_ggx",
                  "ASHIKHMIN_SHIRLEY": "ggx"}


def _distribution(node, notes):
    name = getattr(node, "distribution", "GGX")
    if name == "ASHIKHMIN_SHIRLEY":
        notes.append("Ashikhmin-Shirley distribution rendered as GGX")
    return _DISTRIBUTIONS.get(name, "ggx")


def _anisotropic_alphas(b, roughness, anisotropy):
    """Cycles' Glossy/Anisotropic BSDF: alpha = r^2 stretched by the anisotropy in (-0.99, 0.99)."""
    if is_const(roughness) and is_const(anisotropy):
        a = roughness * roughness
        anisotropy = min(max(anisotropy, -0.99), 0.99)
        if anisotropy < 0.0:
            return a / (1.0 + anisotropy), a * (1.0 + anisotropy)
        return a * (1.0 - anisotropy), a / (1.0 - anisotropy)
    a = sp.square(b, roughness)
    if is_const(anisotropy) and anisotropy == 0.0:
        return a, a
    anisotropy = sp.maximum(b, sp.minimum(b, anisotropy, 0.99), -0.99)
    s = sp.one_minus(b, sp.math_op(b, "ABSOLUTE", anisotropy))
    shrunk, stretched = sp.mul(b, a, s), sp.divide(b, a, s)
    negative = sp.math_op(b, "LESS_THAN", anisotropy, 0.0)
    return sp.lerp(b, shrunk, stretched, negative), sp.lerp(b, stretched, shrunk, negative)


def _note_rotation(notes, rotation, tangent_linked):
    if is_reg(rotation) or rotation != 0.0:
        notes.append("anisotropic rotation approximated (the core's tangent runs around the object's Z axis)")
    if tangent_linked:
        notes.append("Tangent input ignored (the core's tangent runs around the object's Z axis)")


def _glossy(node, stack, notes):
    """Glossy BSDF (3.4), Anisotropic BSDF (3.4) and 4.x's Glossy (one node): reflection without Fresnel."""
    b = _program(notes)
    _shading_normal(node, stack, notes)
    inputs = _Inputs(node, stack, notes)
    color, texture = inputs.color_or_texture("Color")
    roughness = sp.clamp01(b, inputs.number("Roughness", 0.5))
    distribution = _distribution(node, notes)
    alpha_x = alpha_y = sp.square(b, roughness)
    if "Anisotropy" in node.inputs:
        anisotropy = inputs.number("Anisotropy")
        alpha_x, alpha_y = _anisotropic_alphas(b, roughness, anisotropy)
        if is_reg(anisotropy) or alpha_x != alpha_y:
            _note_rotation(notes, inputs.number("Rotation"), node.inputs["Tangent"].is_linked)
    c = _microfacet("reflection", color, roughness, sp.minimum(b, alpha_x, 1.0), sp.minimum(b, alpha_y, 1.0),
                    distribution, label="glossy")
    if c.distribution == "multi_ggx":
        # Cycles' random walk tints every bounce after the first by the colour again.
        c = replace(c, specular_color=sp.clamp01(b, color))
    summary = "glossy" if c.distribution != "sharp" else "mirror"
    return Shader([_textured_color(c, texture, color)], summary=summary)


def _textured_color(closure, texture, color):
    """A closure whose colour is an image: colour 1 times the image."""
    if texture is None:
        return closure
    return replace(closure, texture=texture, texture_target="color", color=WHITE)


def _metallic(node, stack, notes):
    """Metallic BSDF (Blender 4.3 and later): Schlick's Fresnel from Base Color (F82 mode) or from a physical
    conductor's normal reflectance ((n-1)^2 + k^2) / ((n+1)^2 + k^2) per channel."""
    b = _program(notes)
    _shading_normal(node, stack, notes)
    inputs = _Inputs(node, stack, notes)
    roughness = sp.clamp01(b, inputs.number("Roughness", 0.5))
    texture = None
    if getattr(node, "fresnel_type", "F82") == "PHYSICAL_CONDUCTOR":
        n = inputs.color("IOR")
        k = inputs.color("Extinction")
        k2 = sp.mul(b, k, k)
        color = sp.divide(b, sp.add(b, sp.square(b, sp.sub(b, n, WHITE)), k2),
                          sp.add(b, sp.square(b, sp.add(b, n, WHITE)), k2))
        notes.append("conductor Fresnel rendered as Schlick's from its normal-incidence reflectance")
    else:
        color, texture = inputs.color_or_texture("Base Color")
        if _is_tinted(inputs.color("Edge Tint")):
            notes.append("Edge Tint ignored (F82 edge rendered white)")
    anisotropy = inputs.number("Anisotropy")
    alpha_x, alpha_y = _anisotropic_alphas(b, roughness, anisotropy)
    if is_reg(anisotropy) or alpha_x != alpha_y:
        _note_rotation(notes, inputs.number("Rotation"), node.inputs["Tangent"].is_linked)
    c = _microfacet("reflection", WHITE, roughness, sp.minimum(b, alpha_x, 1.0), sp.minimum(b, alpha_y, 1.0),
                    _distribution(node, notes), fresnel="schlick", specular_color=sp.clamp01(b, color),
                    label="metal")
    if texture is not None:
        c = replace(c, texture=texture, texture_target="specular_color")
    return Shader([c], summary="metal")


def _ior_text(eta):
    return "programmed IOR" if is_reg(eta) else f"IOR {eta:.2f}"


def _glass(node, stack, notes):
    """Glass BSDF: reflection and refraction split by a Fresnel factor of its IOR (Cycles' Glass)."""
    b = _program(notes)
    _shading_normal(node, stack, notes)
    inputs = _Inputs(node, stack, notes)
    color, texture = inputs.color_or_texture("Color")
    roughness = sp.clamp01(b, inputs.number("Roughness"))
    eta = sp.clamp_min(b, inputs.number("IOR", 1.45), 1e-5)
    distribution = _distribution(node, notes)
    a = sp.square(b, roughness)
    if distribution == "multi_ggx" and _is_rough(roughness):
        # Multiscatter GGX: Cycles 3.x's random walk on the microsurface, each microfacet reflecting with its own
        # Fresnel or refracting, not a split by the Fresnel of the shading normal. The core's multi_ggx_glass
        # closures are its two sides; the Glass colour also tints each scattering after the first (Cycles clamps
        # it to [0, 1] there).
        notes.append("multiscatter GGX glass: the light scattered more than once given a cosine shape")
        tint = _tuple(sp.clamp01(b, color))
        reflection, refraction = (
            Closure(kind, _tuple(color), distribution="multi_ggx_glass", specular_color=tint, alpha_x=a, alpha_y=a,
                    ior=eta, label=kind) for kind in ("reflection", "refraction"))
        closures = [_textured_color(reflection, texture, color), _textured_color(refraction, texture, color)]
        return Shader(closures, summary=f"glass, {_ior_text(eta)}, rough, multiscatter")
    if distribution == "multi_ggx":
        distribution = "ggx"
    on, off = _fresnel_split(b, notes, eta)
    reflection = _microfacet("reflection", color, roughness, a, a, distribution, ior=eta, label="reflection")
    refraction = _microfacet("refraction", color, roughness, a, a, distribution, ior=eta, label="refraction")
    closures = [on(_textured_color(reflection, texture, color)), off(_textured_color(refraction, texture, color))]
    summary = f"glass, {_ior_text(eta)}" + (", rough" if reflection.distribution != "sharp" else "")
    return Shader(closures, summary=summary)


def _refraction(node, stack, notes):
    """Refraction BSDF: refraction only, no Fresnel, no reflection."""
    b = _program(notes)
    _shading_normal(node, stack, notes)
    inputs = _Inputs(node, stack, notes)
    color, texture = inputs.color_or_texture("Color")
    roughness = sp.clamp01(b, inputs.number("Roughness"))
    eta = sp.clamp_min(b, inputs.number("IOR", 1.45), 1e-5)
    a = sp.square(b, roughness)
    c = _microfacet("refraction", color, roughness, a, a, _distribution(node, notes), ior=eta, label="refraction")
    return Shader([_textured_color(c, texture, color)], summary=f"refraction, {_ior_text(eta)}")


def _diffuse(node, stack, notes):
    _shading_normal(node, stack, notes)
    inputs = _Inputs(node, stack, notes)
    color, texture = inputs.color_or_texture("Color")
    roughness = sp.clamp01(_program(notes), inputs.number("Roughness"))
    c = Closure("diffuse", color, roughness=roughness, label="diffuse")
    return Shader([_textured_color(c, texture, color)], summary="diffuse")


def _translucent(node, stack, notes):
    _shading_normal(node, stack, notes)
    inputs = _Inputs(node, stack, notes)
    color, texture = inputs.color_or_texture("Color")
    return Shader([_textured_color(Closure("translucent", color, label="translucent"), texture, color)],
                  summary="translucent")


def _transparent(node, stack, notes):
    inputs = _Inputs(node, stack, notes)
    return Shader([Closure("transparent", inputs.color("Color"), label="transparent")], summary="transparent")


def _velvet(node, stack, notes):
    _shading_normal(node, stack, notes)
    inputs = _Inputs(node, stack, notes)
    color, texture = inputs.color_or_texture("Color")
    sigma = sp.clamp01(_program(notes), inputs.number("Sigma" if "Sigma" in node.inputs else "Roughness", 1.0))
    if getattr(node, "distribution", "ASHIKHMIN") == "MICROFIBER":
        notes.append("microfibre sheen rendered as velvet")
    return Shader([_textured_color(Closure("velvet", color, roughness=sigma, label="velvet"), texture, color)],
                  summary="velvet")


def _subsurface(node, stack, notes):
    _shading_normal(node, stack, notes)
    inputs = _Inputs(node, stack, notes)
    color, texture = inputs.color_or_texture("Color")
    notes.append("subsurface rendered as diffuse")
    return Shader([_textured_color(Closure("diffuse", color, label="diffuse"), texture, color)],
                  summary="subsurface")


def _emission(node, stack, notes):
    inputs = _Inputs(node, stack, notes)
    radiance = sp.mul(_program(notes), inputs.color("Color"), inputs.number("Strength", 1.0))
    return Shader([], radiance, summary="emission")


def _holdout(node, stack, notes):
    return Shader([], holdout=1.0, summary="holdout")


def _mix_shader(node, stack, notes):
    # Inputs 1 and 2 are the two shader sockets (both are called "Shader").
    b = _program(notes)
    first = _convert_socket(node.inputs[1], stack, notes)
    second = _convert_socket(node.inputs[2], stack, notes)
    factor = _view_factor(node.inputs["Fac"], stack, notes)
    if factor is None:
        fac = sp.clamp01(b, _Inputs(node, stack, notes).number("Fac", 0.5))
        combined = _add(first.scaled(sp.one_minus(b, fac), b), second.scaled(fac, b), b)
    else:
        at_normal = _factor_at_normal_incidence(factor)
        a = _with_factor(first, factor, off=True, at_normal=1.0 - at_normal, notes=notes)
        b_ = _with_factor(second, factor, off=False, at_normal=at_normal, notes=notes)
        combined = _add(a, b_, b)
    combined.summary = _mix_summary("mix", first, second)
    return combined


def _add_shader(node, stack, notes):
    first = _convert_socket(node.inputs[0], stack, notes)
    second = _convert_socket(node.inputs[1], stack, notes)
    combined = _add(first, second, _program(notes))
    combined.summary = _mix_summary("add", first, second)
    return combined


def _mix_summary(what, first, second):
    parts = [s.summary for s in (first, second) if s.summary]
    if len(parts) == 1:
        return parts[0]
    if len(parts) == 2 and parts[0] == parts[1]:
        return parts[0]
    return f"{what} of " + " and ".join(parts) if parts else ""


def _add(a, c, b=None):
    return Shader(a.closures + c.closures, sp.add(b, a.emission, c.emission), sp.add(b, a.holdout, c.holdout))


def _with_factor(shader, factor, off, at_normal, notes):
    """`shader` weighted by a view-dependent factor (or 1 - it): its closures carry the factor; its emission and
    holdout take the factor's value at normal incidence."""
    closures = []
    for c in shader.closures:
        present = c.factors_off if off else c.factors_on
        if factor in present:
            # A closure's factor bits OR together: the core cannot square a factor.
            notes.append("a view-dependent mix factor applied twice to the same shader is applied once")
            closures.append(c)
        elif off:
            closures.append(replace(c, factors_off=c.factors_off + (factor,)))
        else:
            closures.append(replace(c, factors_on=c.factors_on + (factor,)))
    if positive(shader.emission, 0.0) or positive(shader.holdout, 0.0):
        notes.append("view-dependent mix factor above an emission or holdout evaluated at normal incidence")
    b = _program(notes)
    return Shader(closures, sp.mul(b, shader.emission, at_normal), sp.mul(b, shader.holdout, at_normal),
                  shader.summary)


def _view_factor(socket, stack, notes):
    """The (kind, value) key of a Fresnel or Layer Weight node of constant IOR or Blend driving a Mix Shader's Fac,
    or None (with node programs, a computed IOR or Blend, or a linked Normal, compiles the node instead)."""
    out, _, inner = follow(socket, stack)
    if out is None:
        return None
    node = out.node
    if node.bl_idname == "ShaderNodeFresnel":
        kind, value_name = "fresnel", "IOR"
    elif node.bl_idname == "ShaderNodeLayerWeight":
        kind, value_name = ("layer_fresnel" if out.name == "Fresnel" else "layer_facing"), "Blend"
    else:
        return None
    programs = _program(notes) is not None
    if programs and node.inputs["Normal"].is_linked:
        return None
    value_out, value_socket, _ = follow(node.inputs[value_name], inner)
    if value_out is not None and value_out.node.bl_idname != "ShaderNodeValue":
        return None                        # a computed IOR or Blend: compiled, or the Fac's constant value, noted
    value = value_out.default_value if value_out is not None else value_socket.default_value
    value = float(value)
    if not math.isfinite(value):
        return None
    if node.inputs["Normal"].is_linked:
        notes.append(f"{node.bl_label} node's Normal input ignored (the shading normal used)")
    if kind == "fresnel":
        value = max(value, 1e-5)
    else:
        value = _clamp01(value)
    return (kind, value)


def _fresnel_dielectric_cos(cosi, eta):
    """Cycles' fresnel_dielectric_cos."""
    c = abs(cosi)
    g = eta * eta - 1.0 + c * c
    if g <= 0.0:
        return 1.0
    g = math.sqrt(g)
    a = (g - c) / (g + c)
    b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
    return 0.5 * a * a * (1.0 + b * b)


def _factor_at_normal_incidence(key):
    kind, value = key
    if kind == "fresnel":
        return _fresnel_dielectric_cos(1.0, max(value, 1e-5))
    if kind == "layer_fresnel":
        return _fresnel_dielectric_cos(1.0, 1.0 / max(1.0 - value, 1e-5))
    return 0.0                             # layer_facing: 1 - cos^k is 0 facing the viewer


def _f0(b, ior):
    if is_const(ior):
        return ((ior - 1.0) / (ior + 1.0)) ** 2
    return sp.square(b, sp.divide(b, sp.sub(b, ior, 1.0), sp.add(b, ior, 1.0)))


def _unsupported_shader(node, stack, notes):
    """Toon, Hair, volumes...: a diffuse surface of its colour, if it has one."""
    if "Color" in node.inputs:
        color = _Inputs(node, stack, notes).color("Color")
    else:
        color = DEFAULT_COLOR
    notes.append(f"unsupported shader '{node.bl_label}' rendered as diffuse")
    return Shader([Closure("diffuse", color, label="diffuse")], summary="diffuse")


_SHADERS = {
    "ShaderNodeBsdfPrincipled": _principled,
    "ShaderNodeBsdfDiffuse": _diffuse,
    "ShaderNodeBsdfGlossy": _glossy,
    "ShaderNodeBsdfAnisotropic": _glossy,
    "ShaderNodeBsdfMetallic": _metallic,      # Blender 4.3 and later
    "ShaderNodeBsdfGlass": _glass,
    "ShaderNodeBsdfRefraction": _refraction,
    "ShaderNodeBsdfTranslucent": _translucent,
    "ShaderNodeBsdfTransparent": _transparent,
    "ShaderNodeBsdfVelvet": _velvet,
    "ShaderNodeBsdfSheen": _velvet,           # 4.0 renamed Velvet to Sheen (Ashikhmin: Sigma as Roughness)
    "ShaderNodeSubsurfaceScattering": _subsurface,
    "ShaderNodeEmission": _emission,
    "ShaderNodeHoldout": _holdout,
    "ShaderNodeMixShader": _mix_shader,
    "ShaderNodeAddShader": _add_shader,
}


# --- reading socket values ------------------------------------------------------------------------------------

def _group_output(tree):
    outputs = [n for n in tree.nodes if n.bl_idname == "NodeGroupOutput"]
    for n in outputs:
        if getattr(n, "is_active_output", False):
            return n
    return outputs[0] if outputs else None


def _by_identifier(sockets, identifier):
    for s in sockets:
        if s.identifier == identifier:
            return s
    return None


_NEVER_MUTED = {"NodeReroute", "NodeGroupInput", "NodeGroupOutput", "NodeFrame"}


def follow(socket, stack=()):
    """What feeds the input `socket`: (output socket or None, the socket whose own value applies when there is
    none, the group nodes we are inside). Looks through reroutes, muted nodes (their internal links), into node
    groups (to their Group Output) and back out of them (a Group Input socket leads to the Group node's input).
    Muted links count as unconnected."""
    for _ in range(1000):
        if not socket.is_linked:
            return None, socket, stack
        link = socket.links[0]
        if getattr(link, "is_muted", False) or not getattr(link, "is_valid", True):
            return None, socket, stack
        out, node = link.from_socket, link.from_node
        if getattr(node, "mute", False) and node.bl_idname not in _NEVER_MUTED:
            # A muted node passes its internal links through; an output without one has its own value.
            internal = next((l for l in node.internal_links if l.to_socket.identifier == out.identifier), None)
            if internal is None:
                return None, out, stack
            socket = internal.from_socket
        elif node.bl_idname == "NodeReroute":
            socket = node.inputs[0]
        elif node.bl_idname == "ShaderNodeGroup":
            group_output = _group_output(node.node_tree) if node.node_tree is not None else None
            inner = _by_identifier(group_output.inputs, out.identifier) if group_output is not None else None
            if inner is None:
                return None, socket, stack
            socket, stack = inner, stack + (node,)
        elif node.bl_idname == "NodeGroupInput" and stack:
            outer = _by_identifier(stack[-1].inputs, out.identifier)
            if outer is None:
                return None, socket, stack
            socket, stack = outer, stack[:-1]
        else:
            return out, socket, stack
    return None, socket, stack


def source_node(socket):
    """The node feeding `socket`, looking through reroutes and groups; None when unconnected."""
    out, _, _ = follow(socket)
    return None if out is None else out.node


class _Inputs:
    """A node's inputs inside the group nesting `stack`: Values (constants or program registers) when the material
    has a ProgramBuilder; otherwise constants, noting the inputs driven by nodes."""

    def __init__(self, node, stack, notes):
        self.node, self.stack, self.notes = node, stack, notes
        self.program = _program(notes)

    def value(self, name):
        socket = self.node.inputs[name]
        out, own, _ = follow(socket, self.stack)
        if out is None:
            return own.default_value
        if out.node.bl_idname in ("ShaderNodeRGB", "ShaderNodeValue"):
            return out.default_value
        self.notes.append(f"'{name}' driven by a {out.node.bl_label} node: its unconnected value used")
        return socket.default_value

    def number(self, name, default=0.0):
        if name is None or name not in self.node.inputs:
            return default
        if self.program is not None:
            value = self.program.value_of(self.node.inputs[name], self.stack)
            if is_reg(value):
                return value if value.type == "f" else self.program.convert(value, "vector", "f")
        else:
            value = self.value(name)
        if isinstance(value, (int, float)):
            value = float(value)
        else:
            value = sum(_color(value)) / 3.0   # a colour plugged into a number: Cycles takes its average
        if not math.isfinite(value):
            self.notes.append(f"'{name}' is not a number: {default} used")
            return default
        return value

    def optional_number(self, name):
        return self.number(name, 0.0)

    def color(self, name, default=DEFAULT_COLOR):
        if name is None or name not in self.node.inputs:
            return default
        if self.program is not None:
            value = self.program.value_of(self.node.inputs[name], self.stack)
            if is_reg(value):
                return value if value.type == "v" else self.program.convert(value, "f", "color")
            rgb = _color(value)
        else:
            rgb = _color(self.value(name))
        if not all(math.isfinite(c) for c in rgb):
            self.notes.append(f"'{name}' is not a number: default used")
            return default
        return rgb

    def color_or_texture(self, name):
        """(colour, TextureRef or None): an Image Texture node plugged in becomes a texture the core looks up at
        the hit's UV; anything else is read as color() does. Colours are clamped to [0, 1]."""
        out, _, _ = follow(self.node.inputs[name], self.stack)
        if out is not None and out.node.bl_idname == "ShaderNodeTexImage" and (self.program is None
                                                                              or _plain_image(out)):
            reference, color = textures.texture_reference(out.node, self.notes)
            return color, reference
        value = self.color(name)
        if is_reg(value):
            return value, None
        return _clamped_color(value, self.notes), None


def _plain_image(out):
    """An Image Texture's Color output with Cycles' defaults (UV map, Linear, Repeat, flat), which the core
    looks up as a closure texture; any other Image Texture use is compiled into the node program."""
    node = out.node
    return (out.identifier == "Color" and node.image is not None and not node.inputs["Vector"].is_linked
            and node.interpolation == 'Linear' and node.extension == 'REPEAT' and node.projection == 'FLAT')


def _input_value(node, socket_name, notes):
    return _Inputs(node, (), notes).value(socket_name)


def color_input(node, socket_name, notes):
    return _Inputs(node, (), notes).color(socket_name)


def float_input(node, socket_name, notes):
    return _Inputs(node, (), notes).number(socket_name)


def color_or_texture(node, socket_name, notes):
    return _Inputs(node, (), notes).color_or_texture(socket_name)


def _color(value):
    """An RGB(A) value or a single number, as an (r, g, b) tuple of floats."""
    if isinstance(value, (int, float)):
        return (float(value),) * 3
    return tuple(float(c) for c in tuple(value)[:3])


def _clamped_color(rgb, notes):
    clamped = _clamp_color(rgb)
    if clamped != tuple(rgb):
        notes.append("colour outside [0, 1] clamped")
    return clamped


def _clamp_color(rgb):
    return tuple(_clamp01(c) for c in rgb)


def _hue(b, rgb, weights):
    """Colour over its luminance (hue and saturation alone), white for black: Cycles' m_ctint (a programmed
    colour: black for black, the vector_math divide being safe)."""
    if is_reg(rgb):
        return sp.divide(b, rgb, sp.dot(b, rgb, weights))
    lum = sum(w * c for w, c in zip(weights, rgb))
    return tuple(c / lum for c in rgb) if lum > 0.0 else WHITE


def _is_tinted(rgb):
    return is_reg(rgb) or any(abs(c - 1.0) > 1e-6 for c in rgb)


def _clamp01(value):
    return min(max(value, 0.0), 1.0)
