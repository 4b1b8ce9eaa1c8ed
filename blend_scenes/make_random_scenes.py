"""Writes random scenes for differential testing against Cycles (issue 18): a seed in, a .blend out.

Each seed gives one scene that nobody designed around the engine, drawn with Python's own `random.Random(seed)`
(the same file for the same seed under any Blender):
  - a layout: an open scene (a floor under the world) or a closed room (six walls, sometimes with a window);
  - 2 to 6 objects: cubes, smooth UV spheres, subdivided ico spheres, cylinders, tori, Suzannes, thin walls
    (planes), with random positions, rotations and non-uniform scales, some of them occluders between a light
    and the rest;
  - a material each, of every kind the engine translates: Diffuse (Lambert or Oren-Nayar), Glossy (GGX,
    Beckmann, Multiscatter GGX, any roughness), sharp and rough Glass, Principled (dielectric, metal, glass,
    with clearcoat and sheen), a Mix of two of them, Emission, Translucent, Transparent;
  - 1 to 3 lights of every type (point, spot, area square/rectangle/disk/ellipse, sun) with random sizes (never
    0: Cycles cannot render a delta light's caustics), spot angles and blends, and powers scaled to their distance
    so that the image is neither black nor white;
  - a perspective (18 to 85 mm) or orthographic camera looking at the objects from a random direction;
  - a world of random constant colour and strength;
  - the whole scene sometimes scaled by 0.01 or 100 and sometimes moved 1e3 to 1e5 of its own sizes from the origin.
What was drawn is kept in the scene's custom property `differential` (JSON), for the runner's report.

Cycles is set up as the oracle (CPU, no denoising, no clamping, Filmic off: Standard view); with the add-on on
Blender's path (BLENDER_USER_SCRIPTS=$PWD/build/blender) the files are saved with Photon Splat as their engine.

Run:  blender -b --factory-startup -P blend_scenes/make_random_scenes.py -- OUTDIR [--seeds 0-199] [--size 64x64]
The files are OUTDIR/random_<seed>.blend (not committed: generated where they are used).
"""

import argparse
import json
import math
import random
import sys
from pathlib import Path

import bpy
from mathutils import Euler, Matrix, Vector

sys.path.insert(0, str(Path(__file__).resolve().parent))  # for scene_kit
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))  # for differential (its seed lists)
from differential import parse_seeds  # noqa: E402
from scene_kit import new_empty_scene  # noqa: E402

SHAPES = ["cube", "uv_sphere", "ico_sphere", "cylinder", "torus", "monkey", "wall"]
MATERIALS = ["diffuse", "oren_nayar", "glossy", "glass", "rough_glass", "principled_dielectric",
             "principled_metal", "principled_glass", "mix", "emission", "translucent", "transparent"]
LIGHTS = ["point", "spot", "area_square", "area_rectangle", "area_disk", "area_ellipse", "sun"]


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", help="folder for random_<seed>.blend")
    parser.add_argument("--seeds", default="0-199", help="e.g. 0-199 or 3,7,12")
    parser.add_argument("--size", default="64x64", help="render resolution WxH")
    return parser.parse_args(argv)


def colour(rng, low=0.05, high=0.9):
    return tuple(rng.uniform(low, high) for _ in range(3))


# ---- materials ------------------------------------------------------------------------------------------------

def new_material(name):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    material.node_tree.nodes.clear()
    output = material.node_tree.nodes.new("ShaderNodeOutputMaterial")
    return material, output


