# Renders Blender 3.4's own Cycles (CPU) to get golden values for the sky_texture op (native/src/nodes/
# sky_texture.cpp), and writes them to tests/native/golden/sky_goldens.h.
#
#     blender -b --factory-startup --python tests/native/golden/make_sky_goldens.py
#
# (run from the repository root; Debian's /usr/bin/blender, 3.4.1). Takes about a minute.
#
# As make_texture_goldens.py: a grid of W x H unit quads under an orthographic camera, one quad per pixel, each
# carrying a face attribute "dir" that an Attribute node feeds into the Sky Texture's Vector, whose Color drives
# an Emission shader of strength 1; the float OpenEXR render is the node's output at exactly the stored float32
# direction. Per case: 20 directions above the horizon (some near it), 6 below it (down to z = -0.5), 2 not of
# unit length (Cycles does not normalise the Vector) and 4 more above the horizon.
#
# The sun disc. In Nishita mode with the disc on, Blender makes the node's Vector socket unavailable: Cycles
# ignores its link and evaluates the default, the Generated coordinates (the direction in a world). So a disc
# case is two cases here: its sky, rendered as above with the disc off (outside the disc svm/sky.h does not read
# it; points that fall inside it are left out), and "<case> disc": the world itself, the Sky Texture behind a
# Background of strength 1, seen by a perspective camera aimed at the sun whose 8 x 4 pixels span 1.4 disc
# diameters; each pixel's direction is worked out from the camera (the single sample lies within 0.005 pixel of
# the centre), and pixels within 15 % of the disc's edge, where that offset would matter, are left out.
import math
import os
import random
import struct

import bpy

W, H = 8, 4  # 32 directions per case
OUT_DIR = "/tmp/ps_sky_goldens"
HEADER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "sky_goldens.h")
DEG = math.pi / 180.0


def f32(x):
    return struct.unpack("f", struct.pack("f", x))[0]


