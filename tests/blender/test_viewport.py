"""The viewport's machinery in blender -b (no window: drawing itself is tested under Xvfb by
tests/window/viewport_window.py): the sync kept between updates re-exports only what changed, and the background
refinement produces an image that improves pass after pass and stops when asked."""

import time
from dataclasses import replace

import bpy
import numpy as np

from photonsplat import export, refine, viewport


class RecordingCore:
    """The real core, except that every Scene it makes records the calls made on it (method names, in order):
    what the sync did to the core scene, without changing what it renders."""

    def __init__(self, core):
        self._core = core
        self.scenes = []

    def __getattr__(self, name):
        return getattr(self._core, name)

    def Scene(self):
        scene = RecordingScene(self._core.Scene())
        self.scenes.append(scene)
        return scene

    def calls(self, method):
        return sum(scene.calls.count(method) for scene in self.scenes)


class RecordingScene:
    def __init__(self, scene):
        self.scene = scene
        self.calls = []

    def __getattr__(self, name):
        attribute = getattr(self.scene, name)
        if not callable(attribute):
            return attribute
        self.calls.append(name)
        return attribute


class DepsgraphUpdates:
    """Calls sync.sync(depsgraph) from depsgraph_update_post, the only place (besides view_update) where
    depsgraph.updates lists what changed."""

    def __init__(self, sync, release=None):
        self.sync = sync
        self.release = release
        self.reports = []

    def __enter__(self):
        bpy.app.handlers.depsgraph_update_post.append(self.handler)
        return self

    def __exit__(self, *exc):
        bpy.app.handlers.depsgraph_update_post.remove(self.handler)

    def handler(self, scene, depsgraph):
        self.reports.append(self.sync.sync(depsgraph, release=self.release))

    def evaluate(self):
        self.reports.clear()
        bpy.context.view_layer.update()
        return self.reports


def test_moved_light_re_exports_lights_only(caustics_scene, core):
    recording = RecordingCore(core)
    sync = export.BlenderSync(recording)
    sync.sync(bpy.context.evaluated_depsgraph_get())     # the first sync reads everything
    meshes, lights = sync.mesh_exports, sync.light_exports
    assert meshes == 3 and lights == 1         # box, glass sphere, mirror sphere; one light
    before = sync.scene
    counts = (before.triangle_count, before.light_count, before.mesh_count)

    with DepsgraphUpdates(sync) as updates:
        bpy.data.objects["Light"].location.z -= 0.3
        reports = updates.evaluate()
        assert reports and any(r.lights for r in reports) and not any(r.rebuilt for r in reports)
        assert sync.mesh_exports == meshes                        # no mesh read again
        assert sync.light_exports > lights
        # The lights were replaced in the same core scene: no mesh added, no new scene.
        assert sync.scene is before and len(recording.scenes) == 1
        assert recording.calls("clear_lights") == 1 and recording.calls("add_mesh_data") == 3
        assert (before.triangle_count, before.light_count, before.mesh_count) == counts

        # Editing the geometry: that one mesh, and only it, is read again (into a new core scene).
        sphere = bpy.data.objects["GlassSphere"]
        sphere.data.vertices[0].co.x += 0.01
        sphere.data.update()
        reports = updates.evaluate()
        assert sync.mesh_exports == meshes + 1 and any(r.rebuilt for r in reports)
        assert (sync.scene.mesh_count, sync.scene.light_count) == (3, 1)


