"""Writes atrium.blend next to this script: a procedurally generated atrium in the spirit of Crytek Sponza, the
benchmark scene with depth complexity (many surfaces behind each other along most camera rays).

  - a courtyard of 30 m x 12 m, open to the sky, paved with a chequer of two stones;
  - around it two storeys of arcades: columns (base, shaft with entasis, capital), round arches, walkways behind
    them vaulted by transverse arches between the columns and pilasters on the outer walls;
  - a gallery floor on the first storey with a balustrade of turned balusters between the upper columns;
  - a roof rim over the walkways, projecting over the courtyard;
  - coloured curtains hanging from the gallery in front of the lower arcade, banners in the upper walkways and
    two awnings sagging across the courtyard (subdivided, displaced thin planes: double-sided);
  - a glass sphere on a stone plinth in the courtyard (the sun focuses it into a caustic on the plinth), a mirror
    sphere and terracotta vases;
  - lit by a sun through the opening and a dim sky (uniform world).

The camera flies through 8 key positions, one per frame (frames 1..8): a benchmark iterates the frames.

Run:  blender -b --factory-startup --python blend_scenes/make_atrium.py

Geometry is built with numpy arrays and written into the meshes with foreach_set (no Python loop over vertices).
Units are metres; the courtyard is centred on the origin, its long axis along X; Z is up. The column axes of the
arcades stand on the rectangle |x| = 15, |y| = 6; the walkways behind them are 3 m deep (outer walls at
|x| = 18, |y| = 9). The file opens in Cycles (CPU, view transform Standard, 1920x1080); tests pick the engine.
"""

import math
from pathlib import Path

import bpy
import sys
sys.path.insert(0, str(Path(__file__).resolve().parent))  # for scene_kit
from scene_kit import diffuse_material, glass_material, glossy_material, save, new_empty_scene as _new_scene  # noqa: E402
import numpy as np
from mathutils import Vector


# --- layout (metres) ---------------------------------------------------------------------------------------------
HALF_X, HALF_Y = 15.0, 6.0          # column axes of the arcades: the courtyard's edge
BAY = 3.0                           # column spacing
WALK = 3.0                          # walkway depth: outer walls' inner faces at |x| = 18, |y| = 9
WALL = 0.4                          # outer wall thickness
ARCADE_DEPTH = 0.7                  # thickness of the arcade wall carried by the columns
PILASTER_DEPTH = 0.3

# Per storey: floor level, springing line of the arches (top of the capitals), top (underside of the slab above),
# column scale (1 = the ground-floor column: 4 m high, shaft radius 0.28 m).
STOREYS = [
    dict(floor=0.0, spring=4.0, top=6.0, scale=1.0),
    dict(floor=6.3, spring=9.5, top=11.5, scale=0.8),
]
SLAB = 0.3                          # gallery floor / roof slab thickness
ROOF_TOP = 12.1
ARCH_RADIUS = 1.2                   # arcade arches: 2.4 m span between the capitals
ARCH_SEGMENTS = 32

SUN_STRENGTH = 5.0                  # W/m^2 on a surface facing the sun (Cycles' sun Strength)
SUN_ANGLE = math.radians(1.0)       # angular diameter: crisp shadows
SUN_DIRECTION = Vector((0.42, 0.30, -0.86)).normalized()    # where the light travels (local -Z of the lamp)
SKY = (0.45, 0.62, 1.0)             # dim uniform sky, colour x strength
SKY_STRENGTH = 0.6

# Scene-linear albedos.
STONE = (0.62, 0.56, 0.46)
STONE_LIGHT = (0.72, 0.66, 0.56)
PAVING_A = (0.56, 0.51, 0.43)
PAVING_B = (0.34, 0.30, 0.25)
PLASTER = (0.68, 0.60, 0.48)
TERRACOTTA = (0.45, 0.16, 0.07)
CLOTH_COLORS = {
    "Red": (0.62, 0.04, 0.03),
    "Green": (0.06, 0.38, 0.07),
    "Blue": (0.04, 0.10, 0.55),
    "Yellow": (0.75, 0.50, 0.04),
}

