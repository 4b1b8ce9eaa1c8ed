"""Photons on a smooth-shaded low-poly mesh, against Cycles (native/include/photonsplat/photon_shading_normals.h).

Cycles shades a smooth mesh by its interpolated normal: a surface reflects ∫ f (n_s·ω_i) L_i dω_i. Photons measure
light per unit of the triangle's area, (n_g·ω_i) L_i dω_i, so each photon a smooth-shaded view sample receives
counts (n_s·ω_i)/(n_g·ω_i) of its flux. Without that, an 80-face smooth sphere lit only by light bounced off the
floor came out 0.90 to 1.13 of Cycles in its blocks (a bias no radius removes)."""

import bpy
import mathutils
import numpy as np

from blender_helpers import render_pixels, use_cycles, use_photonsplat

SIZE = 32
BOUNCES = 2


def diffuse_material(name, value):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    tree = material.node_tree
    diffuse = tree.nodes.new('ShaderNodeBsdfDiffuse')
    diffuse.inputs['Color'].default_value = (value, value, value, 1.0)
    tree.links.new(diffuse.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    return material


def sphere_over_a_floor(scene):
    """An 80-face ico sphere, smooth-shaded, over a white floor in a near-overhead sun: the sphere's lower half
    sees the sun not at all, only the floor's bounce."""
    scene.world = bpy.data.worlds.new("Black")
    scene.world.color = (0.0, 0.0, 0.0)
    bpy.ops.mesh.primitive_plane_add(size=20.0)
    bpy.context.active_object.data.materials.append(diffuse_material("Floor", 0.9))
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=1, radius=1.0, location=(0.0, 0.0, 1.3))
    bpy.ops.object.shade_smooth()
    bpy.context.active_object.data.materials.append(diffuse_material("Sphere", 0.7))
    bpy.ops.object.light_add(type='SUN', location=(0.0, 0.0, 5.0))
    sun = bpy.context.active_object
    sun.data.energy = 5.0
    sun.data.angle = 0.05
    sun.rotation_euler = (0.3, 0.0, 0.0)
    bpy.ops.object.camera_add(location=(0.0, -5.0, 0.6))
    camera = bpy.context.active_object
    camera.rotation_euler = (mathutils.Vector((0.0, 0.0, 1.0)) - camera.location).normalized().to_track_quat(
        '-Z', 'Y').to_euler()
    camera.data.lens = 70
    scene.camera = camera
    return scene


