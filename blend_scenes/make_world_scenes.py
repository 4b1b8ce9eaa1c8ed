"""Writes world_hdri.blend, world_sky.blend and world_portal.blend: scenes lit by the world alone (issue 17).

  - world_hdri.blend: a glass sphere "GlassSphere" (Glass BSDF, sharp, IOR 1.5, radius 0.5 m, smooth), a gold torus
    "GoldTorus" (Glossy BSDF, GGX, roughness 0.2) and a white block "WhiteBlock" (Diffuse 0.8) on a grey floor
    (Diffuse 0.5, 12 m square), lit only by the world: an Environment Texture of Blender's own studio-light HDRI
    city.exr (1024 x 512; the strongest sun of the HDRIs Debian's Blender ships: peak luminance 31749, a quarter of
    the map's power in its brightest 0.1 % of pixels, 47.6 degrees above the horizon). The image is packed into
    the file (213 kB; its filepath still names /usr/share/blender/datafiles/studiolights/world/city.exr), so the
    scene renders the same under every Blender. The camera looks across the sun's direction so that the glass
    sphere's caustic lies on the floor beside its shadow.
  - world_sky.blend: the same objects and a back wall, lit by a Sky Texture (Nishita, sun disc on, sun 35 degrees
    up, Background strength 0.05): an exterior.
  - world_portal.blend: a closed room 5 x 4 x 2.6 m (walls 0.1 m thick, Diffuse 0.7) with one window opening of
    1.6 x 1.2 m in its wall facing the HDRI's sun, a rectangular area light with Cycles' Portal checkbox
    (`light.cycles.is_portal`) filling the window and facing in, a white block and the gold torus inside; lit by
    the same HDRI through the window (the sun makes a patch on the floor).

All three are 480 x 270, view transform Standard, Cycles CPU (128 samples, no denoising, no clamping, world MIS
automatic: the map's resolution is the image's, 1024 x 512). The sun direction of the HDRI (the centroid of its
brightest pixels) is kept in the scene's custom property `sun_direction` (a unit vector towards the sun),
the glass sphere's centre and radius in `glass_center`, `glass_radius`.

Run:  blender -b --factory-startup -P blend_scenes/make_world_scenes.py [-- OUTDIR]
With the add-on on Blender's path (BLENDER_USER_SCRIPTS=$PWD/build/blender) the files are saved with Photon
Splat as their render engine (200k photons, progressive until 16 s); without it, with Cycles.
`tools/world_compare.py` renders them with Cycles and Photon Splat (docs/results/worlds.md).
"""

import math
import sys
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector

sys.path.insert(0, str(Path(__file__).resolve().parent))  # for scene_kit
from scene_kit import (add_camera, diffuse_material, glass_material, glossy_material,  # noqa: E402
                       new_empty_scene)

HDRI = "/usr/share/blender/datafiles/studiolights/world/city.exr"
WIDTH, HEIGHT = 480, 270
FLOOR = (0.5, 0.5, 0.5)
WHITE = (0.8, 0.8, 0.8)
WALL = (0.7, 0.7, 0.7)
GOLD = (1.0, 0.766, 0.336)
GOLD_ROUGHNESS = 0.2
GLASS_RADIUS = 0.5
SKY_ELEVATION = math.radians(35.0)
SKY_ROTATION = math.radians(-60.0)
SKY_STRENGTH = 0.05


def out_dir():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    return Path(argv[0]).resolve() if argv else Path(__file__).resolve().parent


def hdri_image():
    image = bpy.data.images.load(HDRI, check_existing=True)
    image.colorspace_settings.name = 'Linear'
    if image.packed_file is None:
        image.pack()
    return image


def hdri_sun_direction(image):
    """Unit vector towards the HDRI's sun: the luminance-weighted centroid of its brightest 0.05 % of pixels,
    with Cycles' equirectangular mapping (u = -atan2(y, x) / 2pi + 0.5, v = atan2(z, hypot(x, y)) / pi + 0.5)."""
    width, height = image.size
    pixels = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    pixels = pixels.reshape(height, width, 4)                    # row 0 at the bottom (v = 0)
    lum = 0.2126 * pixels[..., 0] + 0.7152 * pixels[..., 1] + 0.0722 * pixels[..., 2]
    threshold = np.quantile(lum, 0.9995)
    rows, cols = np.nonzero(lum >= threshold)
    weights = lum[rows, cols]
    u = (cols + 0.5) / width
    v = (rows + 0.5) / height
    phi = -(u - 0.5) * 2.0 * math.pi
    theta = (v - 0.5) * math.pi
    dirs = np.stack([np.cos(theta) * np.cos(phi), np.cos(theta) * np.sin(phi), np.sin(theta)], axis=-1)
    d = (dirs * weights[:, None]).sum(axis=0)
    return Vector(d / np.linalg.norm(d))


