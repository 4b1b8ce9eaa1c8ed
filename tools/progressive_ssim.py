#!/usr/bin/python3
"""SSIM of two builds' progressive images: a change that alters an estimator (not its expectation) must keep the
converged image, so the 64-pass images of the old and the new build must agree (SSIM >= 0.99, issue 19).
tools/image_identity.py checks the bits where an estimator is unchanged; this checks the rest.

    /usr/bin/python3 tools/progressive_ssim.py render --tree DIR --out FILE.npz [--passes 64] [--size 480x270]
        Renders blend_scenes/{cornell_caustics,atrium,glossy_row}.blend (--scenes) with the add-on of
        DIR/build/blender, through the core as the engine exports them, progressive with --passes iterations at
        the scene's seed, cluster_cone, 50,000 photons a pass; writes the images into FILE.npz.
    /usr/bin/python3 tools/progressive_ssim.py compare A.npz B.npz
        SSIM (display luminance, Wang et al.'s 11x11 Gaussian window, as tools/benchmark.py) and the ratio of
        means, per scene. Exits 1 when an SSIM is below --min (0.99).
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = "cornell_caustics,atrium,glossy_row"

INSIDE_BLENDER = r"""
import sys, bpy, numpy as np
from photonsplat import _core as core
from photonsplat import export
out, passes, width, height = sys.argv[-4], int(sys.argv[-3]), int(sys.argv[-2]), int(sys.argv[-1])
scene = bpy.context.scene
scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = width, height, 100
scene.photonsplat.photons = 50000
scene.photonsplat.method = "cluster_cone"
scene.photonsplat.radius = 0.0
frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
frame.settings.iterations = passes
frame.settings.time_limit = 0.0
image, stats = core.render(frame.scene, frame.camera, frame.settings)
np.save(out, image)
"""


def render(args):
    images = {}
    with tempfile.TemporaryDirectory() as scratch:
        script = os.path.join(scratch, "render.py")
        with open(script, "w") as f:
            f.write(INSIDE_BLENDER)
        width, height = (int(v) for v in args.size.split("x"))
        for name in args.scenes.split(","):
            out = os.path.join(scratch, name + ".npy")
            env = dict(os.environ, BLENDER_USER_SCRIPTS=os.path.join(os.path.abspath(args.tree), "build", "blender"))
            subprocess.run(["blender", "-b", "--factory-startup", "-noaudio", "--python-exit-code", "1",
                            "--addons", "photonsplat", os.path.join(ROOT, "blend_scenes", name + ".blend"),
                            "--python", script, "--", out, str(args.passes), str(width), str(height)],
                           env=env, check=True, stdout=subprocess.DEVNULL)
            images[name] = np.load(out)
            print(f"progressive_ssim: {name} rendered", flush=True)
    np.savez_compressed(args.out, **images)


def display_luminance(image):
    rgb = np.clip(image[..., :3], 0.0, 1.0)
    srgb = np.where(rgb <= 0.0031308, 12.92 * rgb, 1.055 * np.power(rgb, 1.0 / 2.4) - 0.055)
    return srgb @ np.array([0.2126, 0.7152, 0.0722])


def compare(args):
    from skimage.metrics import structural_similarity

    a, b = np.load(args.a), np.load(args.b)
    worst = 1.0
    print("| scene | SSIM | mean ratio (B / A) |")
    print("|---|---|---|")
    for name in a.files:
        x, y = a[name], b[name]
        ssim = float(structural_similarity(display_luminance(x), display_luminance(y), gaussian_weights=True,
                                           sigma=1.5, use_sample_covariance=False, data_range=1.0))
        worst = min(worst, ssim)
        print(f"| `{name}` | {ssim:.4f} | {y[..., :3].mean() / x[..., :3].mean():.4f} |")
    return 0 if worst >= args.min else 1


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render")
    r.add_argument("--tree", default=ROOT)
    r.add_argument("--out", required=True)
    r.add_argument("--passes", type=int, default=64)
    r.add_argument("--size", default="480x270")
    r.add_argument("--scenes", default=SCENES)
    c = sub.add_parser("compare")
    c.add_argument("a")
    c.add_argument("b")
    c.add_argument("--min", type=float, default=0.99)
    args = parser.parse_args()
    if args.command == "render":
        render(args)
        return 0
    return compare(args)


if __name__ == "__main__":
    sys.exit(main())