def test_moved_object_moves_its_instance_only(caustics_scene, core):
    recording = RecordingCore(core)
    sync = export.BlenderSync(recording)
    sync.sync(bpy.context.evaluated_depsgraph_get())
    scene, meshes = sync.scene, sync.mesh_exports
    calls_before = list(recording.scenes[0].calls)
    with DepsgraphUpdates(sync, release=lambda: True) as updates:
        bpy.data.objects["GlassSphere"].location.x += 0.1
        reports = updates.evaluate()
    assert sum(r.moved for r in reports) == 1 and not any(r.rebuilt or r.meshes for r in reports)
    assert sync.scene is scene and len(recording.scenes) == 1 and sync.mesh_exports == meshes
    new_calls = recording.scenes[0].calls[len(calls_before):]
    assert new_calls.count("set_instance_transform") == 1
    assert not {"add_mesh_data", "add_instance", "add_mesh", "add_material"} & set(new_calls)


def test_added_and_removed_objects_rebuild_from_kept_meshes(caustics_scene, core):
    """A linked duplicate is one more instance of the same core mesh; deleting it drops the instance again."""
    sync = export.BlenderSync(core)
    sync.sync(bpy.context.evaluated_depsgraph_get())
    meshes, instances = sync.meshes, sync.instances
    sphere = bpy.data.objects["GlassSphere"]
    with DepsgraphUpdates(sync, release=lambda: True) as updates:
        twin = bpy.data.objects.new("Twin", sphere.data)
        twin.location = (sphere.location.x + 0.5, sphere.location.y, sphere.location.z)
        bpy.context.scene.collection.objects.link(twin)
        reports = updates.evaluate()
        assert any(r.rebuilt for r in reports)
        assert (sync.meshes, sync.instances) == (meshes, instances + 1)
        bpy.data.objects.remove(twin)
        reports = updates.evaluate()
        assert any(r.rebuilt for r in reports)
        assert (sync.meshes, sync.instances) == (meshes, instances)


def test_busy_scene_is_rebuilt_not_changed(caustics_scene, core):
    """When the running render does not release the scene in time, a new scene is built (from kept arrays:
    no mesh read) and the old one is left untouched for the render still using it."""
    recording = RecordingCore(core)
    sync = export.BlenderSync(recording)
    sync.sync(bpy.context.evaluated_depsgraph_get())
    old, meshes = sync.scene, sync.mesh_exports
    with DepsgraphUpdates(sync, release=lambda: False) as updates:
        bpy.data.objects["Light"].location.x += 0.2
        reports = updates.evaluate()
    assert any(r.rebuilt for r in reports) and sync.scene is not old and sync.mesh_exports == meshes
    assert recording.scenes[0].calls.count("clear_lights") == 0


def test_moved_object_renders_as_a_fresh_export(caustics_scene, core):
    """After a transform-only update (top-level BVH refit in the kept scene), the render equals that of a
    scene exported afresh from the moved objects, same seed, 40×40 pixels, one thread. Tolerance: 1e-4 per pixel
    and channel (a refitted and a fresh BVH could order equal-distance hits differently)."""
    sync = export.BlenderSync(core)
    sync.sync(bpy.context.evaluated_depsgraph_get())
    camera = viewport_camera(core, bpy.context.scene, 40, 40)
    settings = core.RenderSettings(photons=5_000, seed=3, threads=1)
    before, _ = core.render(sync.scene, camera, settings)     # builds the BVH, so the move is a refit
    with DepsgraphUpdates(sync, release=lambda: True) as updates:
        bpy.data.objects["GlassSphere"].location.x += 0.15
        bpy.data.objects["MirrorSphere"].location.y -= 0.1
        reports = updates.evaluate()
    assert sum(r.moved for r in reports) == 2 and not any(r.rebuilt for r in reports)
    moved, _ = core.render(sync.scene, camera, settings)
    fresh = export.export_frame(core, bpy.context.evaluated_depsgraph_get()).scene
    expected, _ = core.render(fresh, camera, settings)
    moved, expected, before = (np.asarray(a, dtype=np.float64) for a in (moved, expected, before))
    difference = np.abs(moved - expected).max()
    print(f"\nmoved vs fresh export: max |diff| {difference:.2e}; "
          f"moved vs before the move: mean |diff| {np.abs(moved - before).mean():.2e}")
    assert difference <= 1e-4
    assert np.abs(moved - before).mean() > 100 * max(difference, 1e-6)   # the move itself shows


