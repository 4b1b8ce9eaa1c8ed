"""Writes glossy_row.blend next to this script: five metal spheres of increasing roughness in a row.

  - five spheres (radius 0.4 m) of a gold-tinted metal, Glossy BSDF (GGX) with roughness 0.05, 0.2, 0.35, 0.5
    and 0.8 from left to right;
  - a diffuse grey floor and a warm back wall behind them;
  - lit by a small square area light above and in front of the row and a point light to the left, so that each
    sphere shows both lights as highlights whose size and softness follow its roughness.

Run:  blender -b --factory-startup --python blend_scenes/make_glossy_row.py

The spheres use plain Glossy BSDF nodes with the Roughness input set, the way an artist makes a brushed metal:
an engine without rough glossy surfaces may render them as mirrors (and say so), one with them renders the row as
Cycles does. Units are metres: the spheres stand on the floor (z = 0) along X at y = 0, the back wall is at
y = 1.5 and the camera looks along +Y. The file opens in Cycles (CPU, view transform Standard, 1280x720).
"""

import math
from pathlib import Path

import bpy
import sys
sys.path.insert(0, str(Path(__file__).resolve().parent))  # for scene_kit
from scene_kit import diffuse_material, glossy_material, save, new_empty_scene as _new_scene  # noqa: E402
from scene_kit import add_camera as add_scene_camera  # noqa: E402
from mathutils import Vector


ROUGHNESS = (0.05, 0.2, 0.35, 0.5, 0.8)
SPHERE_RADIUS = 0.4
SPHERE_SPACING = 1.1
METAL = (0.95, 0.72, 0.42)          # gold-like tint (scene-linear reflectance)
FLOOR = (0.45, 0.45, 0.45)
WALL = (0.62, 0.55, 0.46)
WALL_Y = 1.5

AREA_POWER = 110.0                  # watts (Cycles units)
AREA_SIZE = 0.4                     # metres, square
AREA_LOCATION = (0.6, -2.4, 2.8)
POINT_POWER = 200.0
POINT_RADIUS = 0.05
POINT_LOCATION = (-3.2, -1.2, 2.2)
WORLD = (0.08, 0.08, 0.08)          # a faint uniform fill, so the spheres' upper halves are not black

CAMERA_LOCATION = (0.0, -6.0, 1.1)
CAMERA_TARGET = (0.0, 0.0, 0.55)
CAMERA_LENS = 34.0                  # mm on a 36 mm sensor


def new_empty_scene():
    return _new_scene(1280, 720, "Fill", WORLD)


def add_room(scene):
    """Floor (8 m x 6 m) and back wall as one mesh, two material slots."""
    v = [(-4.0, -4.5, 0.0), (4.0, -4.5, 0.0), (4.0, WALL_Y, 0.0), (-4.0, WALL_Y, 0.0),
         (-4.0, WALL_Y, 3.5), (4.0, WALL_Y, 3.5)]
    faces = [(0, 1, 2, 3), (3, 2, 5, 4)]           # floor facing +Z, wall facing -Y
    mesh = bpy.data.meshes.new("Room")
    mesh.from_pydata(v, [], faces)
    mesh.materials.append(diffuse_material("Floor", FLOOR))
    mesh.materials.append(diffuse_material("Wall", WALL))
    mesh.polygons.foreach_set("material_index", [0, 1])
    mesh.update()
    obj = bpy.data.objects.new("Room", mesh)
    scene.collection.objects.link(obj)
    return obj


def add_spheres(scene):
    first = -SPHERE_SPACING * (len(ROUGHNESS) - 1) / 2.0
    for k, roughness in enumerate(ROUGHNESS):
        bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=SPHERE_RADIUS,
                                             location=(first + k * SPHERE_SPACING, 0.0, SPHERE_RADIUS))
        obj = bpy.context.active_object
        obj.name = obj.data.name = f"Sphere{k + 1}_r{roughness:.2f}"
        obj.data.polygons.foreach_set("use_smooth", [True] * len(obj.data.polygons))
        obj.data.materials.append(glossy_material(f"Metal_r{roughness:.2f}", METAL, roughness))


def add_lights(scene):
    area = bpy.data.lights.new("AreaLight", type='AREA')
    area.shape = 'SQUARE'
    area.size = AREA_SIZE
    area.energy = AREA_POWER
    area_obj = bpy.data.objects.new("AreaLight", area)
    area_obj.location = AREA_LOCATION
    # Shine (local -Z) at the middle of the row.
    aim = Vector(CAMERA_TARGET) - Vector(AREA_LOCATION)
    area_obj.rotation_euler = aim.to_track_quat('-Z', 'Y').to_euler()
    point = bpy.data.lights.new("PointLight", type='POINT')
    point.energy = POINT_POWER
    point.shadow_soft_size = POINT_RADIUS
    point_obj = bpy.data.objects.new("PointLight", point)
    point_obj.location = POINT_LOCATION
    for obj in (area_obj, point_obj):
        # Photon Splat never shows lights to the camera; Cycles is told the same. Reflections still show them.
        obj.visible_camera = False
        scene.collection.objects.link(obj)


def add_camera(scene):
    aim = Vector(CAMERA_TARGET) - Vector(CAMERA_LOCATION)
    return add_scene_camera(scene, CAMERA_LENS, CAMERA_LOCATION, aim.to_track_quat('-Z', 'Y').to_euler())


def make_glossy_row():
    scene = new_empty_scene()
    add_room(scene)
    add_spheres(scene)
    add_lights(scene)
    add_camera(scene)
    save("glossy_row.blend")


if __name__ == "__main__":
    make_glossy_row()
