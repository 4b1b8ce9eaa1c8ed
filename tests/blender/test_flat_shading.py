"""Flat-shaded faces that are not planar, against Cycles (addon/photonsplat/compat.py: triangles_shaded_flat).

Blender's split normal of a flat face is the polygon's normal; Cycles shades a flat face with its triangle's own
normal (3.x: a mesh without Auto Smooth or custom normals; 4.1+: a mesh whose normals domain is 'FACE'). Suzanne's
quads are not planar, so the two differ by a few degrees on most of its triangles. Exported as split normals,
Suzanne made flat came out 0.992 of Cycles' direct light here (3.4 and 4.5 alike), with 17 % of its 4 x 4 blocks
more than 5 % off (5th to 95th percentile 0.87-1.04); with its triangles' own normals, 1.000, and none (0.98-1.01).
Per pixel at 64 x 64: 45 % more than 5 % off before, 16 % after, where the smooth Suzanne has 13 % (its edges and
Cycles' noise)."""

import bpy
import numpy as np

from blender_helpers import block_means, direct_light_pair
from test_photon_shading_normals import lone_smooth_suzanne

SIZE = 48


def test_a_flat_shaded_suzanne_is_lit_by_its_triangles_normals_as_in_cycles(empty_scene, tmp_path, core):
    scene = lone_smooth_suzanne(empty_scene)
    suzanne = bpy.data.objects["Suzanne"]
    for obj in scene.objects:
        obj.select_set(obj is suzanne)
    bpy.context.view_layer.objects.active = suzanne
    bpy.ops.object.shade_flat()
    assert not any(polygon.use_smooth for polygon in suzanne.data.polygons)
    cycles, ours = direct_light_pair(scene, SIZE, tmp_path, core)
    lit = block_means(cycles) > 0.05 * block_means(cycles).max()
    ratios = block_means(ours)[lit] / block_means(cycles)[lit]
    print(f"\nflat-shaded Suzanne's direct light, Photon Splat / Cycles: {ours.sum() / cycles.sum():.4f}; "
          f"4 x 4 blocks {np.percentile(ratios, 5):.3f}-{np.percentile(ratios, 95):.3f} (5th-95th percentile), "
          f"{np.mean(np.abs(ratios - 1.0) > 0.05):.3f} of them more than 5 % off")
    assert abs(ours.sum() / cycles.sum() - 1.0) < 0.01
    assert np.mean(np.abs(ratios - 1.0) > 0.05) < 0.05


def test_triangle_normals_are_taken_in_chunks(monkeypatch):
    """_take_triangle_normals in steps of a few triangles gives every flat triangle its own unit normal, leaves the
    others and a degenerate one as they were."""
    from photonsplat.export import mesh as export_mesh
    rng = np.random.default_rng(1)
    vertices = rng.normal(size=(50, 3)).astype(np.float32)
    triangles = np.array([rng.choice(50, 3, replace=False) for _ in range(40)], dtype=np.int32)
    triangles[6] = (5, 5, 9)                       # no area
    flat = np.ones(40, dtype=bool)
    flat[::4] = False
    normals = np.full((40, 3, 3), 7.0, dtype=np.float32)
    monkeypatch.setattr(export_mesh, "FLAT_NORMALS_CHUNK", 7)
    export_mesh._take_triangle_normals(normals, vertices, triangles, flat)
    corners = vertices[triangles].astype(np.float64)
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    for t in range(40):
        if flat[t] and t != 6:
            expected = cross[t] / np.linalg.norm(cross[t])
            assert np.allclose(normals[t], expected[None, :], atol=1e-6), t
        else:
            assert np.all(normals[t] == 7.0), t
