"""Cycles' shadow terminator Geometry Offset (Object > Shading > Shadow Terminator, 0.1 by default): a low-poly
smooth sphere lit from the side is lit as far as its shading normals face the sun, not only as far as its facets
do (native/include/photonsplat/shadow_terminator.h). Photon Splat follows the setting as Cycles does."""

import math

import bpy
import numpy as np

from blender_helpers import render_pixels, single_node_material, use_cycles, use_photonsplat


def low_poly_sphere_in_sunlight(scene):
    """An 8 x 6 UV sphere, smooth-shaded and white-diffuse, under a sun 10° above its horizon as the
    orthographic camera sees it (the terminator crosses the view), in a black world. Returns the sphere."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=8, ring_count=6, radius=1.0)
    sphere = bpy.context.active_object
    # Smooth through the data, not bpy.ops.object.shade_smooth: that acts on the context's selection, which other
    # tests in the same session may leave elsewhere (the sphere stayed flat under 4.5 in the suite).
    sphere.data.polygons.foreach_set("use_smooth", [True] * len(sphere.data.polygons))
    sphere.data.update()
    sphere.data.materials.append(single_node_material("White", "ShaderNodeBsdfDiffuse", Color=(0.8, 0.8, 0.8, 1.0)))
    sun = bpy.data.lights.new("Sun", 'SUN')
    sun.energy, sun.angle = 3.0, 0.0
    sun_object = bpy.data.objects.new("Sun", sun)
    sun_object.rotation_euler = (math.radians(90.0), 0.0, math.radians(80.0))
    scene.collection.objects.link(sun_object)
    camera = bpy.data.cameras.new("Camera")
    camera.type, camera.ortho_scale = 'ORTHO', 2.4
    camera_object = bpy.data.objects.new("Camera", camera)
    camera_object.location, camera_object.rotation_euler = (0.0, -5.0, 0.0), (math.radians(90.0), 0.0, 0.0)
    scene.collection.objects.link(camera_object)
    scene.camera = camera_object
    scene.world = bpy.data.worlds.new("Black")
    scene.world.color = (0.0, 0.0, 0.0)
    return sphere


def set_geometry_offset(obj, offset):
    """The object's Geometry Offset where Cycles reads it: the Cycles add-on's object settings in 3.x, the object
    itself in 4.x (whose add-on still registers the old one, unread)."""
    owner = obj if hasattr(obj, "shadow_terminator_geometry_offset") else obj.cycles
    owner.shadow_terminator_geometry_offset = offset


def test_the_geometry_offset_lights_a_low_poly_sphere_as_in_cycles(empty_scene, tmp_path, core):
    """The light the offset adds (0.1 against 0) is Cycles' within 10 %, and each image's mean within 1.5 %.
    Measured: the offset adds 2.2 % of the image in Cycles 3.4 and 2.2 % in Photon Splat (0 before it followed
    the setting); the images agree within 0.8 %."""
    sphere = low_poly_sphere_in_sunlight(empty_scene)
    means = {}
    for offset in (0.1, 0.0):
        set_geometry_offset(sphere, offset)
        use_cycles(empty_scene, 48, 4, samples=16)
        empty_scene.cycles.pixel_filter_type, empty_scene.cycles.filter_width = 'BOX', 0.01  # pixel centres, as ours
        cycles = render_pixels(tmp_path / f"cycles_{offset}.exr")[..., :3]
        use_photonsplat(empty_scene, 48, 10_000, max_bounces=4)
        ours = render_pixels(tmp_path / f"ours_{offset}.exr")[..., :3]
        means[offset] = (float(cycles.mean()), float(ours.mean()))
        print(f"\ngeometry offset {offset}: Cycles {means[offset][0]:.5f}, Photon Splat {means[offset][1]:.5f}")
        assert abs(means[offset][1] / means[offset][0] - 1.0) < 0.015
    cycles_gain = means[0.1][0] - means[0.0][0]
    ours_gain = means[0.1][1] - means[0.0][1]
    assert cycles_gain > 0.015 * means[0.0][0]       # the scene shows the offset at all
    assert abs(ours_gain / cycles_gain - 1.0) < 0.1
    assert np.isfinite(ours_gain)