# Camera fly-through: (eye, target) per frame, frames 1..8.
FLY_THROUGH = [
    ((-13.2, 0.0, 1.7), (10.0, 0.6, 4.2)),        # 1 courtyard end, looking down the long axis
    ((-16.6, 7.6, 1.7), (12.0, 7.0, 2.4)),        # 2 inside the ground walkway, looking down its length
    ((-7.0, -8.2, 1.5), (5.0, 3.5, 2.2)),         # 3 from the walkway through the columns into the courtyard
    ((-11.0, 6.6, 8.4), (3.0, -3.0, 0.0)),        # 4 from the gallery, over the balustrade, into the courtyard
    ((16.6, 7.6, 7.9), (-12.0, 7.0, 8.6)),        # 5 down the upper gallery, past the banners
    ((-5.2, -3.0, 2.2), (-1.0, -6.0, 3.6)),       # 6 close-up of the curtains in front of the lower arcade
    ((4.0, 3.2, 1.3), (0.0, 0.0, 0.6)),           # 7 the glass sphere, its caustic and the arcade behind
    ((13.8, -0.6, 12.9), (-5.0, 0.8, 1.0)),       # 8 from above the roof rim, down over the awnings
]
LENS = 20.0                          # mm on a 36 mm sensor: about 84 degrees across a 16:9 frame


# --- mesh building with numpy ------------------------------------------------------------------------------------

class Parts:
    """Polygons gathered as numpy arrays (vertices, quads, triangles, per-face material slot) before they become
    one Blender mesh."""

    def __init__(self):
        self.vertices, self.quads, self.tris, self.quad_slots, self.tri_slots = [], [], [], [], []
        self.count = 0

    def add(self, vertices, quads=None, tris=None, slot=0):
        vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
        for faces, out, slots in ((quads, self.quads, self.quad_slots), (tris, self.tris, self.tri_slots)):
            if faces is None:
                continue
            faces = np.asarray(faces, dtype=np.int64)
            out.append(faces + self.count)
            slots.append(np.broadcast_to(np.asarray(slot, dtype=np.int64), faces.shape[:1]))
        self.vertices.append(vertices)
        self.count += len(vertices)

    def add_instances(self, template, matrices, slot=0):
        """Add `template` (vertices, quads, tris) once per 4x4 matrix, transformed, all in one numpy step."""
        vertices, quads, tris = template
        matrices = np.asarray(matrices, dtype=np.float64).reshape(-1, 4, 4)
        n, k = len(vertices), len(matrices)
        moved = np.einsum("kij,nj->kni", matrices[:, :3, :3], vertices) + matrices[:, None, :3, 3]
        offsets = (np.arange(k) * n)[:, None, None]
        self.add(moved.reshape(-1, 3),
                 None if quads is None else (np.asarray(quads)[None] + offsets).reshape(-1, 4),
                 None if tris is None else (np.asarray(tris)[None] + offsets).reshape(-1, 3), slot)

    def to_object(self, scene, name, materials, smooth_angle=None):
        vertices = np.concatenate(self.vertices)
        quads = np.concatenate(self.quads) if self.quads else np.zeros((0, 4), np.int64)
        tris = np.concatenate(self.tris) if self.tris else np.zeros((0, 3), np.int64)
        slots = np.concatenate([np.concatenate(self.quad_slots) if self.quad_slots else np.zeros(0, np.int64),
                                np.concatenate(self.tri_slots) if self.tri_slots else np.zeros(0, np.int64)])
        loop_total = np.concatenate([np.full(len(quads), 4), np.full(len(tris), 3)])
        loop_start = np.concatenate([[0], np.cumsum(loop_total)[:-1]])

        mesh = bpy.data.meshes.new(name)
        mesh.vertices.add(len(vertices))
        mesh.vertices.foreach_set("co", vertices.astype(np.float32).ravel())
        mesh.loops.add(int(loop_total.sum()))
        mesh.loops.foreach_set("vertex_index", np.concatenate([quads.ravel(), tris.ravel()]).astype(np.int32))
        mesh.polygons.add(len(loop_total))
        mesh.polygons.foreach_set("loop_start", loop_start.astype(np.int32))
        mesh.polygons.foreach_set("loop_total", loop_total.astype(np.int32))
        mesh.polygons.foreach_set("material_index", slots.astype(np.int32))
        if smooth_angle is not None:
            # Smooth across gentle bends (round shafts, cloth), sharp along real edges (auto smooth).
            mesh.polygons.foreach_set("use_smooth", np.ones(len(loop_total), dtype=bool))
            mesh.use_auto_smooth = True
            mesh.auto_smooth_angle = math.radians(smooth_angle)
        mesh.update(calc_edges=True)
        mesh.validate(clean_customdata=False)
        for material in materials:
            mesh.materials.append(material)
        obj = bpy.data.objects.new(name, mesh)
        scene.collection.objects.link(obj)
        return obj


