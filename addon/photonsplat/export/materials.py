"""Blender materials -> the core's four surface types (diffuse, mirror, glass, glossy) plus emission.

The core knows only:
  diffuse  Lambertian reflection, albedo = colour
  mirror   perfect specular reflection, Fresnel-Schlick with F0 = colour (a smooth metal)
  glass    smooth dielectric with index `ior`, refracted light tinted by colour
  glossy   GGX microfacet reflection (a rough metal), Fresnel-Schlick with F0 = colour, alpha = roughness^2 as
           in Cycles; the core itself renders roughness <= ROUGHNESS_SHARP as a mirror
and every surface may also emit radiance `emission` (W/(sr m^2), both faces, as Cycles' Emission shader).

We read the node tree Cycles would render (get_output_node('CYCLES')) and map the shader plugged into the
Surface input. Whatever cannot be represented exactly is replaced by the nearest supported surface, and a
note says so; the sync (export/sync.py) turns the notes into one warning per material in its report.

Known approximations that are NOT warned about, because they apply to nearly every material:
  - Principled BSDF's dielectric specular layer (Specular input, about 4 % reflectance) is dropped, and its
    diffuse lobe is rendered as Lambert (Cycles adds a slight retro-reflection depending on Roughness).
  - Roughness below ROUGHNESS_SHARP is rendered as a perfectly smooth interface (Cycles' alpha = r^2 is then
    below 0.0025, visually sharp).
  - Glossy BSDF and the Principled metal lobe are single-scatter GGX with Cycles 3.4's Smith shadowing. The
    node's distribution is otherwise ignored: Beckmann and Ashikhmin-Shirley are rendered as GGX (noted), and
    Multiscatter GGX without its multiple-scattering energy (slightly darker at high roughness; noted).

Rough glass (and Refraction BSDF) stays perfectly smooth: the core has no rough dielectric; a note says so.

Colours (Principled Base Color, the Color of Diffuse, Glossy and Glass) may come from an Image Texture node
plugged in directly: the core then looks the image up at the hit's UV (export/textures.py). Any other node
driving an input (a Mix RGB, a Math node, a texture behind a Mapping node's output...) is not interpreted:
the socket's unconnected value is used and a note says so.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from .. import compat
from . import textures

# Above this roughness a glossy or glass surface visibly blurs in Cycles: a metal becomes "glossy" (the core's
# own threshold for a mirror is the same number); glass is still rendered sharp, with a warning.
ROUGHNESS_SHARP = 0.05

# The default of the core's add_material(roughness=...), used by every kind that has none.
DEFAULT_ROUGHNESS = 0.5

# Cycles renders objects without a material with a plain grey diffuse surface; so do we.
DEFAULT_COLOR = (0.8, 0.8, 0.8)
DEFAULT_MATERIAL_NAME = "Photon Splat default"

BLACK = (0.0, 0.0, 0.0)


@dataclass
class MaterialSpec:
    """One material as the core's add_material() takes it, plus the notes gathered while converting it."""
    name: str
    kind: str = "diffuse"          # "diffuse" | "mirror" | "glass" | "glossy"
    color: tuple = DEFAULT_COLOR
    ior: float = 1.45
    roughness: float = DEFAULT_ROUGHNESS   # glossy only: Blender's roughness, in [0, 1]
    emission: tuple = BLACK
    notes: list = field(default_factory=list)
    # True when the shader reflects no light at all (an Emission shader, an unconnected shader socket):
    # mixing it with a real surface then only scales that surface.
    no_surface: bool = False
    # An Image Texture node driving the colour (textures.TextureRef), looked up at the hit's UV by the core.
    texture: object = None
    holdout: bool = False          # Holdout shader or holdout object: cut out of the image

    def core_arguments(self):
        """Keyword arguments for core Scene.add_material() (the texture index is added by the caller)."""
        arguments = dict(name=self.name, kind=self.kind, color=tuple(self.color), ior=float(self.ior),
                         emission=tuple(self.emission), roughness=float(self.roughness))
        if self.holdout:
            arguments["holdout"] = True
        return arguments

    def describe(self):
        """Short human description, e.g. for the material panel: 'glass, IOR 1.50'."""
        text = self.kind
        if self.kind == "glass":
            text += f", IOR {self.ior:.2f}"
        if self.kind == "glossy":
            text += f", roughness {self.roughness:.2f}"
        if any(c > 0.0 for c in self.emission):
            text += ", emitting"
        if self.texture is not None:
            text += f", image '{self.texture.image.name}'"
        if self.holdout:
            text = "holdout"
        return text


