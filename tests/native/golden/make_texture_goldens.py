# Renders Blender 3.4's own Cycles (CPU) to get golden values for the procedural texture ops
# (native/src/nodes/texture_nodes.cpp), and writes them to tests/native/golden/texture_goldens.h.
#
#     blender -b --factory-startup --python tests/native/golden/make_texture_goldens.py
#
# (run from the repository root; Debian's /usr/bin/blender, 3.4.1). Takes a few minutes.
#
# How each value is known exactly: the scene is a grid of W x H separate unit quads under an orthographic camera
# that maps each quad onto one pixel. Every quad carries face-domain attributes, "pco" (a vector) and "pw" (a
# float), which the material reads with Attribute nodes into the texture node's Vector and W inputs. A face
# attribute is constant over its face, so the shading point's input is exactly the stored float32, wherever in
# the pixel the (single, filter width 0.01) sample lands. The texture node's outputs drive an Emission shader of
# strength 1, directly (a vector/colour output) or three floats at a time through a Combine XYZ, so each pixel of
# the float OpenEXR render is the node's output. Blender itself reads the EXR back (bpy.data.images.load).
# A first "identity" case renders the attributes themselves and checks they come back bit-exact, negatives
# included, so the pipeline adds nothing.
import os
import random
import struct
import sys

import bpy

W, H = 8, 4  # 32 points per case
OUT_DIR = "/tmp/ps_texture_goldens"
HEADER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "texture_goldens.h")


def f32(x):
    return struct.unpack("f", struct.pack("f", x))[0]


# --- the scene ---------------------------------------------------------------------------------------------------
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
    scene.render.resolution_x = W
    scene.render.resolution_y = H
    scene.render.resolution_percentage = 100
    scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0
    scene.render.use_compositing = False
    scene.render.use_sequencer = False
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.exr_codec = "ZIP"
    scene.render.image_settings.color_mode = "RGBA"
    if scene.world:
        scene.world.use_nodes = False
        scene.world.color = (0.0, 0.0, 0.0)

    cam_data = bpy.data.cameras.new("cam")
    cam_data.type = "ORTHO"
    cam_data.ortho_scale = float(max(W, H))
    cam_data.sensor_fit = "AUTO"
    cam_data.clip_start = 0.1
    cam_data.clip_end = 100.0
    cam = bpy.data.objects.new("cam", cam_data)
    cam.location = (W / 2.0, H / 2.0, 5.0)
    cam.rotation_euler = (0.0, 0.0, 0.0)
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
    mesh.attributes.new(name="pco", type="FLOAT_VECTOR", domain="FACE")
    mesh.attributes.new(name="pw", type="FLOAT", domain="FACE")
    grid = bpy.data.objects.new("grid", mesh)
    scene.collection.objects.link(grid)
    mat = bpy.data.materials.new("tex")
    mat.use_nodes = True
    mesh.materials.append(mat)
    return scene, mesh, mat


def set_points(mesh, points):
    """points: list of (x, y, z, w) for face index = pixel index (row-major from the bottom row)."""
    assert len(points) == W * H
    pco = mesh.attributes["pco"].data
    pw = mesh.attributes["pw"].data
    stored = []
    for k, (x, y, z, w) in enumerate(points):
        pco[k].vector = (x, y, z)
        pw[k].value = w
        v = pco[k].vector
        stored.append((f32(v[0]), f32(v[1]), f32(v[2]), f32(pw[k].value)))
    mesh.update()
    return stored


def render_pixels(scene, tag):
    os.makedirs(OUT_DIR, exist_ok=True)
    path = os.path.join(OUT_DIR, tag + ".exr")
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(path, check_existing=False)
    img.colorspace_settings.name = "Non-Color"
    px = list(img.pixels[:])
    assert img.size[0] == W and img.size[1] == H, img.size
    bpy.data.images.remove(img)
    return [(px[4 * k], px[4 * k + 1], px[4 * k + 2]) for k in range(W * H)]