def new_empty_scene():
    return _new_scene(1920, 1080, "Sky", SKY, SKY_STRENGTH)


def box(lo, hi):
    """An axis-aligned box: 8 vertices, 6 quads with outward normals."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = np.array([(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
                  (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)])
    q = np.array([(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)])
    return v, q, None


def lathe(profile, segments, cap_bottom=False, cap_top=False):
    """A surface of revolution about Z from (radius, z) profile points, bottom to top; normals outward."""
    profile = np.asarray(profile, dtype=np.float64)
    r, z = profile[:, 0], profile[:, 1]
    rings, s = len(profile), segments
    angle = 2.0 * math.pi * np.arange(s) / s
    v = np.stack([r[:, None] * np.cos(angle), r[:, None] * np.sin(angle),
                  np.broadcast_to(z[:, None], (rings, s))], axis=-1).reshape(-1, 3)
    p, k = np.meshgrid(np.arange(rings - 1), np.arange(s), indexing="ij")
    k1 = (k + 1) % s
    quads = np.stack([p * s + k, p * s + k1, (p + 1) * s + k1, (p + 1) * s + k], axis=-1).reshape(-1, 4)
    tris = []
    if cap_bottom:
        c = len(v)
        v = np.vstack([v, [(0.0, 0.0, z[0])]])
        tris.append(np.stack([np.full(s, c), (np.arange(s) + 1) % s, np.arange(s)], axis=-1))
    if cap_top:
        c, base = len(v), (rings - 1) * s
        v = np.vstack([v, [(0.0, 0.0, z[-1])]])
        tris.append(np.stack([np.full(s, c), base + np.arange(s), base + (np.arange(s) + 1) % s], axis=-1))
    return v, quads, (np.vstack(tris) if tris else None)


def grid(nu, nv):
    """Quads of a (nv + 1) x (nu + 1) vertex grid, row-major (v rows of u vertices)."""
    i, j = np.meshgrid(np.arange(nv), np.arange(nu), indexing="ij")
    a = i * (nu + 1) + j
    return np.stack([a, a + 1, a + nu + 2, a + nu + 1], axis=-1).reshape(-1, 4)


def arch(half_width, radius, height, depth, segments=ARCH_SEGMENTS):
    """A round arch in a wall panel: the panel spans u in [-half_width, half_width] (X), v in [0, height] (Z)
    above the springing line v = 0, w in [-depth/2, depth/2] (Y), with a semicircular opening of `radius`
    centred on u = 0, v = 0. Faces: the two spandrel faces and the intrados (soffit). The panel's sides, top and
    the ledges on the springing line rest against neighbours (capitals, slabs, the next bay) and are left open."""
    corner = math.atan2(height, half_width)
    theta = np.unique(np.concatenate([np.linspace(0.0, math.pi, segments + 1), [corner, math.pi - corner]]))
    n = len(theta)
    arc = np.stack([radius * np.cos(theta), radius * np.sin(theta)], axis=-1)
    # The panel's outline, projected from the arch centre: right side, top, left side (corners are in theta).
    with np.errstate(divide="ignore", invalid="ignore"):
        outer = np.where((theta <= corner)[:, None],
                         np.stack([np.full(n, half_width), half_width * np.tan(theta)], axis=-1),
                         np.where((theta >= math.pi - corner)[:, None],
                                  np.stack([np.full(n, -half_width), -half_width * np.tan(theta)], axis=-1),
                                  np.stack([height / np.tan(theta), np.full(n, height)], axis=-1)))
    def at(points, w):
        return np.stack([points[:, 0], np.full(n, w), points[:, 1]], axis=-1)
    v = np.vstack([at(arc, -depth / 2), at(outer, -depth / 2), at(arc, depth / 2), at(outer, depth / 2)])
    i = np.arange(n - 1)
    af, of, ab, ob = 0, n, 2 * n, 3 * n
    quads = np.vstack([
        np.stack([af + i, of + i, of + i + 1, af + i + 1], axis=-1),     # front spandrel, facing -Y
        np.stack([ab + i, ab + i + 1, ob + i + 1, ob + i], axis=-1),     # back spandrel, facing +Y
        np.stack([af + i, af + i + 1, ab + i + 1, ab + i], axis=-1),     # intrados, facing the opening
    ])
    return v, quads, None


def placement(x, y, z, angle=0.0):
    """4x4 matrix: rotate about Z by `angle`, then move to (x, y, z)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0, x], [s, c, 0, y], [0, 0, 1, z], [0, 0, 0, 1]], dtype=np.float64)


