"""Writes the two Cornell-box scenes of the project next to this script:

  cornell_caustics.blend  a glass sphere and a mirror sphere on the floor, lit by a small point light near the
                          ceiling: the glass sphere focuses it into a caustic on the floor in front of it.
  cornell_diffuse.blend   the same box with two diffuse blocks, for comparing brightness with Cycles.

Run:  blender -b --factory-startup --python blend_scenes/make_cornell.py

Both files render in Cycles as they are (CPU, no denoising); the tests switch them to Photon Splat. Units are
metres: the box spans x in [-1, 1], y in [-1, 1] (back wall at y = +1, open front at y = -1), z in [0, 2];
the camera looks along +Y through the open front.
"""

import math
from pathlib import Path

import bpy
import sys
sys.path.insert(0, str(Path(__file__).resolve().parent))  # for scene_kit
from scene_kit import diffuse_material, glass_material, save, new_empty_scene as _new_scene  # noqa: E402
from scene_kit import add_camera as add_scene_camera  # noqa: E402


# Classic Cornell-box albedos (scene-linear).
WHITE = (0.73, 0.73, 0.73)
RED = (0.63, 0.065, 0.05)
GREEN = (0.14, 0.45, 0.091)

SPHERE_RADIUS = 0.35
GLASS_SPHERE_CENTER = (-0.35, -0.40, SPHERE_RADIUS)
MIRROR_SPHERE_CENTER = (0.45, 0.35, SPHERE_RADIUS)
# Behind and above the glass sphere, so its caustic lands on the floor on the camera's side of the sphere.
CAUSTICS_LIGHT_LOCATION = (0.10, 0.45, 1.60)
DIFFUSE_LIGHT_LOCATION = (0.0, 0.0, 1.60)
LIGHT_POWER = 30.0          # watts, Cycles units
LIGHT_RADIUS = 0.03          # metres: small, so shadows and the caustic stay sharp


def new_empty_scene():
    # A black world: the box is lit by its light only, in both engines.
    return _new_scene(512, 512, "Black", (0.0, 0.0, 0.0))


def mirror_material(name, color=(0.9, 0.9, 0.9)):
    """A polished metal through the Principled BSDF (metallic 1, roughness 0), as artists usually make one."""
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    bsdf = material.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Metallic"].default_value = 1.0
    bsdf.inputs["Roughness"].default_value = 0.0
    return material


def add_box(scene):
    """The five walls as one mesh with three material slots (white, red, green), normals facing inside."""
    v = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0),     # floor corners
         (-1, -1, 2), (1, -1, 2), (1, 1, 2), (-1, 1, 2)]     # ceiling corners
    faces = [
        (0, 1, 2, 3),    # floor, normal +Z
        (4, 7, 6, 5),    # ceiling, normal -Z
        (3, 2, 6, 7),    # back wall, normal -Y
        (0, 3, 7, 4),    # left wall (x = -1), normal +X
        (1, 5, 6, 2),    # right wall (x = +1), normal -X
    ]
    slots = [0, 0, 0, 1, 2]
    mesh = bpy.data.meshes.new("CornellBox")
    mesh.from_pydata(v, [], faces)
    for material in (diffuse_material("White", WHITE), diffuse_material("Red", RED),
                     diffuse_material("Green", GREEN)):
        mesh.materials.append(material)
    mesh.polygons.foreach_set("material_index", slots)
    mesh.update()
    obj = bpy.data.objects.new("CornellBox", mesh)
    scene.collection.objects.link(obj)
    return obj


def add_sphere(scene, name, center, material):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=SPHERE_RADIUS, location=center)
    obj = bpy.context.active_object
    obj.name = obj.data.name = name
    obj.data.polygons.foreach_set("use_smooth", [True] * len(obj.data.polygons))
    obj.data.materials.append(material)
    return obj


def add_block(scene, name, size, location_xy, angle_degrees, material):
    """A diffuse block standing on the floor; the size is an object scale (exercises transform export)."""
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(location_xy[0], location_xy[1], size[2] / 2.0))
    obj = bpy.context.active_object
    obj.name = obj.data.name = name
    obj.scale = size
    obj.rotation_euler = (0.0, 0.0, math.radians(angle_degrees))
    obj.data.materials.append(material)
    return obj


def add_light(scene, location):
    light = bpy.data.lights.new("Light", type='POINT')
    light.energy = LIGHT_POWER
    light.shadow_soft_size = LIGHT_RADIUS
    light.color = (1.0, 1.0, 1.0)
    obj = bpy.data.objects.new("Light", light)
    obj.location = location
    # Cycles would show the light's small disk to the camera; Photon Splat never does. Hide it so both agree.
    obj.visible_camera = False
    scene.collection.objects.link(obj)
    return obj


def add_camera(scene):
    # Local -Z (the view axis) turned to world +Y: the camera looks into the box through its open front.
    return add_scene_camera(scene, 50.0, (0.0, -3.9, 1.0), (math.radians(90.0), 0.0, 0.0))


def make_caustics():
    scene = new_empty_scene()
    add_box(scene)
    add_sphere(scene, "GlassSphere", GLASS_SPHERE_CENTER, glass_material("Glass"))
    add_sphere(scene, "MirrorSphere", MIRROR_SPHERE_CENTER, mirror_material("Mirror"))
    add_light(scene, CAUSTICS_LIGHT_LOCATION)
    add_camera(scene)
    save("cornell_caustics.blend")


def make_diffuse():
    scene = new_empty_scene()
    box = add_box(scene)
    white = box.data.materials[0]
    add_block(scene, "ShortBlock", (0.6, 0.6, 0.6), (0.35, -0.3), -17.0, white)
    add_block(scene, "TallBlock", (0.6, 0.6, 1.2), (-0.35, 0.3), 17.0, white)
    add_light(scene, DIFFUSE_LIGHT_LOCATION)
    add_camera(scene)
    save("cornell_diffuse.blend")


if __name__ == "__main__":
    make_caustics()
    make_diffuse()
