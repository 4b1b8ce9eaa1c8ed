"""Final renders through Blender (bpy.ops.render.render, as F12) with the native core.

Images stay tiny (the suite runs on 2 shared cores); what is checked does not need more pixels:
finite and not black, the caustic in its place, brightness equal to Cycles', cancel, error reports.
"""

import math
import time

import bpy
import numpy as np
import pytest

from blender_helpers import (caustic_landing, emissive_plane, enable_nodes, open_scene, pixel_of, render_pixels,
                             use_cycles, use_photonsplat)
from photonsplat import engine
from scene_geometry import floor_ring


def luminance(rgb):
    return rgb[..., 0] * 0.2126 + rgb[..., 1] * 0.7152 + rgb[..., 2] * 0.0722


@pytest.mark.parametrize("name", ["cornell_caustics", "cornell_diffuse"])
def test_renders_the_scenes(name, tmp_path, core):
    scene = open_scene(name)
    use_photonsplat(scene, 96, 100_000)
    started = time.perf_counter()
    pixels = render_pixels(tmp_path / f"{name}.exr")
    print(f"\n{name}: 96x96, 100k photons, {time.perf_counter() - started:.2f} s, {engine.last_outcome.message}")
    assert engine.last_outcome.status == "finished", engine.last_outcome.message
    assert pixels.shape == (96, 96, 4)
    assert np.isfinite(pixels).all()
    rgb = pixels[..., :3]
    assert rgb.min() >= 0.0
    assert rgb.mean() > 0.05                          # lit, not black
    assert (rgb.max(axis=2) > 0.01).mean() > 0.8      # the box fills the frame: almost every pixel lit
    # The red wall is on the left, the green one on the right (checks the image is not flipped).
    middle = pixels[48, :, :3]
    assert middle[:10, 0].mean() > middle[:10, 1].mean() and middle[-10:, 1].mean() > middle[-10:, 0].mean()


def test_caustic_under_the_glass_sphere(caustics_scene, tmp_path, core):
    scene = caustics_scene
    size = 128
    use_photonsplat(scene, size, 400_000)
    pixels = render_pixels(tmp_path / "caustics.exr")
    assert engine.last_outcome.status == "finished", engine.last_outcome.message
    brightness = luminance(pixels[..., :3])

    # Where the caustic is, from the scene itself: trace light through the glass sphere onto the floor.
    eye = np.array(scene.camera.matrix_world.translation)
    landing, spheres = caustic_landing(eye)
    assert len(landing) > 1000, "the caustic should be visible from the camera in this scene"

    # Caustic pixels: those showing many of the landing points.
    hits = {}
    for point in landing:
        pixel = pixel_of(scene, scene.camera, point)
        if pixel is not None:
            hits[pixel] = hits.get(pixel, 0) + 1
    caustic = [p for p, n in hits.items() if n >= 0.02 * len(landing)]
    assert caustic

    # Surroundings: floor points on rings around the caustic, away from both spheres and seen by the camera.
    ring = floor_ring(landing, eye, spheres)
    around = {pixel_of(scene, scene.camera, p) for p in ring} - {None} - set(caustic)
    assert len(around) >= 10

    caustic_level = np.mean([brightness[p] for p in caustic])
    around_level = np.median([brightness[p] for p in around])
    print(f"\ncaustic {caustic_level:.3f} vs surroundings {around_level:.3f} ({len(caustic)} / {len(around)} pixels)")
    assert caustic_level > 2.0 * around_level


def render_with_both(scene, tmp_path, size=64, bounces=8):
    """Render `scene` with Cycles (CPU, 256 samples, no denoising or clamping) and with Photon Splat at the
    same size and bounce limit. Returns both RGB images and both render times."""
    use_cycles(scene, size, bounces)
    started = time.perf_counter()
    reference = render_pixels(tmp_path / "cycles.exr")[..., :3]
    cycles_seconds = time.perf_counter() - started

    use_photonsplat(scene, size, 400_000, max_bounces=bounces)
    started = time.perf_counter()
    ours = render_pixels(tmp_path / "photonsplat.exr")[..., :3]
    ours_seconds = time.perf_counter() - started
    assert engine.last_outcome.status == "finished", engine.last_outcome.message
    return reference, ours, cycles_seconds, ours_seconds


