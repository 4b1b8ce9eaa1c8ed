"""The benchmark scenes (blend_scenes/atrium.blend, blend_scenes/glossy_row.blend) open and render with Photon Splat.

Tiny images and few photons (the suite runs on 2 shared cores): what is checked is that each scene is what its
generator promises (resolution, frames, materials) and that every frame renders finite and lit.
"""

import itertools

import bpy
import numpy as np
import pytest

from blender_helpers import open_scene, pixel_of, render_pixels
from photonsplat import compat, engine

WIDTH, HEIGHT = 96, 54
PHOTONS = 20_000
FLY_THROUGH_FRAMES = range(1, 9)


def use_photonsplat_16_9(scene):
    scene.render.engine = 'PHOTONSPLAT'
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    scene.render.resolution_percentage = 100
    scene.photonsplat.photons = PHOTONS


def render_checked(path):
    """Render the current frame through bpy.ops; check it finished with finite, non-negative pixels; return RGB."""
    pixels = render_pixels(path)
    outcome = engine.last_outcome
    assert outcome.status == "finished", outcome.message
    assert pixels.shape == (HEIGHT, WIDTH, 4)
    assert np.isfinite(pixels).all()
    rgb = pixels[..., :3]
    assert rgb.min() >= 0.0
    return rgb


def test_atrium_is_saved_as_the_benchmark_expects():
    scene = open_scene("atrium")
    assert (scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage) == \
        (1920, 1080, 100)
    assert scene.view_settings.view_transform == 'Standard'
    assert scene.render.engine == 'CYCLES'           # tests and benchmarks pick the engine
    assert scene.frame_start == 1 and scene.frame_end >= 8
    assert any(ob.type == 'LIGHT' and ob.data.type == 'SUN' for ob in scene.objects)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    triangles = 0
    for ob in scene.objects:
        if ob.type == 'MESH':
            mesh = ob.evaluated_get(depsgraph).data
            mesh.calc_loop_triangles()
            triangles += len(mesh.loop_triangles)
    assert 50_000 <= triangles <= 300_000
    kinds = {node.bl_idname for material in bpy.data.materials if compat.uses_nodes(material)
             for node in material.node_tree.nodes}
    assert {"ShaderNodeBsdfDiffuse", "ShaderNodeBsdfGlass", compat.GLOSSY_BSDF_IDNAME} <= kinds


def test_atrium_fly_through_renders_every_frame(tmp_path, core):
    scene = open_scene("atrium")
    use_photonsplat_16_9(scene)
    positions, images = [], []
    for frame in FLY_THROUGH_FRAMES:
        scene.frame_set(frame)
        positions.append(np.array(scene.camera.matrix_world.translation))
        rgb = render_checked(tmp_path / f"atrium_{frame}.exr")
        print(f"\natrium frame {frame}: {engine.last_outcome.message}")
        # Not black: sun, sky and bounced light reach most of what each camera sees (the shaded walkways are
        # dim, and at this photon count a few of their pixels catch no photon at all).
        assert rgb.mean() > 0.015, f"frame {frame} is (nearly) black"
        assert (rgb.max(axis=2) > 0.003).mean() > 0.5, f"frame {frame}: most pixels should see light"
        images.append(rgb)
    # One key position per frame: every frame has its own camera, and so its own image.
    for (a, pa, ia), (b, pb, ib) in itertools.combinations(zip(FLY_THROUGH_FRAMES, positions, images), 2):
        assert np.linalg.norm(pa - pb) > 1.0, f"frames {a} and {b} share a camera position"
        assert np.abs(ia - ib).mean() > 0.01, f"frames {a} and {b} render the same image"


def test_glossy_row_renders_five_spheres_in_order(tmp_path, core):
    scene = open_scene("glossy_row")
    assert (scene.render.resolution_x, scene.render.resolution_y) == (1280, 720)
    spheres = sorted((ob for ob in scene.objects if ob.name.startswith("Sphere")),
                     key=lambda ob: ob.matrix_world.translation.x)
    roughness = []
    for ob in spheres:
        glossy = [n for n in ob.active_material.node_tree.nodes if n.bl_idname == compat.GLOSSY_BSDF_IDNAME]
        assert len(glossy) == 1 and glossy[0].distribution == 'GGX'
        roughness.append(round(glossy[0].inputs["Roughness"].default_value, 3))
    assert roughness == [0.05, 0.2, 0.35, 0.5, 0.8]

    use_photonsplat_16_9(scene)
    rgb = render_checked(tmp_path / "glossy_row.exr")
    print(f"\nglossy row: {engine.last_outcome.message}")
    assert rgb.mean() > 0.05
    # Each sphere is in the picture, left to right in order of roughness, and lit.
    columns = []
    for ob in spheres:
        pixel = pixel_of(scene, scene.camera, ob.matrix_world.translation)
        assert pixel is not None, f"{ob.name} is outside the frame"
        assert rgb[pixel].max() > 0.02, f"{ob.name} is black"
        columns.append(pixel[1])
    assert columns == sorted(columns) and len(set(columns)) == len(columns)


@pytest.mark.parametrize("name", ["atrium", "glossy_row"])
def test_scene_has_no_export_warnings_but_roughness(name, tmp_path, core):
    """Everything in the scenes maps onto the core, except (until the core has rough glossy surfaces) the
    glossy roughness: the only warnings allowed are about roughness."""
    scene = open_scene(name)
    use_photonsplat_16_9(scene)
    scene.render.resolution_x, scene.render.resolution_y = 16, 9
    scene.photonsplat.photons = 1_000
    render_pixels(tmp_path / f"{name}_warnings.exr")
    assert engine.last_outcome.status == "finished", engine.last_outcome.message
    assert all("roughness" in w.lower() for w in engine.last_outcome.warnings), engine.last_outcome.warnings
