"""The world as a light (issue 17): blend_scenes/world_hdri.blend, lit by nothing but an HDRI (Blender's
studio-light city.exr, packed, with a strong sun), rendered small by Photon Splat and by Cycles in the same run:
the whole-image mean must agree within MEAN_TOLERANCE.

96 x 54 pixels (the file's 16:9 at 20 %). Cycles: 128 samples, no denoising, adaptive sampling or clamping, box
filter 1 px, 16 bounces; its own noise on the mean at this size is 0.8 % (one standard deviation over seeds 1-6:
means 0.864-0.881), caustic fireflies included. Photon Splat: 8 iterations of 50k photons. The tolerance, 5 %, is
the issue's 3 % (tools/world_compare.py, docs/results/worlds.md, at full size and converged) plus room for both
renderers' noise at this size: an engine that lights the scene by its world as Cycles does meets it.

Before issue 17 the engine lit this scene with a constant world colour (the Environment Texture replaced by its
socket's unconnected value): about 4 % of Cycles' mean. Blender 3.4 only (Cycles' conventions of the other
versions are measured elsewhere).
"""

import time

import bpy
import numpy as np
import pytest

from blender_helpers import open_scene, render_pixels, use_cycles, use_photonsplat

WIDTH, HEIGHT = 96, 54
CYCLES_SAMPLES = 128
BOUNCES = 16
MEAN_TOLERANCE = 0.05

only_blender_34 = pytest.mark.skipif(bpy.app.version[:2] != (3, 4),
                                     reason="measured against Blender 3.4's Cycles (Debian's)")


def small(scene):
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    scene.render.resolution_percentage = 100


def render_cycles(scene, path):
    use_cycles(scene, WIDTH, BOUNCES, samples=CYCLES_SAMPLES)
    small(scene)
    cycles = scene.cycles
    cycles.seed = 1
    cycles.light_sampling_threshold = 0.0
    cycles.pixel_filter_type = 'BOX'
    cycles.filter_width = 1.0
    cycles.glossy_bounces = cycles.transmission_bounces = cycles.transparent_max_bounces = BOUNCES
    cycles.blur_glossy = 0.0
    scene.render.film_transparent = False
    return render_pixels(path)


def render_photonsplat(scene, path):
    use_photonsplat(scene, WIDTH, 50_000, iterations=8, time_limit=0.0, seed=1, max_bounces=BOUNCES)
    small(scene)
    scene.render.film_transparent = False
    return render_pixels(path)


def test_world_scenes_hold_what_the_acceptance_measures():
    """The three scenes open with the world the issue is about (not an xfail: this is the files, not the engine)."""
    scene = open_scene("world_hdri")
    nodes = scene.world.node_tree.nodes
    env = next(n for n in nodes if n.bl_idname == "ShaderNodeTexEnvironment")
    assert env.image is not None and env.image.packed_file is not None
    assert env.image.filepath.endswith("city.exr")
    assert len(scene["sun_direction"]) == 3 and scene["sun_direction"][2] > 0.5
    scene = open_scene("world_sky")
    sky = next(n for n in scene.world.node_tree.nodes if n.bl_idname == "ShaderNodeTexSky")
    # Blender 5.0 opens a 3.4 Nishita sky as its 'SINGLE_SCATTERING' (the same model, renamed).
    assert sky.sky_type in ('NISHITA', 'SINGLE_SCATTERING') and sky.sun_disc
    scene = open_scene("world_portal")
    portals = [o for o in scene.objects if o.type == 'LIGHT' and o.data.cycles.is_portal]
    assert len(portals) == 1 and portals[0].data.type == 'AREA'
    assert not [o for o in scene.objects if o.type == 'LIGHT' and not o.data.cycles.is_portal]


@only_blender_34
def test_hdri_scene_mean_matches_cycles(tmp_path, core):
    scene = open_scene("world_hdri")
    started = time.perf_counter()
    cycles = render_cycles(scene, tmp_path / "cycles.exr")
    cycles_seconds = time.perf_counter() - started
    started = time.perf_counter()
    ours = render_photonsplat(scene, tmp_path / "photonsplat.exr")
    ours_seconds = time.perf_counter() - started
    assert cycles.shape == ours.shape == (HEIGHT, WIDTH, 4)
    assert np.isfinite(ours).all()
    ratio = float(ours[..., :3].mean() / cycles[..., :3].mean())
    print(f"\nworld_hdri {WIDTH}x{HEIGHT}: Cycles {cycles[..., :3].mean():.4f} ({CYCLES_SAMPLES} spp, "
          f"{cycles_seconds:.1f} s), Photon Splat {ours[..., :3].mean():.4f} ({ours_seconds:.1f} s): ratio "
          f"{ratio:.4f}")
    assert abs(ratio - 1.0) <= MEAN_TOLERANCE
