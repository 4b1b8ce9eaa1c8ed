"""Benchmark (issue 19): how long a 4-million-triangle scene takes to its first image through F12, against Cycles'
first sample of it, and the peak memory of each.

Run with Debian's Python (it starts one Blender per engine, so each peak memory is its own process's):

    /usr/bin/python3 tools/big_scene_timing.py [--scene build/big_scene.blend] [--repeats 3] [--json OUT]
        [--scripts B/blender]     (the add-on of build B; default this tree's build/blender)

The scene is blend_scenes/make_big_scene.py's (written to build/big_scene.blend when missing). In each Blender:
one warm-up render of the engine, then --repeats timed renders through bpy.ops.render.render() (F12), all at
640x360; medians are printed.
  - Photon Splat (the scene's own settings): the time from the operator's call to the first image written to the
    render result (engine._write_pixels), split into Blender's depsgraph evaluation (until the engine's render()
    runs), the export (mesh reads from Blender, the core's mesh storage, the rest), and the core's stages
    (scene_build is the Embree BVH) as its stats report them.
  - Cycles: CPU, 1 sample, no denoising, the same resolution: the whole operator's time, which is its time to
    the first sample (its own scene sync and BVH build included, as ours are).
  - Peak memory: VmHWM of each Blender process at its end (warm-up and timed renders included), and the bytes of
    Photon Splat's photon structures (its stats' bytes: photon map, hierarchy, splat lists).
This is a benchmark, not a test: the machine is shared, so compare figures of one run.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# The photon structures of the issue's acceptance ("Cycles' peak plus the photon structures").
PHOTON_STRUCTURES = ("photon_map", "hierarchy", "cones", "leaf_summaries", "leaf_photon_lists", "accepted_flux",
                     "cone_traversal_nodes", "tile_bounds", "tile_samples", "tile_photon_lists", "direction_bins",
                     "directional_nodes", "photon_grid", "gather_lists")


def peak_memory_mb():
    """This process's peak resident memory (VmHWM), MB."""
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024.0
    import resource
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


# --- inside Blender -------------------------------------------------------------------------------------------

def _timed(owner, name, totals, key):
    """Wraps owner.name so that its time adds to totals[key]."""
    original = getattr(owner, name)

    def wrapper(*args, **kwargs):
        start = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            totals[key] = totals.get(key, 0.0) + time.perf_counter() - start
    setattr(owner, name, wrapper)


def photonsplat_run(scene):
    import bpy
    from photonsplat import engine, export
    from photonsplat.export import instancing, mesh

    marks = {}
    totals = {}
    write_pixels, render_into = engine._write_pixels, engine.PhotonSplatRenderEngine._render_into

    def first_pixels(*args, **kwargs):
        marks.setdefault("first_image", time.perf_counter())
        return write_pixels(*args, **kwargs)

    def entered(self, *args, **kwargs):
        marks.setdefault("render_entered", time.perf_counter())
        return render_into(self, *args, **kwargs)
    engine._write_pixels = first_pixels
    engine.PhotonSplatRenderEngine._render_into = entered
    _timed(export, "export_frame", totals, "export")
    _timed(mesh, "triangle_mesh", totals, "mesh_read")
    # (GeometryTable._add_mesh gets the mesh already read: its time is the core's storage of the arrays.)
    _timed(instancing.GeometryTable, "_add_mesh", totals, "core_add_mesh")

    def render_once():
        marks.clear()
        totals.clear()
        start = time.perf_counter()
        bpy.ops.render.render()
        end = time.perf_counter()
        outcome = engine.last_outcome
        if outcome.status != "finished":
            raise RuntimeError(f"Photon Splat render {outcome.status}: {outcome.message}")
        seconds = outcome.stats.get("seconds", {})
        row = {"first_image": marks["first_image"] - start, "operator": end - start,
               "depsgraph": marks["render_entered"] - start, "export": totals["export"],
               "export_mesh_read": totals.get("mesh_read", 0.0),
               "export_core_meshes": totals.get("core_add_mesh", 0.0)}
        row["export_other"] = row["export"] - row["export_mesh_read"] - row["export_core_meshes"]
        for stage, value in seconds.items():
            row[f"core_{stage}"] = value
        # What the phases above leave: begin_result, the settings, the bindings, writing the pixels.
        row["rest"] = row["first_image"] - row["depsgraph"] - row["export"] - seconds.get("total", 0.0)
        return row, outcome.stats
    scene.render.engine = 'PHOTONSPLAT'
    return render_once


def cycles_run(scene):
    import bpy
    scene.render.engine = 'CYCLES'
    scene.cycles.device = 'CPU'
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.render.use_persistent_data = False

    def render_once():
        start = time.perf_counter()
        bpy.ops.render.render()
        return {"first_image": time.perf_counter() - start}, {}
    return render_once


def in_blender(engine_name, repeats, out):
    import bpy
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 640, 360, 100
    scene.render.threads_mode = 'AUTO'
    loaded_mb = peak_memory_mb()
    render_once = photonsplat_run(scene) if engine_name == "photonsplat" else cycles_run(scene)
    warmup, _ = render_once()
    rows, stats = [], {}
    for _ in range(repeats):
        row, stats = render_once()
        rows.append(row)
    result = {"engine": engine_name, "warmup": warmup, "runs": rows,
              "median": {k: statistics.median(r[k] for r in rows) for k in rows[0]},
              "peak_mb": peak_memory_mb(), "loaded_peak_mb": loaded_mb,
              "bytes": stats.get("bytes", {}), "counters": stats.get("counters", {})}
    Path(out).write_text(json.dumps(result, indent=1))


