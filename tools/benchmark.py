"""Benchmark: splatting methods on a .blend scene, measured like the paper (HPG 2016), written as markdown.

Runs inside Blender so it measures exactly what the engine renders (the add-on's own export). Every render of
one frame and photon count uses the same seed, so all methods splat the same photons onto the same samples.

    BLENDER_USER_SCRIPTS=build/blender blender -b --factory-startup -noaudio --addons photonsplat \\
        blend_scenes/atrium.blend --python tools/benchmark.py -- \\
        --resolution 1920x1080 --frames 1-8 --photons 10000,50000,200000,1000000 \\
        --methods tiled,cluster,cluster_cone,directional,gather --repeats 1 \\
        --json docs/results/bench_atrium.json --markdown docs/results/bench_atrium.md

Times are medians over --repeats runs (--brute-repeats for brute, the slow oracle); counters and bytes come from
the last run (they do not change between runs with the same seed). Radii are the engine's automatic ones: the
scene's size scaled by 1/sqrt(photons). With PHOTONSPLAT_PROGRAM_TIMING=1 in the environment the materials' node
programs are timed too (seconds "programs (summed over threads)", counter "program_runs"; zero otherwise). This is a benchmark, not a test: the machines are shared and noisy, so
compare ratios measured in the same run.
"""
import argparse
import json
import os
import platform
import statistics
import sys
import time

import bpy
import numpy as np

from photonsplat import _core as core
from photonsplat import export

STAGES = ["view_samples", "direct_light", "photon_trace", "hierarchy_build", "splat", "total"]


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution", action="append", default=None, help="WxH (repeatable)")
    parser.add_argument("--frames", default="", help="e.g. 1-8 or 1,3,5 (default: the current frame)")
    parser.add_argument("--photons", default="200000", help="comma-separated photon counts")
    parser.add_argument("--methods", default="cluster", help="comma-separated methods")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--brute-repeats", type=int, default=1, help="brute is the slow oracle: fewer runs")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", help="write every record here")
    parser.add_argument("--markdown", help="write the tables here")
    args = parser.parse_args(argv)
    args.resolution = args.resolution or ["1920x1080"]
    return args


def parse_frames(text):
    if not text:
        return [bpy.context.scene.frame_current]
    frames = []
    for part in text.split(","):
        if "-" in part:
            a, b = part.split("-")
            frames += list(range(int(a), int(b) + 1))
        else:
            frames.append(int(part))
    return frames


def display_luminance(image):
    """Luminance of the display image (linear -> clamp [0, 1] -> sRGB): what SSIM is measured on."""
    rgb = np.clip(image[..., :3], 0.0, 1.0)
    srgb = np.where(rgb <= 0.0031308, 12.92 * rgb, 1.055 * np.power(rgb, 1.0 / 2.4) - 0.055)
    return srgb @ np.array([0.2126, 0.7152, 0.0722])


def ssim(a, b):
    """SSIM of Wang et al. 2004 (11x11 Gaussian window, sigma 1.5, K1 0.01, K2 0.03) on display luminance."""
    from skimage.metrics import structural_similarity

    return float(structural_similarity(display_luminance(a), display_luminance(b), gaussian_weights=True,
                                       sigma=1.5, use_sample_covariance=False, data_range=1.0))


def render_once(frame, settings):
    start = time.perf_counter()
    image, stats = core.render(frame.scene, frame.camera, settings)
    stats["seconds"]["wall (incl. bindings)"] = time.perf_counter() - start
    return image, stats