def shader_node(tree, kind, rng, record):
    """A new shader node of `kind` in `tree` with random inputs; what was drawn goes into `record`."""
    nodes = tree.nodes
    if kind in ("diffuse", "oren_nayar"):
        node = nodes.new("ShaderNodeBsdfDiffuse")
        record["color"] = colour(rng)
        record["roughness"] = 0.0 if kind == "diffuse" else rng.uniform(0.1, 1.0)
        node.inputs["Color"].default_value = (*record["color"], 1.0)
        node.inputs["Roughness"].default_value = record["roughness"]
    elif kind == "glossy":
        node = nodes.new("ShaderNodeBsdfGlossy")
        record["distribution"] = node.distribution = rng.choice(["GGX", "BECKMANN", "MULTI_GGX"])
        record["color"] = colour(rng, 0.3, 1.0)
        record["roughness"] = rng.choice([0.0, 0.02, rng.uniform(0.05, 0.8)])
        node.inputs["Color"].default_value = (*record["color"], 1.0)
        node.inputs["Roughness"].default_value = record["roughness"]
    elif kind in ("glass", "rough_glass"):
        node = nodes.new("ShaderNodeBsdfGlass")
        node.distribution = "SHARP" if kind == "glass" else rng.choice(["GGX", "BECKMANN", "MULTI_GGX"])
        record["distribution"] = node.distribution
        record["ior"] = rng.uniform(1.1, 2.0)
        record["roughness"] = 0.0 if kind == "glass" else rng.uniform(0.05, 0.5)
        record["color"] = colour(rng, 0.7, 1.0)
        node.inputs["Color"].default_value = (*record["color"], 1.0)
        node.inputs["IOR"].default_value = record["ior"]
        node.inputs["Roughness"].default_value = record["roughness"]
    elif kind.startswith("principled"):
        node = nodes.new("ShaderNodeBsdfPrincipled")
        record["base_color"] = colour(rng, 0.1, 0.95)
        record["roughness"] = rng.uniform(0.0, 0.9)
        record["metallic"] = 1.0 if kind == "principled_metal" else (0.0 if rng.random() < 0.8 else rng.random())
        record["transmission"] = 1.0 if kind == "principled_glass" else 0.0
        record["ior"] = rng.uniform(1.3, 1.8)
        record["specular"] = rng.uniform(0.2, 0.8)
        record["clearcoat"] = rng.uniform(0.0, 1.0) if rng.random() < 0.25 else 0.0
        record["sheen"] = rng.uniform(0.0, 1.0) if rng.random() < 0.2 else 0.0
        if kind == "principled_glass":
            record["roughness"] = rng.choice([0.0, rng.uniform(0.0, 0.4)])
        node.inputs["Base Color"].default_value = (*record["base_color"], 1.0)
        node.inputs["Roughness"].default_value = record["roughness"]
        node.inputs["Metallic"].default_value = record["metallic"]
        node.inputs["IOR"].default_value = record["ior"]
        for name, key in (("Transmission", "transmission"), ("Transmission Weight", "transmission"),
                          ("Specular", "specular"), ("Clearcoat", "clearcoat"), ("Coat Weight", "clearcoat"),
                          ("Sheen", "sheen"), ("Sheen Weight", "sheen")):
            if name in node.inputs:  # the names of Blender 3.4 and of 4.x
                node.inputs[name].default_value = record[key]
    elif kind == "emission":
        node = nodes.new("ShaderNodeEmission")
        record["color"] = colour(rng, 0.3, 1.0)
        record["strength"] = rng.uniform(0.5, 5.0)
        node.inputs["Color"].default_value = (*record["color"], 1.0)
        node.inputs["Strength"].default_value = record["strength"]
    elif kind == "translucent":
        node = nodes.new("ShaderNodeBsdfTranslucent")
        record["color"] = colour(rng, 0.2, 0.9)
        node.inputs["Color"].default_value = (*record["color"], 1.0)
    elif kind == "transparent":
        node = nodes.new("ShaderNodeBsdfTransparent")
        record["color"] = colour(rng, 0.3, 0.9)
        node.inputs["Color"].default_value = (*record["color"], 1.0)
    else:
        raise ValueError(kind)
    return node


def random_material(rng, name, kinds=MATERIALS):
    kind = rng.choice(kinds)
    record = {"kind": kind}
    material, output = new_material(name)
    tree = material.node_tree
    if kind == "mix":
        parts = [k for k in MATERIALS if k not in ("mix", "emission", "transparent")]
        a, b = rng.choice(parts), rng.choice(parts)
        record["parts"] = [{"kind": a}, {"kind": b}]
        first = shader_node(tree, a, rng, record["parts"][0])
        second = shader_node(tree, b, rng, record["parts"][1])
        mix = tree.nodes.new("ShaderNodeMixShader")
        record["factor"] = rng.uniform(0.1, 0.9)
        mix.inputs["Fac"].default_value = record["factor"]
        tree.links.new(first.outputs[0], mix.inputs[1])
        tree.links.new(second.outputs[0], mix.inputs[2])
        tree.links.new(mix.outputs[0], output.inputs["Surface"])
    else:
        node = shader_node(tree, kind, rng, record)
        tree.links.new(node.outputs[0], output.inputs["Surface"])
    return material, record


# ---- geometry -------------------------------------------------------------------------------------------------

