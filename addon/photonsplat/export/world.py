"""The world: the radiance seen by rays that leave the scene, as Cycles' world shader gives it.

The world's Surface output (get_output_node('CYCLES')) is lowered as a material's is (export/materials.py), with the
same node compiler (export/shader_program.py, a ProgramBuilder): Background and Emission shaders give
emission = Color x Strength, Mix Shader blends two of them by its (clamped) Fac, Add Shader adds them. Whatever
drives those inputs (Environment and Sky Textures, Mapping and Texture Coordinate, gradients over the direction,
Light Path's Is Camera Ray...) becomes the world's node program: the core runs it per direction, with the shading
point's P, Generated and Object coordinates = the ray's direction and N = -direction, and the Light Path flags of
the ray (Scene.set_world_program). A world whose emission folds to a constant has no program: the core gets the
constant alone (Scene.set_background), which costs nothing.

Cycles' world settings read here: the Ray Visibility's Camera (off: camera rays see black, compiled into the program
through Light Path's Is Camera Ray; lighting stays), the sampling method and map resolution (the core's importance
map width; None is noted: the core always importance-samples the world, which changes the noise, not the light).
Anything not rendered (Volume output, other shaders, the other ray visibilities) is a note, as materials' notes.

A world without nodes is its colour; no world renders black, as in Cycles. A core without world programs (older
modules) gets the constant of the unconnected values, with a note for each driven input.
"""

import math
from dataclasses import dataclass, field

from .. import compat
from . import materials
from . import shader_program as sp
from .shader_program import is_const, is_reg

BLACK = (0.0, 0.0, 0.0)


@dataclass
class WorldSpec:
    """The world as the core takes it: `radiance` for Scene.set_background, and a node program (`program`, the
    ProgramBuilder, and `emission`, its Reg) for Scene.set_world_program, or none."""
    name: str = ""
    radiance: tuple = BLACK
    program: object = None
    emission: object = None
    map_resolution: int = 0
    notes: list = field(default_factory=list)

    @property
    def uses_program(self):
        return self.program is not None and is_reg(self.emission)

    @property
    def textures(self):
        """The TextureRefs the program's image ops read, once each, in order."""
        if not self.uses_program:
            return []
        found = {}
        for _, params, _, _ in self.program.instructions:
            for p in params:
                if isinstance(p, sp.TextureParam):
                    found.setdefault(p.reference.key, p.reference)
        return list(found.values())

    def core_program(self, texture_index=None):
        """The program dict of Scene.set_world_program (None without one); `texture_index(TextureRef)` gives the
        core's texture index (the scene's texture table, shared with the materials)."""
        if not self.uses_program:
            return None
        return self.program.encode([("emission", 0, self.emission)], texture_index, lambda name: -1)

    @property
    def signature(self):
        """What the core scene gets from this world, comparable between syncs (textures by key)."""
        keys = [reference.key for reference in self.textures]
        program = self.core_program(lambda reference: keys.index(reference.key))
        if program is not None:
            program = (tuple(program["code"]), tuple(program["registers"]), tuple(program["tables"]),
                       tuple((o["target"], o["index"], o["register"]) for o in program["outputs"]))
        return (tuple(self.radiance), program, tuple(keys), self.map_resolution)

    @property
    def emits(self):
        return self.uses_program or max(self.radiance) > 0.0

    def report_lines(self):
        """The notes as the render reports them, one line each, naming the world."""
        return [f"World '{self.name}': {note}" for note in self.notes]

    def describe(self):
        if self.uses_program:
            text = f"node program ({len(self.program.instructions)} ops)"
            for reference in self.textures:
                text += f", image '{reference.image.name}'"
            return text
        return "constant ({})".format(", ".join(f"{c:.3g}" for c in self.radiance))


def convert_world(world, programs=True):
    """The WorldSpec of `world` (bpy.types.World or None). `programs`: whether the core takes world programs
    (otherwise driven inputs take their unconnected values, noted). Never raises for odd node setups."""
    if world is None:
        return WorldSpec(name="", radiance=BLACK)      # no world: Cycles renders a black background
    notes = []
    ops = sp.op_table() if programs else None
    spec = WorldSpec(name=world.name, map_resolution=_map_resolution(world, notes))
    if not compat.uses_nodes(world):
        spec.radiance = _finite_color(tuple(float(c) for c in world.color))
        return _finish(world, spec, None, spec.radiance, notes, programs)

    output = world.node_tree.get_output_node('CYCLES')
    if output is None:
        return _finish(world, spec, None, BLACK, notes, programs)
    volume = output.inputs.get("Volume")
    if volume is not None and materials.source_node(volume) is not None:
        notes.append("Volume output ignored")
    lines = materials._Notes(ops)
    try:
        emission = _shader(lines.program, output.inputs["Surface"], (), lines)
    except RecursionError:
        lines = materials._Notes(None, ["node tree too deeply nested: rendered black"])
        emission = BLACK
    except Exception as error:  # noqa: BLE001 -- a node setup the compiler did not foresee: never fail a render
        if lines.program is None:
            raise
        failure = f"node program not compiled ({type(error).__name__}: {error}): driven inputs use their values"
        lines = materials._Notes(None, [failure])
        emission = _shader(None, output.inputs["Surface"], (), lines)
    notes.extend(lines)
    return _finish(world, spec, lines.program, emission, notes, programs)


