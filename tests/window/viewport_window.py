"""The real-window test: Blender (under Xvfb, software OpenGL) opens the caustic Cornell box, switches its 3D
viewport to Rendered shading through the camera, waits for the refinement, takes a screenshot and checks that
the caustic under the glass sphere is brighter on screen than the floor around it.

Run by tests/window/run.sh (which also fails on any Python error in Blender's log). Writes under the folder
given as PHOTONSPLAT_ARTIFACTS (default build/test-artifacts): viewport_caustic.png (the screenshot checked) and,
with PHOTONSPLAT_DOC_IMAGES=<folder>, the user guide's screenshots (window, render and view-layer panels).
"""

import os
import shutil
import sys
import time
from pathlib import Path

import bpy
import numpy as np

REPO = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(REPO / "tools"), str(REPO / "tests" / "blender")]

import blender_window as bw                                       # noqa: E402
from blender_helpers import caustic_landing                         # noqa: E402
from scene_geometry import floor_ring                             # noqa: E402

ARTIFACTS = Path(os.environ.get("PHOTONSPLAT_ARTIFACTS", REPO / "build" / "test-artifacts"))
DOC_IMAGES = os.environ.get("PHOTONSPLAT_DOC_IMAGES")
REFINE_SECONDS = 20.0


def luminance(rgb):
    return rgb[..., 0] * 0.2126 + rgb[..., 1] * 0.7152 + rgb[..., 2] * 0.0722


def caustic_and_surroundings(scene, region, region_data):
    """Region pixels (column, row from top) showing the glass sphere's caustic, and floor pixels around it."""
    eye = np.array(region_data.view_matrix.inverted().translation)
    landing, spheres = caustic_landing(eye)
    counts = {}
    for pixel in bw.region_pixels(region, region_data, landing):
        if pixel is not None:
            counts[pixel] = counts.get(pixel, 0) + 1
    # The caustic's core: the pixels showing the most landing points.
    threshold = np.percentile(list(counts.values()), 90)
    caustic = [p for p, n in counts.items() if n >= threshold]
    ring = floor_ring(landing, eye, spheres)
    around = [p for p in bw.region_pixels(region, region_data, ring) if p is not None and p not in counts]
    return caustic, around


def steps():
    scene = bpy.context.scene
    scene.render.engine = 'PHOTONSPLAT'
    settings = scene.photonsplat
    settings.viewport_preview_photons = 20_000
    settings.viewport_photons = 100_000
    settings.viewport_iterations = 6
    settings.viewport_time_limit = REFINE_SECONDS
    window, area, region, space = bw.view3d()
    bw.rendered_through_camera(space)
    yield 0.5

    started = time.perf_counter()
    while time.perf_counter() - started < REFINE_SECONDS + 15.0:
        session = bw.session()
        if session is not None and session.refinement is not None and not session.refinement.running:
            break
        yield 0.25
    session = bw.session()
    assert session is not None, "the viewport never called view_update: no Photon Splat session"
    assert session.error is None, session.error
    refinement = session.refinement
    assert refinement is not None and refinement.error is None, refinement and refinement.error
    frame = refinement.latest()
    assert frame is not None and frame.iterations >= 1, "no refined image"
    print(f"viewport_window: region {region.width}x{region.height}, {frame.iterations} iterations in "
          f"{frame.seconds:.1f} s, first image {refinement.first_image_seconds:.2f} s")
    yield 0.5                                   # let Blender draw the last image

    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    shot = bw.screenshot_area(window, area, ARTIFACTS / "viewport_caustic.png")
    # The region's place inside the area's screenshot (rows from the top).
    left = region.x - area.x
    top = (area.y + area.height) - (region.y + region.height)
    view = shot[top:top + region.height, left:left + region.width]
    brightness = luminance(view)
    caustic, around = caustic_and_surroundings(scene, region, space.region_3d)
    assert len(caustic) >= 5 and len(around) >= 10, (len(caustic), len(around))
    caustic_level = np.mean([brightness[r, c] for c, r in caustic])
    around_level = np.median([brightness[r, c] for c, r in around])
    print(f"viewport_window: caustic {caustic_level:.3f} vs surroundings {around_level:.3f} on screen "
          f"({len(caustic)} / {len(around)} pixels)")
    assert caustic_level > 1.25 * around_level, "the caustic is not brighter than the floor around it"

    if DOC_IMAGES:
        yield from doc_screenshots(window, Path(DOC_IMAGES))


def doc_screenshots(window, folder):
    """The user guide's pictures: the whole window with the viewport, and the engine's panels."""
    folder.mkdir(parents=True, exist_ok=True)
    # The viewport picture is the screenshot the test just checked. (Taken again after the window screenshot it
    # can show a restarted refinement's first image: the screenshot operator redraws the window.)
    shutil.copyfile(ARTIFACTS / "viewport_caustic.png", folder / "viewport_caustic.png")
    bw.screenshot_window(window, folder / "viewport_window.png")
    window, area, region, space = bw.view3d()
    # The panels, readable: the big viewport area turned into a Properties editor for the shots.
    area.type = 'PROPERTIES'
    settings = bpy.context.scene.photonsplat
    for name in ("viewport_iterations", "viewport_time_limit"):     # show the defaults, not the test's limits
        settings.property_unset(name)
    yield 0.3
    for context, name in (('RENDER', "panel_render.png"), ('VIEW_LAYER', "panel_passes.png")):
        area.spaces.active.context = context
        yield 0.5
        bw.screenshot_area(window, area, folder / name)
    area.type = 'VIEW_3D'


bw.run_steps(steps(), timeout=90.0)
