"""Evaluated Blender geometry -> triangle arrays for the core.

Everything goes through numpy and foreach_get (no Python loop over vertices or faces): a million triangles
take a fraction of a second. Meshes are exported in object space; the object's world matrix goes along as
the transform and the core applies it.
"""

from dataclasses import dataclass

import numpy as np

# Geometry we cannot render yet: skipped with a note (other non-mesh types, e.g. empties, have no surface).
UNSUPPORTED_TYPES = {'CURVES', 'POINTCLOUD', 'VOLUME', 'GPENCIL'}


@dataclass
class TriangleMesh:
    vertices: np.ndarray       # float32 (N, 3), object space
    triangles: np.ndarray      # int32 (M, 3), indices into vertices
    normals: np.ndarray        # float32 (M, 3, 3), shading normal of each triangle corner (split normals)
    slots: np.ndarray          # int32 (M,), material slot index of each triangle


def triangle_mesh(ob_eval):
    """Triangles of an evaluated MESH object (modifiers applied), or None if it has no faces.

    Only MESH objects are read. In Blender 3.x the depsgraph hands over the evaluated geometry of curves,
    text, surfaces and metaballs as an extra instance of type MESH, next to the original object; converting
    the original too (with to_mesh) would render that geometry twice.
    """
    # The evaluated object's data already is the final mesh: no copy, no to_mesh() needed.
    return _from_mesh(ob_eval.data)


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
    mesh.calc_normals_split()
    normals = np.empty(count * 9, dtype=np.float32)
    mesh.loop_triangles.foreach_get("split_normals", normals)

    return TriangleMesh(vertices=vertices.reshape(-1, 3), triangles=triangles.reshape(-1, 3),
                        normals=normals.reshape(-1, 3, 3), slots=slots)


def scene_material_ids(slots, slot_material_ids):
    """Per-triangle core material ids from per-triangle slot indices and the core id of each slot.

    Blender clamps a material index beyond the last slot to the last slot; an object without slots uses
    the default material (the caller passes a single-entry list then).
    """
    table = np.asarray(slot_material_ids, dtype=np.int32)
    return table[np.clip(slots, 0, len(table) - 1)]
