"""Viewport responsiveness of Photon Splat in a real Blender window: after a light moves (then after an object
moves), how long until the first new image is on screen, and until the refined image (the viewport's pass
limit) is.

Drives Blender's own window under Xvfb (not the engine's Python API) because the figure users feel includes
what the API would skip: the depsgraph update reaching view_update, the scene-cache sync, the texture upload and
the redraw Blender schedules. Times are taken on Blender's main thread when view_draw uploads an image
(photonsplat.viewport.ViewportSession.draw_log), from just before the script moves the light.

    bash tools/viewport_timing.sh            # writes docs/results/viewport_timing.json and prints a summary

Settings measured: the defaults of scene.photonsplat (first image 20k photons at 1/4 resolution, refinement
iterations of 100k photons, 32 iterations or 30 s) except viewport_iterations, given by PHOTONSPLAT_REFINED_ITERATIONS (8).
"""

import json
import os
import statistics
import sys
import time
from pathlib import Path

import bpy

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tools"))
import blender_window as bw     # noqa: E402

MOVES = int(os.environ.get("PHOTONSPLAT_MOVES", "5"))
REFINED_ITERATIONS = int(os.environ.get("PHOTONSPLAT_REFINED_ITERATIONS", "8"))
OUTPUT = Path(os.environ.get("PHOTONSPLAT_TIMING_OUTPUT", REPO / "docs" / "results" / "viewport_timing.json"))


def wait_for(predicate, timeout):
    started = time.perf_counter()
    while not predicate():
        if time.perf_counter() - started > timeout:
            raise RuntimeError("timed out waiting for the viewport")
        yield 0.01


def drawn_after(session, moved_at, restart, iterations):
    """Time from moved_at to the first draw of `iterations` iterations of a refinement newer than `restart`."""
    for when, number, done in session.draw_log:
        if when >= moved_at and number > restart and done >= iterations:
            return when - moved_at
    return None


def measure_moves(session, ob, label):
    """Moves `ob` MOVES times by 5 cm along x; per move, the times to the first and to the refined image."""
    rows = []
    for move in range(MOVES):
        restart = session.restarts
        moved_at = time.perf_counter()
        ob.location.x += 0.05 if move % 2 == 0 else -0.05
        yield from wait_for(lambda: drawn_after(session, moved_at, restart, 0) is not None, 30)
        first = drawn_after(session, moved_at, restart, 0)
        yield from wait_for(lambda: drawn_after(session, moved_at, restart, REFINED_ITERATIONS) is not None, 120)
        refined = drawn_after(session, moved_at, restart, REFINED_ITERATIONS)
        sync = session.last_sync
        rows.append(dict(first_image_s=first, refined_s=refined, meshes_exported=sync.meshes,
                         lights_exported=sync.lights, instances_moved=sync.moved, scene_rebuilt=sync.rebuilt,
                         main_thread_wait_s=session.release_seconds))
        print(f"viewport_timing: {label} {move + 1}: first image {first * 1000:.0f} ms, "
              f"{REFINED_ITERATIONS} iterations {refined:.2f} s (meshes exported {sync.meshes}, lights {sync.lights}, "
              f"instances moved {sync.moved}, scene rebuilt {sync.rebuilt}, main thread waited "
              f"{session.release_seconds * 1000:.0f} ms for the refinement to stop)")
        yield 0.3
    return rows


def measure_busy_waits(session, ob, steps=1):
    """Moves `ob` while a refinement pass is running (1 s after the previous move), as a drag does (`steps`
    moves 50 ms apart, each landing in the pass the previous one started): how long view_update waits on the
    main thread for that pass to stop before the scene changes in place, per step."""
    waits = []
    for move in range(MOVES):
        yield 1.0
        for step in range(steps):
            ob.location.x += 0.01 if move % 2 == 0 else -0.01
            yield 0.05
            waits.append(session.release_seconds)
            print(f"viewport_timing: {ob.name} moved during a pass {move + 1}.{step + 1}: main thread waited "
                  f"{session.release_seconds * 1000:.0f} ms (scene rebuilt {session.last_sync.rebuilt})")
    return waits


def steps():
    scene = bpy.context.scene
    scene.render.engine = 'PHOTONSPLAT'
    scene.photonsplat.viewport_iterations = REFINED_ITERATIONS
    window, area, region, space = bw.view3d()
    bw.rendered_through_camera(space)
    yield 0.5
    yield from wait_for(lambda: bw.session() is not None and bw.session().refinement is not None, 30)
    session = bw.session()
    yield from wait_for(lambda: session.refinement.finished or session.refinement.error, 120)
    assert session.refinement.error is None, session.refinement.error

    light_rows = yield from measure_moves(session, bpy.data.objects["Light"], "light move")
    object_rows = yield from measure_moves(session, bpy.data.objects["GlassSphere"], "object move")
    busy_waits = yield from measure_busy_waits(session, bpy.data.objects["Light"])
    drag_waits = yield from measure_busy_waits(session, bpy.data.objects["GlassSphere"], steps=5)

    settings = scene.photonsplat
    summary = dict(
        scene="blend_scenes/cornell_caustics.blend", window="1280x720", region=f"{region.width}x{region.height}",
        view="camera view, default Layout workspace", blender=bpy.app.version_string,
        cpu_threads=os.cpu_count(), load_average=os.getloadavg(), moves=light_rows, object_moves=object_rows,
        first_image_median_s=statistics.median(r["first_image_s"] for r in light_rows),
        refined_median_s=statistics.median(r["refined_s"] for r in light_rows),
        object_first_image_median_s=statistics.median(r["first_image_s"] for r in object_rows),
        object_refined_median_s=statistics.median(r["refined_s"] for r in object_rows),
        busy_main_thread_waits_s=busy_waits, drag_main_thread_waits_s=drag_waits,
        settings=dict(first_pass_photons=settings.viewport_preview_photons,
                      first_pass_pixel_size=settings.viewport_preview_divider,
                      photons_per_iteration=settings.viewport_photons, refined_iterations=REFINED_ITERATIONS,
                      method=settings.method))
    OUTPUT.parent.mkdir(parents=True, exist_ok=True)
    OUTPUT.write_text(json.dumps(summary, indent=2) + "\n")
    print(f"viewport_timing: region {summary['region']}: first image {summary['first_image_median_s'] * 1000:.0f} ms,"
          f" refined ({REFINED_ITERATIONS} iterations) {summary['refined_median_s']:.2f} s after a light move; object move:"
          f" first image {summary['object_first_image_median_s'] * 1000:.0f} ms,"
          f" refined {summary['object_refined_median_s']:.2f} s; main-thread wait during a pass: max"
          f" {max(busy_waits) * 1000:.0f} ms, dragging the glass sphere: max {max(drag_waits) * 1000:.0f} ms"
          f" (medians of {MOVES}; load average"
          f" {summary['load_average'][0]:.1f}); {OUTPUT}")


bw.run_steps(steps(), timeout=900.0)
