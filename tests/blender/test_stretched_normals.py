"""Smooth normals of a mesh stretched by its object's transform, against Cycles (Scene::normals_in_world).

For a final render Cycles bakes the transform of a mesh that one object alone shows into the mesh
(apply_static_transforms): each corner normal is turned into the world and normalised there, then interpolated
across the triangle. A mesh that several objects show (a linked duplicate, an instance) keeps object space: its
normals are interpolated first and turned after. The two agree unless the transform stretches (a non-uniform scale
or a shear); then the interpolated normals differ between corners, and a glossy highlight moves. The core turned
every instance's normals after interpolating: differential seed 34's glossy UV sphere, scaled 1.31 x 0.78 x 1.27,
had 0.977 of Cycles 3.4's direct light from its rectangle light (0.998 with the normals turned first). Here, a
coarser sphere at roughness 0.3 under a 1.0 x 0.45 rectangle: 0.964 of Cycles 3.4, its lit 4 x 4 blocks
0.79-1.05; now 0.997 and 0.96-1.01. The linked duplicate was and is 0.996."""

import bpy
import numpy as np
import pytest

from blender_helpers import block_means, direct_light_pair

SIZE = 48


def glossy(name, roughness):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    node = tree.nodes.new('ShaderNodeBsdfGlossy')
    node.distribution = 'GGX'
    node.inputs['Roughness'].default_value = roughness
    node.inputs['Color'].default_value = (0.8, 0.63, 0.64, 1.0)
    output = tree.nodes.new('ShaderNodeOutputMaterial')
    tree.links.new(node.outputs['BSDF'], output.inputs['Surface'])
    return material


def stretched_glossy_sphere(scene, linked_duplicate):
    """A 16 x 8 smooth UV sphere, scaled 1.31 x 0.78 x 1.27 and turned, under a 0.6 x 0.27 rectangle light;
    with `linked_duplicate`, a second object showing the same mesh stands far off to the side, out of view."""
    scene.world = bpy.data.worlds.new("Black")
    scene.world.color = (0.0, 0.0, 0.0)
    bpy.ops.mesh.primitive_uv_sphere_add(segments=16, ring_count=8, radius=0.5)
    sphere = bpy.context.active_object
    bpy.ops.object.shade_smooth()
    sphere.scale = (1.31, 0.78, 1.27)
    sphere.rotation_euler = (4.42, 5.39, 4.62)
    sphere.data.materials.append(glossy("Glossy", 0.3))
    if linked_duplicate:
        twin = bpy.data.objects.new("Twin", sphere.data)
        scene.collection.objects.link(twin)
        twin.location = (40.0, 0.0, 0.0)
    bpy.ops.object.light_add(type='AREA', location=(-1.0, -1.6, 1.4))
    lamp = bpy.context.active_object
    lamp.data.shape = 'RECTANGLE'
    lamp.data.size, lamp.data.size_y = 1.0, 0.45
    lamp.data.energy = 300.0
    lamp.rotation_euler = (0.9, 0.0, -0.55)
    bpy.ops.object.camera_add(location=(0.0, -3.0, 0.3), rotation=(1.47, 0.0, 0.0))
    scene.camera = bpy.context.active_object
    scene.camera.data.lens = 55
    return scene


@pytest.mark.parametrize("linked_duplicate", [False, True], ids=["shown_once", "linked_duplicate"])
def test_a_stretched_smooth_sphere_reflects_a_light_where_cycles_does(empty_scene, tmp_path, core, linked_duplicate):
    scene = stretched_glossy_sphere(empty_scene, linked_duplicate)
    cycles, ours = direct_light_pair(scene, SIZE, tmp_path, core)
    c, p = block_means(cycles), block_means(ours)
    lit = c > 0.05 * c.max()
    ratios = p[lit] / c[lit]
    print(f"\n{'a linked duplicate' if linked_duplicate else 'shown once'}: Photon Splat / Cycles "
          f"{ours.sum() / cycles.sum():.4f}; lit 4 x 4 blocks {ratios.min():.3f}-{ratios.max():.3f}")
    # Measured: Cycles 4.5, 0.993 shown once and 0.988 as a linked duplicate (its images of the two differ by
    # 2.8 %, Photon Splat's by 3.4 %); Cycles 5.0, 1.008 and 1.010.
    assert abs(ours.sum() / cycles.sum() - 1.0) < 0.015
    assert 0.9 < ratios.min() and ratios.max() < 1.1
