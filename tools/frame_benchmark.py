"""Issue 19's frame benchmark: one 1080p pass against Embree's floor and against one Cycles sample.

Inside Blender, for the open scene (one Blender process per scene):
  1. the core's frame (export once, a warm-up render, then --repeats renders; medians): each stage's time, its
     rays (stats counters "rays.<stage>") and rays per second, beside Embree's floor for the same frame
     (photonsplat.ray_floor: the primary rays as coherent 4 x 2 packets, median of 3) as "time per ray over the
     floor's";
  2. F12 as a user gets it (bpy.ops.render.render: export, render, pixels written back), Photon Splat with one
     pass against Cycles with one sample (CPU, no denoising, no adaptive sampling), each after a warm-up render
     of its own, medians of --repeats.
Writes the record as JSON. Outside Blender (plain python3), --report turns the records into markdown.

    BLENDER_USER_SCRIPTS=build/blender blender -b --factory-startup -noaudio --addons photonsplat \\
        blend_scenes/cornell_caustics.blend --python tools/frame_benchmark.py -- --json build/frame/cornell.json
    /usr/bin/python3 tools/frame_benchmark.py --report docs/results/frame_benchmark.md build/frame/*.json

tools/frame_benchmark.sh runs both scenes and writes the report. A benchmark, not a test: run it on a quiet machine.
"""
import argparse
import json
import os
import platform
import statistics
import sys
import time

STAGES = ["view_samples", "direct_light", "kernel_coverage", "photon_trace", "hierarchy_build", "splat", "image"]
RAY_STAGES = ["view_samples", "direct_light", "kernel_coverage", "photon_trace"]


def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution", default="1920x1080")
    parser.add_argument("--photons", type=int, default=200000)
    parser.add_argument("--method", default="cluster_cone")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--no-cycles", action="store_true", help="skip the F12 comparison with Cycles")
    parser.add_argument("--json", help="write the record here")
    parser.add_argument("--report", help="outside Blender: write markdown here from the JSON records given")
    parser.add_argument("records", nargs="*")
    return parser.parse_args(argv)


# ---- inside Blender -----------------------------------------------------------------------------------------

def set_photonsplat(scene, args):
    width, height = (int(v) for v in args.resolution.lower().split("x"))
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    settings = scene.photonsplat
    settings.photons = args.photons
    settings.method = args.method
    settings.seed = args.seed
    settings.radius = 0.0
    settings.iterations = 1
    settings.time_limit = 0.0


def core_frame(args):
    import bpy
    from photonsplat import _core as core
    from photonsplat import export

    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    core.render(frame.scene, frame.camera, frame.settings)  # warm-up: BVH, programs, first-touch memory
    runs = [core.render(frame.scene, frame.camera, frame.settings)[1] for _ in range(args.repeats)]
    # (ray_floor: absent from builds before issue 19, which the tool also times with --scripts of another build)
    floor = getattr(core, "ray_floor", None)
    floors = sorted((floor(frame.scene, frame.camera) for _ in range(3)), key=lambda f: f["seconds"]) if floor else [
        None, None]
    seconds = {k: statistics.median(r["seconds"].get(k, 0.0) for r in runs) for k in STAGES + ["total"]}
    rays = {k: runs[-1]["counters"].get(f"rays.{k}", 0.0) for k in RAY_STAGES}
    return {"seconds": seconds, "rays": rays, "floor": floors[1], "radius": runs[-1]["values"]["radius"],
            "view_samples": runs[-1]["counters"].get("view_samples", 0.0)}


def f12_seconds(scene, repeats):
    import bpy

    bpy.ops.render.render()  # warm-up
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        bpy.ops.render.render()
        times.append(time.perf_counter() - start)
    return statistics.median(times), times


def f12(args):
    import bpy
    from photonsplat import engine

    scene = bpy.context.scene
    scene.render.engine = "PHOTONSPLAT"
    photonsplat, photonsplat_runs = f12_seconds(scene, args.repeats)
    outcome = engine.last_outcome
    record = {"photonsplat": photonsplat, "photonsplat_runs": photonsplat_runs,
              "photonsplat_status": getattr(outcome, "status", None)}
    if args.no_cycles:
        return record
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = 1
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    if hasattr(cycles, "use_preview_denoising"):
        cycles.use_preview_denoising = False
    for layer in scene.view_layers:
        if hasattr(layer, "cycles"):
            layer.cycles.use_denoising = False
    record["cycles"], record["cycles_runs"] = f12_seconds(scene, args.repeats)
    record["ratio"] = photonsplat / record["cycles"]
    return record


