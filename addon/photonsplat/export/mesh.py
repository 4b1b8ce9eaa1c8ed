"""Evaluated Blender geometry -> triangle arrays for the core.

Everything goes through numpy and foreach_get (no Python loop over vertices or faces): a million triangles
take a fraction of a second. Meshes are exported in object space, once per distinct evaluated mesh; every
object or instance showing it becomes a core instance with its own world matrix (export/sync.py).
"""

from dataclasses import dataclass

import numpy as np

from .. import compat

# Geometry we cannot render yet: skipped with a note (other non-mesh types, e.g. empties, have no surface).
UNSUPPORTED_TYPES = {'CURVES', 'POINTCLOUD', 'VOLUME', 'GPENCIL'}

# Object types whose evaluated geometry is a surface mesh. The depsgraph hands their mesh over as an extra
# instance of type MESH next to the object itself, except when particles instance them (see needs_to_mesh).
CONVERTIBLE_TYPES = {'CURVE', 'SURFACE', 'FONT', 'META'}


@dataclass
class TriangleMesh:
    vertices: np.ndarray       # float32 (N, 3), object space
    triangles: np.ndarray      # int32 (M, 3), indices into vertices
    normals: np.ndarray        # float32 (M, 3, 3), shading normal of each triangle corner (split normals)
    slots: np.ndarray          # int32 (M,), material slot index of each triangle
    uvs: np.ndarray = None     # float32 (M, 3, 2), the render UV map at each triangle corner; None without one


def needs_to_mesh(instance):
    """Whether a curve, text, surface or metaball instance must be converted with to_mesh().

    In Blender 3.4 the depsgraph lists the evaluated mesh of such an object as an extra MESH instance next to
    the object itself (also inside collection instances), so converting the object too would render it twice.
    Particle systems are the exception: they list only the object, never its mesh."""
    return instance.object.type in CONVERTIBLE_TYPES and instance.particle_system is not None


def triangle_mesh(ob_eval):
    """Triangles of an evaluated object (modifiers applied), or None if it has no faces."""
    if ob_eval.type == 'MESH':
        # The evaluated object's data already is the final mesh: no copy, no to_mesh() needed.
        return _from_mesh(ob_eval.data)
    try:
        mesh = ob_eval.to_mesh()
    except RuntimeError:
        return None
    try:
        return None if mesh is None else _from_mesh(mesh)
    finally:
        ob_eval.to_mesh_clear()


def _from_mesh(mesh):
    mesh.calc_loop_triangles()
    count = len(mesh.loop_triangles)
    if count == 0:
        return None

    vertices = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", vertices)
    triangles = np.empty(count * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", triangles)
    slots = np.empty(count, dtype=np.int32)
    mesh.loop_triangles.foreach_get("material_index", slots)

    # Split normals honour flat/smooth shading, auto smooth and custom normals, exactly what Cycles shades
    # with. In Blender 3.4 they must be computed explicitly first.
    compat.prepare_corner_normals(mesh)
    normals = np.empty(count * 9, dtype=np.float32)
    mesh.loop_triangles.foreach_get("split_normals", normals)

    return TriangleMesh(vertices=vertices.reshape(-1, 3), triangles=triangles.reshape(-1, 3),
                        normals=normals.reshape(-1, 3, 3), slots=slots, uvs=_corner_uvs(mesh, count))


def _corner_uvs(mesh, count):
    """The UV map Cycles' Image Texture uses by default (the active render one) at every triangle corner."""
    layers = mesh.uv_layers
    layer = next((uv for uv in layers if uv.active_render), None) or layers.active
    if layer is None or len(mesh.loops) == 0:
        return None
    per_loop = np.empty(len(mesh.loops) * 2, dtype=np.float32)
    layer.data.foreach_get("uv", per_loop)
    loops = np.empty(count * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("loops", loops)
    return per_loop.reshape(-1, 2)[loops].reshape(count, 3, 2)


def scene_material_ids(slots, slot_material_ids):
    """Per-triangle core material ids from per-triangle slot indices and the core id of each slot.

    Blender clamps a material index beyond the last slot to the last slot; an object without slots uses
    the default material (the caller passes a single-entry list then).
    """
    table = np.asarray(slot_material_ids, dtype=np.int32)
    return table[np.clip(slots, 0, len(table) - 1)]