def replace_light(scene, kind):
    """Swap the scene's point light for another kind, to check each light's units against Cycles."""
    old = bpy.data.objects["Light"]
    if kind == "POINT":
        return
    location = old.location.copy()
    bpy.data.objects.remove(old)
    data = bpy.data.lights.new(kind, kind)
    obj = bpy.data.objects.new(kind, data)
    if kind == "AREA":                 # a 0.6 x 0.4 m panel under the ceiling, shining down
        data.energy, data.shape, data.size, data.size_y = 30.0, 'RECTANGLE', 0.3, 0.4
        obj.location = (location.x, location.y, 1.9)
        obj.scale = (2.0, 1.0, 1.0)    # the size includes the object scale
    else:                              # sunlight through the open front, from above
        data.energy, data.angle = 2.0, math.radians(2.0)
        obj.rotation_euler = (math.radians(60.0), 0.0, 0.0)    # local -Z -> (0, +0.87, -0.5)
    obj.visible_camera = False
    scene.collection.objects.link(obj)


@pytest.mark.parametrize("light", ["POINT", "AREA", "SUN"])
def test_brightness_matches_cycles(light, diffuse_scene, tmp_path, core):
    """Light units follow Cycles: the same .blend has the same mean linear radiance in both engines."""
    replace_light(diffuse_scene, light)
    reference, ours, cycles_seconds, ours_seconds = render_with_both(diffuse_scene, tmp_path)
    ratio = ours.mean() / reference.mean()
    per_channel = ours.reshape(-1, 3).mean(axis=0) / reference.reshape(-1, 3).mean(axis=0)
    print(f"\n{light}: mean radiance Cycles {reference.mean():.4f} ({cycles_seconds:.1f} s), Photon Splat "
          f"{ours.mean():.4f} ({ours_seconds:.1f} s), ratio {ratio:.4f}, per channel {np.round(per_channel, 4)}")
    assert abs(ratio - 1.0) < 0.05


def test_emissive_mesh_matches_cycles(diffuse_scene, tmp_path, core):
    """Mesh emission (Emission shader, both faces) lights the box as brightly as in Cycles."""
    bpy.data.objects.remove(bpy.data.objects["Light"])
    emissive_plane(0.5, (0.0, 0.0, 1.5), 30.0)
    reference, ours, _, _ = render_with_both(diffuse_scene, tmp_path)

    # Compare away from the lamp itself: one sample per pixel (ours) and Cycles' antialiased pixel filter
    # give its few, very bright pixels different coverage, which would swamp the mean.
    near_lamp = (reference.max(axis=2) > 5.0) | (ours.max(axis=2) > 5.0)
    for axis in (0, 1):
        for shift in (-2, -1, 1, 2):
            near_lamp = near_lamp | np.roll(near_lamp, shift, axis)
    ratio = ours[~near_lamp].mean() / reference[~near_lamp].mean()
    print(f"\nemissive mesh: mean radiance away from the lamp, ratio {ratio:.4f}")
    assert abs(ratio - 1.0) < 0.05