def add_shape(rng, shape, name):
    """A new mesh object of `shape` at the origin (about 1 unit across), smooth-shaded where curved."""
    if shape == "cube":
        bpy.ops.mesh.primitive_cube_add(size=1.0)
    elif shape == "uv_sphere":
        bpy.ops.mesh.primitive_uv_sphere_add(radius=0.5, segments=rng.choice([16, 32, 64]), ring_count=16)
    elif shape == "ico_sphere":
        bpy.ops.mesh.primitive_ico_sphere_add(radius=0.5, subdivisions=rng.choice([1, 2, 3, 4]))
    elif shape == "cylinder":
        bpy.ops.mesh.primitive_cylinder_add(radius=0.5, depth=1.0, vertices=rng.choice([8, 24, 48]))
    elif shape == "torus":
        bpy.ops.mesh.primitive_torus_add(major_radius=0.4, minor_radius=rng.uniform(0.05, 0.2))
    elif shape == "monkey":
        bpy.ops.mesh.primitive_monkey_add(size=1.0)
    elif shape == "wall":
        bpy.ops.mesh.primitive_plane_add(size=1.0)
    obj = bpy.context.active_object
    obj.name = name
    if shape in ("uv_sphere", "ico_sphere", "torus", "monkey") and rng.random() < 0.8:
        bpy.ops.object.shade_smooth()
    if shape in ("monkey", "cube") and rng.random() < 0.3:
        modifier = obj.modifiers.new("Subdivision", "SUBSURF")
        modifier.levels = modifier.render_levels = rng.choice([1, 2])
    return obj


def place(obj, location, rotation, scale):
    obj.location = location
    obj.rotation_euler = rotation
    obj.scale = scale


def room(rng, size, materials_record):
    """Six walls (planes facing in) of a box `size` across, the floor at z = 0; sometimes a window in one."""
    sx, sy, sz = size
    material, record = random_material(rng, "RoomWalls", ["diffuse", "oren_nayar", "principled_dielectric"])
    materials_record["RoomWalls"] = record
    window = rng.random() < 0.4
    faces = [((0, 0, 0), (0, 0, 0), (sx, sy, 1)), ((0, 0, sz), (math.pi, 0, 0), (sx, sy, 1)),
             ((sx / 2, 0, sz / 2), (0, -math.pi / 2, 0), (sz, sy, 1)),
             ((-sx / 2, 0, sz / 2), (0, math.pi / 2, 0), (sz, sy, 1)),
             ((0, sy / 2, sz / 2), (math.pi / 2, 0, 0), (sx, sz, 1)),
             ((0, -sy / 2, sz / 2), (-math.pi / 2, 0, 0), (sx, sz, 1))]
    for k, (location, rotation, scale) in enumerate(faces):
        if window and k == 4:
            # The +y wall as four strips around a window.
            w, h = rng.uniform(0.2, 0.5) * sx, rng.uniform(0.2, 0.5) * sz
            strips = [((-(sx + w) / 4, (sx - w) / 2, sz)), (((sx + w) / 4, (sx - w) / 2, sz))]
            for j, (x, width, height) in enumerate(strips):
                obj = add_shape(rng, "wall", f"RoomWall{k}_{j}")
                place(obj, (x, sy / 2, sz / 2), rotation, (width, height, 1))
                obj.data.materials.append(material)
            for j, z in enumerate(((sz - h) / 4, sz - (sz - h) / 4)):
                obj = add_shape(rng, "wall", f"RoomWall{k}_{j + 2}")
                place(obj, (0, sy / 2, z), rotation, (w, (sz - h) / 2, 1))
                obj.data.materials.append(material)
            continue
        obj = add_shape(rng, "wall", f"RoomWall{k}")
        place(obj, location, rotation, scale)
        obj.data.materials.append(material)
    return window


# ---- lights and camera ----------------------------------------------------------------------------------------

def inside(location, box):
    """`location` moved into the room `box` (size), kept 10 % of each side away from its walls."""
    if box is None:
        return location
    sx, sy, sz = box
    return Vector((max(-0.4 * sx, min(0.4 * sx, location.x)), max(-0.4 * sy, min(0.4 * sy, location.y)),
                   max(0.1 * sz, min(0.9 * sz, location.z))))