def scaled(template, factor):
    v, q, t = template
    return v * np.asarray(factor, dtype=np.float64), q, t


# --- materials ---------------------------------------------------------------------------------------------------

# --- the building ------------------------------------------------------------------------------------------------

def column_profile(height):
    """(radius, z) of a column's round part for a ground-floor column of `height` (abacus included above)."""
    shaft_top = height - 0.55
    shaft = [(0.28 - 0.03 * t * t, 0.45 + t * (shaft_top - 0.45)) for t in np.linspace(0.0, 1.0, 7)]
    return ([(0.37, 0.25), (0.37, 0.31), (0.33, 0.36), (0.30, 0.40)] + shaft +
            [(0.27, shaft_top + 0.05), (0.27, shaft_top + 0.10), (0.31, height - 0.38), (0.36, height - 0.30),
             (0.41, height - 0.23), (0.44, height - 0.20)])


def column_template(height):
    parts = Parts()
    parts.add(*box((-0.39, -0.39, 0.0), (0.39, 0.39, 0.25)))                  # square plinth
    parts.add(*lathe(column_profile(height), 24))                              # base, shaft, echinus
    parts.add(*box((-0.42, -0.42, height - 0.20), (0.42, 0.42, height)))      # abacus
    return (np.concatenate(parts.vertices), np.concatenate(parts.quads),
            np.concatenate(parts.tris) if parts.tris else None)


def baluster_template(height):
    profile = np.array([(0.055, 0.0), (0.055, 0.04), (0.040, 0.07), (0.045, 0.11), (0.070, 0.20),
                        (0.085, 0.28), (0.080, 0.34), (0.060, 0.42), (0.042, 0.50), (0.036, 0.56),
                        (0.050, 0.60), (0.040, 0.66), (0.055, 0.70), (0.055, 0.75)])
    profile[:, 1] *= height / 0.75
    return lathe(profile, 12)


def perimeter_positions():
    """Column axes around the courtyard, corners included, and the bays between them.

    Returns (columns, bays): columns as (x, y); bays as (x, y, angle) of each bay's centre, with the angle turning
    the arch template (spanning X, thickness along Y) to lie along that side."""
    xs = np.arange(-HALF_X, HALF_X + 1e-6, BAY)
    ys = np.arange(-HALF_Y, HALF_Y + 1e-6, BAY)
    columns = [(x, y) for y in (-HALF_Y, HALF_Y) for x in xs] + \
              [(x, y) for x in (-HALF_X, HALF_X) for y in ys[1:-1]]
    bays = [((a + b) / 2, y, 0.0) for y in (-HALF_Y, HALF_Y) for a, b in zip(xs[:-1], xs[1:])] + \
           [(x, (a + b) / 2, math.pi / 2) for x in (-HALF_X, HALF_X) for a, b in zip(ys[:-1], ys[1:])]
    return columns, bays


