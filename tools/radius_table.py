"""How the automatic radius of a progressive render is chosen on a scene: the boundary loss of what the camera sees
at each candidate radius, the error model it is scored by, and the pick (docs/results/README.md, "Automatic
radius"). A measurement program, not a test.

    BLENDER_USER_SCRIPTS=build/blender blender -b --factory-startup -noaudio --addons photonsplat \\
        blend_scenes/atrium.blend --python tools/radius_table.py -- --width 128 --photons 12500

Prints one markdown row per candidate, the scale s against default_radius, with its boundary_loss B and the model
B^2 + v / s^2 (v = 1/128, kDiscVariance in native/src/kernel_radius.cpp), then the radius automatic_radius
returns and the wall time it took.
"""
import argparse
import pathlib
import sys
import time

DISC_VARIANCE = 1.0 / 128.0  # kDiscVariance of native/src/kernel_radius.cpp
STEPS = 5                    # candidates: default_radius x 1, 1/sqrt(2), ..., 1/4


def main(argv):
    import bpy

    from photonsplat import _core as core
    from photonsplat import export

    parser = argparse.ArgumentParser()
    parser.add_argument("--width", type=int, default=128)
    parser.add_argument("--photons", type=int, default=12_500)
    args = parser.parse_args(argv)

    scene = bpy.context.scene
    aspect = scene.render.resolution_y / scene.render.resolution_x
    scene.render.resolution_x, scene.render.resolution_y = args.width, max(16, int(round(args.width * aspect)))
    scene.render.resolution_percentage = 100
    scene.photonsplat.radius, scene.photonsplat.passes, scene.photonsplat.time_limit = 0.0, 1, 0.0
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())

    # A one-pass render reports the radius it used: default_radius for this photon count.
    s = frame.settings
    s.photons, s.radius, s.passes, s.time_limit = args.photons, 0.0, 1, 0.0
    _, stats = core.render(frame.scene, frame.camera, s)
    largest = stats["values"]["radius"]

    name = pathlib.Path(bpy.data.filepath).stem
    print(f"radius_table: {name} {frame.camera.width}x{frame.camera.height}, {args.photons} photons, "
          f"default_radius {largest:.4g}")
    print("| scale | radius | boundary loss | loss² + v/scale² |")
    print("|---|---|---|---|")
    for step in range(STEPS):
        scale = 0.5 ** (0.5 * step)
        loss = core.boundary_loss(frame.scene, frame.camera, largest * scale)
        print(f"| {scale:.3f} | {largest * scale:.4g} | {loss:.4f} | {loss * loss + DISC_VARIANCE / scale ** 2:.4f} |")
    started = time.perf_counter()
    chosen = core.automatic_radius(frame.scene, frame.camera, args.photons)
    took = time.perf_counter() - started
    print(f"radius_table: automatic_radius {chosen:.4g} ({chosen / largest:.3f} of default_radius) in {took * 1e3:.0f} ms")


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
