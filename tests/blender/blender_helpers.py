"""Helpers shared by the tests that run inside Blender: open the project's scenes, render them, read pixels."""

from pathlib import Path

import bpy
import numpy as np

REPO = Path(__file__).resolve().parents[2]
BLEND_SCENES = REPO / "blend_scenes"


def open_scene(name):
    """Open blend_scenes/<name>.blend: every test starts from the file as saved."""
    bpy.ops.wm.open_mainfile(filepath=str(BLEND_SCENES / f"{name}.blend"), load_ui=False)
    return bpy.context.scene


def use_photonsplat(scene, size, photons, **settings):
    """Switch `scene` to Photon Splat at size x size pixels with the given settings."""
    scene.render.engine = 'PHOTONSPLAT'
    scene.render.resolution_x = scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.photonsplat.photons = photons
    for key, value in settings.items():
        setattr(scene.photonsplat, key, value)


def use_cycles(scene, size, bounces, samples=256):
    """Switch `scene` to Cycles on the CPU at size x size pixels: `samples` per pixel, no adaptive sampling,
    no denoising (Debian's Blender has no OpenImageDenoise), clamping or Filter Glossy, and `bounces` as the bounce
    limit. Filter Glossy (1 by default) widens glossy and sharp closures met after a rough bounce, which blurs
    caustics: a glass sphere's caustic focus came out 0.21 with it against 0.30 without (docs/results/
    differential.md, "Stop 46"); the oracle renders what the scene describes."""
    scene.render.resolution_x = scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    cycles = scene.cycles
    cycles.device = 'CPU'
    cycles.samples = samples
    cycles.use_denoising = False
    cycles.use_adaptive_sampling = False
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    cycles.blur_glossy = 0.0
    cycles.max_bounces = cycles.diffuse_bounces = bounces
    scene.render.engine = 'CYCLES'


def emissive_plane(size, location, strength):
    """A square plane of `size` at `location` whose material is an Emission shader of `strength` (white);
    returns the object."""
    bpy.ops.mesh.primitive_plane_add(size=size, location=location)
    lamp = bpy.context.active_object
    material = bpy.data.materials.new("Lamp")
    enable_nodes(material)
    tree = material.node_tree
    tree.nodes.clear()
    emission = tree.nodes.new("ShaderNodeEmission")
    emission.inputs["Strength"].default_value = strength
    tree.links.new(emission.outputs[0], tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    lamp.data.materials.append(material)
    return lamp


def render_pixels(path):
    """Render the current scene with bpy.ops (as F12 does) into the OpenEXR file `path` and read it back.

    Returns float32 (height, width, 4) linear pixels with row 0 at the BOTTOM (Blender's order)."""
    scene = bpy.context.scene
    scene.render.filepath = str(path)
    scene.render.use_file_extension = False
    settings = scene.render.image_settings
    settings.file_format = 'OPEN_EXR'
    settings.color_mode = 'RGBA'
    settings.color_depth = '32'
    bpy.ops.render.render(write_still=True)
    return read_exr(path)


def read_exr(path):
    image = bpy.data.images.load(str(path), check_existing=False)
    try:
        width, height = image.size
        pixels = np.empty(width * height * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
        return pixels.reshape(height, width, 4)
    finally:
        bpy.data.images.remove(image)


def enable_nodes(id_block):
    """Make a material or world render its node tree (Blender 5.0 always does; its use_nodes is deprecated)."""
    from photonsplat import compat
    if compat.has_use_nodes_switch(id_block):
        id_block.use_nodes = True


def single_node_material(name, node_type, **inputs):
    """A material whose surface is one shader node of `node_type` (a bl_idname) with the given input values
    (keyword names are the inputs' names, spaces as underscores)."""
    material = bpy.data.materials.new(name)
    enable_nodes(material)
    tree = material.node_tree
    tree.nodes.clear()
    node = tree.nodes.new(node_type)
    for key, value in inputs.items():
        node.inputs[key.replace("_", " ")].default_value = value
    tree.links.new(node.outputs[0], tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    return material


def uniform_world(scene, color=(1.0, 1.0, 1.0), strength=1.0):
    """A new world of constant colour x strength (a Background node) for `scene`; returns it."""
    world = bpy.data.worlds.new("Uniform")
    enable_nodes(world)
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (*color, 1.0)
    background.inputs["Strength"].default_value = strength
    scene.world = world
    return world


def caustic_landing(eye):
    """In blend_scenes/cornell_caustics.blend: the floor points where the light's rays through the glass sphere
    land, those seen from `eye`, and the (center, radius) of the glass and the mirror sphere."""
    from scene_geometry import caustic_floor_points, visible_from

    glass, mirror = bpy.data.objects["GlassSphere"], bpy.data.objects["MirrorSphere"]
    spheres = [(np.array(ob.matrix_world.translation), ob.dimensions.x / 2.0) for ob in (glass, mirror)]
    (center, radius), _ = spheres
    ior = bpy.data.materials["Glass"].node_tree.nodes["Glass BSDF"].inputs["IOR"].default_value
    light = np.array(bpy.data.objects["Light"].matrix_world.translation)
    landing = caustic_floor_points(light, center, radius, ior)
    return landing[visible_from(landing, eye, spheres)], spheres


def pixel_of(scene, camera, point):
    """(row, column) of the pixel showing world `point`, rows counted from the bottom; None if off-screen."""
    from bpy_extras.object_utils import world_to_camera_view
    from mathutils import Vector

    x, y, depth = world_to_camera_view(scene, camera, Vector(point))
    width = scene.render.resolution_x * scene.render.resolution_percentage // 100
    height = scene.render.resolution_y * scene.render.resolution_percentage // 100
    column, row = int(x * width), int(y * height)
    if depth <= 0.0 or not (0 <= column < width and 0 <= row < height):
        return None
    return row, column


def direct_light_pair(scene, size, tmp_path, core, cycles_samples=512, passes=64):
    """The direct light of `scene` (no bounces) at size x size, as (Cycles, Photon Splat) float64 RGB images with
    row 0 at the top: Cycles at `cycles_samples` with a 1 px box filter and no light threshold, Photon Splat after
    `passes` progressive passes."""
    from photonsplat import export
    use_cycles(scene, size, 0, samples=cycles_samples)
    scene.cycles.light_sampling_threshold = 0.0
    scene.cycles.pixel_filter_type = 'BOX'
    scene.cycles.filter_width = 1.0
    cycles = np.flipud(render_pixels(tmp_path / "cycles.exr"))[..., :3].astype(np.float64)
    scene.render.engine = 'PHOTONSPLAT'
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    settings = frame.settings
    settings.max_bounces, settings.threads, settings.seed = 0, 2, 1
    progressive = core.Progressive(frame.scene, frame.camera, settings)
    for _ in range(passes):
        progressive.step()
    return cycles, np.asarray(progressive.image())[..., :3].astype(np.float64)


def block_means(image, block=4):
    """Means of block x block pixels (RGB averaged)."""
    h, w = image.shape[:2]
    return image[..., :3].reshape(h // block, block, w // block, block, 3).mean(axis=(1, 3, 4))
