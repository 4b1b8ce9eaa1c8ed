"""Cycles against the reference renderer (and optionally Photon Splat) on variants of one generated scene.

A difference that both renderers share with each other but not with Cycles is found by taking the scene apart:
hide a light or a mesh, turn the world off, stop at a bounce, swap a material, and see which change makes the
difference go away. Each variant is a ';'-separated list of edits applied to the scene as drawn (brought to scale
1 around the origin, as tools/differential.py renders it); an empty variant is the scene itself.

    BLENDER_USER_SCRIPTS=build/blender blender -b --factory-startup -noaudio --addons photonsplat \\
        --python tools/scene_variants.py -- random_15.blend "" "hide:Light1" "hide:Light1;world:0" \\
        [--bounces 16] [--cycles-samples 512] [--reference-samples 256] [--passes 100] [--blocks] [--save DIR]

Edits:
  hide:NAME[,NAME...]     hide meshes or lights (from render and the viewport's depsgraph, which the export reads)
  world:STRENGTH          the world's Background strength
  diffuse:MAT[,MAT...]    the materials as Diffuse BSDFs of their base colour (tools/indirect_compare.py)
  glossy:MAT:DISTRIBUTION a material as a Glossy BSDF of its base colour and roughness (GGX, BECKMANN, MULTI_GGX...)
  shade-flat:NAME[,...]   meshes flat-shaded
  set:EXPR=VALUE          any property, as Python: set:bpy.data.lights['Light0'].shadow_soft_size=0.1

Prints per variant Cycles' mean (two seeds, their relative difference as its noise), the reference's (likewise) and
their ratio; with --passes, Photon Splat's after that many progressive passes; with --blocks, the 8 x 8 maps of the
reference's blocks (and Photon Splat's) over Cycles'. Found stop 50's two biases: seed 15's soft point light under its ceiling (its
light alone 0.972, at one bounce 0.976, direct light 1.000) and seed 34's stretched glossy sphere (its light
alone 0.982, direct light 0.971, the sphere flat-shaded 1.000).
"""
import argparse
import json
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tools"))
sys.path.insert(0, str(REPO / "blend_scenes"))


def parse_args(argv):
    p = argparse.ArgumentParser(prog="scene_variants.py")
    p.add_argument("blend")
    p.add_argument("variants", nargs="*", default=[""])
    p.add_argument("--bounces", type=int, default=16, help="Cycles' and the renderers' bounce limit")
    p.add_argument("--cycles-samples", type=int, default=512, help="per seed (two seeds)")
    p.add_argument("--reference-samples", type=int, default=256, help="per seed (two seeds)")
    p.add_argument("--passes", type=int, default=0, help="Photon Splat progressive passes (0: not rendered)")
    p.add_argument("--blocks", action="store_true", help="print the reference / Cycles map of 8 x 8 blocks")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--save", type=Path, help="folder for each variant's images (variant_K.npz: cycles, reference, "
                   "photonsplat), to look at pixel by pixel")
    return p.parse_args(argv)


def material_as_glossy(material, distribution):
    import bpy  # noqa: F401
    from indirect_compare import base_colour
    tree = material.node_tree
    roughness = next((n.inputs["Roughness"].default_value for n in tree.nodes if "Roughness" in n.inputs), 0.5)
    node = tree.nodes.new("ShaderNodeBsdfGlossy")
    node.distribution = distribution
    node.inputs["Roughness"].default_value = roughness
    node.inputs["Color"].default_value = base_colour(material)
    output = next(n for n in tree.nodes if n.type == "OUTPUT_MATERIAL" and n.is_active_output)
    tree.links.new(node.outputs["BSDF"], output.inputs["Surface"])


