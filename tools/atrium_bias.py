"""Where does splatting lose light against the reference? A measurement program (docs/results/README.md,
"Atrium: where splatting's missing light is"), not a test.

    BLENDER_USER_SCRIPTS=build/blender blender -b --factory-startup -noaudio --addons photonsplat \\
        blend_scenes/atrium.blend --python tools/atrium_bias.py -- --width 64 --lights sun --bounces 1 2 8

For every --bounces value b it renders the same exported frame with render_reference(max_bounces=b, or
--reference-bounces; --reference-npy loads a saved one instead and adds SSIM) and with splatting (max_bounces=b,
--photons, each --radii value, 0 = the automatic radius; one-shot, or --iterations jittered iterations with --alpha 1
for a fixed radius and a box filter like the reference's) and prints the mean linear radiance of each,
splatting split into emission / direct / indirect / caustics. --lights picks which
light sources stay: all, sun (the world made black) or world (the sun's strength set to 0). The images go to
--save (npz) for per-region analysis.

Bounce counts are not the same thing in the two renderers: a reference path of max_bounces b has b + 1
surface vertices with light sampling (b scattering events after the first hit); a photon of max_bounces b is
stored at its hits 1..b, and the view sample adds one scattering: the same b + 1 vertices for a light that is
sampled by shadow rays at both ends (sun, area, point). The world is different: the reference reaches it by
BSDF sampling only (an escaping ray), so reference(b) holds world paths of b vertices while splatting(b) holds
b + 1. Compare world-only renders as reference(b + 1) against splatting(b).
"""
import argparse
import sys
import time

import numpy as np


def mean(image):
    return float(np.mean(np.asarray(image, np.float64)[..., :3]))


def main(argv):
    import bpy

    from photonsplat import _core as core
    from photonsplat import export

    parser = argparse.ArgumentParser()
    parser.add_argument("--width", type=int, default=64)
    parser.add_argument("--frame", type=int, default=1)
    parser.add_argument("--lights", choices=("all", "sun", "world"), default="all")
    parser.add_argument("--bounces", type=int, nargs="+", default=[8])
    parser.add_argument("--reference-samples", type=int, default=512)
    parser.add_argument("--reference-bounces", type=int, default=None,
                        help="one reference max_bounces for every --bounces value (default: the same b)")
    parser.add_argument("--reference-seed", type=int, default=7)
    parser.add_argument("--reference-npy", default="",
                        help="a saved reference of the same size, used instead of rendering one (then SSIM is printed)")
    parser.add_argument("--photons", type=int, default=200_000)
    parser.add_argument("--radii", type=float, nargs="+", default=[0.0])
    parser.add_argument("--method", default="cluster_cone")
    parser.add_argument("--direct-samples", type=int, default=4)
    parser.add_argument("--no-guide", action="store_true")
    parser.add_argument("--aimed-photons", type=float, default=None, help="default: the core's")
    parser.add_argument("--iterations", "--passes", type=int, default=1,  # --passes: the old name
                        help="> 1: progressive iterations (jittered pixels: a box filter like the reference's)")
    parser.add_argument("--alpha", type=float, default=2.0 / 3.0, help="radius shrinking over the iterations; 1 = fixed")
    parser.add_argument("--save", default="")
    args = parser.parse_args(argv)

    scene = bpy.context.scene
    scene.frame_set(args.frame)
    aspect = scene.render.resolution_y / scene.render.resolution_x
    scene.render.resolution_x, scene.render.resolution_y = args.width, max(16, int(round(args.width * aspect)))
    scene.render.resolution_percentage = 100
    if args.lights == "world":
        for ob in scene.objects:
            if ob.type == 'LIGHT':
                ob.data.energy = 0.0
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    if args.lights == "sun":
        frame.scene.set_background(radiance=(0.0, 0.0, 0.0))
    print(f"atrium_bias: {frame.width}x{frame.height} frame {args.frame} lights={args.lights} "
          f"{frame.triangles} triangles", flush=True)

    saved = {}
    for b in args.bounces:
        rb = args.reference_bounces if args.reference_bounces is not None else b
        started = time.perf_counter()
        if args.reference_npy:
            reference = np.load(args.reference_npy)
        else:
            reference, _ = core.render_reference(frame.scene, frame.camera, samples=args.reference_samples,
                                                 seed=args.reference_seed, max_bounces=rb)
        ref_mean = mean(reference)
        print(f"reference b={rb}: mean {ref_mean:.5f} ({time.perf_counter() - started:.1f} s)", flush=True)
        saved[f"reference_b{rb}"] = np.asarray(reference)
        for radius in args.radii:
            s = frame.settings
            s.method, s.photons, s.radius, s.iterations, s.max_bounces = args.method, args.photons, radius, args.iterations, b
            s.alpha = args.alpha
            if args.aimed_photons is not None:
                s.aimed_photons = args.aimed_photons
            s.direct_samples, s.caustics_pass, s.guide_photons = args.direct_samples, True, not args.no_guide
            image, stats, passes = core.render(frame.scene, frame.camera, s, passes=True)
            parts = {k: mean(passes[k]) for k in ("emission", "direct", "indirect", "caustics")}
            used = stats["values"].get("radius", radius)
            print(f"  splat b={b} r={used:.4g} photons={args.photons}: mean {mean(image):.5f} "
                  f"ratio {mean(image) / ref_mean:.4f}  " +
                  " ".join(f"{k} {v:.5f}" for k, v in parts.items()) +
                  f"  stored {stats['counters'].get('photons_stored', 0):.0f}" +
                  (f"  SSIM {float(core.ssim(image, reference)):.4f}" if args.reference_npy else ""), flush=True)
            key = f"splat_b{b}_r{radius:g}"
            saved[key] = np.asarray(image)
            for k in ("emission", "direct", "indirect", "caustics", "depth", "normal"):
                saved[f"{key}_{k}"] = np.asarray(passes[k])
    if args.save:
        np.savez_compressed(args.save, **saved)


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
