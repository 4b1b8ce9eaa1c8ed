"""Writes glints_point.blend and glints_area.blend next to this script: smooth glass and metal under a small light.

  - a glass sphere "GlassSphere" (Glass BSDF, sharp, IOR 1.5, radius 0.45 m, 64 x 32, smooth) on the left and a
    smooth metal Suzanne "MetalMonkey" (Glossy BSDF, sharp, gold, subdivided twice, smooth) on the right, standing
    on a grey diffuse floor (albedo 0.5);
  - a faint grey world (0.03), so that nearly all light comes from the one small light;
  - glints_point.blend: a 100 W point light of radius 0.05 m (a small sphere light) above and in front of them;
    glints_area.blend: a 0.2 m square area light of 100 W at the same place, facing the objects.
    The light is hidden from camera rays; the glass and the metal show it as a glint, which is most of what
    a smooth surface shows of a small light: the test tests/blender/test_glints.py looks for it.
  - a 50 mm camera at 128 x 128.

Run:  blender -b --factory-startup --python blend_scenes/make_glints.py

`tools/closure_gallery.py --glints` renders both with Cycles and Photon Splat and compares whole-image means.
"""

import sys
from pathlib import Path

import bpy
from mathutils import Vector

sys.path.insert(0, str(Path(__file__).resolve().parent))  # for scene_kit
from scene_kit import add_camera, diffuse_material, glass_material, new_empty_scene, save  # noqa: E402

SIZE = 128
FLOOR = (0.5, 0.5, 0.5)
WORLD = (0.03, 0.03, 0.03)
GOLD = (0.95, 0.68, 0.35)
GLASS_CENTER = (-0.55, 0.0, 0.45)
GLASS_RADIUS = 0.45
MONKEY_LOCATION = (0.6, 0.1, 0.42)
LIGHT_POWER = 100.0
LIGHT_LOCATION = (0.4, -2.0, 2.0)
POINT_RADIUS = 0.05
AREA_SIZE = 0.2
CAMERA_LOCATION = (0.0, -3.2, 1.3)
CAMERA_TARGET = (0.0, 0.0, 0.4)
CAMERA_LENS = 45.0


def sharp_metal(name):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    nodes = material.node_tree.nodes
    nodes.clear()
    bsdf = nodes.new("ShaderNodeBsdfGlossy")
    bsdf.distribution = 'SHARP'
    bsdf.inputs["Color"].default_value = (*GOLD, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.0
    output = nodes.new("ShaderNodeOutputMaterial")
    material.node_tree.links.new(bsdf.outputs["BSDF"], output.inputs["Surface"])
    return material


def build(kind):
    scene = new_empty_scene(SIZE, SIZE, "Faint", WORLD)
    scene.cycles.samples = 512
    mesh = bpy.data.meshes.new("Floor")
    h = 20.0
    mesh.from_pydata([(-h, -h, 0.0), (h, -h, 0.0), (h, h, 0.0), (-h, h, 0.0)], [], [(0, 1, 2, 3)])
    mesh.materials.append(diffuse_material("Floor", FLOOR))
    floor = bpy.data.objects.new("Floor", mesh)
    scene.collection.objects.link(floor)

    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=GLASS_RADIUS, location=GLASS_CENTER)
    glass = bpy.context.active_object
    glass.name = glass.data.name = "GlassSphere"
    glass.data.polygons.foreach_set("use_smooth", [True] * len(glass.data.polygons))
    glass.data.materials.append(glass_material("Glass"))

    bpy.ops.mesh.primitive_monkey_add(size=0.8, location=MONKEY_LOCATION, rotation=(0.0, 0.0, 0.35))
    monkey = bpy.context.active_object
    monkey.name = monkey.data.name = "MetalMonkey"
    monkey.data.polygons.foreach_set("use_smooth", [True] * len(monkey.data.polygons))
    subsurf = monkey.modifiers.new("Subdivision", 'SUBSURF')
    subsurf.levels = subsurf.render_levels = 2
    monkey.data.materials.append(sharp_metal("Metal"))

    if kind == "point":
        light = bpy.data.lights.new("Light", type='POINT')
        light.shadow_soft_size = POINT_RADIUS
    else:
        light = bpy.data.lights.new("Light", type='AREA')
        light.shape = 'SQUARE'
        light.size = AREA_SIZE
    light.energy = LIGHT_POWER
    obj = bpy.data.objects.new("Light", light)
    obj.location = LIGHT_LOCATION
    obj.rotation_euler = (Vector(CAMERA_TARGET) - Vector(LIGHT_LOCATION)).to_track_quat('-Z', 'Y').to_euler()
    obj.visible_camera = False
    scene.collection.objects.link(obj)

    aim = Vector(CAMERA_TARGET) - Vector(CAMERA_LOCATION)
    add_camera(scene, CAMERA_LENS, CAMERA_LOCATION, aim.to_track_quat('-Z', 'Y').to_euler())
    save(f"glints_{kind}.blend")


if __name__ == "__main__":
    build("point")
    build("area")