# --- the ops: our input/output layout (shader_program.h's table) and Blender's sockets ---------------------------
# inputs: (kind, source); source is "VEC" (the per-point vector), "W" (the per-point float), a socket name, or
# ("prop", name) for a node property our op takes as an input (brick's offset and squash).
OPS = {
    "noise_texture": dict(
        node="ShaderNodeTexNoise",
        inputs=[("v", "VEC"), ("f", "W"), ("f", "Scale"), ("f", "Detail"), ("f", "Roughness"), ("f", "Distortion")],
        outputs=[("f", "Fac"), ("v", "Color")]),
    "voronoi_texture": dict(
        node="ShaderNodeTexVoronoi",
        inputs=[("v", "VEC"), ("f", "W"), ("f", "Scale"), ("f", "Smoothness"), ("f", "Exponent"),
                ("f", "Randomness")],
        outputs=[("f", "Distance"), ("v", "Color"), ("v", "Position"), ("f", "W"), ("f", "Radius")]),
    "musgrave_texture": dict(
        node="ShaderNodeTexMusgrave",
        inputs=[("v", "VEC"), ("f", "W"), ("f", "Scale"), ("f", "Detail"), ("f", "Dimension"), ("f", "Lacunarity"),
                ("f", "Offset"), ("f", "Gain")],
        outputs=[("f", "Fac")]),
    "wave_texture": dict(
        node="ShaderNodeTexWave",
        inputs=[("v", "VEC"), ("f", "Scale"), ("f", "Distortion"), ("f", "Detail"), ("f", "Detail Scale"),
                ("f", "Detail Roughness"), ("f", "Phase Offset")],
        outputs=[("v", "Color"), ("f", "Fac")]),
    "magic_texture": dict(
        node="ShaderNodeTexMagic",
        inputs=[("v", "VEC"), ("f", "Scale"), ("f", "Distortion")],
        outputs=[("v", "Color"), ("f", "Fac")]),
    "brick_texture": dict(
        node="ShaderNodeTexBrick",
        inputs=[("v", "VEC"), ("v", "Color1"), ("v", "Color2"), ("v", "Mortar"), ("f", "Scale"), ("f", "Mortar Size"),
                ("f", "Mortar Smooth"), ("f", "Bias"), ("f", "Brick Width"), ("f", "Row Height"),
                ("f", ("prop", "offset")), ("f", ("prop", "squash"))],
        outputs=[("v", "Color"), ("f", "Fac")]),
    "checker_texture": dict(
        node="ShaderNodeTexChecker",
        inputs=[("v", "VEC"), ("v", "Color1"), ("v", "Color2"), ("f", "Scale")],
        outputs=[("v", "Color"), ("f", "Fac")]),
    "gradient_texture": dict(
        node="ShaderNodeTexGradient",
        inputs=[("v", "VEC")],
        outputs=[("v", "Color"), ("f", "Fac")]),
    "white_noise_texture": dict(
        node="ShaderNodeTexWhiteNoise",
        inputs=[("v", "VEC"), ("f", "W")],
        outputs=[("f", "Value"), ("v", "Color")]),
}

DIMS = {1: "1D", 2: "2D", 3: "3D", 4: "4D"}
VORONOI_FEATURES = ["F1", "F2", "SMOOTH_F1", "DISTANCE_TO_EDGE", "N_SPHERE_RADIUS"]
VORONOI_METRICS = ["EUCLIDEAN", "MANHATTAN", "CHEBYCHEV", "MINKOWSKI"]
MUSGRAVE_TYPES = ["MULTIFRACTAL", "FBM", "HYBRID_MULTIFRACTAL", "RIDGED_MULTIFRACTAL", "HETERO_TERRAIN"]
WAVE_TYPES = ["BANDS", "RINGS"]
WAVE_BANDS = ["X", "Y", "Z", "DIAGONAL"]
WAVE_RINGS = ["X", "Y", "Z", "SPHERICAL"]
WAVE_PROFILES = ["SIN", "SAW", "TRI"]
# shader_program.h numbers the gradient types 0 linear, 1 quadratic, 2 easing, 3 diagonal, 4 spherical,
# 5 quadratic sphere, 6 radial (its comment; Blender's and Cycles' own values have radial 4, spherical 6).
GRADIENT_TYPES = ["LINEAR", "QUADRATIC", "EASING", "DIAGONAL", "SPHERICAL", "QUADRATIC_SPHERE", "RADIAL"]


