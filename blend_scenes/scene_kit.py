"""What the scene generators share: an empty Cycles scene, the few materials they build, a camera, and saving.

Imported by make_*.py (run as `blender -b --factory-startup --python blend_scenes/make_<scene>.py`), which put
this folder on sys.path first.
"""
from pathlib import Path

import bpy

HERE = Path(__file__).resolve().parent


def new_empty_scene(width, height, world_name, world_color, world_strength=1.0):
    """A factory-empty scene set up for both engines: Cycles on the CPU, Standard view, a uniform world."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    scene.render.resolution_x = width
    scene.render.resolution_y = height
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = 'Standard'
    scene.view_settings.look = 'None'
    scene.cycles.device = 'CPU'
    scene.cycles.samples = 128
    scene.cycles.use_denoising = False          # Debian's Blender has no OpenImageDenoise
    scene.cycles.sample_clamp_indirect = 0.0    # no clamping: keep Cycles' result unbiased for comparisons
    world = bpy.data.worlds.new(world_name)
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (*world_color, 1.0)
    background.inputs["Strength"].default_value = world_strength
    world.color = tuple(c * world_strength for c in world_color)
    scene.world = world
    return scene


def _material_with(name, node_type, viewport_color=None):
    """A material whose surface is one new shader node of `node_type`; returns (material, node)."""
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    nodes = material.node_tree.nodes
    nodes.clear()
    bsdf = nodes.new(node_type)
    output = nodes.new("ShaderNodeOutputMaterial")
    material.node_tree.links.new(bsdf.outputs["BSDF"], output.inputs["Surface"])
    if viewport_color is not None:
        material.diffuse_color = (*viewport_color, 1.0)
    return material, bsdf


def diffuse_material(name, color):
    material, bsdf = _material_with(name, "ShaderNodeBsdfDiffuse", color)
    bsdf.inputs["Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.0      # Lambertian
    return material


def glass_material(name, ior=1.5):
    material, bsdf = _material_with(name, "ShaderNodeBsdfGlass")
    bsdf.distribution = 'SHARP'
    bsdf.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.0
    bsdf.inputs["IOR"].default_value = ior
    return material


def glossy_material(name, color, roughness):
    """A metal as a plain Glossy BSDF node: GGX distribution, Roughness input set."""
    material, bsdf = _material_with(name, "ShaderNodeBsdfGlossy", color)
    bsdf.distribution = 'GGX'
    bsdf.inputs["Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    material.metallic = 1.0                            # viewport look
    material.roughness = roughness
    return material


def add_camera(scene, lens, location, rotation_euler):
    """The scene's camera, "Camera": `lens` mm on a 36 mm sensor (fit AUTO), at `location`, turned by `rotation_euler`."""
    camera = bpy.data.cameras.new("Camera")
    camera.lens = lens
    camera.sensor_width = 36.0
    camera.sensor_fit = 'AUTO'
    obj = bpy.data.objects.new("Camera", camera)
    obj.location = location
    obj.rotation_euler = rotation_euler
    scene.collection.objects.link(obj)
    scene.camera = obj
    return obj


def save(name):
    path = HERE / name
    bpy.context.preferences.filepaths.save_version = 0      # no .blend1 backup next to the committed file
    bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=True)
    print(f"wrote {path}")
