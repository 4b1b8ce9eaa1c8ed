"""A rough Glass cylinder on a floor, by Cycles and by Photon Splat at a fixed radius: its 8 x 8 blocks' ratios.

The scene of docs/results/differential.md's "Stop 41" (where seeds 39 and 176 of the generated set were traced
to): a Glass BSDF cylinder (GGX) 0.15 above a diffuse floor, under a tilted disk area light and a sun, seen from
above at 62 degrees. A fixed radius (0.1, no shrinking, no radius levels) keeps the kernel's blur from hiding a
bias of light transport. Cycles renders two seeds (its oracle as tools/closure_gallery.py runs it); their mean is
the oracle and their difference its noise.

    blender -b --factory-startup -noaudio --python tools/rough_glass_cylinder.py -- --ior 1.8 --roughness 0.4
    blender -b --factory-startup -noaudio --python tools/rough_glass_cylinder.py -- --ior 1.2 --big-light

with the add-on installed or on BLENDER_USER_SCRIPTS (build/blender after scripts/demo.sh), as
    BLENDER_USER_SCRIPTS=build/blender blender -b --factory-startup -noaudio --addons photonsplat --python ...
"""
import argparse
import math
import sys
import tempfile
from pathlib import Path

import bpy
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from closure_gallery import render_exr, use_cycles_oracle  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ior", type=float, default=1.8)
    parser.add_argument("--roughness", type=float, default=0.4)
    parser.add_argument("--big-light", action="store_true",
                        help="a 2.5 m area light and no sun, where path tracing converges fast")
    parser.add_argument("--black-floor", action="store_true", help="the glass alone: no light from the floor")
    parser.add_argument("--cycles-samples", type=int, default=8192, help="per seed")
    parser.add_argument("--iterations", type=int, default=60, help="Photon Splat's passes")
    return parser.parse_args(argv)


def material(name, make):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    tree = m.node_tree
    for node in list(tree.nodes):
        tree.nodes.remove(node)
    bsdf = make(tree)
    tree.links.new(bsdf.outputs[0], tree.nodes.new("ShaderNodeOutputMaterial").inputs[0])
    return m


def build_scene(args):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.resolution_x = scene.render.resolution_y = 64

    def floor_bsdf(tree):
        b = tree.nodes.new("ShaderNodeBsdfDiffuse")
        b.inputs["Color"].default_value = (0, 0, 0, 1) if args.black_floor else (0.6, 0.7, 0.5, 1)
        return b

    def glass_bsdf(tree):
        b = tree.nodes.new("ShaderNodeBsdfGlass")
        b.distribution = 'GGX'
        b.inputs["Roughness"].default_value = args.roughness
        b.inputs["IOR"].default_value = args.ior
        b.inputs["Color"].default_value = (0.95, 0.9, 0.95, 1)
        return b

    bpy.ops.mesh.primitive_plane_add(size=20)
    bpy.context.object.data.materials.append(material("floor", floor_bsdf))
    # Not resting on the floor: coincident faces would be a different question.
    bpy.ops.mesh.primitive_cylinder_add(radius=0.5, depth=1.2, location=(0, 0, 0.75))
    bpy.context.object.data.materials.append(material("glass", glass_bsdf))
    bpy.ops.object.light_add(type='AREA', location=(1.5, -1, 3), rotation=(0.3, 0.4, 0))
    area = bpy.context.object.data
    area.shape, area.size, area.energy = 'DISK', 2.5 if args.big_light else 0.2, 200
    bpy.ops.object.light_add(type='SUN', location=(0, 0, 5), rotation=(0.5, -0.3, 0.2))
    bpy.context.object.data.energy = 0 if args.big_light else 3
    bpy.ops.object.camera_add(location=(0, -4, 3), rotation=(math.radians(62), 0, 0))
    scene.camera = bpy.context.object
    scene.camera.data.lens = 50
    scene.world = bpy.data.worlds.new("black")
    scene.world.color = (0, 0, 0)
    return scene


def block_means(image, size=8):
    h, w = image.shape[:2]
    return image[:h - h % size, :w - w % size, :3].reshape(h // size, size, w // size, size, 3).mean(axis=(1, 3, 4))


def main():
    args = parse_args()
    scene = build_scene(args)
    folder = Path(tempfile.mkdtemp())
    cycles = []
    for seed in (1, 2):
        use_cycles_oracle(scene, args.cycles_samples, seed, 2)
        cycles.append(render_exr(scene, folder / f"cycles_{seed}.exr")[..., :3])
    oracle = (cycles[0] + cycles[1]) / 2

    from photonsplat import export
    from photonsplat.engine import load_core
    core = load_core()
    scene.render.engine = 'PHOTONSPLAT'
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    settings = frame.settings
    settings.iterations, settings.max_bounces, settings.threads, settings.seed = args.iterations, 16, 2, 1
    settings.radius, settings.alpha, settings.adaptive_radius = 0.1, 1.0, False
    progressive = core.Progressive(frame.scene, frame.camera, settings)
    for _ in range(args.iterations):
        progressive.step()
    ours = np.asarray(progressive.image())[..., :3]

    c, p = block_means(oracle), block_means(ours)
    lit = c > 1e-3
    noise = np.abs(block_means(cycles[0]) - block_means(cycles[1])) / 2
    np.set_printoptions(precision=3, suppress=True, linewidth=160)
    print(f"image: Photon Splat / Cycles {ours.mean() / oracle.mean():.4f} "
          f"(Cycles' pair {abs(cycles[0].mean() - cycles[1].mean()) / (2 * oracle.mean()):.2%} apart)")
    print("blocks, Photon Splat / Cycles (0 where Cycles is black):")
    print(np.where(lit, p / np.where(lit, c, 1.0), 0.0))
    worst = float(np.max(np.where(lit, noise / np.where(lit, c, 1.0), 0.0)))
    print(f"Cycles' own noise in those blocks: at most {worst:.1%}")


if __name__ == "__main__":
    main()