def hdri_world(scene, strength=1.0):
    world = bpy.data.worlds.new("HDRI")
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    env = nodes.new("ShaderNodeTexEnvironment")
    env.image = hdri_image()
    env.interpolation = 'Linear'
    env.projection = 'EQUIRECTANGULAR'
    env.location = (-300, 300)
    background = nodes["Background"]
    background.inputs["Strength"].default_value = strength
    links.new(env.outputs["Color"], background.inputs["Color"])
    world.color = (0.5, 0.5, 0.5)
    scene.world = world
    return world


def sky_world(scene):
    world = bpy.data.worlds.new("Sky")
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    sky = nodes.new("ShaderNodeTexSky")
    sky.sky_type = 'NISHITA'
    sky.sun_disc = True
    sky.sun_size = math.radians(0.545)
    sky.sun_intensity = 1.0
    sky.sun_elevation = SKY_ELEVATION
    sky.sun_rotation = SKY_ROTATION
    sky.altitude = 0.0
    sky.air_density = sky.dust_density = sky.ozone_density = 1.0
    sky.location = (-300, 300)
    background = nodes["Background"]
    background.inputs["Strength"].default_value = SKY_STRENGTH
    links.new(sky.outputs["Color"], background.inputs["Color"])
    world.color = (0.5, 0.6, 0.8)
    scene.world = world
    return world


def sky_sun_direction():
    """Cycles' direction of the Nishita sun (scene/light.cpp: longitude = 2pi - rotation + pi/2)."""
    lon = 2.0 * math.pi - SKY_ROTATION + 0.5 * math.pi
    lat = SKY_ELEVATION
    return Vector((math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)))