def measure(args):
    scene = bpy.context.scene
    records, reference_images = [], {}
    for resolution in args.resolution:
        width, height = (int(x) for x in resolution.lower().split("x"))
        scene.render.resolution_x, scene.render.resolution_y = width, height
        scene.render.resolution_percentage = 100
        for frame_number in parse_frames(args.frames):
            scene.frame_set(frame_number)
            for photons in (int(p) for p in args.photons.split(",")):
                scene.photonsplat.photons = photons
                scene.photonsplat.seed = args.seed
                scene.photonsplat.radius = 0.0
                frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
                radius = None
                for method in args.methods.split(","):
                    settings = frame.settings
                    settings.method = method
                    repeats = args.brute_repeats if method == "brute" else args.repeats
                    print(f"benchmark: {width}x{height} frame {frame_number} {photons} photons {method} "
                          f"x{repeats}", flush=True)
                    runs = []
                    # (program_timing: absent from builds before node programs, which the tool also measures)
                    program_timing = getattr(core, "program_timing", lambda reset: {"seconds": 0.0, "runs": 0})
                    for _ in range(repeats):
                        program_timing(True)
                        runs.append(render_once(frame, settings))
                        timing = program_timing(True)
                        runs[-1][1]["seconds"]["programs (summed over threads)"] = timing["seconds"]
                        runs[-1][1]["counters"]["program_runs"] = timing["runs"]
                    image, last = runs[-1]
                    record = {
                        "resolution": [width, height], "frame": frame_number, "photons": photons,
                        "method": method, "repeats": repeats, "radius": last["values"]["radius"],
                        "seconds": {k: statistics.median(r["seconds"].get(k, 0.0) for _, r in runs)
                                    for k in set().union(*(r["seconds"] for _, r in runs))},
                        "counters": last["counters"], "bytes": last["bytes"],
                    }
                    key = (width, height, frame_number, photons)
                    if method == "cluster_cone":
                        reference_images[key] = image
                    if method == "directional" and key in reference_images:
                        record["ssim_vs_cluster_cone"] = ssim(image, reference_images[key])
                    records.append(record)
                    radius = record["radius"]
                reference_images.pop((width, height, frame_number, photons), None)
                print(f"benchmark: radius {radius:.4g}", flush=True)
    return records


# ---- tables -------------------------------------------------------------------------------------------------

def efficiency(counters):
    return counters.get("photon_sample_tests", 0.0) / max(counters.get("contributing_pairs", 0.0), 1.0)


def mean(values):
    values = list(values)
    return sum(values) / len(values) if values else float("nan")


def summary_tables(records, methods):
    """Per photon count: one row per method, averaged over the frames (the fly-through)."""
    lines = []
    for (width, height) in sorted({tuple(r["resolution"]) for r in records}):
        for photons in sorted({r["photons"] for r in records}):
            rows = [r for r in records if r["photons"] == photons and tuple(r["resolution"]) == (width, height)]
            if not rows:
                continue
            frames = sorted({r["frame"] for r in rows})
            radius = rows[0]["radius"]
            lines.append(f"\n### {width}×{height}, {photons:,} photons, radius {radius:.4g}, "
                         f"{len(frames)} frame{'s' if len(frames) > 1 else ''}\n")
            lines.append("| method | splat (s) | frame (s) | photon–node tests | photon–sample tests | contributing "
                         "pairs | tests ÷ contributing | node accepts | SSIM vs cluster_cone |")
            lines.append("|---|---|---|---|---|---|---|---|---|")
            for method in methods:
                m = [r for r in rows if r["method"] == method]
                if not m:
                    continue
                tests = sum(r["counters"].get("photon_sample_tests", 0) for r in m)
                contributing = sum(r["counters"].get("contributing_pairs", 0) for r in m)
                ssims = [r["ssim_vs_cluster_cone"] for r in m if "ssim_vs_cluster_cone" in r]
                lines.append(
                    f"| `{method}` | {mean(r['seconds']['splat'] for r in m):.3f} | "
                    f"{mean(r['seconds']['total'] for r in m):.3f} | "
                    f"{mean(r['counters'].get('photon_node_tests', 0) for r in m):,.0f} | "
                    f"{mean(r['counters'].get('photon_sample_tests', 0) for r in m):,.0f} | "
                    f"{mean(r['counters'].get('contributing_pairs', 0) for r in m):,.0f} | "
                    f"{tests / max(contributing, 1):.2f} | "
                    f"{mean(r['counters'].get('node_accepts', 0) for r in m):,.0f} | "
                    f"{(f'{mean(ssims):.3f}' if ssims else '–')} |")
    return "\n".join(lines)