def test_thousand_geometry_node_instances_are_one_core_mesh(empty_scene, core):
    from blender_helpers import uniform_world
    from test_translation import add_camera, points_grid_with_instances
    grid = points_grid_with_instances(25, 40)
    add_camera(empty_scene, location=(0.0, 0.0, 30.0))
    uniform_world(empty_scene)
    recording = RecordingCore(core)
    sync = export.BlenderSync(recording)
    report = sync.sync(bpy.context.evaluated_depsgraph_get())
    # Two meshes read from Blender: the sphere (once for 1000 instances) and the grid's own evaluated mesh,
    # which has no faces left (the points became instances) and so is no core mesh.
    assert report.meshes == 2 and sync.mesh_exports == 2
    assert (sync.meshes, sync.instances) == (1, 1000)
    assert sync.scene.stored_triangle_count == 320 and sync.scene.triangle_count == 320_000
    # Moving the instancer moves the 1000 instances in place: no mesh read, no new scene.
    with DepsgraphUpdates(sync, release=lambda: True) as updates:
        grid.location.z += 1.0
        reports = updates.evaluate()
    assert sum(r.moved for r in reports) == 1000 and not any(r.rebuilt for r in reports)
    assert sync.mesh_exports == 2 and len(recording.scenes) == 1
    assert recording.calls("add_mesh_data") == 1 and recording.calls("set_instance_transform") == 1000


class FakeEngine:
    """What ViewportSession needs of a RenderEngine outside view_draw: redraw requests (counted), reports."""

    def __init__(self):
        self.redraws = 0
        self.reports = []

    def tag_redraw(self):
        self.redraws += 1

    def report(self, kind, message):
        self.reports.append(message)


def test_viewport_reports_the_notes_of_a_final_render(empty_scene, core):
    """One sync, one list of notes: an unsupported object and a scene without light are reported by the viewport
    as the final render reports them, once until they change."""
    from test_translation import add_camera
    add_camera(empty_scene)
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    empty_scene.collection.objects.link(bpy.data.objects.new("Fog", bpy.data.volumes.new("Fog")))
    session = viewport.ViewportSession(core)
    engine = FakeEngine()
    session.update(engine, bpy.context.evaluated_depsgraph_get())
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    assert any("volume objects are not supported" in w for w in frame.warnings)
    assert any("no lights" in w for w in frame.warnings)
    assert session.warnings == frame.warnings
    assert engine.reports == export.warning_lines(frame.warnings)
    session.update(engine, bpy.context.evaluated_depsgraph_get())
    assert engine.reports == export.warning_lines(frame.warnings)      # unchanged: not reported again
    session.stop()


def test_session_stops_its_refinement_before_moving_an_instance(caustics_scene, core):
    """view_update with a refinement running: the session stops it (joins) before the sync changes the
    core scene in place, then starts a new one on the same, updated scene."""
    session = viewport.ViewportSession(core)
    engine = FakeEngine()
    session.update(engine, bpy.context.evaluated_depsgraph_get())
    cam = bpy.context.scene.camera
    session._view = (None, None, 48, 48)
    session._make_camera = viewport.view_camera_factory(
        core, cam.matrix_world.normalized().inverted(),
        cam.calc_matrix_camera(bpy.context.evaluated_depsgraph_get(), x=48, y=48))
    session.settings = replace(session.settings, photons_per_iteration=2_000_000, max_iterations=0, time_limit=0.0)
    session.restart()
    first, scene = session.refinement, session.scene
    time.sleep(0.3)                                    # inside a long pass
    assert first.running

    def handler(_scene, depsgraph):
        session.update(engine, depsgraph)
    bpy.app.handlers.depsgraph_update_post.append(handler)
    try:
        bpy.data.objects["GlassSphere"].location.x += 0.1
        bpy.context.view_layer.update()
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(handler)
    try:
        assert not first.running                       # joined before set_instance_transform
        assert session.last_sync.moved == 1 and not session.last_sync.rebuilt
        assert session.scene is scene and session.refinement is not first and session.refinement.running
    finally:
        session.stop()
        assert session.join(5.0)