def test_export_warnings_reach_the_report(caustics_scene, tmp_path, core):
    bpy.data.lights["Light"].type = 'AREA'
    bpy.data.lights["Light"].spread = math.radians(90.0)               # not modelled: rendered as 180 degrees, with a note
    toon = bpy.data.materials.new("Toon")
    enable_nodes(toon)
    tree = toon.node_tree
    tree.nodes.clear()
    tree.links.new(tree.nodes.new("ShaderNodeBsdfToon").outputs[0],
                   tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    bpy.data.objects["MirrorSphere"].material_slots[0].material = toon
    use_photonsplat(caustics_scene, 32, 10_000)
    render_pixels(tmp_path / "warnings.exr")
    outcome = engine.last_outcome
    assert outcome.status == "finished"
    assert any("spread" in w for w in outcome.warnings)
    assert any("Toon" in w and "Material 'Toon'" in w for w in outcome.warnings)


def test_cancel_stops_the_render_and_the_next_one_works(caustics_scene, monkeypatch, tmp_path, core):
    use_photonsplat(caustics_scene, 128, 2_000_000)
    polls = []

    def escape_after_first_progress(self):
        polls.append(time.perf_counter())
        return len(polls) >= 2             # poll 1 is before the core starts, poll 2 its first progress call

    # Blender's test_break cannot be replaced from Python; the engine asks through this method.
    monkeypatch.setattr(engine.PhotonSplatRenderEngine, "_cancel_requested", escape_after_first_progress)
    bpy.ops.render.render()
    stopped = time.perf_counter()
    assert engine.last_outcome.status == "cancelled", engine.last_outcome.message
    assert len(polls) >= 2
    print(f"\ncancel: stopped {stopped - polls[1]:.3f} s after the simulated Esc")
    assert stopped - polls[1] < 1.0, "the core should stop within a second of Esc"

    monkeypatch.undo()
    caustics_scene.photonsplat.photons = 20_000
    pixels = render_pixels(tmp_path / "after_cancel.exr")
    assert engine.last_outcome.status == "finished"
    assert np.isfinite(pixels).all() and pixels[..., :3].mean() > 0.05


class FakeEngine:
    """Just enough of RenderEngine to run PhotonSplatRenderEngine.render outside Blender's render pipeline
    (which refuses scenes without a camera before the engine sees them)."""
    camera_override = None

    def __init__(self):
        self.reports, self.ended = [], []

    def begin_result(self, x, y, w, h, layer="", view=""):
        return object()

    def end_result(self, result, cancel=False, highlight=False, do_merge_results=False):
        self.ended.append(cancel)

    def report(self, kind, message):
        self.reports.append((next(iter(kind)), message))

    def error_set(self, message):
        pass

    def update_stats(self, stats, info):
        pass

    def update_progress(self, value):
        pass

    def test_break(self):
        return False


for _name in ("render", "_render_into", "_cancel_requested", "_cancelled"):
    setattr(FakeEngine, _name, getattr(engine.PhotonSplatRenderEngine, _name))


def test_no_camera_is_reported(caustics_scene, tmp_path, core):
    caustics_scene.render.engine = 'PHOTONSPLAT'
    caustics_scene.render.filepath = str(tmp_path / "no_camera.exr")
    bpy.data.objects.remove(bpy.data.objects["Camera"])
    # Through Blender: refused with a report, the operator returns, Blender lives on.
    with pytest.raises(RuntimeError, match="camera"):
        bpy.ops.render.render(write_still=True)
    # Through our engine directly: the export says so in an ERROR report; nothing is raised.
    fake = FakeEngine()
    fake.render(bpy.context.evaluated_depsgraph_get())
    assert fake.ended == [False]                     # the result was closed
    assert [kind for kind, _ in fake.reports] == ["ERROR"]
    assert "camera" in fake.reports[0][1]
    assert engine.last_outcome.status == "failed"


def test_bad_settings_are_reported(caustics_scene, tmp_path, core):
    use_photonsplat(caustics_scene, 32, 10_000)
    # The panel clamps radius at 0; a script or an old file can still store a negative value.
    caustics_scene.photonsplat["radius"] = -1.0
    assert caustics_scene.photonsplat.radius == -1.0
    with pytest.raises(RuntimeError, match="radius"):
        render_pixels(tmp_path / "bad.exr")          # write_still: an open result would crash Blender here
    assert engine.last_outcome.status == "failed"

    caustics_scene.photonsplat.radius = 0.0
    pixels = render_pixels(tmp_path / "good.exr")
    assert engine.last_outcome.status == "finished" and np.isfinite(pixels).all()