def make_cases():
    """Each case: label, op, params (ours), props (Blender node properties), values (socket name -> value),
    passes (what each render shows), points generator arguments (range, seed)."""
    cases = []

    def add(label, op, params, props, values, outputs, rng=2.0, w_rng=2.0, special=True, integers=False):
        cases.append(dict(label=label, op=op, params=params, props=props, values=values, outputs=outputs, rng=rng,
                          w_rng=w_rng, special=special, integers=integers))

    noise_sets = [
        ("plain", {"Scale": 2.5, "Detail": 0.0, "Roughness": 0.5, "Distortion": 0.0}),
        ("fractal", {"Scale": 1.3, "Detail": 5.7, "Roughness": 0.63, "Distortion": 0.0}),
        ("distorted", {"Scale": 3.1, "Detail": 2.0, "Roughness": 0.45, "Distortion": 1.4}),
        ("detail15", {"Scale": 0.7, "Detail": 15.0, "Roughness": 0.8, "Distortion": -0.6}),
    ]
    for d in (1, 2, 3, 4):
        for name, vals in noise_sets:
            add("noise %dd %s" % (d, name), "noise_texture", [d], {"noise_dimensions": DIMS[d]}, vals,
                ["Fac", "Color"])

    for d in (1, 2, 3, 4):
        for fi, feat in enumerate(VORONOI_FEATURES):
            metrics = range(4) if (d > 1 and fi <= 2) else [0]
            for mi in metrics:
                vals = {"Scale": 2.3, "Smoothness": 0.6, "Exponent": 1.7, "Randomness": 0.85}
                if d == 1:
                    outs = ["Distance", "Color", "W"] if fi <= 2 else (["Distance"] if fi == 3 else ["Radius"])
                elif d == 4:
                    outs = ["Distance", "Color", "Position", "W"] if fi <= 2 else (
                        ["Distance"] if fi == 3 else ["Radius"])
                else:
                    outs = ["Distance", "Color", "Position"] if fi <= 2 else (["Distance"] if fi == 3 else ["Radius"])
                add("voronoi %dd %s %s" % (d, feat.lower(), VORONOI_METRICS[mi].lower()), "voronoi_texture",
                    [d, fi, mi], {"voronoi_dimensions": DIMS[d], "feature": feat, "distance": VORONOI_METRICS[mi]},
                    vals, outs)
    # randomness 1 (the default) and a large smoothness once each
    add("voronoi 3d f1 euclidean randomness1", "voronoi_texture", [3, 0, 0],
        {"voronoi_dimensions": "3D", "feature": "F1", "distance": "EUCLIDEAN"},
        {"Scale": 1.6, "Smoothness": 1.0, "Exponent": 0.5, "Randomness": 1.0}, ["Distance", "Color", "Position"])
    add("voronoi 2d smooth_f1 euclidean smooth1", "voronoi_texture", [2, 2, 0],
        {"voronoi_dimensions": "2D", "feature": "SMOOTH_F1", "distance": "EUCLIDEAN"},
        {"Scale": 1.6, "Smoothness": 1.0, "Exponent": 0.5, "Randomness": 1.0}, ["Distance", "Color", "Position"])

    for d in (1, 2, 3, 4):
        for ti, t in enumerate(MUSGRAVE_TYPES):
            vals = {"Scale": 1.9, "Detail": 3.6, "Dimension": 1.3, "Lacunarity": 2.1, "Offset": 0.8, "Gain": 1.2}
            add("musgrave %dd %s" % (d, t.lower()), "musgrave_texture", [d, ti],
                {"musgrave_dimensions": DIMS[d], "musgrave_type": t}, vals, ["Fac"])
            vals2 = {"Scale": 2.7, "Detail": 6.0, "Dimension": 0.7, "Lacunarity": 1.8, "Offset": 1.1, "Gain": 0.9}
            add("musgrave %dd %s whole detail" % (d, t.lower()), "musgrave_texture", [d, ti],
                {"musgrave_dimensions": DIMS[d], "musgrave_type": t}, vals2, ["Fac"])

    for ti, t in enumerate(WAVE_TYPES):
        dirs = WAVE_BANDS if t == "BANDS" else WAVE_RINGS
        for di, dr in enumerate(dirs):
            for pi, prof in enumerate(WAVE_PROFILES):
                vals = {"Scale": 1.4, "Distortion": 2.5, "Detail": 3.3, "Detail Scale": 1.7, "Detail Roughness": 0.6,
                        "Phase Offset": 0.7}
                props = {"wave_type": t, "wave_profile": prof}
                props["bands_direction" if t == "BANDS" else "rings_direction"] = dr
                params = [ti, di if t == "BANDS" else 0, di if t == "RINGS" else 0, pi]
                add("wave %s %s %s" % (t.lower(), dr.lower(), prof.lower()), "wave_texture", params, props, vals,
                    ["Color", "Fac"])
    add("wave bands x sin undistorted", "wave_texture", [0, 0, 0, 0],
        {"wave_type": "BANDS", "bands_direction": "X", "wave_profile": "SIN"},
        {"Scale": 2.2, "Distortion": 0.0, "Detail": 2.0, "Detail Scale": 1.0, "Detail Roughness": 0.5,
         "Phase Offset": 0.0}, ["Color", "Fac"])

    for depth in (0, 1, 2, 3, 5, 10):
        add("magic depth %d" % depth, "magic_texture", [depth], {"turbulence_depth": depth},
            {"Scale": 3.1, "Distortion": 1.7}, ["Color", "Fac"])
    add("magic depth 2 undistorted", "magic_texture", [2], {"turbulence_depth": 2},
        {"Scale": 2.0, "Distortion": 0.0}, ["Color", "Fac"])

    brick_colors = {"Color1": (0.8, 0.1, 0.3), "Color2": (0.2, 0.7, 0.45), "Mortar": (0.05, 0.15, 0.9)}
    add("brick default", "brick_texture", [2, 2], {"offset_frequency": 2, "squash_frequency": 2, "offset": 0.5,
                                                    "squash": 1.0},
        dict(brick_colors, **{"Scale": 5.0, "Mortar Size": 0.02, "Mortar Smooth": 0.1, "Bias": 0.0,
                              "Brick Width": 0.5, "Row Height": 0.25}), ["Color", "Fac"], rng=1.5)
    add("brick squash", "brick_texture", [3, 2], {"offset_frequency": 3, "squash_frequency": 2, "offset": 0.3,
                                                  "squash": 0.6},
        dict(brick_colors, **{"Scale": 3.0, "Mortar Size": 0.08, "Mortar Smooth": 0.4, "Bias": -0.2,
                              "Brick Width": 0.7, "Row Height": 0.3}), ["Color", "Fac"], rng=1.5)
    add("brick hard mortar", "brick_texture", [1, 4], {"offset_frequency": 1, "squash_frequency": 4, "offset": 0.7,
                                                       "squash": 1.5},
        dict(brick_colors, **{"Scale": 2.0, "Mortar Size": 0.12, "Mortar Smooth": 0.0, "Bias": 0.3,
                              "Brick Width": 0.4, "Row Height": 0.35}), ["Color", "Fac"], rng=1.5)

    checker_colors = {"Color1": (0.9, 0.2, 0.1), "Color2": (0.1, 0.3, 0.8)}
    add("checker", "checker_texture", [], {}, dict(checker_colors, Scale=2.7), ["Color", "Fac"])
    add("checker scale 1", "checker_texture", [], {}, dict(checker_colors, Scale=1.0), ["Color", "Fac"], rng=3.0)

    for gi, g in enumerate(GRADIENT_TYPES):
        add("gradient %s" % g.lower(), "gradient_texture", [gi], {"gradient_type": g}, {}, ["Color", "Fac"],
            rng=1.3)

    for d in (1, 2, 3, 4):
        add("white noise %dd" % d, "white_noise_texture", [d], {"noise_dimensions": DIMS[d]}, {}, ["Value", "Color"],
            rng=50.0, w_rng=50.0)
    # Far from the origin (float precision of the lattice and cells), and checker on exact integer coordinates.
    for d in (2, 3, 4):
        add("noise %dd far" % d, "noise_texture", [d], {"noise_dimensions": DIMS[d]},
            {"Scale": 1.0, "Detail": 3.0, "Roughness": 0.5, "Distortion": 0.3}, ["Fac", "Color"], rng=2000.0,
            w_rng=2000.0)
    add("noise 1d far", "noise_texture", [1], {"noise_dimensions": "1D"},
        {"Scale": 1.0, "Detail": 3.0, "Roughness": 0.5, "Distortion": 0.3}, ["Fac", "Color"], rng=2000.0, w_rng=2000.0)
    add("voronoi 3d f1 euclidean far", "voronoi_texture", [3, 0, 0],
        {"voronoi_dimensions": "3D", "feature": "F1", "distance": "EUCLIDEAN"},
        {"Scale": 1.0, "Smoothness": 1.0, "Exponent": 0.5, "Randomness": 1.0}, ["Distance", "Color", "Position"],
        rng=5000.0)
    add("musgrave 3d fbm far", "musgrave_texture", [3, 1], {"musgrave_dimensions": "3D", "musgrave_type": "FBM"},
        {"Scale": 1.0, "Detail": 2.0, "Dimension": 2.0, "Lacunarity": 2.0, "Offset": 0.0, "Gain": 1.0}, ["Fac"],
        rng=3000.0)
    # Inputs beyond their ranges, clamped as Cycles clamps them (and a Minkowski exponent below 1).
    add("noise 3d clamped", "noise_texture", [3], {"noise_dimensions": "3D"},
        {"Scale": 2.0, "Detail": -1.0, "Roughness": 1.7, "Distortion": 0.0}, ["Fac", "Color"])
    add("noise 2d rough clamped", "noise_texture", [2], {"noise_dimensions": "2D"},
        {"Scale": 2.0, "Detail": 4.5, "Roughness": -0.5, "Distortion": 0.0}, ["Fac", "Color"])
    add("musgrave 3d fbm clamped", "musgrave_texture", [3, 1], {"musgrave_dimensions": "3D", "musgrave_type": "FBM"},
        {"Scale": 1.5, "Detail": 16.0, "Dimension": -1.0, "Lacunarity": 0.5, "Offset": 0.0, "Gain": 1.0}, ["Fac"])
    add("voronoi 3d smooth_f1 clamped", "voronoi_texture", [3, 2, 0],
        {"voronoi_dimensions": "3D", "feature": "SMOOTH_F1", "distance": "EUCLIDEAN"},
        {"Scale": 1.8, "Smoothness": 3.0, "Exponent": 0.5, "Randomness": 1.5}, ["Distance", "Color", "Position"])
    add("voronoi 2d f2 minkowski half", "voronoi_texture", [2, 1, 3],
        {"voronoi_dimensions": "2D", "feature": "F2", "distance": "MINKOWSKI"},
        {"Scale": 2.2, "Smoothness": 1.0, "Exponent": 0.5, "Randomness": 0.7}, ["Distance", "Color", "Position"])
    add("voronoi 4d f1 randomness0", "voronoi_texture", [4, 0, 0],
        {"voronoi_dimensions": "4D", "feature": "F1", "distance": "EUCLIDEAN"},
        {"Scale": 1.3, "Smoothness": 1.0, "Exponent": 0.5, "Randomness": 0.0}, ["Distance", "Color", "Position", "W"])
    add("wave rings spherical saw detail clamped", "wave_texture", [1, 0, 3, 1],
        {"wave_type": "RINGS", "rings_direction": "SPHERICAL", "wave_profile": "SAW"},
        {"Scale": 0.9, "Distortion": -3.0, "Detail": 20.0, "Detail Scale": 2.5, "Detail Roughness": 1.4,
         "Phase Offset": -2.0}, ["Color", "Fac"])
    add("checker integers", "checker_texture", [], {}, dict(checker_colors, Scale=1.0), ["Color", "Fac"],
        integers=True)
    return cases


