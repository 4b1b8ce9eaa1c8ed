"""Shader node programs against Cycles, pixel by pixel, on nineteen representative cases of
blend_scenes/make_node_planes.py at 32 x 32 (the full set: tools/node_compare.py, docs/results/node_programs.md).

Each case is a node driving an Emission shader (strength 1) on a plane filling an orthographic camera. Cycles renders
it here (1 sample, box filter 0.01 px: the pixel centres; no cache) and Photon Splat with one iteration (pixel
centres). Acceptance (a): mean |ours - Cycles| / mean |Cycles| <= 1e-3 for deterministic nodes, <= 1 % for the
noise-based textures.
"""

import sys
from pathlib import Path

import bpy
import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "blend_scenes"))
sys.path.insert(0, str(REPO / "tools"))

import make_node_planes as planes  # noqa: E402
import node_compare  # noqa: E402

SIZE = 32
CASES = [
    "noise_3d_color",
    "voronoi_3d_f1_euclidean_distance",
    "musgrave_3d_fbm",
    "wave_bands_x_sin_fac",
    "magic_depth2_dist1_color",
    "brick_default_color",
    "gradient_quadratic_sphere",
    "image_grid_float_closest",
    "colorramp_linear",
    "math_power_negative_base",
    "vmath_cross_product",
    "mix_rgba_overlay",
    "hsv",
    "mapping_point",
    "attribute_vertexcolor_color",
    "fresnel_1.45",
    "sky_nishita_horizon",
    "sky_nishita_disc",
    "sky_preetham",
]


@pytest.fixture(scope="module")
def program_core():
    from photonsplat import engine
    core = engine.load_core()
    if bpy.app.version[:2] != (3, 4):
        # the cases are built from 3.4's nodes (Musgrave, the 3.4 Noise), and acceptance (a) is against 3.4's Cycles
        pytest.skip(f"the node cases are Blender 3.4's nodes; this is Blender {bpy.app.version_string}")
    return core


def test_cases_exist():
    """The cases named here are cases of the generator (a rename there would silently drop one here)."""
    names = {c[0] for c in planes.CASES}
    assert set(CASES) <= names, set(CASES) - names


@pytest.mark.parametrize("name", CASES)
def test_node_matches_cycles(name, program_core, tmp_path):
    (case,) = planes.build(SIZE, [name])
    _, cls, _, _ = case
    planes.use_case(name)
    node_compare.cycles_plane_settings(bpy.context.scene, threads=2)
    cycles = node_compare.render_cycles(tmp_path / "cycles.exr")
    ours, notes, _ = node_compare.photonsplat_case(program_core, threads=2)
    assert ours.shape == cycles.shape == (SIZE, SIZE, 4)
    m = node_compare.compare(cycles, ours, cls)
    print(f"\n{name} ({cls}): rel {m['rel']:.2e}, max {m['max']:.3g}, edge pixels {m['edge_pixels']}, "
          f"Cycles mean {m['cycles_mean']:.4f}, ours {m['ours_mean']:.4f}; notes {notes}")
    assert np.isfinite(ours).all()
    assert m["rel"] <= node_compare.THRESHOLD[cls], (name, m, notes)