def build_scene():
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob, do_unlink=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 1
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.filter_width = 0.01
    scene.cycles.max_bounces = 0
    scene.cycles.seed = 0
    scene.render.resolution_x, scene.render.resolution_y = W, H
    scene.render.resolution_percentage = 100
    scene.render.use_compositing = False
    scene.render.use_sequencer = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.color_mode = "RGBA"
    if scene.world:
        scene.world.use_nodes = False
        scene.world.color = (0.0, 0.0, 0.0)
    cam_data = bpy.data.cameras.new("cam")
    cam_data.type = "ORTHO"
    cam_data.ortho_scale = float(max(W, H))
    cam = bpy.data.objects.new("cam", cam_data)
    cam.location = (W / 2.0, H / 2.0, 5.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    verts, faces = [], []
    for j in range(H):
        for i in range(W):
            b = len(verts)
            verts += [(i, j, 0.0), (i + 1, j, 0.0), (i + 1, j + 1, 0.0), (i, j + 1, 0.0)]
            faces.append((b, b + 1, b + 2, b + 3))
    mesh = bpy.data.meshes.new("grid")
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    mesh.attributes.new(name="dir", type="FLOAT_VECTOR", domain="FACE")
    grid = bpy.data.objects.new("grid", mesh)
    scene.collection.objects.link(grid)
    mat = bpy.data.materials.new("sky")
    mat.use_nodes = True
    mesh.materials.append(mat)
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    emit = nt.nodes.new("ShaderNodeEmission")
    sky = nt.nodes.new("ShaderNodeTexSky")
    attr = nt.nodes.new("ShaderNodeAttribute")
    attr.attribute_name = "dir"
    sky.sun_disc = False  # Blender 4.x/5.x have no Vector socket at all with Nishita's disc
    nt.links.new(attr.outputs["Vector"], sky.inputs["Vector"])
    nt.links.new(sky.outputs["Color"], emit.inputs["Color"])
    nt.links.new(emit.outputs["Emission"], out.inputs["Surface"])
    return scene, mesh, sky


# Settings in the core's order (nodes/sky_texture.h): sun direction xyz, turbidity, ground albedo, sun size,
# sun intensity, sun elevation, sun rotation, altitude, air, dust, ozone density.
DEFAULTS = dict(sun_direction=(0.0, 0.0, 1.0), turbidity=2.2, ground_albedo=0.3, sun_size=0.545 * DEG,
                sun_intensity=1.0, sun_elevation=15.0 * DEG, sun_rotation=0.0, altitude=0.0, air_density=1.0,
                dust_density=1.0, ozone_density=1.0)
ORDER = ["sun_direction", "turbidity", "ground_albedo", "sun_size", "sun_intensity", "sun_elevation",
         "sun_rotation", "altitude", "air_density", "dust_density", "ozone_density"]
TYPES = {"PREETHAM": 0, "HOSEK_WILKIE": 1, "NISHITA": 2}

CASES = [
    ("nishita default", "NISHITA", True, {}),
    ("nishita high sun", "NISHITA", True, dict(sun_elevation=45 * DEG, sun_rotation=60 * DEG, sun_size=2 * DEG,
                                               sun_intensity=0.5, altitude=1000.0, air_density=1.5,
                                               dust_density=0.5, ozone_density=2.0)),
    ("nishita sunset disc", "NISHITA", True, dict(sun_elevation=1 * DEG, sun_rotation=200 * DEG, sun_size=5 * DEG,
                                                  dust_density=2.0)),
    ("nishita below horizon", "NISHITA", False, dict(sun_elevation=-3 * DEG, sun_rotation=-40 * DEG)),
    ("nishita altitude", "NISHITA", True, dict(sun_elevation=70 * DEG, sun_rotation=400 * DEG, altitude=30000.0,
                                               dust_density=3.0, ozone_density=0.0, sun_size=3 * DEG,
                                               sun_intensity=2.0)),
    ("nishita no disc thin air", "NISHITA", False, dict(air_density=0.2, dust_density=0.0, sun_elevation=30 * DEG,
                                                         sun_rotation=120 * DEG)),
    ("preetham default", "PREETHAM", False, dict(sun_direction=(0.0, 0.5, 0.8))),
    ("preetham hazy", "PREETHAM", False, dict(turbidity=6.0, sun_direction=(1.0, -1.0, 0.2))),
    ("preetham low sun", "PREETHAM", False, dict(turbidity=9.5, sun_direction=(-0.3, 0.9, 0.05))),
    ("hosek default", "HOSEK_WILKIE", False, dict(sun_direction=(0.0, 0.5, 0.8))),
    ("hosek hazy", "HOSEK_WILKIE", False, dict(turbidity=6.0, ground_albedo=0.7, sun_direction=(1.0, -1.0, 0.2))),
]


def sun_vector(elevation, rotation):
    """The disc's centre as svm/sky.h places it: elevation, and 2π − rotation (wrapped) + π/2 of azimuth."""
    r = math.fmod(rotation, 2 * math.pi)
    if r < 0:
        r += 2 * math.pi
    az = 2 * math.pi - r + math.pi / 2
    return (math.cos(elevation) * math.cos(az), math.cos(elevation) * math.sin(az), math.sin(elevation))


def directions(rng, disc, settings):
    pts = []
    for k in range(20):
        z = rng.uniform(0.0, 0.15) if k < 6 else rng.uniform(0.0, 1.0)
        a = rng.uniform(-math.pi, math.pi)
        s = math.sqrt(max(0.0, 1 - z * z))
        pts.append((s * math.cos(a), s * math.sin(a), z))
    for k in range(6):
        z = -0.5 + 0.49 * k / 5.0
        a = rng.uniform(-math.pi, math.pi)
        s = math.sqrt(1 - z * z)
        pts.append((s * math.cos(a), s * math.sin(a), z))
    for scale in (0.6, 1.7):
        z = rng.uniform(0.1, 0.9)
        a = rng.uniform(-math.pi, math.pi)
        s = math.sqrt(1 - z * z)
        pts.append((scale * s * math.cos(a), scale * s * math.sin(a), scale * z))
    for k in range(4):
        z = rng.uniform(0.0, 1.0)
        a = rng.uniform(-math.pi, math.pi)
        s = math.sqrt(1 - z * z)
        pts.append((s * math.cos(a), s * math.sin(a), z))
    if disc:  # none inside the disc or near its edge
        sun = sun_vector(settings["sun_elevation"], settings["sun_rotation"])
        half = 0.5 * max(settings["sun_size"], 0.0005)
        pts = [p if angle_to(p, sun) > 1.5 * half else (p[0], p[1], -p[2] if p[2] > 0 else p[2]) for p in pts]
    return pts


def angle_to(p, sun):
    n = math.sqrt(sum(c * c for c in p))
    return math.acos(max(-1.0, min(1.0, sum(a * b for a, b in zip(p, sun)) / n)))


def disc_directions(scene, cam, settings):
    """Aims the camera at the sun; the world direction of each pixel's centre (bottom row first)."""
    from mathutils import Vector
    sun = Vector(sun_vector(settings["sun_elevation"], settings["sun_rotation"]))
    diameter = max(settings["sun_size"], 0.0005)
    cam.data.type = "PERSP"
    cam.data.sensor_fit = "HORIZONTAL"
    cam.data.sensor_width = 36.0
    cam.data.lens = 18.0 / math.tan(0.7 * diameter)
    cam.data.clip_start = 1e-3
    cam.location = (0.0, 0.0, 0.0)
    q = sun.to_track_quat("-Z", "Y")
    cam.rotation_mode = "QUATERNION"
    cam.rotation_quaternion = q
    t = 36.0 / cam.data.lens
    pts = []
    for j in range(H):
        for i in range(W):
            d = Vector((((i + 0.5) / W - 0.5) * t, ((j + 0.5) / H - 0.5) * t * H / W, -1.0)).normalized()
            pts.append(tuple(q @ d))
    return pts, 0.5 * diameter, tuple(sun)


def render(scene, tag):
    os.makedirs(OUT_DIR, exist_ok=True)
    path = os.path.join(OUT_DIR, tag + ".exr")
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(path, check_existing=False)
    img.colorspace_settings.name = "Non-Color"
    px = list(img.pixels[:])
    bpy.data.images.remove(img)
    return [(px[4 * k], px[4 * k + 1], px[4 * k + 2]) for k in range(W * H)]


def fmt(x):
    s = "%.9g" % x
    if "e" not in s and "." not in s:
        s += ".0"
    return s + "f"


def add_block(blocks, rows, label, sky_type, disc, settings, points):
    index = len(blocks)
    lines = ["    " + ", ".join(fmt(v) for v in p + c) + "," for p, c in points]
    blocks.append("// %s\nconst float kData%02d[] = {\n%s\n};\n" % (label, index, "\n".join(lines)))
    rows.append('    {"%s", %d, %d, {%s}, %d, kData%02d},' % (
        label, TYPES[sky_type], int(disc), ", ".join(fmt(v) for v in settings), len(points), index))


def main():
    scene, mesh, sky = build_scene()
    rng = random.Random(20261126)
    blocks, rows = [], []
    for index, (label, sky_type, disc, overrides) in enumerate(CASES):
        settings = dict(DEFAULTS, **overrides)
        sky.sky_type = sky_type
        sky.sun_disc = disc
        for name in ORDER:
            setattr(sky, name, settings[name])
        stored_settings = []
        for name in ORDER:
            v = getattr(sky, name)
            stored_settings += [f32(c) for c in v] if name == "sun_direction" else [f32(v)]
        with_disc = disc and sky_type == "NISHITA"
        pts = directions(rng, with_disc, settings)
        data = mesh.attributes["dir"].data
        stored = []
        for k, p in enumerate(pts):
            data[k].vector = p
            stored.append(tuple(f32(c) for c in data[k].vector))
        mesh.update()
        sky.sun_disc = False if with_disc else disc  # the Vector socket is available only without the disc
        px = render(scene, "case%02d" % index)
        sky.sun_disc = disc
        add_block(blocks, rows, label, sky_type, disc, stored_settings, list(zip(stored, px)))
        if with_disc:
            world_pts, half, sun = disc_directions(scene, scene.camera, settings)
            grid = bpy.data.objects["grid"]
            grid.hide_render = True
            world = scene.world
            world.use_nodes = True
            wt = world.node_tree
            wt.nodes.clear()
            wsky = wt.nodes.new("ShaderNodeTexSky")
            for name in ("sky_type", "sun_disc") + tuple(ORDER):
                setattr(wsky, name, getattr(sky, name))
            bg = wt.nodes.new("ShaderNodeBackground")
            wout = wt.nodes.new("ShaderNodeOutputWorld")
            wt.links.new(wsky.outputs["Color"], bg.inputs["Color"])
            wt.links.new(bg.outputs["Background"], wout.inputs["Surface"])
            wpx = render(scene, "case%02d_disc" % index)
            keep = [(tuple(f32(c) for c in p), c) for p, c in zip(world_pts, wpx)
                    if abs(angle_to(p, sun) / half - 1.0) > 0.15]
            add_block(blocks, rows, label + " disc", sky_type, disc, stored_settings, keep)
            world.use_nodes = False
            grid.hide_render = False
            cam = scene.camera
            cam.data.type = "ORTHO"
            cam.location = (W / 2.0, H / 2.0, 5.0)
            cam.rotation_quaternion = (1.0, 0.0, 0.0, 0.0)
        print(label, "done")
    with open(HEADER, "w") as f:
        f.write("// Generated by tests/native/golden/make_sky_goldens.py from Blender 3.4.1's Cycles (CPU): do not "
                "edit.\n// Each case: the sky type (0 Preetham, 1 Hosek / Wilkie, 2 Nishita), sun disc, the op's "
                "settings\n// (nodes/sky_texture.h order), and per direction: x, y, z, then Cycles' colour r, g, b."
                "\n#pragma once\n\nnamespace sky_goldens {\n\nstruct Case {\n    const char* label;\n    int type;\n"
                "    int sun_disc;\n    float settings[13];\n    int n_points;\n    const float* data;  // n_points x 6"
                "\n};\n\n")
        f.write("\n".join(blocks))
        f.write("\nconst Case kCases[] = {\n%s\n};\n\n}  // namespace sky_goldens\n" % "\n".join(rows))
    print("wrote", HEADER)


main()
