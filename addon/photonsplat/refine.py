"""Progressive refinement of one view, on a background thread: a fast first image, then photon iterations averaged
until a pass count or time limit. No bpy here: Blender's viewport (viewport.py) and the tests drive it alike.

The native calls release the GIL, so Blender's UI keeps running while a pass renders. Stopping never blocks:
stop() raises a flag that the core's progress callback returns (polled every 25 ms), the pass raises
Cancelled and the thread ends by itself; a restarted view simply starts a new Refinement.
"""

import threading
import time
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class RefineSettings:
    render: dict                 # core RenderSettings fields (photons, iterations and time_limit set here)
    preview_photons: int = 20_000
    preview_divider: int = 4     # the first image is rendered at 1/divider of the resolution
    photons_per_iteration: int = 100_000
    max_iterations: int = 32         # 0 = no limit
    time_limit: float = 30.0     # seconds; 0 = no limit


@dataclass(frozen=True)
class Frame:
    """One image to show. pixels: float32 (height, width, 4) linear premultiplied RGBA, row 0 at the BOTTOM
    (what a GPU texture wants)."""
    pixels: np.ndarray
    iterations: int      # refinement iterations averaged in; 0 = the fast first image
    seconds: float       # since the refinement started (i.e. since the change that caused it)
    version: int         # increases with every new frame


def first_image(core, scene, camera, settings, progress):
    """The fast image answering a change: few photons, one pass (the caller gives a reduced-size camera)."""
    fields = dict(settings.render, photons=settings.preview_photons, iterations=1, time_limit=0.0)
    image, _ = core.render(scene, camera, core.RenderSettings(**fields), progress=progress)
    return np.asarray(image, dtype=np.float32)


# The core's own bound on progressive iterations (RenderSettings.iterations); our loop stops by itself before it.
MAX_CORE_ITERATIONS = 1_000_000


def refined_images(core, scene, camera, settings, progress):
    """Yields the running mean after each refinement pass, forever (the caller stops): the core's progressive
    render, whose iterations trace new photons with a shrinking radius, so the mean converges to the exact image."""
    fields = dict(settings.render, photons=settings.photons_per_iteration, time_limit=0.0,
                  iterations=settings.max_iterations or MAX_CORE_ITERATIONS)
    progressive = core.Progressive(scene, camera, core.RenderSettings(**fields))
    while True:
        progressive.step(progress=progress)
        yield np.asarray(progressive.image(), dtype=np.float32)


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

    def _publish(self, pixels, iterations):
        with self._lock:
            version = 1 + (self._latest.version if self._latest else 0)
            self._latest = Frame(pixels=pixels, iterations=iterations, seconds=time.perf_counter() - self._started,
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
            camera = self._make_camera(max(1, width // divider), max(1, height // divider))
            image = first_image(core, self._scene, camera, settings, self._cancel_requested)
            self.first_image_seconds = time.perf_counter() - self._started
            self._publish(np.ascontiguousarray(image[::-1]), 0)

            camera = self._make_camera(width, height)
            done = 0
            for mean in refined_images(core, self._scene, camera, settings, self._cancel_requested):
                done += 1
                self._publish(np.ascontiguousarray(mean[::-1]), done)
                if self._stop.is_set() or (settings.max_iterations and done >= settings.max_iterations):
                    break
                if settings.time_limit and time.perf_counter() - self._started >= settings.time_limit:
                    break
            self.finished = not self._stop.is_set()
        except core.Cancelled:
            pass
        except Exception as error:  # shown in the viewport; the thread must not die silently
            self.error = f"{type(error).__name__}: {error}" if not isinstance(error, ValueError) else str(error)