def cuboid(scene, name, lo, hi, material):
    """An axis-aligned box from corner `lo` to corner `hi`, outward normals, flat shaded."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    verts = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
             (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    faces = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)
    return obj


def floor(scene, half, material):
    mesh = bpy.data.meshes.new("Floor")
    mesh.from_pydata([(-half, -half, 0.0), (half, -half, 0.0), (half, half, 0.0), (-half, half, 0.0)], [],
                     [(0, 1, 2, 3)])
    mesh.materials.append(material)
    obj = bpy.data.objects.new("Floor", mesh)
    scene.collection.objects.link(obj)
    return obj


def glass_sphere(scene, center):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=GLASS_RADIUS, location=center)
    glass = bpy.context.active_object
    glass.name = glass.data.name = "GlassSphere"
    glass.data.polygons.foreach_set("use_smooth", [True] * len(glass.data.polygons))
    glass.data.materials.append(glass_material("Glass"))
    scene["glass_center"] = list(center)
    scene["glass_radius"] = GLASS_RADIUS
    return glass


def gold_torus(scene, location, rotation_z=0.0):
    bpy.ops.mesh.primitive_torus_add(major_radius=0.42, minor_radius=0.14, major_segments=64, minor_segments=24,
                                     location=(location[0], location[1], 0.14), rotation=(0.0, 0.0, rotation_z))
    torus = bpy.context.active_object
    torus.name = torus.data.name = "GoldTorus"
    torus.data.polygons.foreach_set("use_smooth", [True] * len(torus.data.polygons))
    torus.data.materials.append(glossy_material("Gold", GOLD, GOLD_ROUGHNESS))
    return torus


def white_block(scene, location, size=(0.6, 0.6, 0.7), rotation_z=0.0):
    x, y = location
    sx, sy, sz = size
    block = cuboid(scene, "WhiteBlock", (-sx / 2, -sy / 2, 0.0), (sx / 2, sy / 2, sz),
                   diffuse_material("White", WHITE))
    block.location = (x, y, 0.0)
    block.rotation_euler = (0.0, 0.0, rotation_z)
    return block


def frame_axes(sun):
    """(u, w): u the horizontal direction the sun's light travels (its caustic lies along it from the sphere), w
    horizontal and perpendicular to it."""
    u = -Vector((sun.x, sun.y, 0.0)).normalized()
    w = Vector((-u.y, u.x, 0.0))
    return u, w


def look_at(scene, location, target, lens):
    aim = Vector(target) - Vector(location)
    add_camera(scene, lens, tuple(location), aim.to_track_quat('-Z', 'Y').to_euler())


def cycles_defaults(scene):
    scene.cycles.samples = 128
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.sample_clamp_direct = 0.0
    scene.cycles.sample_clamp_indirect = 0.0
    scene.cycles.blur_glossy = 0.0
    scene.cycles.caustics_reflective = scene.cycles.caustics_refractive = True
    world = scene.world
    world.cycles.sampling_method = 'AUTOMATIC'     # map resolution: the environment image's (1024 x 512)
    world.cycles.max_bounces = 1024


def photonsplat_defaults(scene):
    """Photon Splat as the engine when its add-on is available (else the file keeps Cycles)."""
    try:
        import addon_utils
        addon_utils.enable("photonsplat", default_set=True)
        scene.render.engine = 'PHOTONSPLAT'
    except Exception as error:      # noqa: BLE001 - no add-on on the path: Cycles stays the engine
        print(f"make_world_scenes: Photon Splat add-on not available ({error}); engine left at Cycles")
        scene.render.engine = 'CYCLES'
        return
    ps = scene.photonsplat
    ps.photons = 200_000
    ps.iterations = 0
    ps.time_limit = 16.0
    ps.radius = 0.0
    ps.max_bounces = 16


def save(name, directory):
    path = directory / name
    bpy.context.preferences.filepaths.save_version = 0
    bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=True)
    print(f"wrote {path}")


def objects_on_floor(scene, u, w):
    """The glass sphere at the origin, the torus on the sun's side of it and the block beyond its caustic, in a row
    across the view (along u, the way the sun's light travels)."""
    glass_sphere(scene, (0.0, 0.0, GLASS_RADIUS))
    t = -1.5 * u - 0.3 * w
    gold_torus(scene, (t.x, t.y), rotation_z=0.3)
    b = 1.75 * u + 0.6 * w
    white_block(scene, (b.x, b.y), rotation_z=math.atan2(w.y, w.x) + 0.4)


def build_hdri(directory):
    scene = new_empty_scene(WIDTH, HEIGHT, "HDRI", (0.5, 0.5, 0.5))
    bpy.data.worlds.remove(scene.world)
    hdri_world(scene)
    sun = hdri_sun_direction(scene.world.node_tree.nodes["Environment Texture"].image)
    scene["sun_direction"] = list(sun)
    u, w = frame_axes(sun)
    floor(scene, 6.0, diffuse_material("Floor", FLOOR))
    objects_on_floor(scene, u, w)
    # The camera looks along the sun's travel rotated 90 degrees, from the side the caustic lies on, slightly
    # behind it (the sun behind-right): the caustic beside the sphere, its shadow, the lit faces in view.
    eye = -5.2 * w + 1.2 * u + Vector((0.0, 0.0, 2.3))
    look_at(scene, eye, (0.3 * u.x, 0.3 * u.y, 0.25), 32.0)
    scene.view_settings.exposure = -1.5
    cycles_defaults(scene)
    photonsplat_defaults(scene)
    save("world_hdri.blend", directory)


def build_sky(directory):
    scene = new_empty_scene(WIDTH, HEIGHT, "Sky", (0.5, 0.5, 0.5))
    bpy.data.worlds.remove(scene.world)
    sky_world(scene)
    sun = sky_sun_direction()
    scene["sun_direction"] = list(sun)
    u, w = frame_axes(sun)
    floor(scene, 6.0, diffuse_material("Floor", FLOOR))
    objects_on_floor(scene, u, w)
    # A back wall across the view, behind the objects: bounced light and a shadowed face.
    wall = cuboid(scene, "BackWall", (-3.0, -0.1, 0.0), (3.0, 0.1, 2.0), diffuse_material("Wall", WALL))
    c = 2.2 * w
    wall.location = (c.x, c.y, 0.0)
    wall.rotation_euler = (0.0, 0.0, math.atan2(u.y, u.x))
    eye = -5.2 * w + 1.2 * u + Vector((0.0, 0.0, 2.3))
    look_at(scene, eye, (0.3 * u.x, 0.3 * u.y, 0.4), 30.0)
    scene.view_settings.exposure = -2.0
    cycles_defaults(scene)
    photonsplat_defaults(scene)
    save("world_sky.blend", directory)


def build_portal(directory):
    scene = new_empty_scene(WIDTH, HEIGHT, "HDRI", (0.5, 0.5, 0.5))
    bpy.data.worlds.remove(scene.world)
    hdri_world(scene)
    sun = hdri_sun_direction(scene.world.node_tree.nodes["Environment Texture"].image)
    scene["sun_direction"] = list(sun)
    # The room in a frame turned so that its window wall (+X of the room) faces the sun's azimuth.
    azimuth = math.atan2(sun.y, sun.x)
    wall = diffuse_material("Wall", WALL)
    lx, ly, lz, t = 2.5, 2.0, 2.6, 0.1                     # half length, half width, height, thickness
    wx0, wx1, wz0, wz1 = -0.8, 0.8, 0.9, 2.1               # window across the +X wall (local y) and in height
    parts = [
        ("RoomFloor", (-lx - t, -ly - t, -t), (lx + t, ly + t, 0.0)),
        ("RoomCeiling", (-lx - t, -ly - t, lz), (lx + t, ly + t, lz + t)),
        ("WallBack", (-lx - t, -ly, 0.0), (-lx, ly, lz)),
        ("WallLeft", (-lx - t, -ly - t, 0.0), (lx + t, -ly, lz)),
        ("WallRight", (-lx - t, ly, 0.0), (lx + t, ly + t, lz)),
        ("WindowBelow", (lx, -ly, 0.0), (lx + t, ly, wz0)),
        ("WindowAbove", (lx, -ly, wz1), (lx + t, ly, lz)),
        ("WindowSideA", (lx, -ly, wz0), (lx + t, wx0, wz1)),
        ("WindowSideB", (lx, wx1, wz0), (lx + t, ly, wz1)),
    ]
    room = bpy.data.objects.new("Room", None)
    scene.collection.objects.link(room)
    for name, lo, hi in parts:
        cuboid(scene, name, lo, hi, wall).parent = room
    # The portal: a rectangle filling the window at the wall's outer face, facing into the room (-Z along -X).
    light = bpy.data.lights.new("Portal", type='AREA')
    light.shape = 'RECTANGLE'
    light.size = wx1 - wx0                 # along local X of the light
    light.size_y = wz1 - wz0
    light.energy = 0.0
    light.cycles.is_portal = True
    portal = bpy.data.objects.new("Portal", light)
    portal.location = (lx + t, 0.5 * (wx0 + wx1), 0.5 * (wz0 + wz1))
    # Local -Z (emission) towards -X, local X along world Y, local Y along world Z.
    portal.rotation_euler = (math.radians(90.0), math.radians(0.0), math.radians(90.0))
    portal.parent = room
    scene.collection.objects.link(portal)
    room.rotation_euler = (0.0, 0.0, azimuth)
    # Inside: the white block and the gold torus on the floor, in room coordinates, then turned with the room.
    bpy.context.view_layer.update()
    m = room.matrix_world

    def at(x, y, z=0.0):
        return m @ Vector((x, y, z))

    b = at(0.2, 0.9)
    white_block(scene, (b.x, b.y), size=(0.6, 0.6, 0.8), rotation_z=azimuth + 0.3)
    tor = at(-0.6, -0.8)
    gold_torus(scene, (tor.x, tor.y), rotation_z=azimuth)
    eye = at(-2.2, -1.5, 1.6)
    look_at(scene, eye, at(1.2, 0.4, 0.7), 18.0)
    cycles_defaults(scene)
    photonsplat_defaults(scene)
    scene["window_normal"] = list((m.to_3x3() @ Vector((1.0, 0.0, 0.0))).normalized())
    save("world_portal.blend", directory)


if __name__ == "__main__":
    directory = out_dir()
    directory.mkdir(parents=True, exist_ok=True)
    build_hdri(directory)
    build_sky(directory)
    build_portal(directory)
