"""Photon Splat's indirect light against Cycles', object by object, on diffuse surfaces.

An image's mean hides a bias in indirect light wherever direct light dominates: a Suzanne that lacks 40 % of its
bounced light can leave the image within 1 % of Cycles. This tool measures the bounced light alone. Photon Splat's
Indirect pass (the splatted photons) is compared with Cycles' diffuse indirect light, DiffInd × DiffCol (composited
from its render passes), summed over the pixels where the camera sees each object. The two agree in meaning only
where the surfaces are Diffuse BSDFs (Lambert or Oren–Nayar): --diffuse turns the named materials into one, of
their base colour, and the tool says which kept objects are not.

Run inside Debian's Blender with the add-on of the build tree:

    BLENDER_USER_SCRIPTS=build/blender blender -b --factory-startup -noaudio --addons photonsplat \\
        --python tools/indirect_compare.py -- SCENE.blend [--keep OBJ,...] [--diffuse MAT,...] [--diffuse-roughness R] \\
        [--flat OBJ,...] [--setting NAME=VALUE ...] [--passes 200] [--cycles-samples 1024]

A scene of blend_scenes/make_random_scenes.py is first brought to scale 1 around the origin, as tools/
differential.py renders it. --keep hides every other mesh; --flat flat-shades the named meshes. Cycles renders as
tools/closure_gallery.py's oracle (CPU, no denoising, 16 bounces of every kind, Filter Glossy 0), with two seeds
whose relative difference is printed as its noise; Photon Splat renders --passes progressive passes at 16 bounces.
"""
import argparse
import json
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
BOUNCES = 16


def parse_args(argv):
    p = argparse.ArgumentParser(prog="indirect_compare.py")
    p.add_argument("blend")
    p.add_argument("--keep", default="", help="meshes to keep, comma separated (the others are hidden)")
    p.add_argument("--diffuse", default="", help="materials to replace by a Diffuse BSDF of their base colour")
    p.add_argument("--diffuse-roughness", type=float, default=0.0, help="their Roughness (above 0: Oren–Nayar)")
    p.add_argument("--flat", default="", help="meshes to flat-shade")
    p.add_argument("--setting", action="append", default=[], help="a Photon Splat setting NAME=VALUE")
    p.add_argument("--passes", type=int, default=200)
    p.add_argument("--cycles-samples", type=int, default=1024, help="per seed (two seeds)")
    p.add_argument("--threads", type=int, default=2)
    return p.parse_args(argv)


def names(text):
    return [n for n in text.split(",") if n]


def base_colour(material):
    for node in material.node_tree.nodes:
        for socket in ("Base Color", "Color"):
            if socket in node.inputs and not node.inputs[socket].is_linked and node.type != 'OUTPUT_MATERIAL':
                return tuple(node.inputs[socket].default_value)
    return (0.8, 0.8, 0.8, 1.0)


def make_diffuse(material, roughness):
    tree = material.node_tree
    output = next(n for n in tree.nodes if n.type == 'OUTPUT_MATERIAL' and n.is_active_output)
    diffuse = tree.nodes.new('ShaderNodeBsdfDiffuse')
    diffuse.inputs['Color'].default_value = base_colour(material)
    diffuse.inputs['Roughness'].default_value = roughness  # above 0: Oren–Nayar
    tree.links.new(diffuse.outputs[0], output.inputs['Surface'])


def is_diffuse_only(material):
    """Whether the material's active output is a Diffuse BSDF straight from its node: what DiffInd × DiffCol
    and Photon Splat's Indirect pass both measure whole."""
    if material is None or not material.use_nodes:
        return False
    output = next((n for n in material.node_tree.nodes if n.type == 'OUTPUT_MATERIAL' and n.is_active_output), None)
    links = output.inputs['Surface'].links if output else ()
    return bool(links) and links[0].from_node.type == 'BSDF_DIFFUSE'


def object_masks(bpy, scene, objects):
    """{object name: bool (h, w) array} of the pixels whose centre's camera ray first meets that object, row 0 at
    the top (bpy's ray_cast against the evaluated scene)."""
    import numpy as np
    from mathutils import Vector
    depsgraph = bpy.context.evaluated_depsgraph_get()
    camera = scene.camera
    width = scene.render.resolution_x * scene.render.resolution_percentage // 100
    height = scene.render.resolution_y * scene.render.resolution_percentage // 100
    frame = [camera.matrix_world @ v for v in camera.data.view_frame(scene=scene)]  # tr, br, bl, tl
    top_right, bottom_right, bottom_left, top_left = frame
    origin = camera.matrix_world.translation
    ortho = camera.data.type == 'ORTHO'
    forward = -(camera.matrix_world.to_3x3() @ Vector((0, 0, 1))).normalized()
    masks = {name: np.zeros((height, width), bool) for name in objects}
    for y in range(height):
        v = (y + 0.5) / height
        left = top_left.lerp(bottom_left, v)
        right = top_right.lerp(bottom_right, v)
        for x in range(width):
            point = left.lerp(right, (x + 0.5) / width)
            start, direction = (point, forward) if ortho else (origin, (point - origin).normalized())
            hit, _, _, _, obj, _ = scene.ray_cast(depsgraph, start, direction)
            if hit and obj.name in masks:
                masks[obj.name][y, x] = True
    return masks