def points_for(case, index):
    rnd = random.Random(1000 + index)
    r, wr = case["rng"], case["w_rng"]
    pts = []
    if case["special"]:
        pts += [(0.0, 0.0, 0.0, 0.0), (1.0, -1.0, 2.0, -2.0), (0.25, 0.5, -0.75, 0.125)]
    while case.get("integers") and len(pts) < W * H:
        pts.append(tuple(float(rnd.randint(-3, 3)) for _ in range(4)))
    while len(pts) < W * H:
        pts.append((rnd.uniform(-r, r), rnd.uniform(-r, r), rnd.uniform(-r, r), rnd.uniform(-wr, wr)))
    return pts


def run_case(scene, mesh, mat, case, index):
    spec = OPS[case["op"]]
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    emit = nt.nodes.new("ShaderNodeEmission")
    emit.inputs["Strength"].default_value = 1.0
    nt.links.new(emit.outputs["Emission"], out.inputs["Surface"])
    aco = nt.nodes.new("ShaderNodeAttribute")
    aco.attribute_type = "GEOMETRY"
    aco.attribute_name = "pco"
    aw = nt.nodes.new("ShaderNodeAttribute")
    aw.attribute_type = "GEOMETRY"
    aw.attribute_name = "pw"
    comb = nt.nodes.new("ShaderNodeCombineXYZ")

    stored = set_points(mesh, points_for(case, index))

    if case["op"] == "identity":
        tex = None
    else:
        tex = nt.nodes.new(spec["node"])
        for k, v in case["props"].items():
            setattr(tex, k, v)
        for k, v in case["values"].items():
            sock = tex.inputs[k]
            sock.default_value = (v[0], v[1], v[2], 1.0) if isinstance(v, tuple) else v
        nt.links.new(aco.outputs["Vector"], tex.inputs["Vector"])
        if "W" in tex.inputs:
            nt.links.new(aw.outputs["Fac"], tex.inputs["W"])

    # The outputs measured: vectors one render each, floats up to three a render.
    measured = {}
    kinds = {name: kind for kind, name in spec["outputs"]}
    vec_outs = [o for o in case["outputs"] if kinds[o] == "v"]
    flt_outs = [o for o in case["outputs"] if kinds[o] == "f"]
    renders = [("v", [o]) for o in vec_outs]
    for i in range(0, len(flt_outs), 3):
        renders.append(("f", flt_outs[i:i + 3]))
    for ri, (kind, names) in enumerate(renders):
        for l in list(nt.links):
            if l.to_node == emit or l.to_node == comb:
                nt.links.remove(l)
        if kind == "v":
            nt.links.new(tex.outputs[names[0]], emit.inputs["Color"])
        else:
            for ci, name in enumerate(names):
                nt.links.new(tex.outputs[name], comb.inputs[ci])
            for ci in range(len(names), 3):
                comb.inputs[ci].default_value = 0.0
            nt.links.new(comb.outputs["Vector"], emit.inputs["Color"])
        px = render_pixels(scene, "case%03d_%d" % (index, ri))
        if kind == "v":
            measured[names[0]] = px
        else:
            for ci, name in enumerate(names):
                measured[name] = [p[ci] for p in px]
    return stored, measured


