"""The viewport's machinery in blender -b (no window: drawing itself is tested under Xvfb by
tests/window/test_viewport_window.py): the scene cache re-exports only what changed, and the background
refinement produces an image that improves pass after pass and stops when asked. About 10 s on 2 cores."""

import time

import bpy
import numpy as np

from photonsplat import refine, viewport
from photonsplat.export.scene_cache import SceneCache


class DepsgraphUpdates:
    """Calls cache.sync(depsgraph) from depsgraph_update_post, the only place (besides view_update) where
    depsgraph.updates lists what changed."""

    def __init__(self, cache):
        self.cache = cache
        self.reports = []

    def __enter__(self):
        bpy.app.handlers.depsgraph_update_post.append(self.handler)
        return self

    def __exit__(self, *exc):
        bpy.app.handlers.depsgraph_update_post.remove(self.handler)

    def handler(self, scene, depsgraph):
        self.reports.append(self.cache.sync(depsgraph))

    def evaluate(self):
        self.reports.clear()
        bpy.context.view_layer.update()
        return self.reports


def test_moved_light_re_exports_lights_only(caustics_scene, core):
    cache = SceneCache()
    cache.sync(bpy.context.evaluated_depsgraph_get())          # the first sync reads everything
    meshes, lights = cache.mesh_exports, cache.light_exports
    assert meshes == 3 and lights == 1         # box, glass sphere, mirror sphere; one light
    before = cache.build(core)

    with DepsgraphUpdates(cache) as updates:
        bpy.data.objects["Light"].location.z -= 0.3
        reports = updates.evaluate()
        assert reports and any(r.lights for r in reports)
        assert cache.mesh_exports == meshes                        # no mesh read again
        assert cache.light_exports > lights
        after = cache.build(core)
        assert (after.triangle_count, after.light_count) == (before.triangle_count, before.light_count)

        # Moving a mesh object: its transform changes, its geometry is not read again either.
        bpy.data.objects["GlassSphere"].location.x += 0.1
        reports = updates.evaluate()
        assert any(r.structure for r in reports)
        assert cache.mesh_exports == meshes

        # Editing the geometry: that one object, and only it, is read again.
        sphere = bpy.data.objects["GlassSphere"]
        sphere.data.vertices[0].co.x += 0.01
        sphere.data.update()
        updates.evaluate()
        assert cache.mesh_exports == meshes + 1


def test_moved_light_changes_the_rendered_image(caustics_scene, core):
    cache = SceneCache()
    cache.sync(bpy.context.evaluated_depsgraph_get())
    camera = viewport_camera(core, bpy.context.scene, 48, 48)
    settings = core.RenderSettings(photons=5_000, seed=1)
    first, _ = core.render(cache.build(core), camera, settings)
    with DepsgraphUpdates(cache) as updates:
        bpy.data.objects["Light"].location.x += 0.5
        updates.evaluate()
    second, _ = core.render(cache.build(core), camera, settings)
    assert np.abs(np.asarray(first) - np.asarray(second)).max() > 0.01


def viewport_camera(core, scene, width, height):
    """A camera as a viewport looking through the scene camera would make it (view and window matrices)."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    cam = scene.camera
    view = cam.matrix_world.normalized().inverted()
    window = cam.calc_matrix_camera(depsgraph, x=width, y=height)
    return viewport.view_camera_factory(core, view, window)(width, height)


def refinement_for(core, width=48, height=48, **limits):
    cache = SceneCache()
    cache.sync(bpy.context.evaluated_depsgraph_get())
    scene = bpy.context.scene
    settings = viewport.refine_settings(core, scene)
    from dataclasses import replace
    settings = replace(settings, **limits)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    cam = scene.camera
    make_camera = viewport.view_camera_factory(core, cam.matrix_world.normalized().inverted(),
                                               cam.calc_matrix_camera(depsgraph, x=width, y=height))
    frames = []
    return refine.Refinement(core, cache.build(core), make_camera, width, height, settings,
                             on_frame=frames.append), frames


def test_refinement_first_image_then_averaged_passes(caustics_scene, core):
    job, frames = refinement_for(core, preview_photons=2_000, preview_divider=4, photons_per_pass=5_000,
                                 max_passes=4, time_limit=0.0)
    job.start()
    assert job.join(60.0), "the refinement did not finish its 4 passes"
    assert job.error is None and job.finished
    assert [f.passes for f in frames] == [0, 1, 2, 3, 4]
    assert frames[0].pixels.shape == (12, 12, 4)                  # the fast first image: 1/4 resolution
    assert all(f.pixels.shape == (48, 48, 4) for f in frames[1:])
    assert all(np.isfinite(f.pixels).all() and f.pixels[..., :3].mean() > 0.01 for f in frames)
    assert job.first_image_seconds is not None and job.first_image_seconds <= frames[1].seconds
    # Averaging independent passes: pass-to-pass changes shrink (noise falls as 1/n).
    steps = [np.abs(frames[i + 1].pixels - frames[i].pixels).mean() for i in range(1, 4)]
    assert steps[2] < steps[0]


def test_refinement_stops_quickly_when_asked(caustics_scene, core):
    job, frames = refinement_for(core, 96, 96, preview_photons=2_000, photons_per_pass=2_000_000,
                                 max_passes=0, time_limit=0.0)
    job.start()
    deadline = time.perf_counter() + 30.0
    while not frames and time.perf_counter() < deadline:
        time.sleep(0.05)
    assert frames, "no first image"
    time.sleep(0.2)                          # now inside a long pass
    asked = time.perf_counter()
    job.stop()
    assert job.join(5.0), "the refinement thread did not stop"
    print(f"\nstopped {time.perf_counter() - asked:.2f} s after being asked")
    assert not job.finished and job.error is None


def test_stop_all_ends_every_viewport_thread(caustics_scene, core):
    """What unregistering the add-on and loading a file do (viewport.unregister, the load_pre handler)."""
    job, frames = refinement_for(core, 96, 96, preview_photons=2_000, photons_per_pass=2_000_000,
                                 max_passes=0, time_limit=0.0)

    class Session:                       # stands in for a ViewportSession holding this refinement
        def stop(self):
            job.stop()

        def join(self, timeout):
            return job.join(timeout)
    session = Session()
    viewport._sessions.add(session)
    job.start()
    time.sleep(0.3)
    viewport.stop_all(wait=5.0)
    assert not job.running