def default_material():
    return MaterialSpec(name=DEFAULT_MATERIAL_NAME)


def holdout_material():
    """What objects marked as holdout render with, whatever their own materials."""
    return MaterialSpec(name="Photon Splat holdout", color=BLACK, holdout=True)


def convert_material(material):
    """Map a Blender material (or None) to a MaterialSpec. Never raises for odd node setups."""
    if material is None:
        return default_material()
    name = material.name_full

    if not compat.uses_nodes(material):
        # Without nodes Cycles shades the material as a diffuse surface of its viewport colour.
        spec = MaterialSpec(name=name, color=_color(material.diffuse_color))
        return _finish(spec)

    output = material.node_tree.get_output_node('CYCLES')
    if output is None:
        spec = MaterialSpec(name=name)
        spec.notes.append("no Material Output node, rendered as default grey diffuse")
        return _finish(spec)

    surface = output.inputs["Surface"]
    if not surface.is_linked:
        # Cycles renders an unconnected Surface as black.
        spec = MaterialSpec(name=name, color=BLACK)
        return _finish(spec)

    spec = _convert_shader(source_node(surface), name)
    spec.name = name
    return _finish(spec)


def _finish(spec):
    """Clamp colours into the range the core accepts (albedo and tints in [0, 1], emission >= 0)."""
    clamped = tuple(min(max(c, 0.0), 1.0) for c in spec.color)
    if clamped != tuple(spec.color):
        spec.notes.append("colour outside [0, 1] clamped")
    spec.color = clamped
    spec.emission = tuple(max(c, 0.0) for c in spec.emission)
    roughness = _clamp01(spec.roughness) if math.isfinite(spec.roughness) else DEFAULT_ROUGHNESS
    if spec.kind == "glossy" and roughness != spec.roughness:
        spec.notes.append(f"roughness {spec.roughness} outside [0, 1] replaced by {roughness:.2f}")
    spec.roughness = roughness
    return spec


# --- shader nodes ---------------------------------------------------------------------------------------------

def _convert_shader(node, name):
    """Convert the shader node `node` (may be None: an unconnected shader socket)."""
    if node is None:
        # An unconnected shader socket adds nothing: no surface and no light.
        return MaterialSpec(name=name, color=BLACK, no_surface=True)
    converter = _SHADERS.get(node.bl_idname)
    if converter is not None:
        return converter(node, name)
    return _unsupported_shader(node, name)


def _principled(node, name):
    """Principled BSDF, v1 (Blender 3.x) or v2 (4.0 and later): compat.principled_input names its inputs."""
    notes = []
    role = compat.principled_input
    base, texture = color_or_texture(node, role("base_color"), notes)
    metallic = _clamp01(float_input(node, role("metallic"), notes))
    transmission = _clamp01(float_input(node, role("transmission"), notes))
    roughness = float_input(node, role("roughness"), notes)
    ior = float_input(node, role("ior"), notes)
    emission = _scaled(color_input(node, role("emission_color"), notes),
                       float_input(node, role("emission_strength"), notes))

    # Cycles' weights (3.4 and 4.x alike): metal = metallic, glass = transmission * (1 - metallic),
    # diffuse = (1 - metallic)(1 - transmission). We keep the dominant lobe; metal wins ties like in Cycles.
    if metallic >= 0.5:
        spec = _metal(name, base, roughness)
        if metallic < 1.0:
            notes.append(f"Metallic {metallic:.2f} rendered as a pure metal")
        if spec.kind == "glossy":
            _note_distribution(notes, getattr(node, "distribution", "GGX"))
        if role("specular_ior_level") is not None and _is_tinted(color_input(node, role("specular_tint"), [])):
            # v2's metal is an F82-tint Fresnel; with a white tint it is Schlick's with F0 = Base Color, ours.
            notes.append("Specular Tint of the metal ignored (F82 edge tint rendered white)")
    elif transmission >= 0.5:
        spec = MaterialSpec(name=name, kind="glass", color=base, ior=ior)
        if transmission < 1.0 or metallic > 0.0:
            notes.append(f"Transmission {transmission:.2f} rendered as pure glass")
        _note_rough(notes, roughness)
    else:
        subsurface = _clamp01(float_input(node, role("subsurface"), notes))
        color = base
        if subsurface > 0.0:
            if role("subsurface_color") is not None:
                # v1: Cycles' subsurface albedo blends towards Subsurface Color; diffuse with that colour is
                # close. v2 scatters Base Color itself.
                color = _mix(base, color_input(node, role("subsurface_color"), notes), subsurface)
            notes.append("subsurface scattering rendered as diffuse")
        spec = MaterialSpec(name=name, kind="diffuse", color=color)
        if metallic > 0.0 or transmission > 0.0:
            notes.append(f"Metallic {metallic:.2f} / Transmission {transmission:.2f} ignored (rendered diffuse)")

    if float_input(node, role("alpha"), notes) < 1.0:
        notes.append("Alpha ignored (rendered opaque)")
    if float_input(node, role("coat"), notes) > 0.0:
        notes.append(f"{role('coat')} ignored (no coat layer)")
    if float_input(node, role("sheen"), notes) > 0.0:
        notes.append(f"{role('sheen')} ignored (no sheen layer)")
    if _optional_float(node, role("diffuse_roughness"), notes) > 0.0:
        notes.append("Diffuse Roughness ignored (rendered Lambertian)")
    if _optional_float(node, role("thin_film"), notes) > 0.0:
        notes.append("thin film ignored")
    if node.inputs[role("normal")].is_linked:
        notes.append("normal/bump map ignored")
    spec.emission = emission
    spec.texture = texture if spec.color == base else None
    if texture is not None and spec.texture is None:
        notes.append(f"image '{texture.image.name}' ignored (its colour is blended with Subsurface Color)")
    spec.notes = notes
    return spec


