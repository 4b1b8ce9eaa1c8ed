"""Blender lights -> the core's lights, converting Cycles 3.4's units into radiometric ones.

The core takes physical quantities; Blender's light settings follow Cycles 3.4's conventions. With colour c and
Power/Strength P:
  point  isotropic intensity I = c P / (4 pi)  [W/sr]; radius = Radius (soft shadows)
  spot   the same intensity on the axis, with Cycles 3.4's falloff I(θ) = I cos θ smoothstep(...) inside the cone
         of full angle Spot Size, softened by Blend (the core's spot light); radius as for point lights
  sun    irradiance E = c P  [W/m^2] on a surface facing the sun; travels along the object's local -Z;
         angle = the sun's full angular diameter
  area   one-sided rectangle emitting radiance L = c P / (4 A)  [W/(sr m^2)] along local -Z, where A is the
         area including the object's scale (so the flux is pi/4 P, as in Cycles 3.4, not P).
         Disk and ellipse lights are native ellipses: A = π/4 size_x size_y (scale included), as in Cycles.
"""

import math

from mathutils import Matrix, Vector

from . import materials


def export_light(core_scene, name, light, matrix, notes):
    """Add `light` (bpy.types.Light, evaluated) placed by `matrix` (world matrix, a copy) to `core_scene`.
    Returns False when the light was skipped."""
    color = _emitted_color(light, notes)
    power = float(light.energy)
    rgb = tuple(c * power for c in color)

    if light.type == 'SPOT':
        # Cycles 3.4 ignores the object's scale for the cone (it reads only the direction).
        direction = (matrix.to_3x3() @ Vector((0.0, 0.0, -1.0))).normalized()
        core_scene.add_spot_light(name=name, position=tuple(matrix.translation), direction=tuple(direction),
                                  intensity=tuple(c / (4.0 * math.pi) for c in rgb),
                                  spot_size=float(light.spot_size), spot_blend=float(light.spot_blend),
                                  radius=float(light.shadow_soft_size))
        return True
    if light.type == 'POINT':
        core_scene.add_point_light(name=name, position=tuple(matrix.translation),
                                   intensity=tuple(c / (4.0 * math.pi) for c in rgb),
                                   radius=float(light.shadow_soft_size))
        return True
    if light.type == 'SUN':
        direction = (matrix.to_3x3() @ Vector((0.0, 0.0, -1.0))).normalized()
        core_scene.add_sun_light(name=name, direction=tuple(direction), irradiance=rgb, angle=float(light.angle))
        return True
    if light.type == 'AREA':
        return _export_area_light(core_scene, name, light, matrix, rgb, notes)
    notes.append(f"Light '{name}': type {light.type} not supported, skipped")
    return False


def _export_area_light(core_scene, name, light, matrix, rgb, notes):
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
                              axis_v=tuple(axis_v), radiance=tuple(c / (4.0 * area) for c in rgb),
                              shape="ellipse" if round_shape else "rectangle")
    return True


def _emitted_color(light, notes):
    """Light colour times the Emission node of its node tree, if it uses one (Cycles multiplies them)."""
    color = tuple(float(c) for c in light.color)
    if not light.use_nodes or light.node_tree is None:
        return color
    output = light.node_tree.get_output_node('CYCLES')
    node = materials.source_node(output.inputs["Surface"]) if output is not None else None
    if node is None:
        return (0.0, 0.0, 0.0)           # Cycles: a light whose node tree outputs nothing emits nothing
    if node.bl_idname != "ShaderNodeEmission":
        notes.append(f"Light '{light.name}': node '{node.bl_label}' in its node tree ignored")
        return color
    found = []
    tint = materials.color_input(node, "Color", found)
    strength = materials.float_input(node, "Strength", found)
    notes.extend(f"Light '{light.name}': {n}" for n in found)
    return tuple(c * t * strength for c, t in zip(color, tint))


def conversion_notes(light):
    """What the export approximates or skips of `light` (bpy.types.Light) placed without scale, one line each:
    what the light panel shows."""
    notes = []
    export_light(_NoScene(), light.name, light, Matrix.Identity(4), notes)
    return notes


class _NoScene:
    """Takes the add_*_light calls of export_light and keeps nothing."""

    def __getattr__(self, method):
        return lambda **kwargs: None
