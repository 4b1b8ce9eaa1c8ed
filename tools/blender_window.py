"""Driving a real Blender window from a --python script (under Xvfb): the shared part of the window test
(tests/window/viewport_window.py) and of the viewport timing tool (tools/viewport_timing.py).

Blender runs a --python script before its event loop starts, so everything that needs the window happens in
steps: run_steps(generator) calls the generator from a timer on Blender's main loop; each `yield seconds`
lets Blender run (draw, handle events) for that long. The script ends the process itself with finish(code),
after writing its results, so that the caller gets a plain exit status.
"""

import os
import sys
import time
import traceback

import bpy
import numpy as np


def run_steps(steps, timeout):
    """Run generator `steps` on Blender's main loop; a step that raises, or a run longer than `timeout` s,
    ends Blender with status 1."""
    started = time.perf_counter()

    def tick():
        if time.perf_counter() - started > timeout:
            print(f"blender_window: timed out after {timeout} s", file=sys.stderr)
            finish(1)
        try:
            delay = next(steps)
        except StopIteration:
            finish(0)
        except Exception:
            traceback.print_exc()
            finish(1)
        return max(float(delay), 0.01)

    bpy.app.timers.register(tick, first_interval=0.5)


def finish(code):
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)          # from a timer, the only reliable way to leave Blender with a status


def view3d():
    """(window, area, region, space) of the largest 3D viewport."""
    best = None
    for window in bpy.context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == 'VIEW_3D' and (best is None or area.width * area.height > best[1].width * best[1].height):
                best = (window, area)
    if best is None:
        raise RuntimeError("no 3D viewport in the window")
    window, area = best
    region = next(r for r in area.regions if r.type == 'WINDOW')
    return window, area, region, area.spaces.active


def rendered_through_camera(space, overlays=False):
    """Rendered shading, looking through the scene camera, without overlays (grid, outlines) on top."""
    space.shading.type = 'RENDERED'
    space.region_3d.view_perspective = 'CAMERA'
    space.overlay.show_overlays = overlays
    space.show_gizmo = overlays


def session():
    """The newest Photon Splat viewport session (photonsplat.viewport keeps them)."""
    from photonsplat import viewport
    sessions = sorted(viewport._sessions, key=lambda s: s.restarts)
    return sessions[-1] if sessions else None


def screenshot_area(window, area, path):
    """PNG of the area as shown on screen; returns it as float (height, width, 3) in [0, 1], row 0 at the TOP."""
    with bpy.context.temp_override(window=window, area=area):
        bpy.ops.screen.screenshot_area(filepath=str(path))
    image = bpy.data.images.load(str(path), check_existing=False)
    try:
        width, height = image.size
        pixels = np.empty(width * height * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
        return pixels.reshape(height, width, 4)[::-1, :, :3]
    finally:
        bpy.data.images.remove(image)


def screenshot_window(window, path):
    with bpy.context.temp_override(window=window):
        bpy.ops.screen.screenshot(filepath=str(path))


def region_pixels(region, region_data, points):
    """Pixel (column, row-from-top) in the region of each world point; None where behind the viewer or off
    the region."""
    matrix = np.array(region_data.perspective_matrix, dtype=np.float64)
    out = []
    for p in points:
        clip = matrix @ np.array([p[0], p[1], p[2], 1.0])
        if clip[3] <= 0.0:
            out.append(None)
            continue
        x = (clip[0] / clip[3] * 0.5 + 0.5) * region.width
        y = (clip[1] / clip[3] * 0.5 + 0.5) * region.height
        if 0 <= x < region.width and 0 <= y < region.height:
            out.append((int(x), region.height - 1 - int(y)))
        else:
            out.append(None)
    return out