def add_light(rng, kind, name, target, distance, box=None):
    """A light of `kind` about `distance` from `target`, above it, power scaled by the distance squared; inside
    the room `box` where there is one."""
    direction = Vector((rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.4, 1.5))).normalized()
    location = inside(Vector(target) + distance * direction, box)
    record = {"kind": kind}
    if kind == "sun":
        data = bpy.data.lights.new(name, "SUN")
        record["strength"] = data.energy = rng.uniform(1.0, 6.0)
        # Every light has a size (a 0 drawn becomes the smallest size): Cycles, the oracle, cannot find a delta
        # light's caustics (light, then mirror or sharp glass, then a diffuse surface) by path tracing at all.
        record["angle_degrees"] = rng.choice([0.0, rng.uniform(0.5, 20.0)]) or 0.5
        data.angle = math.radians(record["angle_degrees"])
    elif kind in ("point", "spot"):
        data = bpy.data.lights.new(name, kind.upper())
        record["radius"] = data.shadow_soft_size = rng.choice([0.0, rng.uniform(0.01, 0.3) * distance]) or 0.01 * distance
        record["watts"] = data.energy = rng.uniform(20.0, 120.0) * distance * distance
        if kind == "spot":
            record["spot_degrees"] = rng.uniform(20.0, 120.0)
            data.spot_size = math.radians(record["spot_degrees"])
            record["spot_blend"] = data.spot_blend = rng.uniform(0.0, 1.0)
    else:
        data = bpy.data.lights.new(name, "AREA")
        data.shape = {"area_square": "SQUARE", "area_rectangle": "RECTANGLE", "area_disk": "DISK",
                      "area_ellipse": "ELLIPSE"}[kind]
        record["size"] = data.size = rng.uniform(0.05, 0.6) * distance
        if data.shape in ("RECTANGLE", "ELLIPSE"):
            record["size_y"] = data.size_y = rng.uniform(0.05, 0.6) * distance
        record["watts"] = data.energy = rng.uniform(20.0, 150.0) * distance * distance
    record["color"] = colour(rng, 0.6, 1.0)
    data.color = record["color"]
    obj = bpy.data.objects.new(name, data)
    obj.location = location
    # Pointing at the target (lights shine along their −z).
    obj.rotation_euler = (Vector(target) - location).to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.collection.objects.link(obj)
    return obj, record


def add_random_camera(rng, scene, target, distance, box=None):
    data = bpy.data.cameras.new("Camera")
    record = {}
    if rng.random() < 0.2:
        data.type = "ORTHO"
        record["orthographic_scale"] = data.ortho_scale = rng.uniform(1.2, 2.5) * distance
    else:
        record["lens_mm"] = data.lens = rng.uniform(18.0, 85.0)
        data.sensor_width = 36.0
        distance *= data.lens / 35.0  # a longer lens stands back to frame the same objects
    direction = Vector((rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.15, 1.0))).normalized()
    location = inside(Vector(target) + 1.8 * distance * direction, box)
    obj = bpy.data.objects.new("Camera", data)
    obj.location = location
    obj.rotation_euler = (Vector(target) - location).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(obj)
    scene.camera = obj
    record["location"] = tuple(location)
    return record


# ---- scale and offset -----------------------------------------------------------------------------------------

def transform_scene(scene, transform, scale):
    """Applies `transform` (a uniform `scale`, then a move) to every object of `scene`, with what a uniform scale
    does not carry by itself: the radius of point and spot lights (an area light's size follows its object's
    scale), the lights' powers so that the same surfaces see the same irradiance (light transport is then scale
    invariant), the orthographic camera's width and the clip range."""
    for obj in scene.objects:
        obj.matrix_world = transform @ obj.matrix_world
        if obj.type == "LIGHT" and obj.data.type != "SUN":
            obj.data.energy *= scale * scale
            if obj.data.type != "AREA":
                obj.data.shadow_soft_size *= scale
        if obj.type == "CAMERA":
            if obj.data.type == "ORTHO":
                obj.data.ortho_scale *= scale
            obj.data.clip_start *= scale
            obj.data.clip_end *= scale


def canonical(scene, record):
    """Undoes the scale and the move of make_scene on the scene loaded from its file: the scene at scale 1 around
    the origin, as drawn before it was scaled."""
    scale, offset = record["scale"], Vector(record["offset"])
    if scale != 1.0 or offset.length > 0:
        bpy.context.view_layer.update()
        transform_scene(scene, Matrix.Scale(1.0 / scale, 4) @ Matrix.Translation(-offset), 1.0 / scale)


# ---- one scene ------------------------------------------------------------------------------------------------

