"""Blender lights -> the core's lights, converting Cycles' units into radiometric ones.

The core takes physical quantities; Blender's light settings follow the conventions of the Cycles of the running
Blender, which compat.py holds (light_color_power, point_intensity, area_radiance...). With colour c and power P
(Cycles 4.x: times 2^Exposure and the Temperature's blackbody colour):
  point  isotropic intensity I = c P / (4 pi)  [W/sr]; radius = Radius (soft shadows): 3.4's disc facing the
         receiver, or in 4.x with Soft Falloff off a true sphere
  spot   the same intensity on the axis, restricted to the cone of full angle Spot Size and softened by Blend:
         3.4's profile I(θ) = I cos θ smoothstep(...), 4.x's I(θ) = I smoothstep(...)
  sun    irradiance E = c P  [W/m^2] on a surface facing the sun; travels along the object's local -Z;
         angle = the sun's full angular diameter
  area   one-sided rectangle emitting radiance along local -Z: L = c P / (4 A) in 3.4 (flux pi/4 P),
         L = c P / (pi A) in 4.x (flux P), where A is the area including the object's scale.
         Disk and ellipse lights are native ellipses: A = π/4 size_x size_y (scale included), as in Cycles.
  switches  Cycles' Multiple Importance (light.cycles.use_multiple_importance_sampling) and Cast Shadow (3.4:
         light.cycles.cast_shadow, 4.x: light.use_shadow) go to the core as multiple_importance and cast_shadow
         (compat.light_switches): off, no ray but the camera's meets the light and its light samples take full
         weight; no shadow rays. Followed in the reference and in Photon Splat (docs/translation.md, "Light
         switches").
  portal an area light with Cycles' Portal on (light.cycles.is_portal) emits nothing: it guides the world's
         sampling through its rectangle (Scene.add_portal: corner and edges, light passing along
         cross(edge_u, edge_v) = the light's local -Z); a disk or ellipse portal is its bounding rectangle.
"""

import math

from mathutils import Matrix, Vector

from .. import compat
from . import materials


def export_light(core_scene, name, light, matrix, notes):
    """Add `light` (bpy.types.Light, evaluated) placed by `matrix` (world matrix, a copy) to `core_scene`.
    Returns False when the light was skipped."""
    if is_portal(light):
        return _export_portal(core_scene, name, light, matrix, notes)
    tint = _node_tint(light, notes)
    rgb = tuple(c * t for c, t in zip(compat.light_color_power(light), tint))
    switches = compat.light_switches(light)

    if light.type == 'SPOT':
        # Cycles 3.4 ignores the object's scale for the cone (it reads only the direction); 4.x squeezes the
        # cone by a non-uniform scale, which the core's round cone cannot follow.
        direction = (matrix.to_3x3() @ Vector((0.0, 0.0, -1.0))).normalized()
        if compat.spot_cone_follows_scale() and _non_uniform(matrix):
            notes.append(f"Light '{name}': non-uniform scale ignored (the spot's cone is rendered round)")
        core_scene.add_spot_light(name=name, position=tuple(matrix.translation), direction=tuple(direction),
                                  intensity=compat.point_intensity(light, rgb),
                                  spot_size=float(light.spot_size), spot_blend=float(light.spot_blend),
                                  radius=float(light.shadow_soft_size), **compat.point_light_shape(light),
                                  **switches)
        return True
    if light.type == 'POINT':
        core_scene.add_point_light(name=name, position=tuple(matrix.translation),
                                   intensity=compat.point_intensity(light, rgb),
                                   radius=float(light.shadow_soft_size), **compat.point_light_shape(light),
                                   **switches)
        return True
    if light.type == 'SUN':
        direction = (matrix.to_3x3() @ Vector((0.0, 0.0, -1.0))).normalized()
        core_scene.add_sun_light(name=name, direction=tuple(direction), irradiance=rgb, angle=float(light.angle),
                                 **switches)
        return True
    if light.type == 'AREA':
        return _export_area_light(core_scene, name, light, matrix, rgb, notes, switches)
    notes.append(f"Light '{name}': type {light.type} not supported, skipped")
    return False


