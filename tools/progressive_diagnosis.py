"""What limits progressive splatting's SSIM on a scene: per-pass SSIM and CPU time for given settings, and
optionally the error split by component. A measurement program (docs/results/README.md, "Diagnosis"), not a test.

    BLENDER_USER_SCRIPTS=build/blender blender -b --factory-startup -noaudio --addons photonsplat \\
        blend_scenes/cornell_caustics.blend --python tools/progressive_diagnosis.py -- \\
        --reference build/report_384/reference/<key>.npy --width 256 --photons 12500 --iterations 8

The reference is a report reference (tools/report.py) of the same scene at a multiple-or-larger resolution,
area-resampled to --width (exact for box-filtered pixels: a finer reference is a cleaner one). Time is the CPU
time of this process during Progressive.step() (both cores), which a shared machine's load changes far less than
wall time. --split PASS saves the mean after PASS passes and after all passes with their components ('direct',
'indirect', 'caustics', ...) to --save, so that a component of the early mean can be swapped for the late one.
"""
import argparse
import resource
import sys

import numpy as np


def area_resample(image, width):
    """Box-filter resampling of a square-pixel image to `width` columns (and rows in proportion)."""
    def weights(n_in, n_out):
        scale = n_in / n_out
        m = np.zeros((n_out, n_in))
        for i in range(n_out):
            a, b = i * scale, (i + 1) * scale
            for j in range(int(np.floor(a)), min(n_in, int(np.ceil(b)))):
                m[i, j] = max(0.0, min(b, j + 1) - max(a, j))
        return m / scale
    h, w = image.shape[:2]
    rows, cols = weights(h, int(round(h * width / w))), weights(w, width)
    return np.einsum("ij,jkc->ikc", rows, np.einsum("kl,jlc->jkc", cols, image.astype(np.float64))).astype(np.float32)


def cpu_seconds():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main(argv):
    import bpy

    from photonsplat import _core as core
    from photonsplat import export

    parser = argparse.ArgumentParser()
    parser.add_argument("--reference", required=True)
    parser.add_argument("--width", type=int, default=256)
    parser.add_argument("--photons", type=int, default=12_500)
    parser.add_argument("--radius", type=float, default=0.0)
    parser.add_argument("--aimed-photons", type=float, default=None, help="default: the core's")
    parser.add_argument("--iterations", "--passes", type=int, default=8)  # --passes: the old name
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--method", default="cluster_cone")
    parser.add_argument("--no-boundary-correction", action="store_true",
                        help="the paper's plain estimate (then the automatic radius weighs the boundary bias)")
    parser.add_argument("--split", type=int, default=0, help="save the components after this many passes")
    parser.add_argument("--save", default="build/diagnosis.npz")
    args = parser.parse_args(argv)

    scene = bpy.context.scene
    aspect = scene.render.resolution_y / scene.render.resolution_x
    scene.render.resolution_x, scene.render.resolution_y = args.width, int(round(args.width * aspect))
    scene.render.resolution_percentage = 100
    scene.photonsplat.seed, scene.photonsplat.radius, scene.photonsplat.passes = args.seed, 0.0, 1
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    reference = area_resample(np.load(args.reference), args.width)

    s = frame.settings
    s.method, s.photons, s.radius, s.iterations, s.time_limit = args.method, args.photons, args.radius, args.iterations, 0.0
    s.caustics_pass = args.split > 0
    s.boundary_correction = not args.no_boundary_correction
    if args.aimed_photons is not None:
        s.aimed_photons = args.aimed_photons
    progressive = core.Progressive(frame.scene, frame.camera, s)
    spent, saved = 0.0, {}
    print(f"diagnosis: {args.width} px, {s}")
    while not progressive.finished:
        started = cpu_seconds()
        progressive.step()
        spent += cpu_seconds() - started
        image = progressive.image()
        ssim = float(core.ssim(image, reference))
        mean_ratio = float(image[..., :3].mean() / reference[..., :3].mean())
        print(f"diagnosis: pass {progressive.iterations_done} cpu {spent:.3f} s wall {progressive.elapsed:.3f} s "
              f"SSIM {ssim:.4f} mean ratio {mean_ratio:.4f}", flush=True)
        if args.split and progressive.iterations_done == args.split:
            saved.update({f"early_{k}": v for k, v in progressive.passes().items()})
    stats = progressive.stats()
    print("diagnosis: seconds", {k: round(v, 3) for k, v in sorted(stats["seconds"].items())})
    print("diagnosis: counters", {k: stats["counters"][k] for k in ("photons_emitted", "photons_stored",
                                                                    "caustic_photons_stored", "aimed_photons_emitted")
                                  if k in stats["counters"]})
    if args.split:
        saved.update({f"late_{k}": v for k, v in progressive.passes().items()})
        np.savez_compressed(args.save, reference=reference, **saved)
        print(f"diagnosis: components saved to {args.save}")


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