def make_scene(seed, width, height):
    rng = random.Random(seed)
    world_colour = colour(rng, 0.2, 1.0)
    world_strength = rng.choice([0.0, rng.uniform(0.02, 0.5)])
    scene = new_empty_scene(width, height, "World", world_colour, world_strength)
    record = {"seed": seed, "world": {"color": world_colour, "strength": world_strength}, "materials": {}}
    layout = "room" if rng.random() < 0.4 else "open"
    record["layout"] = layout
    size = (rng.uniform(3, 8), rng.uniform(3, 8), rng.uniform(2.5, 4))
    if layout == "room":
        record["window"] = room(rng, size, record["materials"])
    else:
        floor = add_shape(rng, "wall", "Floor")
        place(floor, (0, 0, 0), (0, 0, 0), (3 * size[0], 3 * size[1], 1))
        material, floor_record = random_material(rng, "Floor", ["diffuse", "oren_nayar", "principled_dielectric",
                                                                "glossy"])
        floor.data.materials.append(material)
        record["materials"]["Floor"] = floor_record
    objects = []
    for k in range(rng.randint(2, 6)):
        shape = rng.choice(SHAPES)
        obj = add_shape(rng, shape, f"Object{k}_{shape}")
        extent = rng.uniform(0.3, 1.5)
        scale = tuple(extent * rng.uniform(0.5, 1.5) for _ in range(3))
        if shape == "wall":  # a thin wall standing up
            rotation = (math.pi / 2, 0.0, rng.uniform(0, math.pi))
        else:
            rotation = tuple(rng.uniform(0, 2 * math.pi) for _ in range(3))
        location = (rng.uniform(-0.3, 0.3) * size[0], rng.uniform(-0.3, 0.3) * size[1],
                    rng.uniform(0.5, 0.8) * extent + (rng.uniform(0, 0.3) * size[2] if rng.random() < 0.3 else 0))
        place(obj, location, rotation, scale)
        material, material_record = random_material(rng, f"Material{k}")
        obj.data.materials.append(material)
        record["materials"][obj.name] = {"shape": shape, **material_record}
        objects.append(obj)
    target = (0.0, 0.0, 0.6)
    record["lights"] = []
    for k in range(rng.randint(1, 3)):
        kind = rng.choice(LIGHTS if layout == "open" else [k for k in LIGHTS if k != "sun"])
        distance = rng.uniform(0.3, 0.8) * min(size[0], size[1], size[2] * 1.5)
        _, light_record = add_light(rng, kind, f"Light{k}", target, distance, size if layout == "room" else None)
        record["lights"].append(light_record)
    record["camera"] = add_random_camera(rng, scene, target, 0.45 * max(size[0], size[1]),
                                         size if layout == "room" else None)

    # The whole scene scaled, and moved far from the origin, now and then: 1e3 to 1e5 of its own sizes. Blender
    # keeps object matrices in single precision, so a scene moved further than that relative to its size is no
    # longer the scene drawn (a 5 cm scene 2e4 away moves its objects by up to 2 mm in Blender itself).
    scale = rng.choice([1.0] * 8 + [0.01, 100.0])
    offset = Vector((0, 0, 0)) if rng.random() < 0.85 else Vector(
        (rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1))).normalized() * 10 ** rng.uniform(3, 5) * scale
    record["scale"], record["offset"] = scale, tuple(offset)
    if scale != 1.0 or offset.length > 0:
        bpy.context.view_layer.update()  # matrix_world of what was just placed, before it is read
        transform_scene(scene, Matrix.Translation(offset) @ Matrix.Scale(scale, 4), scale)
    scene["differential"] = json.dumps(record)
    return scene, record


def use_photonsplat(scene):
    try:
        import addon_utils
        addon_utils.enable("photonsplat", default_set=True)
        scene.render.engine = "PHOTONSPLAT"
        return True
    except Exception:  # the add-on not on Blender's path: the file keeps Cycles
        return False


def main():
    args = parse_args()
    width, height = (int(v) for v in args.size.lower().split("x"))
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    bpy.context.preferences.filepaths.save_version = 0
    for seed in parse_seeds(args.seeds):
        scene, record = make_scene(seed, width, height)
        engine = use_photonsplat(scene)
        path = out / f"random_{seed}.blend"
        bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=True)
        print(f"make_random_scenes: {path} ({record['layout']}, {len(record['materials'])} materials, "
              f"{len(record['lights'])} lights, engine {'PHOTONSPLAT' if engine else 'CYCLES'})", flush=True)


if __name__ == "__main__":
    main()