def apply_edit(edit):
    import bpy
    from indirect_compare import make_diffuse
    kind, _, arg = edit.partition(":")
    if kind == "hide":
        for name in arg.split(","):
            bpy.data.objects[name].hide_render = bpy.data.objects[name].hide_viewport = True
    elif kind == "world":
        world = bpy.context.scene.world
        next(n for n in world.node_tree.nodes if n.type == "BACKGROUND").inputs["Strength"].default_value = float(arg)
    elif kind == "diffuse":
        for name in arg.split(","):
            make_diffuse(bpy.data.materials[name], 0.0)
    elif kind == "glossy":
        name, _, distribution = arg.partition(":")
        material_as_glossy(bpy.data.materials[name], distribution or "GGX")
    elif kind == "shade-flat":
        for name in arg.split(","):
            for polygon in bpy.data.objects[name].data.polygons:
                polygon.use_smooth = False
    elif kind == "set":
        target, _, value = arg.partition("=")
        exec(f"{target} = {value}", {"bpy": bpy})
    else:
        raise SystemExit(f"unknown edit {edit!r}")


def blender_main(argv):
    import bpy
    import numpy as np
    import make_random_scenes
    from closure_gallery import render_exr, use_cycles_oracle
    from photonsplat import engine, export

    args = parse_args(argv)
    core = engine.load_core()
    folder = Path(tempfile.mkdtemp())
    for index, variant in enumerate(args.variants):
        bpy.ops.wm.open_mainfile(filepath=args.blend)
        scene = bpy.context.scene
        if "differential" in scene:
            make_random_scenes.canonical(scene, json.loads(scene["differential"]))
        for edit in filter(None, variant.split(";")):
            apply_edit(edit)
        cycles = []
        for seed in (1, 2):
            use_cycles_oracle(scene, args.cycles_samples, seed, args.threads, args.bounces)
            cycles.append(render_exr(scene, folder / "cycles.exr")[..., :3].astype(np.float64))
        scene.render.engine = "PHOTONSPLAT"
        frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
        reference = [np.asarray(core.render_reference(frame.scene, frame.camera, samples=args.reference_samples,
                                                      seed=seed, threads=args.threads,
                                                      max_bounces=args.bounces)[0])[..., :3].astype(np.float64)
                     for seed in (1, 2)]
        c, r = (cycles[0] + cycles[1]) / 2, (reference[0] + reference[1]) / 2
        noise = lambda pair: abs(pair[0].mean() - pair[1].mean()) / max(pair[0].mean() + pair[1].mean(), 1e-12)
        line = (f"variant {variant!r}: Cycles {c.mean():.5f} (noise {noise(cycles):.4f}), reference {r.mean():.5f} "
                f"(noise {noise(reference):.4f}), reference / Cycles {r.mean() / max(c.mean(), 1e-12):.4f}")
        ours = None
        if args.passes > 0:
            settings = frame.settings
            settings.iterations, settings.time_limit = args.passes, 0.0
            settings.max_bounces, settings.threads = args.bounces, args.threads
            progressive = core.Progressive(frame.scene, frame.camera, settings)
            for _ in range(args.passes):
                progressive.step()
            ours = np.asarray(progressive.image())[..., :3]
            line += f", Photon Splat / Cycles {ours.mean() / max(c.mean(), 1e-12):.4f} ({args.passes} passes)"
        print(line, flush=True)
        if args.save is not None:
            args.save.mkdir(parents=True, exist_ok=True)
            images = {"cycles": c, "reference": r}
            if ours is not None:
                images["photonsplat"] = ours
            np.savez_compressed(args.save / f"variant_{index}.npz",
                                **{k: v.astype(np.float32) for k, v in images.items()})
        if args.blocks:
            from differential import block_means
            np.set_printoptions(precision=3, linewidth=200, suppress=True)
            cb = block_means(c).mean(-1)
            print(block_means(r).mean(-1) / np.maximum(cb, 1e-12))
            if ours is not None:
                print("Photon Splat / Cycles:")
                print(block_means(ours).mean(-1) / np.maximum(cb, 1e-12))


if __name__ == "__main__":
    from closure_gallery import entry_point

    def host_main(argv):
        sys.exit("run inside Blender with the add-on (see the docstring)")

    entry_point(host_main, blender_main)