def ratio_lines(records):
    """The headline ratios (`cluster_cone` against `tiled`, `directional` against `cluster_cone`), from this run."""
    lines = []
    for photons in sorted({r["photons"] for r in records}):
        by = {}
        for r in records:
            if r["photons"] == photons:
                by.setdefault(r["method"], {})[(tuple(r["resolution"]), r["frame"])] = r
        pairs = lambda a, b: [(by[a][k], by[b][k]) for k in by.get(a, {}) if k in by.get(b, {})]
        cone_tiled = pairs("cluster_cone", "tiled")
        if cone_tiled:
            ratio_of_means = sum(c["seconds"]["splat"] for c, _ in cone_tiled) / sum(t["seconds"]["splat"] for _, t in cone_tiled)
            mean_ratio = mean(c["seconds"]["splat"] / t["seconds"]["splat"] for c, t in cone_tiled)
            lines.append(f"- {photons:,} photons: `cluster_cone` splat ÷ `tiled` splat = {ratio_of_means:.2f} (total over "
                         f"{len(cone_tiled)} frames; mean of per-frame ratios {mean_ratio:.2f})")
        dir_cone = pairs("directional", "cluster_cone")
        if dir_cone:
            speedup = sum(c["seconds"]["splat"] for _, c in dir_cone) / sum(d["seconds"]["splat"] for d, _ in dir_cone)
            ssims = [d.get("ssim_vs_cluster_cone") for d, _ in dir_cone if "ssim_vs_cluster_cone" in d]
            lines.append(f"- {photons:,} photons: `directional` splat is {speedup:.2f}× faster than `cluster_cone`; "
                         f"SSIM against `cluster_cone` {mean(ssims):.3f} (mean over frames, min {min(ssims):.3f})")
        cone = [r for r in records if r["photons"] == photons and r["method"] == "cluster_cone"]
        if cone:
            tests = sum(r["counters"].get("photon_sample_tests", 0) for r in cone)
            contributing = sum(r["counters"].get("contributing_pairs", 0) for r in cone)
            lines.append(f"- {photons:,} photons: `cluster_cone` photon–sample tests ÷ contributing pairs = "
                         f"{tests / max(contributing, 1):.2f}")
    return "\n".join(lines)


def method_table(title, first_column, keys, methods, cell):
    """A markdown table with a row per key and a column per method; cell(key, method) is a cell's text."""
    lines = [f"\n{title}:\n", f"| {first_column} | " + " | ".join(f"`{m}`" for m in methods) + " |",
             "|---" * (len(methods) + 1) + "|"]
    lines += [f"| {k} | " + " | ".join(cell(k, m) for m in methods) + " |" for k in keys]
    return "\n".join(lines)


def frame_table(records, methods, photons):
    rows = [r for r in records if r["photons"] == photons]
    frames = sorted({r["frame"] for r in rows})
    if len(frames) < 2:
        return ""

    def cell(f, m):
        r = [x for x in rows if x["frame"] == f and x["method"] == m]
        return f"{r[0]['seconds']['splat']:.3f}" if r else "–"
    return method_table(f"Splat time per frame (s), {photons:,} photons", "frame", frames, methods, cell)


def memory_table(records, methods, photons):
    rows = [r for r in records if r["photons"] == photons]

    def cell(k, m):
        values = [r["bytes"][k] for r in rows if r["method"] == m and k in r["bytes"]]
        return f"{max(values) / 2**20:.1f}" if values else "–"
    return method_table(f"Memory per structure (MiB, largest over the frames), {photons:,} photons", "structure",
                        sorted({k for r in rows for k in r["bytes"]}), methods, cell)


def stage_table(records, methods, photons):
    rows = [r for r in records if r["photons"] == photons]

    def cell(k, m):
        values = [r["seconds"].get(k, 0.0) for r in rows if r["method"] == m]
        return f"{mean(values):.3f}" if values else "–"
    return method_table(f"Stage times (s, mean over the frames), {photons:,} photons", "stage",
                        sorted({k for r in rows for k in r["seconds"]}), methods, cell)


def markdown(records, args):
    methods = [m for m in args.methods.split(",")]
    photon_counts = sorted({r["photons"] for r in records})
    focus = 200000 if 200000 in photon_counts else photon_counts[-1]
    header = (f"Scene `{os.path.basename(bpy.data.filepath)}`; frames {args.frames or 'current'}; medians of "
              f"{args.repeats} runs ({args.brute_repeats} for `brute`); seed {args.seed}; {os.cpu_count()} cores "
              f"({platform.machine()}); Photon Splat {core.__version__}.\n")
    parts = [header, "**Ratios (acceptance figures):**\n", ratio_lines(records), summary_tables(records, methods),
             frame_table(records, methods, focus), stage_table(records, methods, focus),
             memory_table(records, methods, focus)]
    return "\n".join(p for p in parts if p) + "\n"


def main():
    args = parse_args()
    records = measure(args)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(records, f, indent=1)
    text = markdown(records, args)
    print(text)
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write(text)


try:
    main()
except Exception:  # make Blender exit non-zero with --python-exit-code
    import traceback

    traceback.print_exc()
    sys.exit(1)
