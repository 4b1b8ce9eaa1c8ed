"""Blender survives whatever it is handed: malformed and extreme scenes and absurd settings end in an
ERROR report naming the cause, never a crash, and the next valid scene renders in the same process; cancelling
in the middle of each stage leaves no thread running and no memory growth across 20 cancelled renders.

Renders stay tiny; the cancel test's stages are made just long enough to be caught by the ~10 Hz progress poll.
"""

import ctypes
import math
import time

import bmesh
import bpy
import numpy as np
import pytest

from blender_helpers import open_scene, render_pixels, use_photonsplat
from photonsplat import engine


def render_outcome(tmp_path, name):
    """Render as F12 does; return Blender's error text ('' when none) and the engine's outcome."""
    try:
        render_pixels(tmp_path / f"{name}.exr")
        error = ""
    except RuntimeError as raised:  # bpy.ops raises RuntimeError carrying the engine's ERROR report
        error = str(raised)
    return error, engine.last_outcome


def assert_next_valid_scene_renders(tmp_path):
    scene = open_scene("cornell_diffuse")
    use_photonsplat(scene, 16, 5_000)
    pixels = render_pixels(tmp_path / "next_valid.exr")
    assert engine.last_outcome.status == "finished", engine.last_outcome.message
    assert np.isfinite(pixels).all() and pixels[..., :3].mean() > 0.01


def add_mesh_object(name, vertices, faces):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(vertices, [], faces)
    ob = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(ob)
    return ob


# --- malformed scenes ------------------------------------------------------------------------------------------

def test_no_camera(tmp_path, core):
    scene = open_scene("cornell_diffuse")
    use_photonsplat(scene, 16, 5_000)
    bpy.data.objects.remove(bpy.data.objects["Camera"])
    error, _ = render_outcome(tmp_path, "no_camera")
    assert "camera" in error.lower()
    assert_next_valid_scene_renders(tmp_path)


def test_empty_meshes_render(tmp_path, core):
    scene = open_scene("cornell_diffuse")
    use_photonsplat(scene, 16, 5_000)
    add_mesh_object("NoVertices", [], [])
    add_mesh_object("OnlyAnEdge", [(0, 0, 0), (1, 0, 0)], [])
    add_mesh_object("ZeroArea", [(0, 0, 0), (1, 0, 0), (2, 0, 0)], [(0, 1, 2)])
    pixels = render_pixels(tmp_path / "empty_meshes.exr")
    assert engine.last_outcome.status == "finished", engine.last_outcome.message
    assert np.isfinite(pixels).all()
    assert_next_valid_scene_renders(tmp_path)


def test_nan_transform_is_reported_naming_the_object(tmp_path, core):
    scene = open_scene("cornell_diffuse")
    use_photonsplat(scene, 16, 5_000)
    ob = add_mesh_object("Broken", [(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 1, 2)])
    ob.location = (math.nan, 0.0, 0.0)
    error, outcome = render_outcome(tmp_path, "nan_transform")
    assert outcome.status == "failed", outcome.message
    assert "Broken" in error and "transform" in error
    assert_next_valid_scene_renders(tmp_path)


def test_many_tiny_triangles(tmp_path, core):
    """A millimetre-sized grid of 500k triangles, well under a pixel each."""
    scene = open_scene("cornell_diffuse")
    use_photonsplat(scene, 16, 5_000)
    mesh = bpy.data.meshes.new("Dust")
    bm = bmesh.new()
    bmesh.ops.create_grid(bm, x_segments=500, y_segments=500, size=0.001)
    bmesh.ops.triangulate(bm, faces=bm.faces[:])
    bm.to_mesh(mesh)
    bm.free()
    ob = bpy.data.objects.new("Dust", mesh)
    ob.location = (0.0, 0.0, 0.5)
    scene.collection.objects.link(ob)
    pixels = render_pixels(tmp_path / "dust.exr")
    assert engine.last_outcome.status == "finished", engine.last_outcome.message
    assert engine.last_outcome.stats["counters"]["triangles"] + \
        engine.last_outcome.stats["counters"]["dropped_triangles"] >= 500_000
    assert np.isfinite(pixels).all()
    assert_next_valid_scene_renders(tmp_path)