def _optional_float(node, socket_name, notes):
    """A number input that only some versions have (socket_name None, or missing from this node): 0 there."""
    if socket_name is None or socket_name not in node.inputs:
        return 0.0
    return float_input(node, socket_name, notes)


def _is_tinted(rgb):
    return any(abs(c - 1.0) > 1e-6 for c in rgb)


def _diffuse(node, name):
    notes = []
    color, texture = color_or_texture(node, "Color", notes)
    spec = MaterialSpec(name=name, kind="diffuse", color=color, texture=texture)
    if float_input(node, "Roughness", notes) > 0.0:
        notes.append("Oren-Nayar roughness ignored (rendered Lambertian)")
    spec.notes = notes
    return spec


def _is_rough(roughness):
    """roughness > ROUGHNESS_SHARP as the core decides it, in float32: Blender stores 0.05 as 0.0500000007."""
    return bool(np.float32(roughness) > np.float32(ROUGHNESS_SHARP))


def _metal(name, color, roughness):
    """A smooth metal is a mirror, a rough one glossy (GGX, alpha = roughness^2 in the core)."""
    if _is_rough(roughness):
        return MaterialSpec(name=name, kind="glossy", color=color, roughness=roughness)
    return MaterialSpec(name=name, kind="mirror", color=color)


def _glossy(node, name):
    notes = []
    distribution = getattr(node, "distribution", "GGX")
    color, texture = color_or_texture(node, "Color", notes)
    roughness = float_input(node, "Roughness", notes)
    if distribution == "SHARP":
        # Cycles renders the Sharp distribution as a perfect mirror whatever the roughness.
        spec = MaterialSpec(name=name, kind="mirror", color=color)
    else:
        spec = _metal(name, color, roughness)
    if spec.kind == "glossy":
        _note_distribution(notes, distribution)
    # Blender 3.4's Anisotropic BSDF and 4.x's Glossy BSDF (one node since 4.0) have an Anisotropy input.
    if "Anisotropy" in node.inputs and (node.inputs["Anisotropy"].is_linked
                                        or float_input(node, "Anisotropy", notes) != 0.0):
        notes.append("anisotropy ignored")
    return _finish_node(spec, node, texture, notes)


def _metallic(node, name):
    """Metallic BSDF (Blender 4.3 and later): a metal whose Fresnel is F82-tint (Base Color at normal
    incidence, Edge Tint near grazing) or a physical conductor (complex IOR n + ik per channel). The core's
    metal is Schlick's Fresnel from the normal-incidence colour: exact for F82 with a white Edge Tint."""
    notes = []
    roughness = float_input(node, "Roughness", notes)
    if getattr(node, "fresnel_type", "F82") == "PHYSICAL_CONDUCTOR":
        n = _color(_input_value(node, "IOR", notes))
        k = _color(_input_value(node, "Extinction", notes))
        color = tuple(((a - 1.0) ** 2 + b * b) / ((a + 1.0) ** 2 + b * b) for a, b in zip(n, k))
        texture = None
        notes.append("conductor Fresnel rendered as Schlick's from its normal-incidence reflectance")
    else:
        color, texture = color_or_texture(node, "Base Color", notes)
        if _is_tinted(color_input(node, "Edge Tint", [])):
            notes.append("Edge Tint ignored (F82 edge rendered white)")
    spec = _metal(name, color, roughness)
    if spec.kind == "glossy":
        _note_distribution(notes, getattr(node, "distribution", "GGX"))
    if node.inputs["Anisotropy"].is_linked or float_input(node, "Anisotropy", notes) != 0.0:
        notes.append("anisotropy ignored")
    return _finish_node(spec, node, texture, notes)