def blocks(image, block=8):
    h, w = image.shape[:2]
    return image[..., :3].reshape(h // block, block, w // block, block, 3).mean(axis=(1, 3, 4))


def test_bounced_light_on_a_smooth_low_poly_sphere_as_cycles(empty_scene, tmp_path, core):
    scene = sphere_over_a_floor(empty_scene)
    use_cycles(scene, SIZE, BOUNCES, samples=1024)
    scene.cycles.light_sampling_threshold = 0.0
    scene.cycles.pixel_filter_type = 'BOX'
    scene.cycles.filter_width = 1.0
    cycles = np.flipud(render_pixels(tmp_path / "cycles.exr"))[..., :3]
    use_photonsplat(scene, SIZE, 100_000, max_bounces=BOUNCES, iterations=64)
    ours = np.flipud(render_pixels(tmp_path / "photonsplat.exr"))[..., :3]
    ratios = blocks(ours) / blocks(cycles)
    print(f"\nsmooth low-poly sphere, Photon Splat / Cycles: {ours.mean() / cycles.mean():.4f}; blocks\n"
          f"{np.round(ratios, 3)}")
    assert abs(ours.mean() / cycles.mean() - 1.0) < 0.02
    # The kernel's own bias on the sphere's facets (its flat-shaded twin: 0.93-1.03) is inside this; the missing
    # ratio was not (0.90 and 1.13).
    assert np.all(np.abs(ratios - 1.0) < 0.07)


def bumpy_floor_by_a_wall(scene):
    """A floor whose Diffuse normal comes from a Wave texture through Bump, lit mostly by the light a white wall
    throws back from a spot light aimed at it."""
    scene.world = bpy.data.worlds.new("Black")
    scene.world.color = (0.0, 0.0, 0.0)
    bpy.ops.mesh.primitive_plane_add(size=8.0)
    floor = diffuse_material("Bumpy", 0.8)
    tree = floor.node_tree
    wave = tree.nodes.new('ShaderNodeTexWave')
    wave.inputs['Scale'].default_value = 2.0
    bump = tree.nodes.new('ShaderNodeBump')
    bump.inputs['Distance'].default_value = 0.3
    tree.links.new(wave.outputs['Fac'], bump.inputs['Height'])
    tree.links.new(bump.outputs['Normal'], tree.nodes['Diffuse BSDF'].inputs['Normal'])
    bpy.context.active_object.data.materials.append(floor)
    bpy.ops.mesh.primitive_plane_add(size=8.0, location=(0.0, 2.0, 2.0), rotation=(1.5708, 0.0, 0.0))
    bpy.context.active_object.data.materials.append(diffuse_material("Wall", 0.8))
    bpy.ops.object.light_add(type='SPOT', location=(0.0, -1.0, 0.5))
    spot = bpy.context.active_object
    spot.data.energy = 2000.0
    spot.data.spot_size = 1.2
    spot.data.shadow_soft_size = 0.1
    spot.rotation_euler = (mathutils.Vector((0.0, 2.0, 1.2)) - spot.location).normalized().to_track_quat(
        '-Z', 'Y').to_euler()
    bpy.ops.object.camera_add(location=(0.0, -4.0, 3.0))
    camera = bpy.context.active_object
    camera.rotation_euler = (mathutils.Vector((0.0, 0.5, 0.0)) - camera.location).normalized().to_track_quat(
        '-Z', 'Y').to_euler()
    scene.camera = camera
    return scene


def test_bounced_light_on_a_bump_mapped_floor_as_the_reference(empty_scene, tmp_path, core):
    """A bump-mapped floor is shaded by its program's normal, as a smooth mesh by its interpolated one. Against the
    reference renderer, which shares the core's closures: Cycles 3.4 also multiplies a bump-mapped diffuse closure
    by its bump shadowing term (closure/bsdf.h: bump_shadowing_term), which neither renderer follows: in this scene
    with a Principled wall both came out 1.02-1.13 of Cycles in the floor's blocks (Photon Splat 1.00-1.37 without
    the ratios). Here, without them, Photon Splat's blocks were 0.89-1.28 of the reference's; 0.97-1.03 with them."""
    import photonsplat
    scene = bumpy_floor_by_a_wall(empty_scene)
    use_photonsplat(scene, SIZE, 100_000, max_bounces=4, iterations=64)
    ours = np.flipud(render_pixels(tmp_path / "photonsplat.exr"))[..., :3]
    reference, _ = photonsplat.reference.render_reference(bpy.context.evaluated_depsgraph_get(), samples=512,
                                                          max_bounces=4)
    ratios = blocks(ours) / blocks(reference[..., :3])
    print(f"\nbump-mapped floor, Photon Splat / reference: {ours.mean() / reference[..., :3].mean():.4f}; blocks\n"
          f"{np.round(ratios, 3)}")
    assert abs(ours.mean() / reference[..., :3].mean() - 1.0) < 0.02
    assert np.all(np.abs(ratios - 1.0) < 0.07)


def lone_smooth_suzanne(scene):
    """Blender's Suzanne (500 faces, smooth-shaded, Lambert) alone under a point light: the light it receives
    beyond the lamp's is what its brows, eyes, ears and cheeks pass between them, at grazing angles."""
    scene.world = bpy.data.worlds.new("Black")
    scene.world.color = (0.0, 0.0, 0.0)
    bpy.ops.mesh.primitive_monkey_add(size=2.0, rotation=(0.4, 0.0, 0.0))
    bpy.ops.object.shade_smooth()
    bpy.context.active_object.data.materials.append(diffuse_material("Suzanne", 0.8))
    bpy.ops.object.light_add(type='POINT', location=(1.5, -3.0, 2.5))
    lamp = bpy.context.active_object
    lamp.data.energy = 1000.0
    lamp.data.shadow_soft_size = 0.0
    bpy.ops.object.camera_add(location=(0.0, -6.0, 0.0), rotation=(1.5708, 0.0, 0.0))
    scene.camera = bpy.context.active_object
    scene.camera.data.lens = 60
    return scene


def test_light_a_smooth_suzanne_passes_between_its_parts_as_cycles(empty_scene, tmp_path, core):
    """Cycles shades a smooth surface with its normal tilted against where the camera path comes from
    (photon_shading_normals.h, exit_normal): a photon leaving one part of Suzanne for another scatters as that
    path sees the surface. Cycles' indirect light is its image at 16 bounces less its image at none (a point light:
    no light is found by BSDF rays, so the second is all of its direct light); Photon Splat's is its Indirect pass.
    With the normal tilted against the photon's arrival, and its directions drawn above that normal only, Photon
    Splat had 0.69 of Cycles 3.4's indirect light here (0.86 now), and 0.63 of 4.5's (0.80 now). The reference
    renderer has 0.994 of Cycles 3.4's. What Photon Splat still lacks is the kernel's bias in Suzanne's crevices
    (it shrinks with the radius) and the cap on the ratios near a horizon (kMaxShadingNormalRatio). Blender 4.x no
    longer tilts a diffuse closure's normal at all (svm/closure.h: only specular ones, and only with Bump Map
    Correction), which the core does not follow yet, on camera paths either (docs/blender-versions.md)."""
    from photonsplat import export
    scene = lone_smooth_suzanne(empty_scene)
    images = []
    for bounces in (16, 0):
        use_cycles(scene, SIZE, bounces, samples=1024)
        scene.cycles.light_sampling_threshold = 0.0
        scene.cycles.pixel_filter_type = 'BOX'
        scene.cycles.filter_width = 1.0
        images.append(render_pixels(tmp_path / f"cycles_{bounces}.exr")[..., :3].astype(np.float64))
    cycles_indirect = images[0] - images[1]
    scene.render.engine = 'PHOTONSPLAT'
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    settings = frame.settings
    settings.photons, settings.max_bounces, settings.threads, settings.seed = 100_000, 16, 2, 1
    progressive = core.Progressive(frame.scene, frame.camera, settings)
    for _ in range(64):
        progressive.step()
    ours = np.asarray(progressive.passes()["indirect"])[..., :3].astype(np.float64)
    ratio = ours.sum() / cycles_indirect.sum()
    print(f"\nsmooth Suzanne's indirect light, Photon Splat / Cycles: {ratio:.4f} (Cycles' indirect is "
          f"{cycles_indirect.sum() / images[0].sum():.3f} of its image)")
    low = 0.8 if bpy.app.version < (4, 0, 0) else 0.75
    assert low < ratio < 1.1