def identity_check(scene, mesh, mat):
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    emit = nt.nodes.new("ShaderNodeEmission")
    nt.links.new(emit.outputs["Emission"], out.inputs["Surface"])
    aco = nt.nodes.new("ShaderNodeAttribute")
    aco.attribute_type = "GEOMETRY"
    aco.attribute_name = "pco"
    nt.links.new(aco.outputs["Vector"], emit.inputs["Color"])
    stored = set_points(mesh, points_for(dict(rng=7.0, w_rng=7.0, special=True), 0))
    px = render_pixels(scene, "identity")
    for s, p in zip(stored, px):
        if tuple(s[:3]) != tuple(f32(c) for c in p):
            raise SystemExit("identity check failed: stored %r rendered %r" % (s, p))
    print("identity check: %d points bit-exact" % len(px))


def fmt(x):
    if x != x:
        return "kNA"
    s = "%.9g" % x
    if "e" not in s and "." not in s and "inf" not in s:
        s += ".0"
    return s + "f"


def main():
    scene, mesh, mat = build_scene()
    identity_check(scene, mesh, mat)
    cases = make_cases()
    only = os.environ.get("PS_GOLDEN_ONLY")
    lines = []
    case_lines = []
    for index, case in enumerate(cases):
        if only and only not in case["label"]:
            continue
        spec = OPS[case["op"]]
        stored, measured = run_case(scene, mesh, mat, case, index)
        # constant inputs in our order (vectors as three floats); the per-point ones are placeholders
        inputs = []
        for kind, src in spec["inputs"]:
            if src in ("VEC", "W"):
                inputs += [0.0] * (3 if kind == "v" else 1)
            elif isinstance(src, tuple):
                inputs.append(float(case["props"][src[1]]))
            else:
                v = case["values"].get(src, 0.0)
                if kind == "v":
                    inputs += [f32(v[0]), f32(v[1]), f32(v[2])]
                else:
                    inputs.append(f32(v))
        out_width = sum(3 if k == "v" else 1 for k, _ in spec["outputs"])
        data = []
        for p in range(W * H):
            row = list(stored[p])
            for kind, name in spec["outputs"]:
                if name in measured:
                    val = measured[name][p]
                    row += list(val) if kind == "v" else [val]
                else:
                    row += [float("nan")] * (3 if kind == "v" else 1)
            data.append(row)
        arr = "kData%03d" % index
        lines.append("// %s" % case["label"])
        lines.append("const float %s[] = {" % arr)
        for row in data:
            lines.append("    " + ", ".join(fmt(x) for x in row) + ",")
        lines.append("};")
        params = case["params"] + [0] * (4 - len(case["params"]))
        case_lines.append('    {"%s", ps::ShaderOp::%s, %d, {%s}, {%s}, %d, %d, %s},' % (
            case["label"], case["op"], len(case["params"]), ", ".join(str(p) for p in params),
            ", ".join(fmt(x) for x in inputs), out_width, W * H, arr))
        print("case %d/%d %s done" % (index + 1, len(cases), case["label"]), flush=True)

    with open(HEADER, "w") as f:
        f.write("// Generated by tests/native/golden/make_texture_goldens.py from Blender %s's Cycles (CPU): do not edit.\n"
                % bpy.app.version_string)
        f.write("// Each case: an op, its params and constant inputs (op-table order, vectors as three floats; the\n"
                "// per-point Vector and W inputs are zeros here), and per point: vector x, y, z, w, then every output\n"
                "// in op-table order (vectors as three floats), kNA where Cycles' node does not show that output.\n")
        f.write("#pragma once\n#include <limits>\n\n#include \"photonsplat/shader_program.h\"\n\n")
        f.write("namespace texture_goldens {\n\n")
        f.write("constexpr float kNA = std::numeric_limits<float>::quiet_NaN();\n\n")
        f.write("struct Case {\n    const char* label;\n    ps::ShaderOp op;\n    int n_params;\n    int params[4];\n"
                "    float inputs[24];\n    int out_width;\n    int n_points;\n    const float* data;  // n_points x (4 + out_width)\n};\n\n")
        f.write("\n".join(lines))
        f.write("\n\nconst Case kCases[] = {\n")
        f.write("\n".join(case_lines))
        f.write("\n};\n\n}  // namespace texture_goldens\n")
    print("wrote %s (%d cases)" % (HEADER, len(case_lines)))


main()