def _export_area_light(core_scene, name, light, matrix, rgb, notes, switches):
    size_x = float(light.size)
    size_y = float(light.size_y) if light.shape in ('RECTANGLE', 'ELLIPSE') else size_x
    # The matrix columns carry the object's rotation and scale: Cycles' light size includes the scale.
    basis = matrix.to_3x3()
    axis_u = basis.col[0] * size_x
    axis_v = basis.col[1] * size_y
    round_shape = light.shape in ('DISK', 'ELLIPSE')
    # Cycles' area uses the edge lengths (not the parallelogram a sheared matrix would give); so do we.
    area = axis_u.length * axis_v.length * (math.pi / 4.0 if round_shape else 1.0)
    if area <= 0.0:
        notes.append(f"Light '{name}': area light of zero size skipped")
        return False
    if light.spread < math.pi - 1e-4:
        notes.append(f"Light '{name}': spread ignored (rendered as 180 degrees)")

    # The core emits towards cross(u, v); Blender's area lights shine along local -Z. Swap the edges if needed
    # (also keeps mirrored objects, with a negative scale, shining the right way).
    facing = -basis.col[2]
    if axis_u.cross(axis_v).dot(facing) < 0.0:
        axis_u, axis_v = axis_v, axis_u
    core_scene.add_area_light(name=name, center=tuple(matrix.translation), axis_u=tuple(axis_u),
                              axis_v=tuple(axis_v), radiance=compat.area_radiance(light, rgb, area),
                              shape="ellipse" if round_shape else "rectangle", **switches)
    return True


def is_portal(light):
    """Whether `light` is a Cycles portal (an area light that emits nothing; read defensively: the property is
    Cycles' own, absent when the Cycles add-on is not loaded)."""
    settings = getattr(light, "cycles", None)
    return light.type == 'AREA' and bool(getattr(settings, "is_portal", False))


def _export_portal(core_scene, name, light, matrix, notes):
    size_x = float(light.size)
    size_y = float(light.size_y) if light.shape in ('RECTANGLE', 'ELLIPSE') else size_x
    basis = matrix.to_3x3()
    # Light passes along cross(edge_u, edge_v): X x -Y = -Z, the area light's own emission direction.
    edge_u = basis.col[0] * size_x
    edge_v = basis.col[1] * -size_y
    if edge_u.cross(edge_v).length <= 0.0:
        notes.append(f"Light '{name}': portal of zero size skipped")
        return False
    facing = -basis.col[2]
    if edge_u.cross(edge_v).dot(facing) < 0.0:      # a mirrored object (negative scale): keep -Z
        edge_u, edge_v = -edge_v, -edge_u
    if light.shape in ('DISK', 'ELLIPSE'):
        notes.append(f"Light '{name}': {light.shape.lower()} portal rendered as its bounding rectangle")
    center = matrix.translation
    corner = center - edge_u * 0.5 - edge_v * 0.5
    core_scene.add_portal(name, tuple(corner), tuple(edge_u), tuple(edge_v))
    return True


def _non_uniform(matrix):
    scale = matrix.to_scale()
    return max(abs(scale.x), abs(scale.y)) > 1.0001 * min(abs(scale.x), abs(scale.y))


def _node_tint(light, notes):
    """The colour × strength of the Emission node of the light's node tree, if it uses one (Cycles multiplies
    the light's own colour and power by it); white without one."""
    white = (1.0, 1.0, 1.0)
    if not compat.uses_nodes(light):
        return white
    output = light.node_tree.get_output_node('CYCLES')
    node = materials.source_node(output.inputs["Surface"]) if output is not None else None
    if node is None:
        return (0.0, 0.0, 0.0)           # Cycles: a light whose node tree outputs nothing emits nothing
    if node.bl_idname != "ShaderNodeEmission":
        notes.append(f"Light '{light.name}': node '{node.bl_label}' in its node tree ignored")
        return white
    found = []
    tint = materials.color_input(node, "Color", found)
    strength = materials.float_input(node, "Strength", found)
    notes.extend(f"Light '{light.name}': {n}" for n in found)
    return tuple(t * strength for t in tint)


def conversion_notes(light):
    """What the export approximates or skips of `light` (bpy.types.Light) placed without scale, one line each:
    what the light panel shows."""
    notes = []
    export_light(_NoScene(), light.name, light, Matrix.Identity(4), notes)
    return notes


class _NoScene:
    """Takes the add_*_light calls of export_light and keeps nothing."""

    def __getattr__(self, method):
        return lambda *args, **kwargs: None
