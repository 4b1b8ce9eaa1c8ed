"""The 3D viewport in Rendered shading: what RenderEngine.view_update / view_draw do for Photon Splat.

Both run on Blender's main thread, so neither may wait on the core:
  - view_update (a depsgraph change) updates the core scene through the sync the final render uses too
    (export/sync.py, kept between updates: only what changed is read from Blender; moved objects and lights are
    changed in the existing core scene once the running refinement has stopped) and restarts the refinement;
  - view_draw compares the view (matrices, region size) with the one being rendered, restarts the refinement
    when it changed (navigation produces no view_update), and draws the newest image it has.
The rendering itself runs in refine.Refinement's thread; it asks Blender for a redraw after every image.
Every session is listed here so that unregistering the add-on or loading a file stops all of them.
"""

import collections
import time
import weakref

import bpy
import gpu
import numpy as np
from gpu_extras.presets import draw_texture_2d

from . import export, refine

_sessions = weakref.WeakSet()

# Longest wait on Blender's main thread for a refinement to stop before its scene is changed in place (a
# cancelled pass ends within ~25 ms, one progress poll; an Embree build in progress may take longer, then a new
# scene is built).
RELEASE_WAIT = 0.5


def stop_all(wait=1.0):
    """Stops every viewport's rendering (add-on unregistered, file loaded); waits up to `wait` s in total."""
    deadline = time.perf_counter() + wait
    sessions = list(_sessions)
    for session in sessions:
        session.stop()
    for session in sessions:
        session.join(max(0.0, deadline - time.perf_counter()))


def refine_settings(core, scene):
    """scene.photonsplat -> RefineSettings of the viewport (read on the main thread; the worker gets a copy).
    The render fields are the final render's, but for the photon count and the film, of which the viewport shows
    only the combined image; the refinement sets its own iterations and time limit."""
    props = scene.photonsplat
    render = dict(export.render_settings_kwargs(props), photons=props.viewport_photons, iterations=1,
                  time_limit=0.0, outputs=("combined",), transparent=scene.render.film_transparent)
    core.RenderSettings(**render)       # validate now: a bad value is reported, not raised in the thread
    return refine.RefineSettings(render=render, preview_photons=props.viewport_preview_photons,
                                 preview_divider=props.viewport_preview_divider,
                                 photons_per_iteration=props.viewport_photons, max_iterations=props.viewport_iterations,
                                 time_limit=props.viewport_time_limit)


def view_key(region, region_data):
    """What the image depends on in the view: both matrices and the region's size."""
    return (tuple(v for row in region_data.view_matrix for v in row),
            tuple(v for row in region_data.window_matrix for v in row),
            region.width, region.height)


def view_camera_factory(core, view_matrix, window_matrix):
    """make_camera(width, height) for the viewport's current view: the viewport's own projection, so the image
    covers the region exactly whatever its resolution (first image at a fraction of it, then full)."""
    to_world = np.array(view_matrix.inverted(), dtype=np.float64)
    projection = np.array(window_matrix, dtype=np.float64)

    def make_camera(width, height):
        return core.Camera(to_world=to_world, projection=projection, width=width, height=height)
    return make_camera


