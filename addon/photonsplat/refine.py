"""Progressive refinement of one view, on a background thread: a fast first image, then photon passes averaged
until a pass count or time limit. No bpy here: Blender's viewport (viewport.py) and the tests drive it alike.

The native calls release the GIL, so Blender's UI keeps running while a pass renders. Stopping never blocks:
stop() raises a flag that the core's progress callback returns (polled ~10x a second), the pass raises
Cancelled and the thread ends by itself; a restarted view simply starts a new Refinement.
"""

import threading
import time
from dataclasses import dataclass, replace

import numpy as np


@dataclass(frozen=True)
class RefineSettings:
    render: dict                 # core RenderSettings fields of every pass (photons replaced per pass)
    preview_photons: int = 20_000
    preview_divider: int = 4     # the first image is rendered at 1/divider of the resolution
    photons_per_pass: int = 100_000
    max_passes: int = 32         # 0 = no limit
    time_limit: float = 30.0     # seconds; 0 = no limit


@dataclass(frozen=True)
class Frame:
    """One image to show. pixels: float32 (height, width, 4) linear premultiplied RGBA, row 0 at the BOTTOM
    (what a GPU texture wants)."""
    pixels: np.ndarray
    passes: int          # refinement passes averaged in; 0 = the fast first image
    seconds: float       # since the refinement started (i.e. since the change that caused it)
    version: int         # increases with every new frame


def photon_pass(core, scene, camera, settings, index, progress):
    """Renders refinement pass `index` (0, 1, ...) of a view: an independent image with its own random seed.
    The one place that knows how a pass is made, so a progressive core can replace it."""
    fields = dict(settings.render, photons=settings.photons_per_pass,
                  seed=settings.render.get("seed", 0) + 1 + index)
    image, _ = core.render(scene, camera, core.RenderSettings(**fields), progress=progress)
    return np.asarray(image, dtype=np.float32)


class Refinement:
    """Renders the view given by make_camera(width, height) of `scene` until the limits, on its own thread.

    `on_frame(frame)` is called from that thread after each image (the viewport asks Blender for a redraw there).
    """

    def __init__(self, core, scene, make_camera, width, height, settings, on_frame=None):
        self._core = core
        self._scene = scene
        self._make_camera = make_camera
        self._size = (int(width), int(height))
        self.settings = settings
        self._on_frame = on_frame
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._latest = None
        self.error = None              # text of what went wrong, for the viewport's status line
        self.finished = False          # reached its limits (not stopped)
        self.first_image_seconds = None
        self._thread = threading.Thread(target=self._run, name="photonsplat-viewport", daemon=True)

    def start(self):
        self._started = time.perf_counter()
        self._thread.start()
        return self

    def stop(self):
        """Asks the thread to end; returns at once."""
        self._stop.set()

    def join(self, timeout=None):
        self._thread.join(timeout)
        return not self._thread.is_alive()

    @property
    def running(self):
        return self._thread.is_alive()

    def latest(self):
        with self._lock:
            return self._latest

    def _cancel_requested(self, stage=None, fraction=None):
        return self._stop.is_set()

    def _publish(self, pixels, passes):
        with self._lock:
            version = 1 + (self._latest.version if self._latest else 0)
            self._latest = Frame(pixels=pixels, passes=passes, seconds=time.perf_counter() - self._started,
                                 version=version)
            frame = self._latest
        if self._on_frame is not None:
            self._on_frame(frame)

    def _run(self):
        core, settings = self._core, self.settings
        width, height = self._size
        try:
            # The first image: few photons at a fraction of the resolution, to answer the change at once.
            divider = max(1, settings.preview_divider)
            preview = replace(settings, photons_per_pass=settings.preview_photons)
            camera = self._make_camera(max(1, width // divider), max(1, height // divider))
            image = photon_pass(core, self._scene, camera, preview, -1, self._cancel_requested)
            self.first_image_seconds = time.perf_counter() - self._started
            self._publish(np.ascontiguousarray(image[::-1]), 0)

            camera = self._make_camera(width, height)
            total, done = None, 0
            while not self._stop.is_set():
                if settings.max_passes and done >= settings.max_passes:
                    break
                if settings.time_limit and time.perf_counter() - self._started >= settings.time_limit:
                    break
                image = photon_pass(core, self._scene, camera, settings, done, self._cancel_requested)
                total = image.astype(np.float64) if total is None else total + image
                done += 1
                self._publish(np.ascontiguousarray((total / done)[::-1], dtype=np.float32), done)
            self.finished = not self._stop.is_set()
        except core.Cancelled:
            pass
        except Exception as error:  # shown in the viewport; the thread must not die silently
            self.error = f"{type(error).__name__}: {error}" if not isinstance(error, ValueError) else str(error)
