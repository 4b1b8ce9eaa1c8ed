"""Evaluated Blender geometry -> triangle arrays for the core.

Everything goes through numpy and foreach_get (no Python loop over vertices or faces): a million triangles
take a fraction of a second. Meshes are exported in object space, once per distinct evaluated mesh; every
object or instance showing it becomes a core instance with its own world matrix (export/sync.py).
"""

from dataclasses import dataclass, field

import numpy as np

from .. import compat
from .shader_program import POINTINESS, RANDOM_PER_ISLAND, TANGENT_PREFIX

# Geometry we cannot render yet: skipped with a note (other non-mesh types, e.g. empties, have no surface).
UNSUPPORTED_TYPES = {'CURVES', 'POINTCLOUD', 'VOLUME', 'GPENCIL'}

# Object types whose evaluated geometry is a surface mesh. The depsgraph hands their mesh over as an extra
# instance of type MESH next to the object itself, except when particles instance them (see needs_to_mesh).
CONVERTIBLE_TYPES = {'CURVE', 'SURFACE', 'FONT', 'META'}


@dataclass
class TriangleMesh:
    vertices: np.ndarray       # float32 (N, 3), object space
    triangles: np.ndarray      # int32 (M, 3), indices into vertices
    # float32 shading normals (split normals): (N, 3) per vertex where every corner's normal is its vertex's
    # (all faces smooth, no auto smooth or custom normals), else (M, 3, 3) per triangle corner.
    normals: np.ndarray
    slots: np.ndarray = None   # int32 (M,), material slot index of each triangle; None: not read (all slot 0)
    uvs: np.ndarray = None     # float32 (M, 3, 2), the render UV map at each triangle corner; None without one
    uvs_read: bool = False     # whether the UV map was looked for (MeshNeeds.uvs)
    # What node programs read (only when some material's program does, MeshNeeds): attribute name -> float32
    # (N, k) per vertex or (M, 3, k) per triangle corner, k 1..4; "" is the default colour attribute.
    attributes: dict = field(default_factory=dict)
    texspace: tuple = None     # ((location), (size)): Generated coordinates' texture space
    missing: tuple = ()        # attribute names looked for that the mesh does not have

    def provides(self, needs):
        """Whether these arrays hold what `needs` asks for (attributes a mesh lacks are not looked for again)."""
        looked_up = set(self.attributes) | set(self.missing)
        return (set(needs.attributes) <= looked_up and (self.texspace is not None or not needs.texspace)
                and (self.uvs_read or not needs.uvs) and (self.slots is not None or not needs.slots))


@dataclass(frozen=True)
class MeshNeeds:
    """What the materials of a mesh's objects read from it besides triangles and normals. Only what is asked
    for is read from Blender and stored in the core: a 4-million-triangle scene of plain materials needs
    neither its UV map (24 bytes a triangle) nor its slots."""
    attributes: tuple = ()     # attribute names, sorted
    texspace: bool = False
    uvs: bool = False          # the render UV map (image textures, node programs)
    slots: bool = False        # the triangles' material slots (the slots hold different materials)

    def __or__(self, other):
        return MeshNeeds(tuple(sorted(set(self.attributes) | set(other.attributes))),
                         self.texspace or other.texspace, self.uvs or other.uvs, self.slots or other.slots)


def needs_to_mesh(instance):
    """Whether a curve, text, surface or metaball instance must be converted with to_mesh().

    In Blender 3.4 the depsgraph lists the evaluated mesh of such an object as an extra MESH instance next to
    the object itself (also inside collection instances), so converting the object too would render it twice.
    Particle systems are the exception: they list only the object, never its mesh."""
    return instance.object.type in CONVERTIBLE_TYPES and instance.particle_system is not None


def triangle_mesh(ob_eval, needs=MeshNeeds()):
    """Triangles of an evaluated object (modifiers applied), or None if it has no faces; with the attributes and
    texture space `needs` asks for."""
    if ob_eval.type == 'MESH':
        # The evaluated object's data already is the final mesh: no copy, no to_mesh() needed.
        return _from_mesh(ob_eval.data, needs)
    try:
        mesh = ob_eval.to_mesh()
    except RuntimeError:
        return None
    try:
        return None if mesh is None else _from_mesh(mesh, needs)
    finally:
        ob_eval.to_mesh_clear()


