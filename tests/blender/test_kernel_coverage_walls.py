"""The boundary correction where a wall stands on a floor (native/include/photonsplat/kernel_coverage.h).

The floor of tests/blender/test_photon_shading_normals.py's scene without its bumps: a white wall standing on a
diffuse floor, lit by a spot aimed at it, so that the floor at its foot is lit by the wall's bounce. The wall pokes
through the floor and the floor goes on behind the wall, as modellers' walls and floors often do. The kernel's
coverage counted the floor behind the wall and the wall below the floor, the samples' own planes going on where no
light of their side lands: against Cycles 3.4 (2048 samples), the pixel row along the wall's foot came out 0.882
and the one above it 0.986 (image mean 0.9943). With the probes of a sample's own plane counted only where the
sample reaches them, every lit row is within 0.4 % (mean 1.0001)."""

import bpy
import numpy as np

from blender_helpers import render_pixels, use_cycles, use_photonsplat
from test_photon_shading_normals import bumpy_floor_by_a_wall

SIZE = 32
BOUNCES = 4


def test_the_foot_of_a_lit_wall_as_cycles(empty_scene, tmp_path, core):
    scene = bumpy_floor_by_a_wall(empty_scene)
    tree = bpy.data.materials["Bumpy"].node_tree
    tree.nodes.remove(tree.nodes["Bump"])
    use_cycles(scene, SIZE, BOUNCES, samples=2048)
    scene.cycles.light_sampling_threshold = 0.0
    scene.cycles.pixel_filter_type, scene.cycles.filter_width = 'BOX', 1.0
    cycles = render_pixels(tmp_path / "cycles.exr")[..., :3]
    use_photonsplat(scene, SIZE, 100_000, max_bounces=BOUNCES, iterations=64)
    ours = render_pixels(tmp_path / "photonsplat.exr")[..., :3]
    rows = ours.mean(axis=(1, 2)) / cycles.mean(axis=(1, 2))
    lit = cycles.mean(axis=(1, 2)) > 0.5          # the wall and the floor near it, where the bounce matters
    print(f"\nPhoton Splat / Cycles: {ours.mean() / cycles.mean():.4f}; lit rows (top first) "
          + " ".join(f"{r:.3f}" for r in np.flipud(rows[lit])))
    assert abs(ours.mean() / cycles.mean() - 1.0) < 0.015
    assert np.all(np.abs(rows[lit] - 1.0) < 0.04)