def test_moved_light_changes_the_rendered_image(caustics_scene, core):
    sync = export.BlenderSync(core)
    sync.sync(bpy.context.evaluated_depsgraph_get())
    camera = viewport_camera(core, bpy.context.scene, 48, 48)
    settings = core.RenderSettings(photons=5_000, seed=1)
    first, _ = core.render(sync.scene, camera, settings)
    with DepsgraphUpdates(sync, release=lambda: True) as updates:
        bpy.data.objects["Light"].location.x += 0.5
        updates.evaluate()
    second, _ = core.render(sync.scene, camera, settings)
    assert np.abs(np.asarray(first) - np.asarray(second)).max() > 0.01


def viewport_camera(core, scene, width, height):
    """A camera as a viewport looking through the scene camera would make it (view and window matrices)."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    cam = scene.camera
    view = cam.matrix_world.normalized().inverted()
    window = cam.calc_matrix_camera(depsgraph, x=width, y=height)
    return viewport.view_camera_factory(core, view, window)(width, height)


def refinement_for(core, width=48, height=48, **limits):
    sync = export.BlenderSync(core)
    sync.sync(bpy.context.evaluated_depsgraph_get())
    scene = bpy.context.scene
    settings = viewport.refine_settings(core, scene)
    settings = replace(settings, **limits)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    cam = scene.camera
    make_camera = viewport.view_camera_factory(core, cam.matrix_world.normalized().inverted(),
                                               cam.calc_matrix_camera(depsgraph, x=width, y=height))
    frames = []
    return refine.Refinement(core, sync.scene, make_camera, width, height, settings,
                             on_frame=frames.append), frames


def test_refinement_first_image_then_averaged_iterations(caustics_scene, core):
    job, frames = refinement_for(core, preview_photons=2_000, preview_divider=4, photons_per_iteration=5_000,
                                 max_iterations=4, time_limit=0.0)
    job.start()
    assert job.join(60.0), "the refinement did not finish its 4 iterations"
    assert job.error is None and job.finished
    assert [f.iterations for f in frames] == [0, 1, 2, 3, 4]
    assert frames[0].pixels.shape == (12, 12, 4)                  # the fast first image: 1/4 resolution
    assert all(f.pixels.shape == (48, 48, 4) for f in frames[1:])
    assert all(np.isfinite(f.pixels).all() and f.pixels[..., :3].mean() > 0.01 for f in frames)
    assert job.first_image_seconds is not None and job.first_image_seconds <= frames[1].seconds
    # Averaging independent iterations: iteration-to-iteration changes shrink (noise falls as 1/n).
    steps = [np.abs(frames[i + 1].pixels - frames[i].pixels).mean() for i in range(1, 4)]
    assert steps[2] < steps[0]


def test_viewport_asks_the_film_for_combined_alone(caustics_scene, core):
    # The viewport shows one image: its progressive sums hold combined only (32 bytes a pixel, test_film.py).
    render = viewport.refine_settings(core, caustics_scene).render
    assert core.RenderSettings(**render).outputs == ("combined",)
    assert not core.RenderSettings(**render).caustics_pass


def test_refinement_stops_quickly_when_asked(caustics_scene, core):
    job, frames = refinement_for(core, 96, 96, preview_photons=2_000, photons_per_iteration=2_000_000,
                                 max_iterations=0, time_limit=0.0)
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
    job, frames = refinement_for(core, 96, 96, preview_photons=2_000, photons_per_iteration=2_000_000,
                                 max_iterations=0, time_limit=0.0)

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