FLAT_NORMALS_CHUNK = 1 << 16  # triangles a step of _take_triangle_normals takes (5 MB of float64 corners)


def _take_triangle_normals(normals, vertices, triangles, flat):
    """Give the corners of the `flat` triangles their triangle's own normal (unit, by the corners' winding), as
    Cycles shades a flat face; the core then takes them as flat-shaded (photon_shading_normals.h). A degenerate
    triangle keeps its split normals."""
    rows = np.flatnonzero(flat)
    for start in range(0, len(rows), FLAT_NORMALS_CHUNK):  # in chunks: a few MB at a time for any mesh
        chunk = rows[start:start + FLAT_NORMALS_CHUNK]
        corners = vertices[triangles[chunk]].astype(np.float64)
        cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        length = np.linalg.norm(cross, axis=1)
        usable = length > 0.0
        normals[chunk[usable]] = (cross[usable] / length[usable, None])[:, None, :].astype(np.float32)


def _from_mesh(mesh, needs=MeshNeeds()):
    mesh.calc_loop_triangles()
    count = len(mesh.loop_triangles)
    if count == 0:
        return None

    vertices = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", vertices)
    triangles = np.empty(count * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", triangles)
    slots = None
    if needs.slots:
        slots = np.empty(count, dtype=np.int32)
        mesh.loop_triangles.foreach_get("material_index", slots)

    # Split normals honour flat/smooth shading, auto smooth and custom normals, exactly what Cycles shades
    # with. Where they are the vertex normals, those are read instead (the same floats, a quarter as many).
    if compat.corner_normals_are_vertex_normals(mesh):
        normals = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
        mesh.vertices.foreach_get("normal", normals)
        normals = normals.reshape(-1, 3)
    else:
        compat.prepare_corner_normals(mesh)    # Blender 3.4 computes them only when asked
        normals = np.empty(count * 9, dtype=np.float32)
        mesh.loop_triangles.foreach_get("split_normals", normals)
        normals = normals.reshape(-1, 3, 3)
        flat = compat.triangles_shaded_flat(mesh)
        if flat is not None:
            _take_triangle_normals(normals, vertices.reshape(-1, 3), triangles.reshape(-1, 3), flat)

    result = TriangleMesh(vertices=vertices.reshape(-1, 3), triangles=triangles.reshape(-1, 3), normals=normals,
                          slots=slots, uvs=_corner_uvs(mesh, count) if needs.uvs else None, uvs_read=needs.uvs)
    missing = []
    for name in needs.attributes:
        array = attribute_array(mesh, name, count)
        if array is None:
            missing.append(name)       # Cycles reads 0 for an attribute a mesh does not have; so does the core
        else:
            result.attributes[name] = array
    result.missing = tuple(missing)
    if needs.texspace:
        result.texspace = (tuple(float(c) for c in mesh.texspace_location),
                           tuple(float(c) for c in mesh.texspace_size))
    return result


# Generic attribute data types: (foreach_get property, components, numpy type).
_ATTRIBUTE_TYPES = {"FLOAT": ("value", 1, np.float32), "INT": ("value", 1, np.int32),
                    "INT8": ("value", 1, np.int32), "BOOLEAN": ("value", 1, bool),
                    "FLOAT2": ("vector", 2, np.float32), "FLOAT_VECTOR": ("vector", 3, np.float32),
                    "FLOAT_COLOR": ("color", 4, np.float32), "BYTE_COLOR": ("color", 4, np.float32)}


def default_color_name(mesh):
    """The colour attribute Cycles' Color Attribute node reads when it names none (the render colour)."""
    attributes = getattr(mesh, "color_attributes", None)
    if attributes is None or len(attributes) == 0:
        return None
    name = getattr(attributes, "default_color_name", "") or ""
    if not name:
        index = getattr(attributes, "render_color_index", -1)
        if 0 <= index < len(attributes):
            name = attributes[index].name
    if not name and attributes.active_color is not None:
        name = attributes.active_color.name
    return name or None


def attribute_array(mesh, name, count):
    """Attribute `name` of `mesh` as float32 (vertices, k) or (triangles, 3, k); None if the mesh has none
    ("" is the default colour attribute). UV maps by name are (triangles, 3, 2)."""
    if name == POINTINESS:
        return pointiness(_vertex_array(mesh.vertices, "co"), _vertex_array(mesh.vertices, "normal"),
                          _edges(mesh))[:, None]
    if name == RANDOM_PER_ISLAND:
        return _random_per_island(mesh, count)
    if name.startswith(TANGENT_PREFIX):
        return _tangents(mesh, name[len(TANGENT_PREFIX):], count)
    if name == "":
        name = default_color_name(mesh)
        if name is None:
            return None
    layer = mesh.uv_layers.get(name)
    if layer is not None:
        per_loop = np.empty(len(mesh.loops) * 2, dtype=np.float32)
        layer.data.foreach_get("uv", per_loop)
        return _per_corner(mesh, per_loop.reshape(-1, 2), count)
    attribute = mesh.attributes.get(name)
    if attribute is None or attribute.data_type not in _ATTRIBUTE_TYPES:
        return None
    prop, k, dtype = _ATTRIBUTE_TYPES[attribute.data_type]
    values = np.empty(len(attribute.data) * k, dtype=dtype)
    attribute.data.foreach_get(prop, values)
    values = values.astype(np.float32).reshape(-1, k)
    if attribute.domain == 'POINT':
        return values
    if attribute.domain == 'CORNER':
        return _per_corner(mesh, values, count)
    if attribute.domain == 'FACE':
        polygons = np.empty(count, dtype=np.int32)
        mesh.loop_triangles.foreach_get("polygon_index", polygons)
        return np.repeat(values[polygons][:, None, :], 3, axis=1)
    return None                        # edge attributes: nothing a surface point reads


def _tangents(mesh, uv_name, count):
    """(M, 3, 4) per triangle corner: the MikkTSpace tangent of UV map `uv_name` ("" the render one) and its
    bitangent sign, as Blender computes them for Cycles (Mesh.calc_tangents); None without that UV map or where
    Blender cannot compute them (faces of more than four corners: the core then uses each triangle's UV tangent)."""
    layers = mesh.uv_layers
    if not uv_name:
        layer = next((uv for uv in layers if uv.active_render), None) or layers.active
        uv_name = layer.name if layer is not None else ""
    if not uv_name or layers.get(uv_name) is None or len(mesh.loops) == 0:
        return None
    try:
        mesh.calc_tangents(uvmap=uv_name)
    except RuntimeError:
        return None
    per_loop = np.empty((len(mesh.loops), 4), dtype=np.float32)
    tangents = np.empty(len(mesh.loops) * 3, dtype=np.float32)
    signs = np.empty(len(mesh.loops), dtype=np.float32)
    mesh.loops.foreach_get("tangent", tangents)
    mesh.loops.foreach_get("bitangent_sign", signs)
    mesh.free_tangents()
    per_loop[:, :3] = tangents.reshape(-1, 3)
    per_loop[:, 3] = signs
    return _per_corner(mesh, per_loop, count)


def _per_corner(mesh, per_loop, count):
    loops = np.empty(count * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("loops", loops)
    return np.ascontiguousarray(per_loop[loops].reshape(count, 3, -1))


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


def scene_material_ids(slots, slot_material_ids, count):
    """Per-triangle core material ids (`count` triangles) from per-triangle slot indices and the core id of each
    slot; slots None (not read: every slot holds the same material) gives the first slot's everywhere.

    Blender clamps a material index beyond the last slot to the last slot; an object without slots uses
    the default material (the caller passes a single-entry list then).
    """
    table = np.asarray(slot_material_ids, dtype=np.int32)
    if slots is None:
        if len(set(table.tolist())) > 1:
            raise ValueError("the triangles' slots were not read, but the slots hold different materials")
        return np.full(count, table[0], dtype=np.int32)
    return table[np.clip(slots, 0, len(table) - 1)]


# --- the Geometry node's Pointiness and Random Per Island, as Cycles 3.4's Blender sync computes them -------------
# (intern/cycles/blender/mesh.cpp: attr_create_pointiness, attr_create_random_per_island), on the evaluated mesh's
# own vertices and edges.

_FLT_EPSILON = np.float32(np.finfo(np.float32).eps)


def _vertex_array(vertices, prop):
    values = np.empty(len(vertices) * 3, dtype=np.float32)
    vertices.foreach_get(prop, values)
    return values.reshape(-1, 3)


def _edges(mesh):
    edges = np.empty(len(mesh.edges) * 2, dtype=np.int32)
    mesh.edges.foreach_get("vertices", edges)
    return edges.reshape(-1, 2)


def _random_per_island(mesh, count):
    """Per triangle corner (M, 3, 1): the island value of each triangle's first vertex (the core's
    random_per_island: a disjoint set joined along Blender's edges in order, whose roots decide the hash)."""
    from .. import _core
    per_vertex = np.asarray(_core.random_per_island(len(mesh.vertices), _edges(mesh)), dtype=np.float32)
    triangles = np.empty(count * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", triangles)
    first = per_vertex[triangles.reshape(count, 3)[:, 0]]
    return np.ascontiguousarray(np.repeat(first[:, None, None], 3, axis=1))


def merged_vertices(positions):
    """Cycles' welding of coincident vertices before pointiness: each vertex's representative. Cycles sorts the
    vertices by the sum of their coordinates (equal positions by decreasing index) and points each at the first
    later one in that order whose sum is within 3 FLT_EPSILON and whose squared distance is below FLT_EPSILON,
    then follows the chains to their end. Scanning the sum order is quadratic where many vertices share a sum (a
    flat grid's diagonals), so the candidates come from a grid of cells 2 sqrt(FLT_EPSILON) wide instead: a
    vertex closer than sqrt(FLT_EPSILON) lies in its own cell or in the neighbour on the near side along each
    axis (8 cells); among the candidates that pass Cycles' two tests the first later one in the order is taken."""
    n = len(positions)
    orig = np.arange(n)
    if n < 2:
        return orig
    positions = np.asarray(positions, dtype=np.float32)
    sums = (positions[:, 0] + positions[:, 1]) + positions[:, 2]          # float32, Cycles' order of additions
    order = np.lexsort((-np.arange(n), sums))
    rank = np.empty(n, dtype=np.int64)
    rank[order] = np.arange(n)
    best = np.full(n, n, dtype=np.int64)                                  # the matching vertex of least rank
    # Cycles' own scan for a few steps settles most vertices (a sum shared by no close neighbour)...
    sorted_sums, sorted_positions = sums[order], positions[order]
    pending = np.arange(n - 1)
    for k in range(1, 9):
        pending = pending[pending + k < n]
        pending = pending[sorted_sums[pending + k] - sorted_sums[pending] <= 3 * _FLT_EPSILON]
        d = sorted_positions[pending + k] - sorted_positions[pending]
        found = np.einsum("ij,ij->i", d, d) < _FLT_EPSILON
        best[order[pending[found]]] = order[pending[found] + k]
        pending = pending[~found]
        if len(pending) == 0:
            break
    # ... the rest (still within the window of a later one) look among their cells' vertices.
    todo = np.zeros(n, dtype=bool)
    todo[order[pending]] = len(pending) > 0 and k == 8
    scaled = positions.astype(np.float64) / (2.0 * np.sqrt(np.float64(_FLT_EPSILON)))
    cell = np.floor(scaled).astype(np.int64)
    near_side = np.where(scaled - cell < 0.5, -1, 1)

    def key(c):
        return (c[:, 0] * 73856093) ^ (c[:, 1] * 19349663) ^ (c[:, 2] * 83492791)
    keys = key(cell)
    by_key = np.argsort(keys, kind="stable")
    sorted_keys = keys[by_key]
    rows = np.nonzero(todo)[0]
    for corner in range(8 if len(rows) else 0):
        offset = np.stack([near_side[rows, a] * ((corner >> a) & 1) for a in range(3)], axis=1)
        wanted = key(cell[rows] + offset)
        lo = np.searchsorted(sorted_keys, wanted, side="left")
        hi = np.searchsorted(sorted_keys, wanted, side="right")
        counts = hi - lo
        i = np.repeat(rows, counts)
        if len(i) == 0:
            continue
        within = np.arange(len(i)) - np.repeat(np.cumsum(counts) - counts, counts)
        j = by_key[np.repeat(lo, counts) + within]
        d = positions[j] - positions[i]
        ok = ((rank[j] > rank[i]) & (sums[j] - sums[i] <= 3 * _FLT_EPSILON)
              & (np.einsum("ij,ij->i", d, d) < _FLT_EPSILON))
        i, j = i[ok], j[ok]
        if len(i):
            current = np.full(n, np.iinfo(np.int64).max)        # (the scan's finds are never beaten here)
            np.minimum.at(current, i, rank[j])
            better = current < np.where(best < n, rank[np.minimum(best, n - 1)], np.iinfo(np.int64).max)
            by_rank = np.empty(n, dtype=np.int64)
            by_rank[rank] = np.arange(n)
            best[better] = by_rank[current[better]]
    has = best < n
    orig[has] = best[has]
    while True:                                                           # follow chains (pointer jumping)
        nxt = orig[orig]
        if np.array_equal(nxt, orig):
            return orig
        orig = nxt


def pointiness(positions, normals, edges):
    """Cycles' Pointiness per vertex (float32 (N,)): the angle between the (welded) vertex normal and the mean
    direction of its edges over pi, then averaged with its edge neighbours'."""
    positions = np.asarray(positions, dtype=np.float32).reshape(-1, 3)
    normals = np.asarray(normals, dtype=np.float32).reshape(-1, 3)
    n = len(positions)
    if n == 0:
        return np.zeros(0, dtype=np.float32)
    orig = merged_vertices(positions)
    # Welded normals: the sum over the duplicates, normalised.
    summed = np.stack([np.bincount(orig, weights=normals[:, a], minlength=n) for a in range(3)], axis=1)
    length = np.linalg.norm(summed, axis=1, keepdims=True)
    welded = np.divide(summed, length, out=np.zeros_like(summed), where=length > 0)
    # Each edge between welded vertices once (either direction).
    e = orig[np.asarray(edges, dtype=np.int64).reshape(-1, 2)]
    if len(e):
        key = np.minimum(e[:, 0], e[:, 1]) * n + np.maximum(e[:, 0], e[:, 1])
        _, first = np.unique(key, return_index=True)
        e = e[np.sort(first)]
    v0, v1 = e[:, 0], e[:, 1]
    d = (positions[v1] - positions[v0]).astype(np.float64)
    length = np.linalg.norm(d, axis=1, keepdims=True)
    d = np.divide(d, length, out=np.zeros_like(d), where=length > 0)
    accum = np.stack([np.bincount(v0, weights=d[:, a], minlength=n) - np.bincount(v1, weights=d[:, a], minlength=n)
                      for a in range(3)], axis=1)
    counter = np.bincount(v0, minlength=n) + np.bincount(v1, minlength=n)
    raw = np.zeros(n, dtype=np.float64)
    keep = (orig == np.arange(n)) & (counter > 0)
    mean = accum[keep] / counter[keep][:, None]
    raw[keep] = np.arccos(np.clip(np.einsum("ij,ij->i", welded[keep], mean), -1.0, 1.0)) / np.pi
    # Blur over the one-ring: each vertex with its neighbours, equally weighted.
    blurred = raw + np.bincount(v0, weights=raw[v1], minlength=n) + np.bincount(v1, weights=raw[v0], minlength=n)
    blurred /= counter + 1
    return blurred[orig].astype(np.float32)
