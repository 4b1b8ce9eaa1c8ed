"""The world: a constant background radiance, as Cycles' Background shader gives it (colour x strength).

Environment textures and sky models are not supported yet: their unconnected colour is used and a note says so.
"""

from .. import compat
from . import materials


def background_radiance(world, notes):
    """Radiance (r, g, b) seen by rays that leave the scene. `notes` collects approximation warnings."""
    if world is None:
        return (0.0, 0.0, 0.0)          # no world: Cycles renders a black background
    if not compat.uses_nodes(world):
        return tuple(float(c) for c in world.color)

    output = world.node_tree.get_output_node('CYCLES')
    if output is None or not output.inputs["Surface"].is_linked:
        return (0.0, 0.0, 0.0)
    node = materials.source_node(output.inputs["Surface"])
    if node is None:
        return (0.0, 0.0, 0.0)

    # Background and Emission shaders both give radiance = Color x Strength in Cycles' world.
    if node.bl_idname in ("ShaderNodeBackground", "ShaderNodeEmission"):
        found = []
        color = materials.color_input(node, "Color", found)
        strength = materials.float_input(node, "Strength", found)
        notes.extend(f"World '{world.name}': {n}" for n in found)
        return tuple(max(c * strength, 0.0) for c in color)

    notes.append(f"World '{world.name}': unsupported shader '{node.bl_label}', world colour used instead")
    return tuple(float(c) for c in world.color)
