"""Writes the 4-million-triangle scene of issue 19: four subdivided Suzannes on a floor, one point light, 640x360.

  - four Suzannes (Blender's monkey), smooth shaded, each with a Subdivision Surface modifier of render level 5
    (about 1.0 M triangles each once evaluated: 4.03 M in all), a diffuse clay material;
  - a diffuse grey floor (one quad) under them;
  - one point light (300 W, radius 0.1 m) above and in front, and a faint uniform world;
  - a camera at 640x360 looking at the row. The engine is Photon Splat when its add-on is loaded, else Cycles.

Run:  blender -b --factory-startup --python blend_scenes/make_big_scene.py [-- OUT.blend]
      (default OUT: build/big_scene.blend; with BLENDER_USER_SCRIPTS=$PWD/build/blender --addons photonsplat the
      file opens in Photon Splat)

The file is not committed (about 100 kB, but its evaluated geometry is 4 M triangles and the point of the scene
is how long that takes to reach the first ray): tools/big_scene_timing.py writes it when missing.
"""

import math
import sys
from pathlib import Path

import bpy

sys.path.insert(0, str(Path(__file__).resolve().parent))  # for scene_kit
from scene_kit import add_camera, diffuse_material, new_empty_scene  # noqa: E402

SUBDIVISION_LEVEL = 5               # Suzanne's 500 faces -> 1968 quads at level 1, x4 per further level
SUZANNE_X = (-3.3, -1.1, 1.1, 3.3)  # metres, a row along X standing on the floor
CLAY = (0.6, 0.45, 0.35)
FLOOR = (0.45, 0.45, 0.45)
WORLD = (0.05, 0.05, 0.05)
POINT_POWER = 300.0                 # watts (Cycles units)
POINT_RADIUS = 0.1
POINT_LOCATION = (1.0, -3.0, 4.0)
CAMERA_LOCATION = (0.0, -8.5, 2.6)
CAMERA_TARGET = (0.0, 0.0, 0.8)
CAMERA_LENS = 35.0


def default_output():
    return Path(__file__).resolve().parent.parent / "build" / "big_scene.blend"


def build_scene():
    scene = new_empty_scene(640, 360, "Fill", WORLD)
    clay = diffuse_material("Clay", CLAY)
    for i, x in enumerate(SUZANNE_X):
        bpy.ops.mesh.primitive_monkey_add(size=2.0, location=(x, 0.0, 1.0), rotation=(0.0, 0.0, 0.0))
        ob = bpy.context.active_object
        ob.name = f"Suzanne.{i}"
        ob.data.materials.append(clay)
        for polygon in ob.data.polygons:
            polygon.use_smooth = True
        modifier = ob.modifiers.new("Subdivision", 'SUBSURF')
        modifier.levels = 1                          # the viewport stays light; renders use render_levels
        modifier.render_levels = SUBDIVISION_LEVEL
        modifier.quality = 3

    floor = bpy.data.meshes.new("Floor")
    floor.from_pydata([(-8.0, -8.0, 0.0), (8.0, -8.0, 0.0), (8.0, 8.0, 0.0), (-8.0, 8.0, 0.0)], [], [(0, 1, 2, 3)])
    floor.materials.append(diffuse_material("Floor", FLOOR))
    scene.collection.objects.link(bpy.data.objects.new("Floor", floor))

    light = bpy.data.lights.new("Point", 'POINT')
    light.energy = POINT_POWER
    light.shadow_soft_size = POINT_RADIUS
    light_object = bpy.data.objects.new("Point", light)
    light_object.location = POINT_LOCATION
    scene.collection.objects.link(light_object)

    direction = [t - c for t, c in zip(CAMERA_TARGET, CAMERA_LOCATION)]
    pitch = math.atan2(math.hypot(direction[0], direction[1]), -direction[2])
    yaw = math.atan2(direction[1], direction[0]) - math.pi / 2
    add_camera(scene, CAMERA_LENS, CAMERA_LOCATION, (pitch, 0.0, yaw))
    try:
        scene.render.engine = 'PHOTONSPLAT'
    except TypeError:               # the add-on is not loaded: the file keeps Cycles (the timing sets the engine)
        print("make_big_scene: Photon Splat add-on not loaded; engine left at Cycles")
    return scene


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    out = Path(argv[0]) if argv else default_output()
    out.parent.mkdir(parents=True, exist_ok=True)
    build_scene()
    bpy.context.preferences.filepaths.save_version = 0
    bpy.ops.wm.save_as_mainfile(filepath=str(out), compress=True)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