def transverse_positions():
    """Transverse arches across the walkways: from each column to the outer wall. Returns (x, y, angle) of each
    arch's centre (the arch template spans its local X) and (x, y, angle) of the pilaster on the wall."""
    arcade_face = ARCADE_DEPTH / 2
    span_start, span_end = arcade_face, WALK - PILASTER_DEPTH
    middle = (span_start + span_end) / 2
    arches, pilasters = [], []
    columns, _ = perimeter_positions()
    for x, y in columns:
        directions = []
        if abs(abs(y) - HALF_Y) < 1e-6:
            directions.append((0.0, math.copysign(1.0, y)))
        if abs(abs(x) - HALF_X) < 1e-6:
            directions.append((math.copysign(1.0, x), 0.0))
        for dx, dy in directions:
            angle = math.atan2(dy, dx)          # the arch's local X runs from the column towards the wall
            arches.append((x + dx * middle, y + dy * middle, angle))
            pilasters.append((x + dx * WALK, y + dy * WALK, angle))
    return arches, pilasters


def ring_slab(outer_x, outer_y, inner_x, inner_y, z0, z1):
    """A rectangular ring (frame) as four boxes: outer half sizes, inner (hole) half sizes."""
    return [box((-outer_x, -outer_y, z0), (outer_x, -inner_y, z1)),
            box((-outer_x, inner_y, z0), (outer_x, outer_y, z1)),
            box((-outer_x, -inner_y, z0), (-inner_x, inner_y, z1)),
            box((inner_x, -inner_y, z0), (outer_x, inner_y, z1))]


