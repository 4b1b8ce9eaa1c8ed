"""The Photon Splat render engine as Blender sees it: F12 / `blender -b ... -E PHOTONSPLAT -f 1`.

Kept thin on purpose: export/ converts the scene, the native core renders it, and this file only moves
pixels, progress and messages between the two. Rules of Blender 3.4 that shape it:
  - end_result() must run whatever happens (an exception with an open result crashes Blender when the
    image is written), hence the try/finally;
  - no exception may escape render(): errors become self.report({'ERROR'}, ...) + error_set();
  - the core releases the GIL while it works and calls our progress callback on this thread, which is where
    Blender calls (update_progress, test_break) are allowed.
"""

import importlib
import sys
import time
import traceback
from dataclasses import dataclass, field

import bpy
import numpy as np

from . import compat, export, passes

class CoreUnavailable(Exception):
    """The compiled module (photonsplat._core) is missing or failed to load."""


def load_core():
    """The compiled core module; raises CoreUnavailable with a readable reason."""
    package = sys.modules[__package__]
    # The package tried the import already; it keeps the reason when that failed.
    reason = getattr(package, "CORE_IMPORT_ERROR", None)
    if reason is None:
        try:
            return importlib.import_module("._core", __package__)
        except Exception as error:  # any failure to load is reported the same way
            reason = f"the native module photonsplat._core could not be loaded: {error}"
    if __package__.startswith("bl_ext."):     # installed as a Blender 4.2+ extension
        advice = (f"The extension's module is built for Python 3.11 on x86-64 Linux with glibc 2.34 or later; this "
                  f"Blender's Python is {sys.version_info.major}.{sys.version_info.minor}")
    else:
        advice = "Build the project (see README) and use the add-on laid out in build/blender/addons"
    raise CoreUnavailable(f"{reason}. {advice}")


@dataclass
class RenderOutcome:
    """What the last final render did: bpy.ops.render.render() only returns {'FINISHED'}, so scripts and
    tests read this instead (engine.last_outcome)."""
    status: str = "none"        # "finished" | "cancelled" | "failed"
    message: str = ""
    warnings: list = field(default_factory=list)
    stats: dict = field(default_factory=dict)
    seconds: float = 0.0
    passes: list = field(default_factory=list)   # names of the passes written


last_outcome = RenderOutcome()