def measure(args):
    import bpy

    scene = bpy.context.scene
    set_photonsplat(scene, args)
    record = {"scene": os.path.basename(bpy.data.filepath), "resolution": args.resolution, "photons": args.photons,
              "method": args.method, "repeats": args.repeats, "cpus": os.cpu_count(),
              "blender": bpy.app.version_string, "load_average_before": os.getloadavg()}
    record["core"] = core_frame(args)
    record["f12"] = f12(args)
    record["load_average_after"] = os.getloadavg()
    return record


# ---- the report ---------------------------------------------------------------------------------------------

def markdown(records):
    lines = []
    first = records[0]
    lines.append(f"{first['resolution']}, {first['photons']:,} photons, one pass, `{first['method']}`, "
                 f"{first['cpus']} cores ({platform.machine()}), Blender {first['blender']}; medians of "
                 f"{first['repeats']} after a warm-up render. Command: `bash tools/frame_benchmark.sh`.")
    lines.append("")
    lines.append("| stage (s) | " + " | ".join(f"`{r['scene']}`" for r in records) + " |")
    lines.append("|---|" + "---|" * len(records))
    for stage in STAGES + ["total"]:
        cells = [f"{r['core']['seconds'][stage]:.3f}" for r in records]
        label = f"**{stage}**" if stage == "total" else stage
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    lines.append("")
    lines.append("Rays per second of each ray-traced stage beside Embree's floor for the same frame (its primary "
                 "rays traced as coherent 4 × 2 packets, nothing shaded); \"× floor\" is the stage's time per ray "
                 "over the floor's (acceptance: ≤ 3).")
    lines.append("")
    lines.append("| scene | stage | rays (M) | Mrays/s | × floor |")
    lines.append("|---|---|---|---|---|")
    for r in records:
        floor = r["core"]["floor"]
        if floor is None:
            continue
        lines.append(f"| `{r['scene']}` | floor: primary rays, packets | {floor['rays'] / 1e6:.2f} | "
                     f"{floor['rays_per_second'] / 1e6:.1f} | 1.00 |")
        for stage in RAY_STAGES:
            rays, seconds = r["core"]["rays"][stage], r["core"]["seconds"][stage]
            rate = rays / seconds if seconds > 0 else 0.0
            over = floor["rays_per_second"] / rate if rate > 0 else float("nan")
            lines.append(f"| | {stage} | {rays / 1e6:.2f} | {rate / 1e6:.1f} | {over:.2f} |")
    lines.append("")
    if all("cycles" in r["f12"] for r in records):
        lines.append("F12 (`bpy.ops.render.render`: export, render, pixels written back), each engine after a "
                     "warm-up render of its own (acceptance: Photon Splat ≤ 0.7 × Cycles):")
        lines.append("")
        lines.append("| scene | Photon Splat, one pass (s) | Cycles, one sample (s) | ratio |")
        lines.append("|---|---|---|---|")
        for r in records:
            f = r["f12"]
            lines.append(f"| `{r['scene']}` | {f['photonsplat']:.2f} | {f['cycles']:.2f} | {f['ratio']:.2f} |")
        lines.append("")
    loads = ", ".join(f"`{r['scene']}` {r['load_average_before'][0]:.2f} → {r['load_average_after'][0]:.2f}"
                      for r in records)
    lines.append(f"Load average (1 min) before → after each scene: {loads}.")
    return "\n".join(lines) + "\n"


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    args = parse_args(argv)
    if args.report:
        records = [json.load(open(path)) for path in args.records]
        text = markdown(records)
        with open(args.report, "w") as out:
            out.write(text)
        print(text)
        return
    record = measure(args)
    print("frame_benchmark:", json.dumps(record), flush=True)
    if args.json:
        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        with open(args.json, "w") as out:
            json.dump(record, out, indent=1)


if __name__ == "__main__":
    main()