def add_building(scene, stone, stone_light, plaster, paving):
    columns, bays = perimeter_positions()
    arches, pilasters = transverse_positions()
    out_x, out_y = HALF_X + WALK, HALF_Y + WALK
    face = ARCADE_DEPTH / 2

    # Columns of both storeys.
    column_parts = Parts()
    for storey in STOREYS:
        height = storey["spring"] - storey["floor"]
        template = scaled(column_template(height / storey["scale"]), storey["scale"])
        column_parts.add_instances(template, [placement(x, y, storey["floor"]) for x, y in columns])
    column_parts.to_object(scene, "Columns", [stone_light], smooth_angle=50.0)

    # Arcade arches, transverse arches over the walkways, pilasters and corner blocks.
    arch_parts = Parts()
    for storey in STOREYS:
        rise = storey["top"] - storey["spring"]
        arcade = arch(BAY / 2, ARCH_RADIUS, rise, ARCADE_DEPTH)
        arch_parts.add_instances(arcade, [placement(x, y, storey["spring"], a) for x, y, a in bays])
        half_span = (WALK - PILASTER_DEPTH - face) / 2
        transverse = arch(half_span, half_span - 0.1, rise, 0.5, segments=24)
        arch_parts.add_instances(transverse, [placement(x, y, storey["spring"], a) for x, y, a in arches])
        pilaster = box((-PILASTER_DEPTH, -0.3, storey["floor"]), (0.0, 0.3, storey["spring"]))
        arch_parts.add_instances(pilaster, [placement(x, y, 0.0, a) for x, y, a in pilasters])
        for sx in (-1, 1):
            for sy in (-1, 1):        # close the arcades' outer corners above the corner capitals
                arch_parts.add(*box((sx * HALF_X - face, sy * HALF_Y - face, storey["spring"]),
                                    (sx * HALF_X + face, sy * HALF_Y + face, storey["top"])))
    arch_parts.to_object(scene, "Arches", [stone], smooth_angle=50.0)

    # Floors, slabs, outer walls, roof rim.
    shell = Parts()
    for storey in STOREYS[1:]:
        for part in ring_slab(out_x, out_y, HALF_X - face - 0.05, HALF_Y - face - 0.05,
                              storey["floor"] - SLAB, storey["floor"]):
            shell.add(*part)
        for part in ring_slab(out_x, out_y, HALF_X - face - 0.2, HALF_Y - face - 0.2,    # string course
                              storey["floor"] - SLAB - 0.15, storey["floor"] - SLAB):
            shell.add(*part)
    for part in ring_slab(out_x, out_y, HALF_X - face - 0.05, HALF_Y - face - 0.05, STOREYS[-1]["top"],
                          STOREYS[-1]["top"] + 0.2):
        shell.add(*part)
    for part in ring_slab(out_x + WALL, out_y + WALL, HALF_X - face - 0.45, HALF_Y - face - 0.45,  # roof rim
                          STOREYS[-1]["top"] + 0.2, ROOF_TOP):
        shell.add(*part)
    for part in ring_slab(out_x + WALL, out_y + WALL, out_x, out_y, 0.0, ROOF_TOP):                 # outer walls
        shell.add(*part, slot=1)
    for storey in STOREYS:       # a moulded band along the foot of the outer walls
        for part in ring_slab(out_x, out_y, out_x - 0.08, out_y - 0.08, storey["floor"], storey["floor"] + 0.35):
            shell.add(*part)
    shell.to_object(scene, "Shell", [stone, plaster])

    # The ground floor: 1 m paving stones in a chequer of two stones (a material slot each).
    nx, ny = int(2 * (out_x + WALL)), int(2 * (out_y + WALL))
    xs = np.linspace(-(out_x + WALL), out_x + WALL, nx + 1)
    ys = np.linspace(-(out_y + WALL), out_y + WALL, ny + 1)
    gx, gy = np.meshgrid(xs, ys)
    vertices = np.stack([gx, gy, np.zeros_like(gx)], axis=-1).reshape(-1, 3)
    quads = grid(nx, ny)
    i, j = np.meshgrid(np.arange(ny), np.arange(nx), indexing="ij")
    floor = Parts()
    floor.add(vertices, quads, slot=((i + j) % 2).ravel())
    floor.to_object(scene, "Floor", paving)

    # The balustrade along the gallery's edge, between the upper columns.
    gallery = STOREYS[1]["floor"]
    rail = Parts()
    clear = BAY / 2 - 0.33
    rail.add(*box((-clear, -0.13, 0.0), (clear, 0.13, 0.15)))
    rail.add(*box((-clear, -0.16, 0.90), (clear, 0.16, 1.02)))
    rail_template = (np.concatenate(rail.vertices), np.concatenate(rail.quads), None)
    baluster = baluster_template(0.75)
    count = 10
    offsets = (np.arange(count) - (count - 1) / 2) * (2 * clear / count)
    balustrade = Parts()
    balustrade.add_instances(rail_template, [placement(x, y, gallery, a) for x, y, a in bays])
    balusters = []
    for x, y, a in bays:
        c, s = math.cos(a), math.sin(a)
        balusters += [placement(x + c * o, y + s * o, gallery + 0.15, a) for o in offsets]
    balustrade.add_instances(baluster, balusters)
    balustrade.to_object(scene, "Balustrade", [stone_light], smooth_angle=50.0)


# --- cloth ---------------------------------------------------------------------------------------------------------

def curtain(width, length, folds, seed, nu=48, nv=90):
    """A hanging cloth in its local frame: top edge along X at z = 0, hanging down to z = -length, displaced
    along Y by folds that deepen towards the hem and a hem swinging slightly out."""
    rng = np.random.default_rng(seed)
    u = np.linspace(0.0, 1.0, nu + 1)
    t = np.linspace(0.0, 1.0, nv + 1)                     # 0 at the top, 1 at the hem
    uu, tt = np.meshgrid(u, t)
    phases = rng.uniform(0.0, 2.0 * math.pi, 3)
    depth = 0.06 + 0.10 * tt
    offset = (depth * np.sin(2.0 * math.pi * folds * uu + phases[0])
              + 0.35 * depth * np.sin(2.0 * math.pi * 2.7 * folds * uu + phases[1] + 3.0 * tt)
              + 0.25 * tt ** 2 + 0.05 * np.sin(math.pi * uu) * np.sin(5.0 * tt + phases[2]))
    # Gathered at the top: the hanging width narrows a little towards the hem's middle.
    x = (uu - 0.5) * width * (1.0 - 0.06 * tt * np.sin(math.pi * uu))
    z = -tt * length * (1.0 - 0.02 * np.sin(math.pi * uu))
    return np.stack([x, offset, z], axis=-1).reshape(-1, 3), grid(nu, nv), None


