"""The Geometry node's Pointiness and Random Per Island: computed by the mesh export as Cycles 3.4's Blender sync
computes them (export/mesh.py; the island roots by the core's disjoint set, photonsplat._core.random_per_island),
exported as mesh attributes only when a program reads them, and read by the geometry op's params 1 and 2.
"""

import math

import bpy
import numpy as np
import pytest

from photonsplat.export import mesh as mesh_export
from photonsplat.export import shader_program
from photonsplat.export.shader_program import POINTINESS, RANDOM_PER_ISLAND
from test_programs import _attribute_recording_core, _export, decode, diffuse_material, op_table  # noqa: F401

UNIT_WIDTH = shader_program.float_bits(1.0)   # the geometry op's bump filter width param, at the point itself

CUBE_CORNER = math.acos(-1.0 / math.sqrt(3.0)) / math.pi      # the three edges' mean against the corner normal


def _lookup3_hash_to_float(k):
    """Cycles' hash_uint_to_float (util/hash.h: lookup3's final mix of one word), written out in Python."""
    m = 0xFFFFFFFF

    def rot(x, r):
        return ((x << r) | (x >> (32 - r))) & m
    a = b = c = (0xDEADBEEF + (1 << 2) + 13) & m
    a = (a + k) & m
    c ^= b; c = (c - rot(b, 14)) & m      # noqa: E702
    a ^= c; a = (a - rot(c, 11)) & m      # noqa: E702
    b ^= a; b = (b - rot(a, 25)) & m      # noqa: E702
    c ^= b; c = (c - rot(b, 16)) & m      # noqa: E702
    a ^= c; a = (a - rot(c, 4)) & m       # noqa: E702
    b ^= a; b = (b - rot(a, 14)) & m      # noqa: E702
    c ^= b; c = (c - rot(b, 24)) & m      # noqa: E702
    return float(np.float32(c) * np.float32(1.0 / 4294967295.0))


def _roots_by_rank(n, edges):
    """Cycles' DisjointSet (union by rank, first argument's root on a tie), one edge at a time."""
    parent, rank = list(range(n)), [0] * n

    def find(x):
        while parent[x] != x:
            x = parent[x]
        return x
    for a, b in edges:
        ra, rb = find(a), find(b)
        if ra == rb:
            continue
        if rank[ra] < rank[rb]:
            ra, rb = rb, ra
        parent[rb] = ra
        if rank[ra] == rank[rb]:
            rank[ra] += 1
    return [find(v) for v in range(n)]


def _count(mesh):
    mesh.calc_loop_triangles()
    return len(mesh.loop_triangles)


def test_pointiness_of_a_cube_corner_and_a_flat_vertex(empty_scene):
    bpy.ops.mesh.primitive_cube_add(size=2.0)
    cube = bpy.context.active_object.data
    values = mesh_export.attribute_array(cube, POINTINESS, _count(cube))
    assert values.shape == (8, 1) and values.dtype == np.float32
    assert values[:, 0] == pytest.approx(CUBE_CORNER, abs=1e-6)          # 0.6959: every vertex a corner
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=5, y_subdivisions=5, size=2.0)
    grid = bpy.context.active_object.data
    assert mesh_export.attribute_array(grid, POINTINESS, _count(grid))[:, 0] == pytest.approx(0.5, abs=1e-6)