# --- the driver -------------------------------------------------------------------------------------------------

def blender_command(script_args, scene_path, env_scripts):
    return (["blender", "-b", "--factory-startup", "-noaudio", "--addons", "photonsplat", str(scene_path),
             "--python", str(Path(__file__).resolve()), "--"] + script_args,
            dict(os.environ, BLENDER_USER_SCRIPTS=str(env_scripts)))


def run_engine(engine_name, scene_path, repeats, workdir, scripts):
    out = workdir / f"big_scene_{engine_name}.json"
    if out.exists():
        out.unlink()
    command, env = blender_command(["--child", engine_name, "--repeats", str(repeats), "--out", str(out)],
                                   scene_path, scripts)
    completed = subprocess.run(command, env=env, capture_output=True, text=True)
    if not out.exists():
        sys.stderr.write(completed.stdout[-4000:] + completed.stderr[-4000:])
        raise SystemExit(f"{engine_name}: no result (exit {completed.returncode})")
    return json.loads(out.read_text())


def table(ps, cycles):
    photon_bytes = sum(v for k, v in ps["bytes"].items() if k in PHOTON_STRUCTURES)
    m = ps["median"]
    core = {k[5:]: v for k, v in m.items() if k.startswith("core_")}
    core_total = core.get("total", 0.0)
    lines = [f"Photon Splat first image: {m['first_image']:.2f} s (F12 operator {m['operator']:.2f} s)",
             f"  depsgraph evaluation (Blender, before render()): {m['depsgraph']:.2f} s",
             f"  export: {m['export']:.2f} s (mesh reads {m['export_mesh_read']:.2f} s, core mesh storage "
             f"{m['export_core_meshes']:.2f} s, rest {m['export_other']:.2f} s)",
             f"  core render: {core_total:.2f} s (scene_build is the BVH; " + ", ".join(
                 f"{k} {v:.2f}" for k, v in core.items() if k != "total" and v >= 0.01) + ")",
             f"  the rest (result, settings, bindings, pixels): {m['rest']:.2f} s",
             "  (each phase is its own median over the runs: they need not add up to the first image's)",
             f"Cycles first sample (1 sample): {cycles['median']['first_image']:.2f} s",
             f"Peak memory: Photon Splat {ps['peak_mb']:.0f} MB, Cycles {cycles['peak_mb']:.0f} MB "
             f"(after loading the file: {ps['loaded_peak_mb']:.0f} / {cycles['loaded_peak_mb']:.0f} MB)",
             f"Photon structures: {photon_bytes / 1e6:.1f} MB ("
             + ", ".join(f"{k} {v / 1e6:.1f}" for k, v in ps["bytes"].items() if k in PHOTON_STRUCTURES and v) + ")",
             f"Embree scene: {ps['bytes'].get('embree_scene', 0) / 1e6:.0f} MB; triangles "
             f"{ps['counters'].get('triangles', 0):,.0f}",
             f"Acceptance: first image {'<=' if m['first_image'] <= cycles['median']['first_image'] else '>'} "
             f"Cycles' first sample; peak {'<=' if ps['peak_mb'] <= cycles['peak_mb'] + photon_bytes / 2**20 else '>'}"
             " Cycles' + photon structures"]
    return "\n".join(lines)


def main():
    if "--child" in sys.argv:
        argv = sys.argv[sys.argv.index("--") + 1:]
        parser = argparse.ArgumentParser()
        parser.add_argument("--child")
        parser.add_argument("--repeats", type=int)
        parser.add_argument("--out")
        args = parser.parse_args(argv)
        in_blender(args.child, args.repeats, args.out)
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default=str(ROOT / "build" / "big_scene.blend"))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--engines", default="photonsplat,cycles")
    parser.add_argument("--json", help="write both engines' records here")
    parser.add_argument("--scripts", default=str(ROOT / "build" / "blender"),
                        help="BLENDER_USER_SCRIPTS holding the add-on to time (another build: B/blender)")
    args = parser.parse_args()
    scene_path = Path(args.scene)
    if not scene_path.exists():
        subprocess.run(["blender", "-b", "--factory-startup", "-noaudio", "--python",
                        str(ROOT / "blend_scenes" / "make_big_scene.py"), "--", str(scene_path)], check=True,
                       capture_output=True)
    workdir = ROOT / "build"
    started = time.strftime("%Y-%m-%d %H:%M:%S")
    load = os.getloadavg()[0]
    results = {name: run_engine(name, scene_path, args.repeats, workdir, args.scripts)
               for name in args.engines.split(",")}
    print(f"{args.scripts}: {started}, {os.cpu_count()} cores, load average {load:.2f} at the start, medians of {args.repeats}")
    if "photonsplat" in results and "cycles" in results:
        print(table(results["photonsplat"], results["cycles"]))
    else:
        print(json.dumps({k: v["median"] for k, v in results.items()}, indent=1))
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