def awning(span, width, sag, seed, nu=40, nv=80):
    """A cloth stretched across the courtyard: from y = -span/2 to +span/2 at z = 0, `width` wide along X,
    sagging by `sag` in the middle, with small ripples."""
    rng = np.random.default_rng(seed)
    u = np.linspace(-0.5, 0.5, nu + 1)
    t = np.linspace(-0.5, 0.5, nv + 1)
    uu, tt = np.meshgrid(u, t)
    phase = rng.uniform(0.0, 2.0 * math.pi)
    z = -sag * (1.0 - 4.0 * tt ** 2) + 0.05 * np.sin(2.0 * math.pi * 5.0 * uu + phase) * (1.0 - 4.0 * tt ** 2)
    x = uu * width * (1.0 - 0.08 * (1.0 - 4.0 * tt ** 2))
    return np.stack([x, tt * span, z], axis=-1).reshape(-1, 3), grid(nu, nv), None


def add_cloth(scene, materials):
    names = list(CLOTH_COLORS)
    face = ARCADE_DEPTH / 2
    hang_from = STOREYS[1]["floor"] - SLAB - 0.15          # under the string course
    cloth = {name: Parts() for name in names}
    # Curtains in front of the lower arcade (courtyard side), three on each long side.
    curtains = [(-10.5, -1, "Red"), (-4.5, -1, "Green"), (4.5, -1, "Blue"),
                (-7.5, 1, "Blue"), (1.5, 1, "Red"), (10.5, 1, "Green")]
    for k, (x, side, name) in enumerate(curtains):
        v, q, _ = curtain(2.5, 3.8, folds=5, seed=k)
        if side > 0:
            v = v * np.array([-1.0, -1.0, 1.0])               # turn it to hang on the other side
        matrix = placement(x, side * (HALF_Y - face - 0.25), hang_from)
        cloth[name].add_instances((v, q, None), [matrix])
    # Banners hanging from the upper walkways' ceiling, across the walkway.
    banner_top = STOREYS[1]["top"] - 0.05
    banners = [(-6.0, -1, "Yellow"), (6.0, -1, "Red"), (0.0, 1, "Yellow"), (12.0, 1, "Blue")]
    for k, (x, side, name) in enumerate(banners):
        v, q, _ = curtain(1.2, 2.6, folds=3, seed=10 + k, nu=24, nv=60)
        matrix = placement(x, side * (HALF_Y + WALK / 2 + 0.1), banner_top, math.pi / 2)
        cloth[name].add_instances((v, q, None), [matrix])
    # Two awnings stretched across the courtyard below the roof rim.
    for k, (x, name) in enumerate([(-9.0, "Red"), (4.5, "Yellow")]):
        v, q, _ = awning(2.0 * (HALF_Y - face), 3.2, 1.6, seed=20 + k)
        cloth[name].add_instances((v, q, None), [placement(x, 0.0, STOREYS[1]["top"] - 0.3)])
    for name in names:
        cloth[name].to_object(scene, f"Cloth{name}", [materials[name]], smooth_angle=80.0)


# --- courtyard objects ----------------------------------------------------------------------------------------------