# --- absurd settings (a script, an old file or a typo can store what the panel would clamp) --------------------

@pytest.mark.parametrize("key, value, cause", [
    ("photons", 2_000_000_000, "photons"),
    ("radius", math.inf, "radius"),
    ("radius", -1.0, "radius"),
    ("max_bounces", 1_000_000, "max_bounces"),
    ("direct_samples", 0, "direct_samples"),
    ("threads", 1_000_000, "threads"),
    ("directional_level", 99, "directional_level"),
    ("memory_budget", 1e-6, "memory budget"),    # 1 kB: nothing fits
])
def test_absurd_settings_are_reported_naming_the_setting(key, value, cause, tmp_path, core):
    scene = open_scene("cornell_diffuse")
    use_photonsplat(scene, 16, 5_000)
    scene.photonsplat[key] = value  # ID property: bypasses the panel's limits
    error, outcome = render_outcome(tmp_path, f"absurd_{key}")
    assert outcome.status == "failed", outcome.message
    assert cause in error, error
    assert_next_valid_scene_renders(tmp_path)


# --- cancel in every stage ------------------------------------------------------------------------------------

def process_state():
    """(resident memory in MiB, number of threads) of this Blender process, from /proc/self/status.

    glibc's malloc first hands freed memory back to the system (malloc_trim): it keeps freed blocks in per-thread
    arenas otherwise, so a process that frees everything (Blender as a Python module, whose allocator is glibc's)
    could still show its resident memory swinging by a few hundred MiB between renders. Memory still in use, a
    leak, stays resident whatever the trim."""
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):       # not glibc: nothing to trim
        pass
    fields = {}
    with open("/proc/self/status") as status:
        for line in status:
            key, _, value = line.partition(":")
            fields[key] = value.split()
    return int(fields["VmRSS"][0]) / 1024.0, int(fields["Threads"][0])


STAGES = ["view samples", "direct light", "photons", "cluster hierarchy", "splat"]


def test_cancel_in_each_stage_leaks_no_thread_and_no_memory(tmp_path, core, monkeypatch):
    scene = open_scene("cornell_caustics")
    # Sizes chosen so that every stage lasts at least a few progress polls on 2 shared cores.
    use_photonsplat(scene, 1280, 300_000, method="cluster_cone", direct_samples=6)
    module = engine.load_core()
    real_render = module.render
    target = {"stage": None, "seen": []}

    def cancelling_render(scene_, camera, settings, progress=None):
        def on_progress(stage, fraction):
            stop = progress(stage, fraction)
            if stage.startswith(target["stage"]):
                target["seen"].append(stage)
                return True
            return stop
        return real_render(scene_, camera, settings, progress=on_progress)

    monkeypatch.setattr(module, "render", cancelling_render)
    states = []
    caught = {stage: 0 for stage in STAGES}
    for attempt in range(20):
        target["stage"] = STAGES[attempt % len(STAGES)]
        target["seen"].clear()
        bpy.ops.render.render()
        outcome = engine.last_outcome
        if target["seen"]:
            assert outcome.status == "cancelled", (target["stage"], outcome.message)
            caught[target["stage"]] += 1
        time.sleep(0.2)  # let worker threads park
        states.append(process_state())
    monkeypatch.undo()
    print(f"\ncancelled renders per stage: {caught}; (RSS MiB, threads) after each: {states}")
    # The hierarchy is built in a few hundredths of a second: it may end between two polls; the others may not.
    for stage in ("view samples", "direct light", "photons", "splat"):
        assert caught[stage] >= 3, caught
    rss = [r for r, _ in states]
    threads = [t for _, t in states]
    assert max(threads[4:]) <= threads[3], f"threads kept growing: {threads}"
    assert rss[-1] - rss[3] < 64.0, f"memory grew over 16 cancelled renders: {rss}"
    assert_next_valid_scene_renders(tmp_path)
