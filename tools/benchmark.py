"""Benchmark: stage timings and counters of the splatting methods on a .blend scene, as markdown.

Runs inside Blender so it measures exactly what the engine renders (the add-on's own export):

    BLENDER_USER_SCRIPTS=build/blender blender -b --factory-startup -noaudio --addons photonsplat \
        blend_scenes/cornell_caustics.blend --python tools/benchmark.py -- \
        --config 1920x1080:200000:cluster --config 480x270:200000:brute,cluster --repeats 3 --out docs/bench.md

Each --config is WIDTHxHEIGHT:PHOTONS:METHOD[,METHOD...]. Times are medians over --repeats runs
(--brute-repeats for brute); counters
and bytes come from the last run (they do not change between runs with the same seed). This is a benchmark,
not a test: the machines are shared and noisy, so compare ratios measured in the same run.
"""
import argparse
import os
import platform
import statistics
import sys
import time

import bpy

import photonsplat
from photonsplat import _core as core
from photonsplat import export

STAGES = ["view_samples", "direct_light", "photon_trace", "hierarchy_build", "splat", "splat_traverse",
          "splat_lists", "splat_shade", "image", "total"]
COUNTERS = ["view_samples", "photons_emitted", "photons_stored", "caustic_photons_stored", "hierarchy_nodes",
            "hierarchy_leaves", "photon_node_tests", "photon_sample_tests", "contributing_pairs", "shadow_rays"]
STRUCTURES = ["view_samples", "hierarchy", "leaf_photon_lists", "photon_map", "embree_scene", "image"]


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", action="append", required=True, help="WxH:PHOTONS:METHOD[,METHOD]")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--brute-repeats", type=int, default=1, help="brute is the slow oracle: fewer runs")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out", help="markdown file to write (default: print only)")
    return parser.parse_args(argv)


def run(width, height, photons, method, repeats, seed):
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    scene.photonsplat.photons = photons
    scene.photonsplat.method = method
    scene.photonsplat.seed = seed
    depsgraph = bpy.context.evaluated_depsgraph_get()
    start = time.perf_counter()
    frame = export.export_frame(core, depsgraph)
    export_seconds = time.perf_counter() - start
    runs = []
    for _ in range(repeats):
        _, stats = core.render(frame.scene, frame.camera, frame.settings)
        runs.append(stats)
    seconds = {k: statistics.median(r["seconds"].get(k, 0.0) for r in runs) for k in STAGES}
    seconds["export (Python)"] = export_seconds
    return {"seconds": seconds, "counters": runs[-1]["counters"], "bytes": runs[-1]["bytes"],
            "radius": runs[-1]["values"]["radius"]}


def fmt_count(x):
    return f"{x:,.0f}"


def table(results):
    """One column per (config, method); rows: stage times, counters, bytes."""
    heads = [f"{w}×{h}, {p:,} photons, `{m}`" for (w, h, p, m) in results]
    lines = ["| | " + " | ".join(heads) + " |", "|---" * (len(heads) + 1) + "|"]
    values = list(results.values())
    lines.append("| radius (world units) | " + " | ".join(f"{v['radius']:.4f}" for v in values) + " |")
    for k in STAGES + ["export (Python)"]:
        lines.append(f"| time: {k} (s) | " + " | ".join(f"{v['seconds'].get(k, 0.0):.3f}" for v in values) + " |")
    for k in COUNTERS:
        lines.append(f"| {k.replace('_', ' ')} | " + " | ".join(fmt_count(v['counters'].get(k, 0)) for v in values) + " |")
    lines.append("| photon–sample tests ÷ contributing pairs | " + " | ".join(
        f"{v['counters']['photon_sample_tests'] / max(v['counters']['contributing_pairs'], 1):.2f}" for v in values) + " |")
    for k in STRUCTURES:
        lines.append(f"| memory: {k} (MiB) | " + " | ".join(
            (f"{v['bytes'][k] / 2**20:.1f}" if k in v["bytes"] else "–") for v in values) + " |")
    return "\n".join(lines)


def main():
    args = parse_args()
    results = {}
    for config in args.config:
        size, photons, methods = config.split(":")
        width, height = (int(x) for x in size.lower().split("x"))
        for method in methods.split(","):
            print(f"benchmark: {width}x{height} {photons} photons {method} ...", flush=True)
            repeats = args.brute_repeats if method == "brute" else args.repeats
            results[(width, height, int(photons), method)] = run(width, height, int(photons), method, repeats,
                                                                 args.seed)
    blend = os.path.basename(bpy.data.filepath)
    header = (f"Scene `{blend}`; median of {args.repeats} runs ({args.brute_repeats} for `brute`); seed {args.seed}; {os.cpu_count()} cores "
              f"({platform.processor() or platform.machine()}); Photon Splat {core.__version__}.")
    text = header + "\n\n" + table(results) + "\n"
    print(text)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text)


try:
    main()
except Exception as error:  # make Blender exit non-zero with --python-exit-code
    import traceback

    traceback.print_exc()
    sys.exit(1)
