"""What radius levels (RenderSettings.adaptive_radius, photon_density.h) cost a progressive iteration: the scene's
own settings with the levels on and off, alternately, in one Blender process.

    BLENDER_USER_SCRIPTS=build/blender blender -b --factory-startup -noaudio --addons photonsplat \\
        blend_scenes/cornell_caustics.blend --python tools/radius_levels_cost.py -- --resolution 960x540

Per setting: --rounds rounds of --iterations progressive iterations each (a fresh render each round, the rounds of
the two settings interleaved), the median over rounds of the seconds per iteration, and, with the levels on, the
seconds of the levels' own stage (stats "radius_levels": the photons' density and their split) and the photons
per level, and the splat's and the boundary correction's seconds with each setting (the levels' splats and
corrections are counted in those). A benchmark, not a test: run it on a quiet machine and compare the two columns of one run.
"""
import argparse
import statistics
import sys
import time

import bpy

from photonsplat import _core as core
from photonsplat import export


STAGES = ("radius_levels", "splat", "kernel_coverage")


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution", default="", help="WxH (default: the scene's)")
    parser.add_argument("--iterations", type=int, default=8)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--threads", type=int, default=2)
    return parser.parse_args(argv)


def run_round(frame, adaptive, iterations, threads):
    settings = frame.settings
    settings.adaptive_radius = adaptive
    settings.threads = threads
    settings.iterations = iterations
    settings.time_limit = 0.0
    progressive = core.Progressive(frame.scene, frame.camera, settings)
    start = time.perf_counter()
    for _ in range(iterations):
        progressive.step()
    seconds = (time.perf_counter() - start) / iterations
    stats = progressive.stats()
    stages = {k: stats["seconds"].get(k, 0.0) / iterations for k in STAGES}
    return seconds, stages, stats["counters"]


def main():
    args = parse_args()
    scene = bpy.context.scene
    if args.resolution:
        scene.render.resolution_x, scene.render.resolution_y = (int(x) for x in args.resolution.lower().split("x"))
        scene.render.resolution_percentage = 100
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    run_round(frame, True, 1, args.threads)  # warm-up
    rounds = {True: [], False: []}
    for _ in range(args.rounds):
        for adaptive in (False, True):
            rounds[adaptive].append(run_round(frame, adaptive, args.iterations, args.threads))
    off = statistics.median(r[0] for r in rounds[False])
    on = statistics.median(r[0] for r in rounds[True])
    stage = {k: (statistics.median(r[1][k] for r in rounds[False]), statistics.median(r[1][k] for r in rounds[True]))
             for k in STAGES}
    counters = rounds[True][-1][2]
    stored = counters.get("photons_stored", 0.0)
    levels = [counters.get(f"photons_radius_level_{k}", 0.0) for k in (1, 2)]
    name = bpy.path.basename(bpy.data.filepath) or "(unsaved)"
    width, height = scene.render.resolution_x, scene.render.resolution_y
    print(f"| {name} {width}x{height} | {off:.3f} | {on:.3f} | {on / off:.3f} | {stage['radius_levels'][1]:.4f} | "
          f"{stage['splat'][0]:.3f} → {stage['splat'][1]:.3f} | "
          f"{stage['kernel_coverage'][0]:.3f} → {stage['kernel_coverage'][1]:.3f} | "
          f"{levels[0] / max(stored, 1):.2%} / {levels[1] / max(stored, 1):.2%} |", flush=True)


main()