def _glass(node, name):
    notes = []
    color, texture = color_or_texture(node, "Color", notes)
    spec = MaterialSpec(name=name, kind="glass", color=color, ior=float_input(node, "IOR", notes))
    _note_rough(notes, float_input(node, "Roughness", notes))
    return _finish_node(spec, node, texture, notes)


# Nodes converted as a kin of theirs, and what that leaves out.
_KIN_NOTES = {
    "ShaderNodeBsdfRefraction": "Refraction BSDF rendered as glass (with Fresnel reflection)",
}


def _finish_node(spec, node, texture, notes):
    """`spec` with the texture of its Color input and its notes, the note of a kin node last."""
    spec.texture = texture
    if node.bl_idname in _KIN_NOTES:
        notes.append(_KIN_NOTES[node.bl_idname])
    spec.notes = notes
    return spec


def _transparent(node, name):
    # A dielectric of index 1 neither bends nor reflects light: exactly a tinted transparent surface.
    notes = []
    return MaterialSpec(name=name, kind="glass", color=color_input(node, "Color", notes), ior=1.0, notes=notes)


def _emission(node, name):
    notes = []
    radiance = _scaled(color_input(node, "Color", notes), float_input(node, "Strength", notes))
    return MaterialSpec(name=name, kind="diffuse", color=BLACK, emission=radiance, notes=notes,
                        no_surface=True)


def _holdout(node, name):
    return MaterialSpec(name=name, color=BLACK, holdout=True)


def _mix_shader(node, name):
    notes = []
    fac = _clamp01(float_input(node, "Fac", notes))
    # Inputs 1 and 2 are the two shader sockets (both are called "Shader").
    first = _convert_shader(source_node(node.inputs[1]), name)
    second = _convert_shader(source_node(node.inputs[2]), name)
    spec = _combine(first, 1.0 - fac, second, fac, "Mix Shader", notes)
    spec.notes = first.notes + second.notes + notes
    return spec


def _add_shader(node, name):
    notes = []
    first = _convert_shader(source_node(node.inputs[0]), name)
    second = _convert_shader(source_node(node.inputs[1]), name)
    spec = _combine(first, 1.0, second, 1.0, "Add Shader", notes)
    spec.notes = first.notes + second.notes + notes
    return spec


def _combine(first, w1, second, w2, what, notes):
    """Weighted sum of two converted shaders, as Cycles sums closures.

    Emission adds exactly, and so do two diffuse surfaces (their albedos add). When one side has no surface
    (an Emission shader or an unconnected socket) the other one's colour is scaled by its weight: exact for
    diffuse, close for mirror, glossy and glass (whose Fresnel reflection is not scaled). Two different surface types
    cannot be blended by the core: the heavier one is kept and a note says so."""
    emission = tuple(w1 * a + w2 * b for a, b in zip(first.emission, second.emission))
    spec = MaterialSpec(name=first.name, emission=emission)
    if first.no_surface and second.no_surface:
        spec.color, spec.no_surface = BLACK, True
    elif first.no_surface or second.no_surface:
        kept, weight = (second, w2) if first.no_surface else (first, w1)
        spec.kind, spec.color, spec.ior = kept.kind, _scaled(kept.color, weight), kept.ior
        spec.roughness, spec.texture, spec.holdout = kept.roughness, kept.texture, kept.holdout
        if kept.texture is not None and weight != 1.0:
            notes.append(f"{what}: image '{kept.texture.image.name}' not scaled by the factor {weight:.2f}")
    elif (first.kind == "diffuse" and second.kind == "diffuse" and first.texture is None
          and second.texture is None and not first.holdout and not second.holdout):
        spec.color = tuple(w1 * a + w2 * b for a, b in zip(first.color, second.color))
    else:
        kept, weight = (first, w1) if w1 >= w2 else (second, w2)
        spec.kind, spec.color, spec.ior, spec.roughness = kept.kind, kept.color, kept.ior, kept.roughness
        spec.texture, spec.holdout = kept.texture, kept.holdout
        label = lambda s: "holdout" if s.holdout else s.kind + (" (image)" if s.texture is not None else "")
        notes.append(f"{what} of {label(first)} and {label(second)} rendered as {label(kept)} alone")
    return spec


