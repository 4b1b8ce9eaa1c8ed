"""Final render features through Blender: render passes, render border / crop, film transparency, view layers and
frame ranges. Tiny images (48-64 px, 20-40k photons)."""

import subprocess

import bpy
import numpy as np
import pytest

from blender_helpers import open_scene, read_exr, render_pixels, uniform_world, use_photonsplat
from photonsplat import compat, engine
from photonsplat.passes import PASSES

ALL_PASSES = ["Combined", "Depth", "Normal", "Emit", "Direct", "Indirect", "Caustics"]


def enable_all_passes(view_layer):
    view_layer.use_pass_z = view_layer.use_pass_normal = view_layer.use_pass_emit = True
    view_layer.photonsplat.use_pass_direct = True
    view_layer.photonsplat.use_pass_indirect = True
    view_layer.photonsplat.use_pass_caustics = True


def render_multilayer(path):
    """Render every view layer into one multilayer EXR at `path`."""
    scene = bpy.context.scene
    scene.render.filepath = str(path)
    scene.render.use_file_extension = False
    compat.set_multilayer_exr(scene.render.image_settings)
    scene.render.image_settings.color_depth = '32'
    bpy.ops.render.render(write_still=True)
    assert engine.last_outcome.status == "finished", engine.last_outcome.message


def read_passes(tmp_path, names):
    """Renders the current view layer once into a multilayer EXR and returns each pass in `names` as float32
    (H, W, 4), rows from the bottom: oiiotool copies a pass's channels into an RGBA file Blender reads."""
    path = tmp_path / "passes.exr"
    render_multilayer(path)
    layer = bpy.context.view_layer.name
    out = {}
    for name in names:
        channels = next(p.channel_ids for p in PASSES if p.name == name)
        mapping = [f"{target}={layer}.{name}.{channel}" for target, channel in zip("RGBA", channels)]
        mapping += [f"{target}=0.0" for target in "RGBA"[len(channels):]]
        single = tmp_path / f"{name}.exr"
        subprocess.run(["oiiotool", str(path), "--ch", ",".join(mapping), "-d", "float", "-o", str(single)],
                       check=True, capture_output=True)
        out[name] = read_exr(single)
    return out


def test_every_pass_is_written_and_finite(caustics_scene, tmp_path, core):
    scene = caustics_scene
    use_photonsplat(scene, 48, 40_000)
    enable_all_passes(bpy.context.view_layer)
    images = read_passes(tmp_path, ALL_PASSES)
    assert engine.last_outcome.passes == ALL_PASSES
    for name, image in images.items():
        assert np.isfinite(image).all(), name
    rgb = {name: images[name][..., :3] for name in ("Combined", "Emit", "Direct", "Indirect", "Caustics")}
    # Combined = Emit + Direct + Indirect, and the caustics are part of the indirect light.
    assert np.allclose(rgb["Combined"], rgb["Emit"] + rgb["Direct"] + rgb["Indirect"], atol=1e-4)
    assert (rgb["Caustics"] <= rgb["Indirect"] + 1e-5).all()
    assert rgb["Caustics"].max() > 0.0 and rgb["Direct"].mean() > 0.0 and rgb["Indirect"].mean() > 0.0
    assert rgb["Caustics"].mean() < rgb["Indirect"].mean()
    # Depth, as Cycles: distance along the camera axis to the first hit, 1e10 where the ray leaves the scene
    # (the box's open front shows the world at the edges); Normal: unit vectors there, 0 elsewhere.
    depth = images["Depth"][..., 0]
    hit = depth < 1e9
    assert hit.mean() > 0.5 and (depth[~hit] == 1e10).all()
    camera = scene.camera
    distance = np.linalg.norm(np.array(camera.matrix_world.translation))
    assert (depth[hit] > camera.data.clip_start).all() and (depth[hit] < 2.0 * distance).all()
    normal = images["Normal"][..., :3]
    assert np.allclose(np.linalg.norm(normal[hit], axis=1), 1.0, atol=1e-3)
    assert (normal[~hit] == 0.0).all()


def test_caustics_pass_matches_a_render_of_caustic_photons(caustics_scene, tmp_path, core):
    """The Caustics pass is the splat of exactly the caustic photons: the glass/mirror spheres made diffuse
    leave no caustic photons, and the pass is then zero, while Indirect is not."""
    scene = caustics_scene
    use_photonsplat(scene, 32, 20_000)
    enable_all_passes(bpy.context.view_layer)
    for material in bpy.data.materials:
        if material.name in ("Glass", "Mirror"):
            material.node_tree.nodes.clear()     # no output node: Photon Splat's default diffuse material
    images = read_passes(tmp_path, ["Caustics", "Indirect"])
    assert images["Caustics"][..., :3].max() == 0.0
    assert images["Indirect"][..., :3].mean() > 0.0


