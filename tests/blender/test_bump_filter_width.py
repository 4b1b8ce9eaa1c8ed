"""A Bump node's normal, pixel by pixel against Cycles: its Height is sampled a Filter Width of ray differentials
away (Blender 3.x: one whole differential; 4.x: the node's Filter Width input, 0.1 for a new node). A wave whose
period is a few pixels shows the step: its finite differences over a whole pixel and over a tenth of one tilt the
normal differently (compat.bump_filter_width, shading_point_ops.cpp)."""

import bpy
import numpy as np
import pytest

from blender_helpers import render_pixels, use_photonsplat

SIZE = 32
HAS_FILTER_WIDTH = bpy.app.version >= (4, 1, 0)


def bumped_normal_as_colour(scene, filter_width):
    """An orthographic view straight down on a 4 m plane whose Emission colour is its bumped normal mapped to
    [0, 1] (N / 2 + 1/2); the bump is a Wave of 0.5 m period in object space, Distance 0.05."""
    bpy.ops.mesh.primitive_plane_add(size=4.0)
    plane = bpy.context.active_object
    material = bpy.data.materials.new("Bumped normal")
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    coordinates = tree.nodes.new('ShaderNodeTexCoord')
    wave = tree.nodes.new('ShaderNodeTexWave')
    wave.inputs['Scale'].default_value = 2.0
    wave.bands_direction = 'DIAGONAL'
    bump = tree.nodes.new('ShaderNodeBump')
    bump.inputs['Distance'].default_value = 0.05
    if filter_width is not None:
        bump.inputs['Filter Width'].default_value = filter_width
    to_colour = tree.nodes.new('ShaderNodeVectorMath')
    to_colour.operation = 'MULTIPLY_ADD'
    to_colour.inputs[1].default_value = (0.5, 0.5, 0.5)
    to_colour.inputs[2].default_value = (0.5, 0.5, 0.5)
    emission = tree.nodes.new('ShaderNodeEmission')
    tree.links.new(coordinates.outputs['Object'], wave.inputs['Vector'])
    tree.links.new(wave.outputs['Fac'], bump.inputs['Height'])
    tree.links.new(bump.outputs['Normal'], to_colour.inputs[0])
    tree.links.new(to_colour.outputs['Vector'], emission.inputs['Color'])
    tree.links.new(emission.outputs['Emission'], tree.nodes['Material Output'].inputs['Surface'])
    plane.data.materials.append(material)
    camera = bpy.data.cameras.new("Camera")
    camera.type, camera.ortho_scale = 'ORTHO', 4.0
    camera_object = bpy.data.objects.new("Camera", camera)
    camera_object.location = (0.0, 0.0, 5.0)
    scene.collection.objects.link(camera_object)
    scene.camera = camera_object
    scene.world = bpy.data.worlds.new("Black")
    scene.world.color = (0.0, 0.0, 0.0)
    scene.render.resolution_x = scene.render.resolution_y = SIZE
    scene.render.resolution_percentage = 100


@pytest.mark.parametrize("filter_width", [None, 1.0, 0.5] if HAS_FILTER_WIDTH else [None])
def test_a_bumped_normal_as_cycles(filter_width, empty_scene, tmp_path, core):
    """Each pixel's normal (as a colour) within 0.01 of Cycles' at pixel centres. A Bump that stepped a whole
    differential where Cycles steps a tenth (4.x's default) is off by up to 0.26 in this scene (0.16 where
    Cycles steps half of one)."""
    bumped_normal_as_colour(empty_scene, filter_width)
    empty_scene.render.engine = 'CYCLES'
    cycles_settings = empty_scene.cycles
    cycles_settings.device, cycles_settings.samples = 'CPU', 1
    cycles_settings.use_denoising = cycles_settings.use_adaptive_sampling = False
    cycles_settings.pixel_filter_type, cycles_settings.filter_width = 'BOX', 0.01   # pixel centres, as ours
    cycles = render_pixels(tmp_path / "cycles.exr")[..., :3]
    use_photonsplat(empty_scene, SIZE, 1000, iterations=1)
    ours = render_pixels(tmp_path / "ours.exr")[..., :3]
    difference = np.abs(ours - cycles)
    print(f"\nfilter width {filter_width}: largest difference {difference.max():.4f}, mean {difference.mean():.5f}; "
          f"normal colour range {cycles.min():.3f}-{cycles.max():.3f}")
    assert np.ptp(cycles[..., 0]) > 0.2                        # the bump tilts the normal a lot
    assert difference.max() < 0.01