def add_courtyard(scene, stone_light, terracotta, glass, mirror):
    plinth = Parts()
    plinth.add(*lathe([(1.6, 0.0), (1.6, 0.12), (1.5, 0.16), (1.45, 0.22), (1.5, 0.26), (1.5, 0.30)],
                      64, cap_top=True))
    plinth.add_instances(lathe([(0.55, 0.0), (0.55, 0.3)], 32, cap_top=True), [placement(-3.5, 1.5, 0.0)])
    plinth.to_object(scene, "Plinths", [stone_light], smooth_angle=50.0)

    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=0.7, location=(0.0, 0.0, 1.0))
    sphere = bpy.context.active_object
    sphere.name = sphere.data.name = "GlassSphere"
    sphere.data.polygons.foreach_set("use_smooth", [True] * len(sphere.data.polygons))
    sphere.data.materials.append(glass)

    bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=0.5, location=(-3.5, 1.5, 0.8))
    sphere = bpy.context.active_object
    sphere.name = sphere.data.name = "MirrorSphere"
    sphere.data.polygons.foreach_set("use_smooth", [True] * len(sphere.data.polygons))
    sphere.data.materials.append(mirror)

    vase = lathe([(0.16, 0.0), (0.22, 0.05), (0.30, 0.20), (0.34, 0.35), (0.30, 0.50), (0.20, 0.62),
                  (0.15, 0.68), (0.17, 0.74), (0.21, 0.78), (0.19, 0.80)], 32, cap_bottom=True)
    vases = Parts()
    spots = [(x, y) for x in (-12.0, -6.0, 6.0, 12.0) for y in (-4.6, 4.6)]
    vases.add_instances(scaled(vase, 1.3), [placement(x, y, 0.0) for x, y in spots])
    vases.to_object(scene, "Vases", [terracotta], smooth_angle=60.0)


# --- lights, camera, scene -----------------------------------------------------------------------------------------

def add_sun(scene):
    light = bpy.data.lights.new("Sun", type='SUN')
    light.energy = SUN_STRENGTH
    light.angle = SUN_ANGLE
    light.color = (1.0, 0.96, 0.90)
    obj = bpy.data.objects.new("Sun", light)
    obj.rotation_euler = SUN_DIRECTION.to_track_quat('-Z', 'Y').to_euler()
    obj.location = (0.0, 0.0, 20.0)
    scene.collection.objects.link(obj)
    return obj


def add_camera(scene):
    camera = bpy.data.cameras.new("Camera")
    camera.lens = LENS
    camera.sensor_width = 36.0
    camera.sensor_fit = 'AUTO'
    camera.clip_start = 0.05
    camera.clip_end = 200.0
    obj = bpy.data.objects.new("Camera", camera)
    scene.collection.objects.link(obj)
    scene.camera = obj
    for frame, (eye, target) in enumerate(FLY_THROUGH, start=1):
        eye, target = Vector(eye), Vector(target)
        obj.location = eye
        obj.rotation_euler = (target - eye).to_track_quat('-Z', 'Y').to_euler()
        obj.keyframe_insert("location", frame=frame)
        obj.keyframe_insert("rotation_euler", frame=frame)
    for curve in obj.animation_data.action.fcurves:
        for key in curve.keyframe_points:
            key.interpolation = 'CONSTANT'      # one key position per frame, nothing in between
    scene.frame_start, scene.frame_end = 1, len(FLY_THROUGH)
    scene.frame_set(1)
    return obj


def make_atrium():
    scene = new_empty_scene()
    stone = diffuse_material("Stone", STONE)
    stone_light = diffuse_material("StoneLight", STONE_LIGHT)
    plaster = diffuse_material("Plaster", PLASTER)
    paving = [diffuse_material("PavingLight", PAVING_A), diffuse_material("PavingDark", PAVING_B)]
    cloth = {name: diffuse_material(f"Cloth{name}", color) for name, color in CLOTH_COLORS.items()}
    add_building(scene, stone, stone_light, plaster, paving)
    add_cloth(scene, cloth)
    add_courtyard(scene, stone_light, diffuse_material("Terracotta", TERRACOTTA), glass_material("Glass"),
                  glossy_material("Mirror", (0.9, 0.9, 0.9), 0.0))
    add_sun(scene)
    add_camera(scene)
    triangles = 0
    for obj in scene.objects:
        if obj.type == 'MESH':
            obj.data.calc_loop_triangles()
            triangles += len(obj.data.loop_triangles)
    print(f"atrium: {triangles:,} triangles, {len(FLY_THROUGH)} camera key positions")
    save("atrium.blend")


if __name__ == "__main__":
    make_atrium()