def test_border_renders_only_the_border_and_crop_keeps_its_size(caustics_scene, tmp_path, core):
    scene = caustics_scene
    use_photonsplat(scene, 64, 20_000)
    full = render_pixels(tmp_path / "full.exr")
    render = scene.render
    render.use_border = True
    render.border_min_x, render.border_max_x = 0.25, 0.75
    render.border_min_y, render.border_max_y = 0.5, 1.0
    render.use_crop_to_border = False
    uncropped = render_pixels(tmp_path / "uncropped.exr")
    assert uncropped.shape == full.shape
    inside = (slice(32, 64), slice(16, 48))
    outside = uncropped.copy()
    outside[inside] = 0.0
    assert outside.max() == 0.0                  # nothing outside the border
    # Inside: the same pixels as the full frame (same rays, same photons), up to the photon noise of a
    # different camera-dependent hierarchy: compare means.
    assert np.allclose(uncropped[inside][..., :3].mean(), full[inside][..., :3].mean(), rtol=0.05)
    direct = engine.last_outcome.stats["values"]
    assert (direct["width"], direct["height"]) == (32, 32)   # only the border's pixels were rendered
    render.use_crop_to_border = True
    cropped = render_pixels(tmp_path / "cropped.exr")
    assert cropped.shape == (32, 32, 4)
    assert np.allclose(cropped, uncropped[inside], atol=1e-6)


def test_resolution_percentage(caustics_scene, tmp_path, core):
    scene = caustics_scene
    use_photonsplat(scene, 64, 10_000)
    scene.render.resolution_percentage = 50
    assert render_pixels(tmp_path / "half.exr").shape == (32, 32, 4)


def test_film_transparency_clears_only_where_rays_escape(empty_scene, tmp_path, core):
    scene = empty_scene
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    bpy.ops.object.light_add(type='POINT', location=(0.0, 0.0, 2.0))
    bpy.context.object.data.energy = 200.0
    bpy.ops.object.camera_add(location=(0.0, 0.0, 4.0))
    scene.camera = bpy.context.object
    uniform_world(scene, (0.5, 0.5, 0.5))
    use_photonsplat(scene, 48, 10_000)
    opaque = render_pixels(tmp_path / "opaque.exr")
    scene.render.film_transparent = True
    clear = render_pixels(tmp_path / "clear.exr")
    sky = np.isclose(opaque[..., :3], 0.5, atol=1e-4).all(axis=2)     # exactly the grey world
    hit = ~sky & (opaque[..., :3].sum(axis=2) > 0.0)                   # the lit plane
    assert hit.any() and sky.any()
    assert (opaque[..., 3] == 1.0).all()
    assert (clear[sky][..., 3] == 0.0).all() and (clear[sky][..., :3] == 0.0).all()
    assert (clear[hit][..., 3] == 1.0).all()
    assert np.allclose(clear[hit], opaque[hit], atol=1e-6)


def test_every_view_layer_is_rendered(caustics_scene, tmp_path, core):
    """Blender calls render() once per view layer; each layer gets its own passes (here Depth only on the
    second). The multilayer EXR's header lists its channels by name."""
    scene = caustics_scene
    use_photonsplat(scene, 32, 10_000)
    first = scene.view_layers[0]
    second = scene.view_layers.new("Second")
    second.use_pass_z = True
    scene.render.use_single_layer = False
    render_multilayer(tmp_path / "layers.exr")
    header = (tmp_path / "layers.exr").read_bytes()[:20000]
    assert f"{first.name}.Combined.R".encode() in header and b"Second.Combined.R" in header
    assert b"Second.Depth.Z" in header and f"{first.name}.Depth".encode() not in header


def test_frame_range_renders_every_frame(caustics_scene, tmp_path, core):
    scene = caustics_scene
    use_photonsplat(scene, 24, 5_000)
    scene.frame_start, scene.frame_end = 1, 3
    light = bpy.data.objects["Light"]
    light.location.z = 1.7
    light.keyframe_insert("location", frame=1)
    light.location.z = 1.2
    light.keyframe_insert("location", frame=3)
    scene.render.filepath = str(tmp_path / "frame_")
    scene.render.image_settings.file_format = 'OPEN_EXR'
    scene.render.image_settings.color_depth = '32'
    scene.render.use_file_extension = True
    bpy.ops.render.render(animation=True)
    frames = [read_exr(tmp_path / f"frame_{n:04d}.exr") for n in (1, 2, 3)]
    for pixels in frames:
        assert pixels.shape == (24, 24, 4) and np.isfinite(pixels).all()
    # The light comes down: the floor gets brighter frame after frame.
    floor = [luminance(p[:6, 8:16]).mean() for p in frames]
    assert floor[0] < floor[1] < floor[2]


def luminance(rgba):
    return rgba[..., 0] * 0.2126 + rgba[..., 1] * 0.7152 + rgba[..., 2] * 0.0722


def test_passes_of_a_progressive_render(caustics_scene, tmp_path, core):
    """With progressive passes the colour passes are means like the image: they still add up to Combined."""
    use_photonsplat(caustics_scene, 32, 10_000, iterations=3)
    enable_all_passes(bpy.context.view_layer)
    images = read_passes(tmp_path, ALL_PASSES)
    assert engine.last_outcome.stats["values"]["iterations"] == 3
    assert all(np.isfinite(image).all() for image in images.values())
    rgb = {name: images[name][..., :3] for name in ("Combined", "Emit", "Direct", "Indirect", "Caustics")}
    assert np.allclose(rgb["Combined"], rgb["Emit"] + rgb["Direct"] + rgb["Indirect"], atol=1e-4)
    assert 0.0 < rgb["Caustics"].mean() < rgb["Indirect"].mean()