def _unsupported_shader(node, name):
    """Translucent, Subsurface, Velvet, Toon, Hair, groups...: a diffuse surface of its colour, if it has one."""
    notes = []
    if "Color" in node.inputs:
        color = color_input(node, "Color", notes)
    else:
        color = DEFAULT_COLOR
    notes.append(f"unsupported shader '{node.bl_label}' rendered as diffuse")
    return MaterialSpec(name=name, kind="diffuse", color=color, notes=notes)


_SHADERS = {
    "ShaderNodeBsdfPrincipled": _principled,
    "ShaderNodeBsdfDiffuse": _diffuse,
    "ShaderNodeBsdfGlossy": _glossy,
    "ShaderNodeBsdfAnisotropic": _glossy,
    "ShaderNodeBsdfMetallic": _metallic,      # Blender 4.3 and later
    "ShaderNodeBsdfGlass": _glass,
    "ShaderNodeBsdfRefraction": _glass,
    "ShaderNodeBsdfTransparent": _transparent,
    "ShaderNodeEmission": _emission,
    "ShaderNodeHoldout": _holdout,
    "ShaderNodeMixShader": _mix_shader,
    "ShaderNodeAddShader": _add_shader,
}


# --- reading socket values ------------------------------------------------------------------------------------

def source_node(socket):
    """The node feeding `socket`, looking through reroutes; None when unconnected or the link is muted."""
    while socket.is_linked:
        link = socket.links[0]
        if getattr(link, "is_muted", False):
            return None
        node = link.from_node
        if node.bl_idname != "NodeReroute":
            return node
        socket = node.inputs[0]
    return None


def _input_value(node, socket_name, notes):
    """Value of an input socket. A constant node (RGB, Value) plugged in is read; for anything else
    (textures, math...) the socket's own unconnected value is used and a note says so."""
    socket = node.inputs[socket_name]
    if socket.is_linked:
        source = source_node(socket)
        if source is not None and source.bl_idname in ("ShaderNodeRGB", "ShaderNodeValue"):
            return source.outputs[0].default_value
        if source is not None:
            notes.append(f"'{socket_name}' driven by a {source.bl_label} node: its unconnected value used")
    return socket.default_value


def color_input(node, socket_name, notes):
    return _color(_input_value(node, socket_name, notes))


def color_or_texture(node, socket_name, notes):
    """(colour, TextureRef or None) of a colour input: an Image Texture node plugged in (directly or through
    reroutes) becomes a texture the core looks up at the hit's UV; anything else is read as color_input does."""
    socket = node.inputs[socket_name]
    source = source_node(socket) if socket.is_linked else None
    if source is not None and source.bl_idname == "ShaderNodeTexImage":
        reference, color = textures.texture_reference(source, notes)
        return color, reference
    return color_input(node, socket_name, notes), None


def float_input(node, socket_name, notes):
    value = _input_value(node, socket_name, notes)
    if isinstance(value, (int, float)):
        return float(value)
    rgb = _color(value)                    # a colour plugged into a number: Cycles takes its average
    return sum(rgb) / 3.0


def _color(value):
    """An RGB(A) value or a single number, as an (r, g, b) tuple of floats."""
    if isinstance(value, (int, float)):
        return (float(value),) * 3
    return tuple(float(c) for c in tuple(value)[:3])


def _scaled(rgb, factor):
    return tuple(c * factor for c in rgb)


def _mix(a, b, t):
    return tuple((1.0 - t) * x + t * y for x, y in zip(a, b))


def _clamp01(value):
    return min(max(value, 0.0), 1.0)


def _note_rough(notes, roughness):
    """For glass only: the core has no rough dielectric."""
    if _is_rough(roughness):
        notes.append(f"Roughness {roughness:.2f} rendered perfectly smooth (rough glass is not supported)")


# Distributions the core renders exactly (Principled and Glossy BSDF's default); others become GGX with a note.
_DISTRIBUTION_NAMES = {"BECKMANN": "Beckmann", "ASHIKHMIN_SHIRLEY": "Ashikhmin-Shirley",
                       "MULTI_GGX": "Multiscatter GGX"}


def _note_distribution(notes, distribution):
    if distribution != "GGX":
        label = _DISTRIBUTION_NAMES.get(distribution, str(distribution))
        notes.append(f"{label} distribution rendered as GGX (single scattering)")