class PhotonSplatRenderEngine(bpy.types.RenderEngine):
    bl_idname = "PHOTONSPLAT"
    bl_label = "Photon Splat"
    # Material/world/light preview thumbnails stay off on purpose: Blender 3.4 re-renders them in a job on every
    # edit and for every thumbnail, and each would be a full photon render of the preview .blend (whose checker
    # floor and world we only approximate, with notes). The Material Preview shading mode uses EEVEE
    # (bl_use_eevee_viewport). See docs/translation.md.
    bl_use_preview = False
    bl_use_eevee_viewport = True         # Material Preview stays EEVEE
    bl_use_shading_nodes_custom = False  # keep Cycles' shader nodes and the Shader Editor
    bl_use_postprocess = True            # let the compositor run on our result

    # --- viewport (Rendered shading): viewport.py does the work, off the main thread ----------------------
    _viewport = None

    def view_update(self, context, depsgraph):
        try:
            if self._viewport is None:
                from . import viewport
                self._viewport = viewport.ViewportSession(load_core())
            self._viewport.update(self, depsgraph)
        except CoreUnavailable as error:
            self.update_stats("", f"Photon Splat | {error}")
        except Exception:            # never into Blender's draw loop
            traceback.print_exc()

    def view_draw(self, context, depsgraph):
        if self._viewport is None:
            return
        try:
            self._viewport.draw(self, context, depsgraph)
        except Exception:
            traceback.print_exc()

    def __del__(self):
        # Blender frees the engine when the viewport leaves Rendered mode or closes: stop its rendering.
        viewport = getattr(self, "_viewport", None)
        if viewport is not None:
            viewport.stop()

    # --- final render ---------------------------------------------------------------------------------------
    def update_render_passes(self, scene=None, renderlayer=None):
        passes.register_passes(self, scene, renderlayer)

    def render(self, depsgraph):
        global last_outcome
        started = time.perf_counter()
        # The whole frame: with a render border Blender hands back a result of the border's size only.
        width, height = export.camera.resolution(depsgraph.scene)
        result = self.begin_result(0, 0, width, height, layer=depsgraph.view_layer.name)
        outcome = RenderOutcome()
        try:
            self._render_into(result, depsgraph, outcome)
        except Exception as error:
            outcome.status = "failed"
            outcome.message = _describe(error)
            if not isinstance(error, (export.ExportError, CoreUnavailable, ValueError)):
                traceback.print_exc()      # unexpected: keep the traceback for the console / bug reports
            self.report({'ERROR'}, f"Photon Splat: {outcome.message}")
            self.error_set(outcome.message)
        finally:
            self.end_result(result, cancel=outcome.status == "cancelled")
            outcome.seconds = time.perf_counter() - started
            last_outcome = outcome

    def _render_into(self, result, depsgraph, outcome):
        core = load_core()
        self.update_stats("", "Photon Splat | Exporting scene")
        frame = export.export_frame(core, depsgraph, camera_override=self.camera_override)
        view_layer = depsgraph.view_layer
        frame.settings.transparent = depsgraph.scene.render.film_transparent
        frame.settings.caustics_pass = view_layer.photonsplat.use_pass_caustics
        frame.settings.outputs = passes.film_outputs(view_layer)
        outcome.warnings = frame.warnings
        for line in export.warning_lines(frame.warnings):
            self.report({'WARNING'}, line)
        if self._cancel_requested():
            self._cancelled(outcome)
            return

        def on_progress(stage, fraction):
            self.update_progress(min(max(float(fraction), 0.0), 1.0))
            self.update_stats("", f"Photon Splat | {stage} {100.0 * fraction:.0f}%")
            return self._cancel_requested()

        components = None
        try:
            image, stats, components = self._render_passes(core, frame, result, on_progress,
                                                           passes.needs_components(view_layer))
        except core.Cancelled:
            self._cancelled(outcome)
            return

        _write_pixels(result, frame, image)
        outcome.passes = ["Combined", *passes.write_passes(result.layers[0], components, frame.width, frame.height)]
        outcome.status = "finished"
        outcome.stats = stats
        outcome.message = _summary(frame, stats, depsgraph.scene.photonsplat.photons)
        self.update_progress(1.0)
        self.update_stats("", f"Photon Splat | {outcome.message}")

    def _render_passes(self, core, frame, result, on_progress, components):
        """(image, stats, per-pass images or None). One iteration: core.render. Progressive (iterations != 1):
        one iteration at a time, the running mean shown after each; Esc after the first iteration keeps the mean
        so far (stats values 'cancelled' = 1). `components`: whether the render passes beyond Combined are
        wanted."""
        _check_result_size(result, frame)
        if frame.settings.iterations == 1:
            if components:
                return core.render(frame.scene, frame.camera, frame.settings, progress=on_progress, passes=True)
            return (*core.render(frame.scene, frame.camera, frame.settings, progress=on_progress), None)
        progressive = core.Progressive(frame.scene, frame.camera, frame.settings)
        cancelled = False
        while not progressive.finished and not cancelled:
            try:
                progressive.step(progress=on_progress)
            except core.Cancelled:
                if progressive.iterations_done == 0:
                    raise
                cancelled = True
            else:
                _write_pixels(result, frame, progressive.image())
                self.update_result(result)
                # An iteration shorter than the core's progress poll (25 ms) never asks: ask between them too.
                cancelled = self._cancel_requested()
        stats = progressive.stats()
        if cancelled:
            stats["values"]["cancelled"] = 1.0
        return progressive.image(), stats, progressive.passes() if components else None

    def _cancel_requested(self):
        """True once the user pressed Esc. (A separate method so tests can simulate Esc: Blender looks up
        test_break itself on the C side, so it cannot be replaced from Python.)"""
        return self.test_break()

    def _cancelled(self, outcome):
        outcome.status = "cancelled"
        outcome.message = "render cancelled"
        self.update_stats("", "Photon Splat | Cancelled")
        self.report({'WARNING'}, "Photon Splat: render cancelled")


def _describe(error):
    """One-line message for the user; the exception type only where the message alone would be cryptic."""
    text = str(error).strip() or type(error).__name__
    if isinstance(error, (export.ExportError, CoreUnavailable, ValueError)):
        return text
    return f"{type(error).__name__}: {text}"


def _check_result_size(result, frame):
    combined = result.layers[0].passes["Combined"]
    if len(combined.rect) != frame.width * frame.height:
        raise RuntimeError(f"Blender's result holds {len(combined.rect)} pixels, the render "
                           f"{frame.width}x{frame.height}: the render border was read differently")


def _write_pixels(result, frame, image):
    image = np.asarray(image, dtype=np.float32)
    if image.shape != (frame.height, frame.width, 4):
        raise RuntimeError(f"the core returned an image of shape {image.shape}, "
                           f"expected {(frame.height, frame.width, 4)}")
    # The core's row 0 is the top of the image; Blender's is the bottom.
    pixels = np.ascontiguousarray(image[::-1].reshape(-1, 4))
    compat.write_pass_pixels(result.layers[0].passes["Combined"], pixels)


def _summary(frame, stats, photons):
    """The line shown in the status bar after a render: photons, scene size, radius used, time."""
    seconds, values = stats.get("seconds", {}), stats.get("values", {})
    total = seconds.get("total", sum(seconds.values()))
    text = f"{photons:,} photons | {frame.triangles:,} triangles | {frame.lights} lights"
    if "radius" in values:
        text += f" | radius {values['radius']:.4g}"
    iterations = int(values.get("iterations", 1))
    if iterations != 1 or frame.settings.iterations != 1:
        text += f" | {iterations} iterations" + (" (stopped by Esc)" if values.get("cancelled") else "")
        if "final_radius" in values:
            text += f", final radius {values['final_radius']:.4g}"
    return text + f" | {total:.2f} s"


def register():
    from . import viewport
    bpy.utils.register_class(PhotonSplatRenderEngine)
    viewport.register()


def unregister():
    from . import viewport
    viewport.unregister()        # stops every viewport's thread before the class goes
    bpy.utils.unregister_class(PhotonSplatRenderEngine)
