"""The same scene translated by 1e5 gives the same image to 1e-3, through Blender.

A small scene (a floor, a cube, a glass sphere, a point light, a camera) rendered at the origin, then with every
object and the camera moved by (1e5, -1e5, 1e5). Blender keeps matrices in float32 (locations 7.8 mm apart at
1e5), so the scene's locations are multiples of 1/128: moved, they stay exactly what they were relative to each
other, and any difference in the image is the renderer's. The core renders far scenes relative to a render origin
near their geometry (native/include/photonsplat/scene.h). Two 32×32 renders of 20k photons, and the viewport's
in-place moves.
"""

import bpy
import numpy as np

from blender_helpers import enable_nodes, render_pixels, use_photonsplat

OFFSET = (1e5, -1e5, 1e5)


def build_scene(scene):
    bpy.ops.mesh.primitive_plane_add(size=8.0, location=(0.0, 0.0, 0.0))
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.75, 0.5, 0.5))
    bpy.ops.mesh.primitive_uv_sphere_add(segments=24, ring_count=12, radius=0.5, location=(-0.75, -0.25, 0.625))
    glass = bpy.data.materials.new("glass")
    enable_nodes(glass)
    nodes = glass.node_tree.nodes
    nodes.remove(nodes["Principled BSDF"])
    bsdf = nodes.new("ShaderNodeBsdfGlass")
    glass.node_tree.links.new(bsdf.outputs["BSDF"], nodes["Material Output"].inputs["Surface"])
    bpy.context.active_object.data.materials.append(glass)
    bpy.ops.object.light_add(type='POINT', location=(0.5, -1.0, 3.0))
    bpy.context.active_object.data.energy = 500.0
    bpy.ops.object.camera_add(location=(0.0, -5.0, 2.5), rotation=(1.15, 0.0, 0.0))
    scene.camera = bpy.context.active_object


def test_scene_moved_by_1e5_renders_the_same_image(empty_scene, tmp_path, core):
    scene = empty_scene
    build_scene(scene)
    use_photonsplat(scene, 32, 20000, seed=1)
    at_origin = render_pixels(tmp_path / "origin.exr")
    for ob in scene.objects:
        before = tuple(ob.location)
        ob.location = tuple(a + b for a, b in zip(before, OFFSET))
        # float32 held the moved location exactly: the scene's own data did not change, only its place.
        assert tuple(a - b for a, b in zip(ob.location, OFFSET)) == before, ob.name
    bpy.context.view_layer.update()
    moved = render_pixels(tmp_path / "moved.exr")
    rgb0, rgb1 = at_origin[..., :3].astype(np.float64), moved[..., :3].astype(np.float64)
    assert rgb0.mean() > 1e-3, "the scene at the origin rendered black"
    difference = np.abs(rgb1 - rgb0).sum() / np.abs(rgb0).sum()
    print(f"\nmoved by 1e5: mean absolute difference {difference:.3g} of the mean radiance {rgb0.mean():.4f}")
    assert difference < 1e-3


def test_viewport_moves_keep_precision(empty_scene, core):
    """The viewport moves objects in place (BlenderSync: set_instance_transform, then fit_origin): moved by 1e5,
    its core scene's render origin is the one a new export gets, so it renders as that export does."""
    from test_viewport import DepsgraphUpdates
    from photonsplat import export

    scene = empty_scene
    build_scene(scene)
    sync = export.BlenderSync(core)
    sync.sync(bpy.context.evaluated_depsgraph_get())
    assert sync.scene.origin == (0.0, 0.0, 0.0)
    with DepsgraphUpdates(sync, release=lambda: True) as updates:
        for ob in scene.objects:
            ob.location = tuple(a + b for a, b in zip(ob.location, OFFSET))
        reports = updates.evaluate()
    assert sum(r.moved for r in reports) == 3 and not any(r.rebuilt for r in reports)
    fresh = export.BlenderSync(core)
    fresh.sync(bpy.context.evaluated_depsgraph_get())
    assert sync.scene.origin == fresh.scene.origin == OFFSET