def cycles_diffuse_indirect(bpy, scene, samples, threads, workdir):
    """Cycles' DiffInd × DiffCol at two seeds: (mean image (h, w, 3), relative difference of their sums)."""
    import numpy as np
    sys.path.insert(0, str(REPO / "tools"))
    from closure_gallery import render_exr, use_cycles_oracle
    layer = scene.view_layers[0]
    layer.use_pass_diffuse_indirect = layer.use_pass_diffuse_color = True
    scene.use_nodes = True
    tree = scene.node_tree
    for node in list(tree.nodes):
        tree.nodes.remove(node)
    layers, composite = tree.nodes.new("CompositorNodeRLayers"), tree.nodes.new("CompositorNodeComposite")
    multiply = tree.nodes.new("CompositorNodeMixRGB")
    multiply.blend_type, multiply.inputs[0].default_value = "MULTIPLY", 1.0
    tree.links.new(layers.outputs["DiffInd"], multiply.inputs[1])
    tree.links.new(layers.outputs["DiffCol"], multiply.inputs[2])
    tree.links.new(multiply.outputs[0], composite.inputs["Image"])
    scene.render.use_compositing = True
    images = []
    for seed in (1, 2):
        use_cycles_oracle(scene, samples, seed, threads, BOUNCES)
        scene.render.film_transparent = False
        images.append(render_exr(scene, workdir / "indirect_compare.exr")[..., :3].astype(np.float64))
    a, b = images[0].sum(), images[1].sum()
    scene.use_nodes = False
    return (images[0] + images[1]) / 2, abs(a - b) / max(a + b, 1e-12)


def setting_value(current, text):
    if isinstance(current, bool):
        return text.lower() == "true"
    if isinstance(current, (int, float)):
        return type(current)(float(text))
    return text


def blender_main(argv):
    import tempfile

    import bpy
    import numpy as np

    args = parse_args(argv)
    bpy.ops.wm.open_mainfile(filepath=str(Path(args.blend).resolve()))
    scene = bpy.context.scene
    if "differential" in scene:  # a generated scene: at scale 1 around the origin, as the differential runs it
        sys.path.insert(0, str(REPO / "blend_scenes"))
        import make_random_scenes
        record = json.loads(scene["differential"])
        if record["scale"] != 1.0 or any(record["offset"]):
            make_random_scenes.canonical(scene, record)
    keep = names(args.keep)
    for obj in scene.objects:
        if obj.type == 'MESH' and keep and obj.name not in keep:
            obj.hide_render = obj.hide_viewport = True
    for name in names(args.flat):
        for polygon in bpy.data.objects[name].data.polygons:
            polygon.use_smooth = False
    for name in names(args.diffuse):
        make_diffuse(bpy.data.materials[name], args.diffuse_roughness)
    shown = [o for o in scene.objects if o.type == 'MESH' and not o.hide_render]
    for obj in shown:
        others = [s.material.name for s in obj.material_slots if not is_diffuse_only(s.material)]
        if others:
            print(f"indirect_compare: {obj.name} has materials other than a Diffuse BSDF ({', '.join(others)}): "
                  "its figures compare different things")
    masks = object_masks(bpy, scene, [o.name for o in shown])

    with tempfile.TemporaryDirectory() as workdir:
        cycles, cycles_noise = cycles_diffuse_indirect(bpy, scene, args.cycles_samples, args.threads, Path(workdir))

    from photonsplat import export
    from photonsplat.engine import load_core
    core = load_core()
    scene.render.engine = 'PHOTONSPLAT'
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    settings = frame.settings
    settings.iterations, settings.time_limit, settings.threads = 1_000_000, 0.0, args.threads
    settings.max_bounces = BOUNCES
    for text in args.setting:
        name, _, value = text.partition("=")
        setattr(settings, name, setting_value(getattr(settings, name), value))
    progressive = core.Progressive(frame.scene, frame.camera, settings)
    for _ in range(args.passes):
        progressive.step()
    indirect = np.asarray(progressive.passes()["indirect"])[..., :3].astype(np.float64)

    print(f"indirect_compare: {Path(args.blend).name}, {args.passes} passes (radius now {progressive.radius:.4g}), "
          f"Cycles 2 x {args.cycles_samples} samples (its seeds {100 * cycles_noise:.2f} % apart)")
    print(f"{'object':<24} {'pixels':>6} {'Photon Splat':>13} {'Cycles':>10} {'ratio':>7}")
    rows = [(name, mask) for name, mask in masks.items()] + [("(whole image)", np.ones(indirect.shape[:2], bool))]
    for name, mask in rows:
        ours, theirs = indirect[mask].sum(), cycles[mask].sum()
        ratio = ours / theirs if theirs > 0 else float("nan")
        print(f"{name:<24} {int(mask.sum()):>6} {ours:>13.4g} {theirs:>10.4g} {ratio:>7.3f}")


if __name__ == "__main__":
    blender_main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