def _finish(world, spec, b, emission, notes, programs):
    """`spec` with its emission: a constant as the radiance, a register as the program; the camera visibility."""
    camera_visible = _visibility(world, notes)
    if not camera_visible:
        if b is None and is_const(emission) and max(emission) > 0.0:
            ops = sp.op_table() if programs else None
            if ops is not None:
                b = sp.ProgramBuilder(ops, notes)
        if b is not None:
            # Cycles' world invisible to the camera: camera rays see black, every other ray the world.
            is_camera = b.emit("light_path", [], [])[0]
            emission = sp.mul(b, emission, sp.one_minus(b, is_camera))
        else:
            notes.append("Ray Visibility 'Camera' off not rendered: the camera sees the world")
    if b is not None and b.attributes and is_reg(emission):
        notes.append("Attribute and UV Map nodes read nothing in the world (0)")
    if is_const(emission):
        spec.radiance = tuple(max(c, 0.0) for c in _finite_color(emission))
    else:
        spec.program, spec.emission = b, emission
        spec.radiance = BLACK
    spec.notes = list(dict.fromkeys(notes))
    return spec


def _shader(b, socket, stack, notes):
    """The emission (a constant colour or a 'v' register) of the world shader plugged into `socket`."""
    out, _, stack = materials.follow(socket, stack)
    if out is None:
        return BLACK
    node = out.node
    kind = node.bl_idname
    if kind in ("ShaderNodeBackground", "ShaderNodeEmission"):
        inputs = materials._Inputs(node, stack, notes)
        return sp.mul(b, inputs.color("Color"), inputs.number("Strength", 1.0))
    if kind == "ShaderNodeMixShader":
        first = _shader(b, node.inputs[1], stack, notes)
        second = _shader(b, node.inputs[2], stack, notes)
        fac = sp.clamp01(b, materials._Inputs(node, stack, notes).number("Fac", 0.5))
        return sp.add(b, sp.mul(b, first, sp.one_minus(b, fac)), sp.mul(b, second, fac))
    if kind == "ShaderNodeAddShader":
        return sp.add(b, _shader(b, node.inputs[0], stack, notes), _shader(b, node.inputs[1], stack, notes))
    if kind == "ShaderNodeHoldout":
        notes.append("Holdout shader in the world rendered black")
        return BLACK
    notes.append(f"shader '{node.bl_label}' not supported in the world: rendered black")
    return BLACK


def _finite_color(value):
    if not isinstance(value, tuple):
        value = (float(value),) * 3
    return tuple(float(c) if math.isfinite(c) else 0.0 for c in value[:3])


def _cycles_settings(world):
    return getattr(world, "cycles", None)


def _map_resolution(world, notes):
    """The importance map width Cycles' world settings ask for (0: automatic); notes sampling method None."""
    settings = _cycles_settings(world)
    if settings is None:
        return 0
    method = getattr(settings, "sampling_method", None)
    if method is None:                             # older Cycles: Multiple Importance Sampling on/off
        method = 'AUTOMATIC' if getattr(settings, "sample_as_light", True) else 'NONE'
    if method == 'NONE':
        notes.append("sampling method None rendered with importance sampling (the same light, other noise)")
        return 0
    if method == 'MANUAL':
        try:
            return max(int(getattr(settings, "sample_map_resolution", 0)), 0)
        except (TypeError, ValueError):
            return 0
    return 0


def _visibility(world, notes):
    """Whether camera rays see the world (Cycles' world Ray Visibility); notes the visibilities not rendered."""
    visibility = getattr(world, "cycles_visibility", None)
    if visibility is None:
        return True
    off = [name for name in ("diffuse", "glossy", "transmission", "scatter")
           if not getattr(visibility, name, True)]
    if off:
        notes.append("Ray Visibility off for " + ", ".join(off) + " rays not rendered (the world lights them)")
    return bool(getattr(visibility, "camera", True))


def background_radiance(world, notes):
    """Radiance (r, g, b) of the world's constant background; the world's notes go to `notes` (the world panel).
    A programmed world has a black constant (its light is the program's)."""
    spec = convert_world(world)
    notes.extend(spec.report_lines())
    return spec.radiance