def test_pointiness_welds_coincident_vertices():
    """Cycles welds vertices closer than sqrt(FLT_EPSILON) (split faces) before measuring: a cube whose corner 0
    is doubled, the copy owning one of its three edges, measures as the closed cube."""
    corners = np.array([(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float32)
    normals = corners / np.linalg.norm(corners, axis=1, keepdims=True)
    edges = np.array([(i, j) for i in range(8) for j in range(i + 1, 8)
                      if np.abs(corners[i] - corners[j]).sum() == 2], dtype=np.int32)
    edges[0, 0] = 8
    split = mesh_export.pointiness(np.vstack([corners, corners[:1]]), np.vstack([normals, normals[:1]]), edges)
    assert split == pytest.approx(CUBE_CORNER, abs=1e-6)
    assert list(mesh_export.merged_vertices(np.vstack([corners, corners[:1]]))) == [0, 1, 2, 3, 4, 5, 6, 7, 0]


def test_random_per_island_hashes_each_islands_root(empty_scene):
    bpy.ops.mesh.primitive_cube_add(size=1.0)
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=1, location=(3.0, 0.0, 0.0))
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(-3.0, 0.0, 0.0))
    for ob in bpy.context.scene.objects:
        ob.select_set(True)
    bpy.context.view_layer.objects.active = bpy.context.scene.objects[0]
    bpy.ops.object.join()
    mesh = bpy.context.active_object.data
    count = _count(mesh)
    values = mesh_export.attribute_array(mesh, RANDOM_PER_ISLAND, count)
    assert values.shape == (count, 3, 1) and values.dtype == np.float32
    edges = np.empty(len(mesh.edges) * 2, dtype=np.int32)
    mesh.edges.foreach_get("vertices", edges)
    roots = _roots_by_rank(len(mesh.vertices), edges.reshape(-1, 2).tolist())
    triangles = np.empty(count * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", triangles)
    expected = [_lookup3_hash_to_float(roots[v]) for v in triangles[::3]]
    assert values[:, 0, 0] == pytest.approx(expected, abs=0.0)
    assert (values == values[:, :1]).all()                           # one value per triangle
    assert len(set(values[:, 0, 0].tolist())) == 3                   # three islands
    # A known island: vertex 0's root 0 is hash_uint_to_float(0) (Cycles' value for that island).
    assert _lookup3_hash_to_float(0) == pytest.approx(0.5824258327484131, abs=0.0)


def test_only_linked_geometry_outputs_are_exported(empty_scene, op_table):  # noqa: F811
    from test_export import add_camera
    Core = _attribute_recording_core()
    add_camera(empty_scene)
    bpy.ops.mesh.primitive_cube_add(size=2.0)
    cube = bpy.context.active_object
    mat, tree, shader = diffuse_material("Pointy")
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    tree.links.new(geometry.outputs["Pointiness"], shader.inputs["Color"])
    cube.data.materials.append(mat)
    frame = _export(Core)
    (exported,) = frame.scene.meshes
    names = frame.scene.attribute_names
    assert names == [POINTINESS]
    (pointiness,) = exported["attributes"].values()
    assert pointiness.shape == (8, 1) and pointiness[:, 0] == pytest.approx(CUBE_CORNER, abs=1e-6)
    (material,) = frame.scene.materials
    code = decode(material["program"], shader_program.op_table())
    assert [c[1] for c in code if c[0] == "geometry"] == [[0, names.index(POINTINESS), -1, UNIT_WIDTH]]

    tree.links.new(geometry.outputs["Random Per Island"], shader.inputs["Roughness"])
    frame = _export(Core)
    (exported,) = frame.scene.meshes
    names = frame.scene.attribute_names
    assert set(names) == {POINTINESS, RANDOM_PER_ISLAND}
    island = exported["attributes"][names.index(RANDOM_PER_ISLAND)]
    assert island.shape == (12, 3, 1)
    (material,) = frame.scene.materials
    code = decode(material["program"], shader_program.op_table())
    assert [c[1] for c in code if c[0] == "geometry"] == [
        [0, names.index(POINTINESS), names.index(RANDOM_PER_ISLAND), UNIT_WIDTH]]


def test_a_pointiness_program_renders(empty_scene, core):
    """Emission = Pointiness on a cube seen face on: every vertex is a corner, so the face shows 0.696."""
    from test_export import add_camera
    from blender_helpers import enable_nodes, uniform_world
    add_camera(empty_scene, location=(0.0, 0.0, 5.0))
    empty_scene.camera.rotation_euler = (0.0, 0.0, 0.0)
    empty_scene.camera.data.type = 'ORTHO'
    empty_scene.camera.data.ortho_scale = 1.0
    bpy.ops.mesh.primitive_cube_add(size=2.0)
    mat = bpy.data.materials.new("Glow")
    enable_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    emission = tree.nodes.new("ShaderNodeEmission")
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    tree.links.new(geometry.outputs["Pointiness"], emission.inputs["Color"])
    tree.links.new(emission.outputs[0], output.inputs["Surface"])
    bpy.context.active_object.data.materials.append(mat)
    uniform_world(empty_scene, strength=0.0)
    empty_scene.render.resolution_x = empty_scene.render.resolution_y = 8
    from photonsplat import export
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    image, _ = core.render(frame.scene, frame.camera, frame.settings)
    rgb = np.asarray(image)[..., :3]
    assert rgb.mean() == pytest.approx(CUBE_CORNER, rel=1e-3), rgb.mean()


def _merged_by_cycles_scan(positions):
    """Cycles' weld written as its loop: sorted by coordinate sum (equal positions by decreasing index), each vertex
    points at the first later one within 3 FLT_EPSILON of sum and FLT_EPSILON of squared distance."""
    eps = np.float32(np.finfo(np.float32).eps)
    p = np.asarray(positions, dtype=np.float32)
    sums = (p[:, 0] + p[:, 1]) + p[:, 2]
    order = np.lexsort((-np.arange(len(p)), sums)).tolist()
    orig = list(range(len(p)))
    for a, v in enumerate(order):
        for w in order[a + 1:]:
            if sums[w] - sums[v] > 3 * eps:
                break
            d = p[w] - p[v]
            if np.float32(d @ d) < eps:
                orig[v] = w
                break
    for v in range(len(p)):
        while orig[orig[v]] != orig[v]:
            orig[v] = orig[orig[v]]
    return orig


def test_the_weld_is_cycles_scan_where_many_vertices_share_a_sum():
    """A flat grid's diagonals share their coordinate sum, which sends the weld to its cell search: planted exact
    and near duplicates (some welded, some just too far) come out as Cycles' scan finds them."""
    rng = np.random.default_rng(7)
    x, y = np.meshgrid(np.linspace(-1, 1, 12), np.linspace(-1, 1, 12))
    grid = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1).astype(np.float32)
    picked = grid[rng.integers(0, len(grid), size=40)]
    jitter = rng.normal(size=picked.shape).astype(np.float32) * np.repeat(
        np.float32([0.0, 1e-8, 1e-7, 1e-4]), 10)[:, None]
    positions = np.vstack([grid, picked, picked + jitter])[rng.permutation(len(grid) + 80)]
    merged = mesh_export.merged_vertices(positions)
    assert merged.tolist() == _merged_by_cycles_scan(positions)
    assert (merged != np.arange(len(positions))).sum() >= 40