class ViewportSession:
    """State of one Rendered viewport: the sync, the core scene, the running refinement, the texture."""

    def __init__(self, core):
        self.core = core
        self.sync = export.BlenderSync(core)
        self.scene = None             # core Scene kept up to date by the sync
        self.warnings = []            # the sync's notes, reported when they change
        self.settings = None
        self.refinement = None
        self.error = None
        self.last_sync = None         # SyncReport of the last view_update
        self.release_seconds = 0.0    # main-thread wait for the refinement to stop, last in-place update
        self._view = None
        self._make_camera = None
        self._texture = None
        self._texture_version = None
        self._engine = None
        self.restarts = 0             # refinements started so far (numbers them)
        # (time.perf_counter(), restart number, iterations) each time view_draw shows a new image: how long a
        # change takes to reach the screen (tools/viewport_timing.py reads it).
        self.draw_log = collections.deque(maxlen=1024)
        _sessions.add(self)

    # --- view_update ------------------------------------------------------------------------------------
    def update(self, engine, depsgraph):
        self._engine = weakref.ref(engine)
        try:
            settings = refine_settings(self.core, depsgraph.scene)
            self.last_sync = self.sync.sync(depsgraph, release=self._release_scene)
            # (A refinement stopped for an in-place change is restarted even if the change showed nothing.)
            changed = (self.last_sync.changed or self.scene is None or settings != self.settings
                       or self.refinement is None)
            self.settings = settings
            self.scene = self.sync.scene
            self.error = None
            self._report_warnings(engine)
        except (ValueError, export.ExportError) as error:
            self.error = str(error)
            self.scene = None
            changed = True
        if changed:               # selection and other changes that do not show restart nothing
            self.restart()

    def _report_warnings(self, engine):
        """The sync's notes, reported as the final render reports them, each time they change."""
        if self.sync.notes != self.warnings:
            self.warnings = list(self.sync.notes)
            for line in export.warning_lines(self.warnings):
                engine.report({'WARNING'}, line)

    def _release_scene(self):
        """Before the sync changes the core scene in place (moved objects, lights): the running refinement
        must be done with it. Stops it and waits up to RELEASE_WAIT s on the main thread (a pass polls its
        cancel flag every 25 ms); False when it is still running, and the sync builds a new scene."""
        self.release_seconds = 0.0
        if self.refinement is None:
            return True
        started = time.perf_counter()
        self.refinement.stop()
        stopped = self.refinement.join(RELEASE_WAIT)
        self.release_seconds = time.perf_counter() - started
        if stopped:
            self.refinement = None
        return stopped

    # --- view_draw --------------------------------------------------------------------------------------
    def draw(self, engine, context, depsgraph):
        region, region_data = context.region, context.region_data
        key = view_key(region, region_data)
        if key != self._view:
            self._view = key
            self._make_camera = view_camera_factory(self.core, region_data.view_matrix, region_data.window_matrix)
            self.restart()
        self._status(engine)
        frame = self.refinement.latest() if self.refinement else None
        if frame is not None and self._texture_version != (self.restarts, frame.version):
            height, width = frame.pixels.shape[:2]
            buffer = gpu.types.Buffer('FLOAT', width * height * 4, frame.pixels.reshape(-1))
            self._texture = gpu.types.GPUTexture((width, height), format='RGBA16F', data=buffer)
            self._texture_version = (self.restarts, frame.version)
            self.draw_log.append((time.perf_counter(), self.restarts, frame.iterations))
        if self._texture is None:
            return
        # Until the first image of a restarted refinement arrives, the previous image stays on screen.
        # Linear, premultiplied pixels: Blender's display transform (view transform, look, exposure) is applied
        # through the display-space shader, as for Cycles.
        gpu.state.blend_set('ALPHA_PREMULT')
        engine.bind_display_space_shader(depsgraph.scene)
        draw_texture_2d(self._texture, (0, 0), region.width, region.height)
        engine.unbind_display_space_shader()
        gpu.state.blend_set('NONE')

    def _status(self, engine):
        text = self._status_text()
        if text is not None:
            # A viewport's reports reach only the console: the status line says that there are some.
            count = len(self.warnings) if not self.error else 0
            engine.update_stats("", f"Photon Splat | {text}" + (f" | {count} warnings" if count else ""))

    def _status_text(self):
        if self.error:
            return f"Error: {self.error}"
        refinement = self.refinement
        if refinement is None:
            return None
        if refinement.error:
            return f"Error: {refinement.error}"
        frame = refinement.latest()
        if frame is None:
            return "Rendering first image"
        if refinement.finished:
            return f"Done: {frame.iterations} iterations, {frame.seconds:.1f} s"
        limit = f"/{self.settings.max_iterations}" if self.settings.max_iterations else ""
        return f"Iteration {frame.iterations}{limit} | {frame.seconds:.1f} s"

    # --- the background work ----------------------------------------------------------------------------
    def restart(self):
        """Stops the current refinement (without waiting) and starts one for the current scene and view."""
        if self.refinement is not None:
            self.refinement.stop()
        self.refinement = None
        if self.scene is None or self._make_camera is None or self.settings is None:
            return
        width, height = self._view[2], self._view[3]
        self.restarts += 1
        self.refinement = refine.Refinement(self.core, self.scene, self._make_camera, width, height,
                                            self.settings, on_frame=self._redraw).start()

    def _redraw(self, frame):
        """From the refinement thread: ask Blender to call view_draw (it checks the flag on its main loop)."""
        engine = self._engine() if self._engine else None
        if engine is None:
            return
        try:
            engine.tag_redraw()
        except ReferenceError:        # the viewport closed meanwhile
            pass

    def stop(self):
        if self.refinement is not None:
            self.refinement.stop()

    def join(self, timeout):
        return self.refinement.join(timeout) if self.refinement is not None else True


@bpy.app.handlers.persistent
def _on_load_pre(*_args):
    stop_all()


def register():
    bpy.app.handlers.load_pre.append(_on_load_pre)


def unregister():
    if _on_load_pre in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(_on_load_pre)
    stop_all()
