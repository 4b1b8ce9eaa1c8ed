"""The node planes: one material per case of a shader node (texture, converter, input) driving an Emission shader
(strength 1), seen face on by an orthographic camera that a plane fills, so each pixel shows the node's value at
the point under the pixel's centre. `tools/node_compare.py` renders every case with Cycles and Photon Splat and
compares them pixel by pixel; `tests/blender/test_node_pixels.py` does a dozen of them at 32 x 32.

The scene (built in memory by `build()`; nothing is committed):
  - "Plane": a 16 x 16 grid of quads, 2 m square in object space, scaled 2.5 and turned 20 degrees about Z around
    (0.3, -0.2, 0), so object, world, generated and UV coordinates all differ; a float point colour attribute
    "Col" (a smooth pattern of the vertex positions) for the Attribute node; pass index 3, object colour set;
  - "Dome": the same grid, smooth shaded, raised into a dome z = 0.45 (1 - r^2) so that normals, incoming angles and
    positions vary across the image (Fresnel, Layer Weight, Normal / Reflection coordinates, box / sphere
    projection, Bump, Normal Map). One of the two is rendered, the other hidden; a material says which
    (its custom property "ps_object");
  - an orthographic camera looking down -Z over a 3 m square centred on (0.3, -0.2); a black world;
  - Standard view transform, look None, exposure 0, gamma 1.
Images (for Image / Environment Texture and Normal Map) are made in memory: "grid_float" (12 x 8 float, linear,
opaque, some values above 1), "grid_float_alpha" (the same with alpha varying from 0.3 to 1), "grid_byte" (12 x 8 byte, sRGB), "normals" (32 x 32 byte, Non-Color, a tangent-space bump pattern).

Each case is a material named after the case, with custom properties "ps_object" (Plane or Dome), "ps_class"
("deterministic" or "noise": acceptance (a) asks 1e-3 of the mean for the first, 1 % for the noise-based
textures: noise, voronoi, musgrave, wave with distortion, magic, white noise) and "ps_node" (the node under test).
CASES lists them in order. Outputs that are signed are moved into [0, ...) after the node (a Math or Vector Math
Multiply Add: `vscale` in the builders, SHIFTS for the cases found negative), since Photon Splat clamped emission at
0 when this was written and Cycles does not; math_subtract_signed alone keeps negative values. Edge cases
(division by zero, logarithms of negatives, out-of-range inverse trigonometry, min > max) are kept as Cycles
computes them.

Run as a script it writes build/node_compare/node_planes.blend (images packed) for a look at the cases:
    blender -b --factory-startup --python blend_scenes/make_node_planes.py [-- --size 64]
The tool and the test import it and call build(size, names) inside their Blender instead.
"""

import math
import sys
from pathlib import Path

import bpy

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
CENTER = (0.3, -0.2)
VIEW = 3.0                      # the orthographic camera's view, metres
PLANE_SCALE = 2.5
PLANE_TURN = math.radians(20.0)
GRID = 16

NOISE, DET = "noise", "deterministic"


# ---- node helpers ---------------------------------------------------------------------------------------------

class Tree:
    """A material's nodes: new(type, props, **inputs) with inputs named as in the UI ("_" for spaces) or by socket
    index (in0=...), values or sockets."""

    def __init__(self, material):
        material.use_nodes = True
        self.tree = material.node_tree
        self.tree.nodes.clear()
        self.output = self.tree.nodes.new("ShaderNodeOutputMaterial")

    def link(self, socket, target):
        self.tree.links.new(socket, target)

    def set(self, socket, value):
        if isinstance(value, bpy.types.NodeSocket):
            self.link(value, socket)
        elif isinstance(value, (tuple, list)):
            n = len(socket.default_value)
            socket.default_value = tuple(value) + (1.0,) * (n - len(value)) if len(value) < n else tuple(value)
        else:
            socket.default_value = value

    def new(self, node_type, props=None, **inputs):
        node = self.tree.nodes.new(node_type)
        for key, value in (props or {}).items():
            setattr(node, key, value)
        for key, value in inputs.items():
            if key.startswith("in") and key[2:].isdigit():
                socket = node.inputs[int(key[2:])]
            else:
                name = key.replace("_", " ")
                socket = next((s for s in node.inputs if s.name == name and s.enabled), None) or node.inputs[name]
            self.set(socket, value)
        return node

    # coordinates
    def coord(self, which="Object", obj=None):
        node = self.new("ShaderNodeTexCoord")
        if obj is not None:
            node.object = obj
        return node.outputs[which]

    def mapped(self, which="Object", location=(0, 0, 0), rotation=(0, 0, 0), scale=(1, 1, 1), vtype='POINT'):
        return self.new("ShaderNodeMapping", {"vector_type": vtype}, Vector=self.coord(which), Location=location,
                        Rotation=rotation, Scale=scale).outputs[0]

    def axis(self, which="UV", component=0, scale=1.0, offset=0.0):
        """One component of a coordinate, times `scale` plus `offset` (a float socket)."""
        sep = self.new("ShaderNodeSeparateXYZ", Vector=self.coord(which))
        if scale == 1.0 and offset == 0.0:
            return sep.outputs[component]
        return self.new("ShaderNodeMath", {"operation": 'MULTIPLY_ADD'}, in0=sep.outputs[component], in1=scale,
                        in2=offset).outputs[0]

    def vscale(self, socket, scale, offset=0.0):
        """A vector socket times `scale` plus `offset` (Vector Math Multiply Add): signed values into [0, ...)."""
        return self.new("ShaderNodeVectorMath", {"operation": 'MULTIPLY_ADD'}, in0=socket, in1=(scale,) * 3,
                        in2=(offset,) * 3).outputs[0]

    def emit(self, socket):
        emission = self.new("ShaderNodeEmission", Strength=1.0)
        self.link(socket, emission.inputs["Color"])
        self.link(emission.outputs[0], self.output.inputs["Surface"])


def uv_color(t):
    """A smooth colour across the plane: (u, v, 1 - u v) from the UV map."""
    sep = t.new("ShaderNodeSeparateXYZ", Vector=t.coord("UV"))
    uv = t.new("ShaderNodeMath", {"operation": 'MULTIPLY'}, in0=sep.outputs[0], in1=sep.outputs[1])
    inv = t.new("ShaderNodeMath", {"operation": 'SUBTRACT'}, in0=1.0, in1=uv.outputs[0])
    return t.new("ShaderNodeCombineXYZ", X=sep.outputs[0], Y=sep.outputs[1], Z=inv.outputs[0]).outputs[0]


def obj_coords(t, scale=4.0):
    return t.mapped("Object", location=(0.1, 0.2, 0.3), rotation=(0.0, 0.0, 0.3), scale=(scale,) * 3)


# ---- the cases -------------------------------------------------------------------------------------------------
# Each builder takes the Tree and returns the socket that drives the Emission colour.

CASES = []        # (name, class, object, node, builder)


def case(name, cls=DET, obj="Plane", node=None):
    def register(builder):
        CASES.append((name, cls, obj, node or name.split("_")[0], builder))
        return builder
    return register


def simple(name, builder, cls=DET, obj="Plane", node=None):
    CASES.append((name, cls, obj, node or name.split("_")[0], builder))


def w_input(t, dims):
    """The W input of a 1D or 4D texture: 1D reads W alone, so it follows the object's x; 4D its y, slower."""
    if dims == "1D":
        return t.axis("Object", 0, 1.0, 0.3)
    if dims == "4D":
        return t.axis("Object", 1, 0.4, 0.61)
    return 0.37


# -- noise texture: each dimension, fac and colour, detail, roughness, distortion
for dims, output, extra in [("1D", "Fac", {}), ("2D", "Color", {}), ("3D", "Fac", {}), ("3D", "Color", {}),
                            ("4D", "Color", {}), ("3D", "Fac", {"Detail": 0.0}),
                            ("3D", "Color", {"Detail": 3.5, "Roughness": 0.7}),
                            ("3D", "Color", {"Distortion": 0.8}), ("4D", "Fac", {"Distortion": 1.5, "Detail": 5.0}),
                            ("2D", "Fac", {"Detail": 15.0, "Roughness": 0.3})]:
    label = "_".join([dims.lower(), output.lower()] + [f"{k.lower()}{v:g}" for k, v in extra.items()])

    def build(t, dims=dims, output=output, extra=extra):
        inputs = {"Scale": 3.0, "Detail": 2.0, "Roughness": 0.5, "W": w_input(t, dims), **extra}
        return t.new("ShaderNodeTexNoise", {"noise_dimensions": dims}, Vector=obj_coords(t, 1.0),
                     **inputs).outputs[output]
    simple(f"noise_{label}", build, NOISE)

# -- voronoi: each dimension x feature, the metrics on F1 (and some on F2 / smooth F1), each output
VORONOI = []
for dims in ("1D", "2D", "3D", "4D"):
    metrics = ["EUCLIDEAN"] if dims == "1D" else ["EUCLIDEAN", "MANHATTAN", "CHEBYCHEV", "MINKOWSKI"]
    for metric in metrics:
        VORONOI.append((dims, "F1", metric, "Distance"))
    VORONOI.append((dims, "F1", metrics[-1], "Color"))
    VORONOI.append((dims, "F2", metrics[0], "Distance"))
    VORONOI.append((dims, "F2", metrics[-1], "Color"))
    VORONOI.append((dims, "SMOOTH_F1", metrics[0], "Distance"))
    VORONOI.append((dims, "SMOOTH_F1", metrics[min(1, len(metrics) - 1)], "Color"))
    VORONOI.append((dims, "DISTANCE_TO_EDGE", metrics[0], "Distance"))
    VORONOI.append((dims, "N_SPHERE_RADIUS", metrics[0], "Radius"))
    if dims in ("2D", "3D"):
        VORONOI.append((dims, "F1", "EUCLIDEAN", "Position"))
    if dims in ("1D", "4D"):
        VORONOI.append((dims, "F1", "EUCLIDEAN", "W"))
for dims, feature, metric, output in VORONOI:
    def build(t, dims=dims, feature=feature, metric=metric, output=output):
        node = t.new("ShaderNodeTexVoronoi", {"voronoi_dimensions": dims, "feature": feature, "distance": metric},
                     Vector=obj_coords(t, 1.0), W=w_input(t, dims), Scale=3.0, Smoothness=0.6, Exponent=1.5, Randomness=0.85)
        out = node.outputs[output]
        if output == "Position":
            return t.vscale(out, 0.1, 0.5)
        if output == "W":
            return t.new("ShaderNodeMath", {"operation": 'MULTIPLY_ADD'}, in0=out, in1=0.1, in2=0.5).outputs[0]
        return out
    simple(f"voronoi_{dims.lower()}_{feature.lower()}_{metric.lower()}_{output.lower()}", build, NOISE)

# -- musgrave: every type in 3D, every dimension for fBM and ridged, non-default settings
for dims, mtype in ([("3D", m) for m in ("MULTIFRACTAL", "RIDGED_MULTIFRACTAL", "HYBRID_MULTIFRACTAL", "FBM",
                                          "HETERO_TERRAIN")]
                    + [(d, "FBM") for d in ("1D", "2D", "4D")] + [(d, "RIDGED_MULTIFRACTAL") for d in ("2D", "4D")]
                    + [("4D", "HETERO_TERRAIN"), ("1D", "HYBRID_MULTIFRACTAL"), ("2D", "MULTIFRACTAL")]):
    def build(t, dims=dims, mtype=mtype):
        node = t.new("ShaderNodeTexMusgrave", {"musgrave_dimensions": dims, "musgrave_type": mtype},
                     Vector=obj_coords(t, 1.0), W=w_input(t, dims), Scale=2.5, Detail=3.5, Dimension=1.6, Lacunarity=2.3,
                     Offset=0.8, Gain=1.3)
        return t.new("ShaderNodeMath", {"operation": 'MULTIPLY_ADD'}, in0=node.outputs[0], in1=0.25,
                     in2=0.5).outputs[0]
    simple(f"musgrave_{dims.lower()}_{mtype.lower()}", build, NOISE)

# -- wave: bands in each direction, rings in each direction, each profile; distortion / detail (noise-based)
for wtype, direction, profile, distortion, output in (
        [("BANDS", d, "SIN", 0.0, "Fac") for d in ("X", "Y", "Z", "DIAGONAL")]
        + [("RINGS", d, "SIN", 0.0, "Fac") for d in ("X", "Y", "Z", "SPHERICAL")]
        + [("BANDS", "X", "SAW", 0.0, "Color"), ("BANDS", "DIAGONAL", "TRI", 0.0, "Fac"),
           ("RINGS", "SPHERICAL", "SAW", 0.0, "Fac"), ("RINGS", "Z", "TRI", 0.0, "Color"),
           ("BANDS", "X", "SIN", 4.0, "Fac"), ("RINGS", "SPHERICAL", "SIN", 6.0, "Color"),
           ("BANDS", "DIAGONAL", "SAW", 3.0, "Fac")]):
    def build(t, wtype=wtype, direction=direction, profile=profile, distortion=distortion, output=output):
        props = {"wave_type": wtype, "wave_profile": profile}
        props["bands_direction" if wtype == "BANDS" else "rings_direction"] = direction
        return t.new("ShaderNodeTexWave", props, Vector=obj_coords(t, 1.0), Scale=2.0, Distortion=distortion,
                     Detail=3.0, Detail_Scale=1.5, Detail_Roughness=0.6, Phase_Offset=0.7).outputs[output]
    label = f"wave_{wtype.lower()}_{direction.lower()}_{profile.lower()}" + (f"_dist{distortion:g}" if distortion
                                                                             else "") + f"_{output.lower()}"
    simple(label, build, NOISE if distortion else DET, node="wave")

# -- magic
for depth, distortion, output in ((2, 1.0, "Color"), (0, 1.0, "Color"), (4, 2.5, "Color"), (6, 0.5, "Fac")):
    def build(t, depth=depth, distortion=distortion, output=output):
        return t.new("ShaderNodeTexMagic", {"turbulence_depth": depth}, Vector=obj_coords(t, 0.5), Scale=2.0,
                     Distortion=distortion).outputs[output]
    simple(f"magic_depth{depth}_dist{distortion:g}_{output.lower()}", build, NOISE)

# -- white noise
for dims, output in (("1D", "Value"), ("2D", "Color"), ("3D", "Value"), ("3D", "Color"), ("4D", "Color")):
    def build(t, dims=dims, output=output):
        # quantised coordinates: one random value per 0.25 m cell, so that the comparison does not hang on which
        # side of a float a pixel's coordinate falls
        snapped = t.new("ShaderNodeVectorMath", {"operation": 'SNAP'}, in0=t.coord("Object"), in1=(0.25,) * 3)
        w = t.new("ShaderNodeMath", {"operation": 'SNAP'}, in0=t.axis("Object", 0, 1.0, 0.1), in1=0.25).outputs[0] \
            if dims in ("1D", "4D") else 0.5
        return t.new("ShaderNodeTexWhiteNoise", {"noise_dimensions": dims}, Vector=snapped.outputs[0],
                     W=w).outputs[output]
    simple(f"whitenoise_{dims.lower()}_{output.lower()}", build, NOISE, node="white_noise")

# -- brick, checker, gradient
for label, props, inputs, output in (
        ("default_color", {}, {}, "Color"),
        ("offset_squash_fac", {"offset_frequency": 3, "squash_frequency": 2},
         {"Mortar_Size": 0.05, "Mortar_Smooth": 0.3, "Bias": 0.4, "Brick_Width": 0.6, "Row_Height": 0.3}, "Fac"),
        ("smooth_bias_color", {"offset": 0.3, "squash": 0.6, "offset_frequency": 2, "squash_frequency": 3},
         {"Mortar_Size": 0.03, "Mortar_Smooth": 0.8, "Bias": -0.5}, "Color")):
    def build(t, props=props, inputs=inputs, output=output):
        return t.new("ShaderNodeTexBrick", props, Vector=obj_coords(t, 1.0), Color1=(0.8, 0.3, 0.1),
                     Color2=(0.2, 0.5, 0.7), Mortar=(0.9, 0.9, 0.8), Scale=3.0, **inputs).outputs[output]
    simple(f"brick_{label}", build)
for output in ("Color", "Fac"):
    simple(f"checker_{output.lower()}", lambda t, output=output: t.new(
        "ShaderNodeTexChecker", Vector=obj_coords(t, 1.0), Color1=(0.9, 0.4, 0.1), Color2=(0.1, 0.3, 0.6),
        Scale=2.5).outputs[output])
for gtype in ('LINEAR', 'QUADRATIC', 'EASING', 'DIAGONAL', 'SPHERICAL', 'QUADRATIC_SPHERE', 'RADIAL'):
    simple(f"gradient_{gtype.lower()}", lambda t, gtype=gtype: t.new(
        "ShaderNodeTexGradient", {"gradient_type": gtype},
        Vector=t.mapped("Object", location=(0.2, 0.1, 0.0), scale=(0.7, 0.9, 1.0))).outputs["Fac"])
simple("gradient_radial_color", lambda t: t.new("ShaderNodeTexGradient", {"gradient_type": 'RADIAL'},
                                                  Vector=t.coord("Object")).outputs["Color"])


# -- image textures: interpolation, extension, projection, byte sRGB and float, alpha
def image_node(t, image, interpolation='Linear', extension='REPEAT', projection='FLAT', vector=None, blend=0.0):
    node = t.new("ShaderNodeTexImage", {"interpolation": interpolation, "extension": extension,
                                        "projection": projection})
    node.image = bpy.data.images[image]
    node.projection_blend = blend
    if vector is not None:
        t.link(vector, node.inputs["Vector"])
    return node


def uv_tiled(t, scale=1.7):
    return t.mapped("UV", location=(-0.35, -0.2, 0.0), rotation=(0.0, 0.0, 0.2), scale=(scale, scale, 1.0))


for image in ("grid_float", "grid_byte"):
    for interpolation in ('Linear', 'Closest', 'Cubic', 'Smart'):
        simple(f"image_{image}_{interpolation.lower()}", lambda t, image=image, interpolation=interpolation:
               image_node(t, image, interpolation, vector=uv_tiled(t)).outputs["Color"], node="image")
    for extension in ('EXTEND', 'CLIP'):
        simple(f"image_{image}_{extension.lower()}", lambda t, image=image, extension=extension:
               image_node(t, image, 'Linear', extension, vector=uv_tiled(t)).outputs["Color"], node="image")
simple("image_grid_float_uv_default", lambda t: image_node(t, "grid_float").outputs["Color"], node="image")
simple("image_grid_float_alpha", lambda t: image_node(t, "grid_float_alpha", vector=uv_tiled(t)).outputs["Alpha"],
       node="image")
simple("image_grid_float_alpha_color", lambda t: image_node(t, "grid_float_alpha", vector=uv_tiled(t)).outputs[
    "Color"], node="image")
simple("image_grid_float_clip_alpha", lambda t: image_node(t, "grid_float_alpha", extension='CLIP',
                                                           vector=uv_tiled(t)).outputs["Alpha"], node="image")
for projection, blend in (('BOX', 0.0), ('BOX', 0.3), ('SPHERE', 0.0), ('TUBE', 0.0)):
    simple(f"image_projection_{projection.lower()}" + (f"_blend{blend:g}" if blend else ""),
           lambda t, projection=projection, blend=blend: image_node(
               t, "grid_float", 'Linear', 'REPEAT', projection, blend=blend,
               vector=t.mapped("Object", location=(0.5, 0.5, 0.2), scale=(0.6, 0.6, 0.6))).outputs["Color"],
           obj="Dome", node="image")
for projection in ('EQUIRECTANGULAR', 'MIRROR_BALL'):
    def build(t, projection=projection):
        node = t.new("ShaderNodeTexEnvironment", {"projection": projection})
        node.image = bpy.data.images["grid_float"]
        t.link(t.coord("Normal"), node.inputs["Vector"])
        return node.outputs["Color"]
    simple(f"environment_{projection.lower()}", build, obj="Dome", node="environment")


# -- sky: directions made from the plane's object coordinates (x, y in [-1, 1]), normalised: "upper" spans the sky
# from about 20 degrees above the horizon to the zenith, "horizon" crosses it into the ground's fade. With
# Nishita's sun disc the Vector socket is unavailable and Cycles evaluates the Generated coordinates, (u, v, 0.5)
# on the flat plane: sky_nishita_disc puts a large sun (40 degrees) where those point, at (1, 1, 1).
def sky_direction(t, kind):
    sep = t.new("ShaderNodeSeparateXYZ", Vector=t.coord("Object"))
    if kind == "upper":
        vec = t.new("ShaderNodeCombineXYZ", X=sep.outputs[0], Y=sep.outputs[1], Z=0.4)
    else:
        z = t.new("ShaderNodeMath", {"operation": 'MULTIPLY'}, in0=sep.outputs[1], in1=0.6)
        vec = t.new("ShaderNodeCombineXYZ", X=sep.outputs[0], Y=0.6, Z=z.outputs[0])
    return t.new("ShaderNodeVectorMath", {"operation": 'NORMALIZE'}, in0=vec.outputs[0]).outputs[0]


SKY_CASES = [
    ("sky_nishita_upper", "Plane", "upper", {"sky_type": 'NISHITA', "sun_disc": False}),
    ("sky_nishita_horizon", "Plane", "horizon", {"sky_type": 'NISHITA', "sun_disc": False,
                                                 "sun_rotation": math.radians(30.0)}),
    ("sky_nishita_atmosphere", "Plane", "upper", {"sky_type": 'NISHITA', "sun_disc": False,
                                                  "sun_elevation": math.radians(5.0),
                                                  "sun_rotation": math.radians(120.0), "altitude": 2000.0,
                                                  "air_density": 2.0, "dust_density": 4.0, "ozone_density": 3.0}),
    ("sky_nishita_default_vector", "Dome", None, {"sky_type": 'NISHITA', "sun_disc": False,
                                                  "sun_elevation": math.radians(40.0)}),
    ("sky_nishita_disc", "Plane", None, {"sky_type": 'NISHITA', "sun_disc": True, "sun_size": math.radians(40.0),
                                         "sun_elevation": math.asin(1.0 / math.sqrt(3.0)),
                                         "sun_rotation": math.radians(45.0), "sun_intensity": 0.05}),
    ("sky_preetham", "Plane", "upper", {"sky_type": 'PREETHAM', "sun_direction": (0.3, -0.6, 0.5)}),
    ("sky_preetham_hazy_horizon", "Plane", "horizon", {"sky_type": 'PREETHAM', "turbidity": 7.0,
                                                       "sun_direction": (-0.8, 0.4, 0.15)}),
    ("sky_hosek", "Plane", "upper", {"sky_type": 'HOSEK_WILKIE', "sun_direction": (0.3, -0.6, 0.5)}),
]
for name, obj, kind, props in SKY_CASES:
    def build(t, kind=kind, props=props):
        node = t.new("ShaderNodeTexSky", props)
        if kind is not None:
            t.link(sky_direction(t, kind), node.inputs["Vector"])
        return node.outputs["Color"]
    simple(name, build, obj=obj, node="sky")


# -- math: a representative set with edge cases (inputs from the UV coordinates so each spans a range)
def math_case(op, a, b=None, c=None, clamp=False, label=None):
    def build(t):
        node = t.new("ShaderNodeMath", {"operation": op, "use_clamp": clamp})
        for i, v in enumerate((a, b, c)):
            if v is None:
                continue
            t.set(node.inputs[i], v(t) if callable(v) else v)
        return node.outputs[0]
    simple(f"math_{(label or op).lower()}" + ("_clamp" if clamp else ""), build, node="math")


U = lambda s=1.0, o=0.0: (lambda t: t.axis("UV", 0, s, o))      # noqa: E731  u * s + o
V = lambda s=1.0, o=0.0: (lambda t: t.axis("UV", 1, s, o))      # noqa: E731
math_case('ADD', U(), V(), clamp=True)
math_case('SUBTRACT', U(2.0), V(), label="subtract_signed")    # negative on part of the plane, kept
math_case('MULTIPLY', U(2.0), V(3.0))
STEP = lambda: (lambda t: t.new("ShaderNodeMath", {"operation": 'FLOOR'}, in0=t.axis("UV", 1, 3.0, -1.0)).outputs[0])  # noqa: E731, -1, 0, 1
math_case('DIVIDE', U(), STEP(), label="divide_by_zero")
math_case('MULTIPLY_ADD', U(), V(), 0.25)
math_case('POWER', U(4.0, -2.0), 1.5, label="power_negative_base")
math_case('POWER', U(3.0, -1.5), 2.0, label="power_integer_exponent")
math_case('LOGARITHM', U(4.0, -1.0), 2.0, label="logarithm_through_zero")
math_case('SQRT', U(2.0, -0.5))
math_case('INVERSE_SQRT', U(2.0, 0.01))
math_case('ABSOLUTE', U(2.0, -1.0))
math_case('EXPONENT', U(2.0, -1.0))
math_case('MINIMUM', U(), V())
math_case('LESS_THAN', U(), V())
math_case('SIGN', U(2.0, -0.7), label="sign")
math_case('COMPARE', U(), V(), 0.1)
math_case('SMOOTH_MIN', U(), V(), 0.3)
math_case('SMOOTH_MAX', U(), V(), 0.3)
math_case('ROUND', U(4.0))
math_case('FLOOR', U(4.0, -2.0))
math_case('CEIL', U(4.0, -2.0))
math_case('TRUNC', U(4.0, -2.0))
math_case('FRACT', U(4.0, -2.0))
math_case('MODULO', U(4.0, -2.0), 0.7, label="modulo_negative")
math_case('MODULO', U(), 0.0, label="modulo_by_zero")
math_case('WRAP', U(4.0, -2.0), 0.8, 0.1)
math_case('SNAP', U(4.0, -2.0), 0.3)
math_case('PINGPONG', U(5.0), 0.7)
math_case('SINE', U(3.1, 0.0))
math_case('COSINE', U(3.0, -1.5))
math_case('TANGENT', U(1.4, -0.7), label="tangent")
math_case('ARCSINE', U(2.4, -1.2), label="arcsine_out_of_range")
math_case('ARCCOSINE', U(2.4, -1.2), label="arccosine_out_of_range")
math_case('ARCTANGENT', U(6.0, -3.0))
math_case('ARCTAN2', U(2.0, -1.0), V(2.0, -1.0))
math_case('TANH', U(4.0, -2.0))
math_case('SINH', U(2.0, -1.0), clamp=True)
math_case('RADIANS', U(90.0))
math_case('MULTIPLY', U(3.0), V(2.0), clamp=True, label="multiply")


# -- vector math: a representative set with edge cases
def vmath_case(op, a, b=None, c=None, scale=None, output="Vector", label=None, post=None):
    def build(t):
        node = t.new("ShaderNodeVectorMath", {"operation": op})
        for i, v in enumerate((a, b, c)):
            if v is None:
                continue
            t.set(node.inputs[i], v(t) if callable(v) else v)
        if scale is not None:
            node.inputs[3].default_value = scale
        out = node.outputs[output]
        if post is not None:
            return t.vscale(out, *post) if output == "Vector" else t.new(
                "ShaderNodeMath", {"operation": 'MULTIPLY_ADD'}, in0=out, in1=post[0], in2=post[1]).outputs[0]
        return out
    simple(f"vmath_{(label or op).lower()}", build, node="vector_math")


OBJ = lambda s=1.0: (lambda t: t.mapped("Object", location=(0.2, -0.1, 0.3), scale=(s, s, s)))  # noqa: E731
UVW = lambda: (lambda t: t.coord("UV"))   # noqa: E731
vmath_case('ADD', UVW(), (0.1, 0.2, 0.3))
vmath_case('SUBTRACT', OBJ(), (-1.0, -0.5, 0.0))
vmath_case('MULTIPLY', UVW(), (2.0, 0.5, 3.0))
vmath_case('DIVIDE', UVW(), lambda t: t.new("ShaderNodeVectorMath", {"operation": 'FLOOR'}, in0=t.vscale(
    t.coord("UV"), 3.0, -1.0)).outputs[0], label="divide_by_zero", post=(0.5, 0.5))
vmath_case('MULTIPLY_ADD', UVW(), (0.5, 1.5, 2.0), (0.1, 0.0, 0.2))
vmath_case('CROSS_PRODUCT', OBJ(), (0.3, 0.5, 0.8), post=(0.5, 0.5))
vmath_case('PROJECT', OBJ(), (0.3, 0.5, 0.8), post=(0.5, 0.5))
vmath_case('PROJECT', OBJ(), (0.0, 0.0, 0.0), label="project_onto_zero", post=(0.5, 0.5))
vmath_case('REFLECT', OBJ(), (0.3, 0.5, 0.8), post=(0.5, 0.5))
vmath_case('REFRACT', lambda t: t.new("ShaderNodeVectorMath", {"operation": 'NORMALIZE'},
                                      in0=t.mapped("Object", location=(0.0, 0.0, -2.0))).outputs[0],
           (0.0, 0.0, 1.0), scale=1.3, post=(0.5, 0.5))
vmath_case('FACEFORWARD', OBJ(), (0.3, -0.5, 0.8), (0.2, 0.4, -0.1), post=(0.5, 0.5))
vmath_case('DOT_PRODUCT', OBJ(), (0.3, 0.5, 0.8), output="Value", post=(0.5, 0.5))
vmath_case('DISTANCE', OBJ(), (0.3, 0.5, 0.8), output="Value")
vmath_case('LENGTH', OBJ(), output="Value")
vmath_case('SCALE', OBJ(), scale=-0.4, post=(1.0, 0.5))
vmath_case('NORMALIZE', OBJ(), post=(0.5, 0.5))
vmath_case('NORMALIZE', lambda t: t.new("ShaderNodeVectorMath", {"operation": 'SNAP'}, in0=t.coord("Object"),
                                        in1=(10.0, 10.0, 10.0)).outputs[0], label="normalize_zero",
           post=(0.5, 0.5))
vmath_case('ABSOLUTE', OBJ())
vmath_case('MINIMUM', UVW(), (0.4, 0.6, 0.2))
vmath_case('MAXIMUM', UVW(), (0.4, 0.6, 0.2))
vmath_case('FLOOR', OBJ(3.0), post=(0.1, 0.5))
vmath_case('CEIL', OBJ(3.0), post=(0.1, 0.5))
vmath_case('FRACTION', OBJ(3.0))
vmath_case('MODULO', OBJ(3.0), (0.7, 0.0, 1.3), label="modulo_with_zero", post=(0.5, 0.5))
vmath_case('WRAP', OBJ(3.0), (0.8, 0.5, 0.9), (0.1, -0.2, 0.3))
vmath_case('SNAP', OBJ(3.0), (0.4, 0.7, 0.0), label="snap_with_zero", post=(0.1, 0.5))
vmath_case('SINE', OBJ(3.0), post=(0.5, 0.5))
vmath_case('COSINE', OBJ(3.0), post=(0.5, 0.5))
vmath_case('TANGENT', OBJ(0.6), post=(0.3, 0.5))


# -- map range, clamp
for interp in ('LINEAR', 'STEPPED', 'SMOOTHSTEP', 'SMOOTHERSTEP'):
    for clamp in (True, False):
        if interp in ('SMOOTHSTEP', 'SMOOTHERSTEP') and not clamp:
            continue
        def build(t, interp=interp, clamp=clamp):
            return t.new("ShaderNodeMapRange", {"interpolation_type": interp, "clamp": clamp, "data_type": 'FLOAT'},
                         Value=t.axis("UV", 0), From_Min=0.2, From_Max=0.8, To_Min=0.1, To_Max=0.9,
                         Steps=4.0).outputs["Result"]
        simple(f"maprange_{interp.lower()}" + ("_clamp" if clamp else ""), build, node="map_range")
for interp in ('LINEAR', 'STEPPED', 'SMOOTHERSTEP'):
    def build(t, interp=interp):
        node = t.new("ShaderNodeMapRange", {"interpolation_type": interp, "clamp": interp != 'LINEAR',
                                            "data_type": 'FLOAT_VECTOR'})
        t.link(t.coord("UV"), node.inputs[6])
        for index, value in ((7, (0.1, 0.2, 0.0)), (8, (0.9, 0.7, 1.0)), (9, (0.0, 0.1, 0.2)), (10, (1.0, 0.8, 0.6)),
                             (11, (3.0, 5.0, 2.0))):
            node.inputs[index].default_value = value
        return node.outputs["Vector"]
    simple(f"maprange_vector_{interp.lower()}", build, node="map_range")
for ctype, lo, hi in (('MINMAX', 0.3, 0.7), ('RANGE', 0.7, 0.3), ('MINMAX', 0.7, 0.3)):
    simple(f"clamp_{ctype.lower()}_{lo:g}_{hi:g}", lambda t, ctype=ctype, lo=lo, hi=hi: t.new(
        "ShaderNodeClamp", {"clamp_type": ctype}, Value=t.axis("UV", 0), Min=lo, Max=hi).outputs[0], node="clamp")


# -- colour ramp
def ramp(t, fac, interpolation, mode="RGB"):
    node = t.new("ShaderNodeValToRGB")
    r = node.color_ramp
    r.color_mode = mode
    r.interpolation = interpolation
    r.elements[0].position, r.elements[0].color = 0.15, (0.9, 0.2, 0.1, 1.0)
    r.elements[1].position, r.elements[1].color = 0.85, (0.1, 0.3, 0.9, 0.5)
    mid = r.elements.new(0.45)
    mid.color = (0.2, 0.9, 0.3, 0.8)
    t.link(fac, node.inputs[0])
    return node


for interpolation in ('CONSTANT', 'LINEAR', 'EASE', 'B_SPLINE', 'CARDINAL'):
    simple(f"colorramp_{interpolation.lower()}", lambda t, interpolation=interpolation: ramp(
        t, t.axis("UV", 0), interpolation).outputs["Color"], node="color_ramp")
simple("colorramp_linear_alpha", lambda t: ramp(t, t.axis("UV", 0), 'LINEAR').outputs["Alpha"], node="color_ramp")
simple("colorramp_hsv_mode", lambda t: ramp(t, t.axis("UV", 0), 'LINEAR', "HSV").outputs["Color"],
       node="color_ramp")
simple("colorramp_out_of_range", lambda t: ramp(t, t.axis("UV", 0, 1.6, -0.3), 'LINEAR').outputs["Color"],
       node="color_ramp")


# -- curves
def curve_points(curve, points):
    while len(curve.points) < len(points):
        curve.points.new(0.5, 0.5)
    for p, (x, y) in zip(curve.points, points):
        p.location = (x, y)


def rgb_curves(t):
    node = t.new("ShaderNodeRGBCurve", Fac=0.9)
    m = node.mapping
    curve_points(m.curves[0], [(0.0, 0.1), (0.4, 0.7), (1.0, 0.9)])
    curve_points(m.curves[1], [(0.0, 0.0), (0.6, 0.2), (1.0, 1.0)])
    curve_points(m.curves[2], [(0.0, 0.3), (1.0, 0.6)])
    curve_points(m.curves[3], [(0.0, 0.0), (0.5, 0.6), (1.0, 1.0)])
    m.update()
    t.link(uv_color(t), node.inputs["Color"])
    return node.outputs[0]


def vector_curves(t):
    node = t.new("ShaderNodeVectorCurve", Fac=1.0)
    m = node.mapping
    curve_points(m.curves[0], [(-1.0, 0.0), (0.0, 0.5), (1.0, 0.2)])
    curve_points(m.curves[1], [(-1.0, 1.0), (1.0, 0.0)])
    curve_points(m.curves[2], [(-1.0, 0.2), (0.3, 0.8), (1.0, 0.4)])
    m.update()
    t.link(t.mapped("Object", location=(-0.5, -0.5, 0.0), scale=(0.8, 0.8, 0.8)), node.inputs["Vector"])
    return node.outputs[0]


def float_curve(t):
    node = t.new("ShaderNodeFloatCurve", Factor=1.0)
    m = node.mapping
    curve_points(m.curves[0], [(0.0, 0.8), (0.3, 0.1), (0.7, 0.6), (1.0, 0.3)])
    m.update()
    t.link(t.axis("UV", 0, 1.2, -0.1), node.inputs["Value"])
    return node.outputs[0]


simple("rgbcurves", rgb_curves, node="rgb_curves")
simple("vectorcurves", vector_curves, node="vector_curves")
simple("floatcurve_extrapolated", float_curve, node="float_curve")


# -- mix
def mix_rgba(t, blend, fac=None, clamp_result=False, clamp_factor=True):
    node = t.new("ShaderNodeMix", {"data_type": 'RGBA', "blend_type": blend, "clamp_result": clamp_result,
                                   "clamp_factor": clamp_factor})
    t.set(node.inputs[0], fac if fac is not None else 0.7)
    t.link(uv_color(t), node.inputs[6])
    t.set(node.inputs[7], (0.8, 0.35, 0.6))
    return node.outputs[2]


for blend in ('MIX', 'DARKEN', 'MULTIPLY', 'BURN', 'LIGHTEN', 'SCREEN', 'DODGE', 'ADD', 'OVERLAY', 'SOFT_LIGHT',
              'LINEAR_LIGHT', 'DIFFERENCE', 'SUBTRACT', 'DIVIDE', 'HUE', 'SATURATION', 'COLOR', 'VALUE'):
    simple(f"mix_rgba_{blend.lower()}", lambda t, blend=blend: mix_rgba(t, blend), node="mix")
simple("mix_rgba_add_clamp_result", lambda t: mix_rgba(t, 'ADD', 1.0, clamp_result=True), node="mix")
simple("mix_rgba_factor_unclamped", lambda t: mix_rgba(t, 'MIX', t.axis("UV", 1, 2.0, -0.5), clamp_factor=False),
       node="mix")
simple("mix_float", lambda t: t.new("ShaderNodeMix", {"data_type": 'FLOAT'}, in0=t.axis("UV", 1), in2=t.axis("UV", 0),
                                    in3=0.8).outputs[0], node="mix")
simple("mix_vector", lambda t: t.new("ShaderNodeMix", {"data_type": 'VECTOR'}, in0=0.35, in4=t.coord("UV"),
                                     in5=(0.9, 0.1, 0.6)).outputs[1], node="mix")
simple("mix_vector_nonuniform", lambda t: t.new("ShaderNodeMix", {"data_type": 'VECTOR', "factor_mode": 'NON_UNIFORM'},
                                                in1=(0.2, 0.5, 0.9), in4=t.coord("UV"),
                                                in5=(0.9, 0.1, 0.6)).outputs[1], node="mix")


def mix_legacy(t):
    node = t.new("ShaderNodeMixRGB", {"blend_type": 'OVERLAY'}, Fac=0.8, Color2=(0.3, 0.7, 0.2))
    t.link(uv_color(t), node.inputs["Color1"])
    return node.outputs[0]


simple("mixrgb_legacy_overlay", mix_legacy, node="mix")

# -- colour converters
simple("hsv", lambda t: t.new("ShaderNodeHueSaturation", Hue=0.3, Saturation=1.4, Value=0.8, Fac=0.9,
                              Color=uv_color(t)).outputs[0], node="hue_saturation_value")
simple("gamma", lambda t: t.new("ShaderNodeGamma", Color=uv_color(t), Gamma=2.2).outputs[0])
simple("brightcontrast", lambda t: t.new("ShaderNodeBrightContrast", Color=uv_color(t), Bright=0.1,
                                         Contrast=0.4).outputs[0], node="bright_contrast")
simple("invert", lambda t: t.new("ShaderNodeInvert", Fac=0.8, Color=uv_color(t)).outputs[0])
for mode in ('RGB', 'HSV', 'HSL'):
    def build_sep(t, mode=mode):
        sep = t.new("ShaderNodeSeparateColor", {"mode": mode}, Color=uv_color(t))
        # the three outputs again as a colour, in another order, so every output shows
        return t.new("ShaderNodeCombineXYZ", X=sep.outputs[2], Y=sep.outputs[0], Z=sep.outputs[1]).outputs[0]
    simple(f"separatecolor_{mode.lower()}", build_sep, node="separate_color")

    def build_comb(t, mode=mode):
        return t.new("ShaderNodeCombineColor", {"mode": mode}, Red=t.axis("UV", 0), Green=t.axis("UV", 1, 0.8, 0.1),
                     Blue=0.7).outputs[0]
    simple(f"combinecolor_{mode.lower()}", build_comb, node="combine_color")
simple("separatexyz_combinexyz", lambda t: t.new("ShaderNodeCombineXYZ", X=t.axis("Object", 1, 0.3, 0.5),
                                                   Y=t.axis("Generated", 0), Z=0.25).outputs[0], node="combine_xyz")
simple("rgbtobw", lambda t: t.new("ShaderNodeRGBToBW", Color=uv_color(t)).outputs[0], node="rgb_to_bw")
simple("blackbody", lambda t: t.new("ShaderNodeBlackbody", Temperature=t.axis("UV", 0, 11000.0, 800.0)).outputs[0])
simple("wavelength", lambda t: t.new("ShaderNodeWavelength", Wavelength=t.axis("UV", 0, 420.0, 370.0)).outputs[0])
simple("value_rgb_constants", lambda t: t.new("ShaderNodeMix", {"data_type": 'RGBA'}, in0=t.new(
    "ShaderNodeValue").outputs[0], in6=t.new("ShaderNodeRGB").outputs[0], in7=(0.2, 0.4, 0.6)).outputs[2],
       node="constants")

# -- mapping, vector rotate, vector transform
for vtype in ('POINT', 'TEXTURE', 'VECTOR', 'NORMAL'):
    simple(f"mapping_{vtype.lower()}", lambda t, vtype=vtype: t.vscale(t.mapped(
        "Object", location=(0.3, -0.2, 0.1), rotation=(0.4, -0.3, 0.7), scale=(1.3, 0.6, -0.8), vtype=vtype),
        0.4, 0.5), node="mapping")
for rtype, invert in (('AXIS_ANGLE', False), ('X_AXIS', False), ('Y_AXIS', False), ('Z_AXIS', True),
                      ('EULER_XYZ', False), ('EULER_XYZ', True)):
    simple(f"vectorrotate_{rtype.lower()}" + ("_invert" if invert else ""), lambda t, rtype=rtype, invert=invert:
           t.vscale(t.new("ShaderNodeVectorRotate", {"rotation_type": rtype, "invert": invert},
                          Vector=t.coord("Object"), Center=(0.2, 0.1, -0.3), Axis=(0.3, 0.4, 0.8), Angle=0.9,
                          Rotation=(0.3, -0.5, 1.1)).outputs[0], 0.4, 0.5), node="vector_rotate")
for vtype, frm, to in (('POINT', 'WORLD', 'OBJECT'), ('VECTOR', 'OBJECT', 'WORLD'), ('NORMAL', 'WORLD', 'CAMERA'),
                       ('POINT', 'WORLD', 'CAMERA')):
    simple(f"vectortransform_{vtype.lower()}_{frm.lower()}_{to.lower()}", lambda t, vtype=vtype, frm=frm, to=to:
           t.vscale(t.new("ShaderNodeVectorTransform", {"vector_type": vtype, "convert_from": frm, "convert_to": to},
                          Vector=t.mapped("Object", location=(0.1, 0.2, 0.3))).outputs[0], 0.3, 0.5),
           obj="Dome", node="vector_transform")

# -- inputs: texture coordinates, geometry, object info, attribute, fresnel / layer weight, camera, light path
for output, obj, post in (("Generated", "Plane", None), ("UV", "Plane", None), ("Object", "Plane", (0.4, 0.5)),
                          ("Normal", "Dome", (0.5, 0.5)), ("Camera", "Plane", (0.3, 0.5)), ("Window", "Plane", None),
                          ("Reflection", "Dome", (0.5, 0.5)), ("Generated", "Dome", None)):
    simple(f"texcoord_{output.lower()}_{obj.lower()}", lambda t, output=output, post=post:
           t.vscale(t.coord(output), *post) if post else t.coord(output), obj=obj, node="texture_coordinate")
simple("texcoord_object_from_camera", lambda t: t.vscale(t.coord("Object", bpy.data.objects["Camera"]), 0.3, 0.5),
       node="texture_coordinate")
simple("uvmap", lambda t: t.new("ShaderNodeUVMap").outputs[0], node="uv_map")
for output, post in (("Position", (0.3, 0.5)), ("Normal", (0.5, 0.5)), ("Tangent", (0.5, 0.5)),
                     ("True Normal", (0.5, 0.5)), ("Incoming", (0.5, 0.5)), ("Parametric", None),
                     ("Backfacing", None), ("Pointiness", None), ("Random Per Island", None)):
    simple(f"geometry_{output.lower().replace(' ', '')}", lambda t, output=output, post=post:
           t.vscale(t.new("ShaderNodeNewGeometry").outputs[output], *post) if post else
           t.new("ShaderNodeNewGeometry").outputs[output], obj="Dome", node="geometry")
for output in ("Location", "Color", "Object Index", "Material Index", "Random"):
    def build_info(t, output=output):
        out = t.new("ShaderNodeObjectInfo").outputs[output]
        if output == "Location":
            return t.vscale(out, 0.5, 0.5)
        if output in ("Object Index", "Material Index"):
            return t.new("ShaderNodeMath", {"operation": 'MULTIPLY_ADD'}, in0=out, in1=0.2, in2=0.1).outputs[0]
        return out
    simple(f"objectinfo_{output.lower().replace(' ', '')}", build_info, node="object_info")
for output in ("Color", "Fac"):
    simple(f"attribute_vertexcolor_{output.lower()}", lambda t, output=output: t.new(
        "ShaderNodeAttribute", {"attribute_name": "Col"}).outputs[output], node="attribute")
simple("vertexcolor_node", lambda t: t.new("ShaderNodeVertexColor", {"layer_name": "Col"}).outputs["Color"],
       node="attribute")
for ior in (1.45, 2.5):
    simple(f"fresnel_{ior:g}", lambda t, ior=ior: t.new("ShaderNodeFresnel", IOR=ior).outputs[0], obj="Dome")
simple("fresnel_normal_input", lambda t: t.new("ShaderNodeFresnel", IOR=1.6, Normal=t.new(
    "ShaderNodeVectorMath", {"operation": 'NORMALIZE'}, in0=t.mapped("Object", location=(0.0, 0.0, 0.6),
                                                                     scale=(1.0, 1.0, 0.0))).outputs[0]
    ).outputs[0], node="fresnel")
for output in ("Fresnel", "Facing"):
    simple(f"layerweight_{output.lower()}", lambda t, output=output: t.new(
        "ShaderNodeLayerWeight", Blend=0.35).outputs[output], obj="Dome", node="layer_weight")
for output, post in (("View Vector", (0.5, 0.5)), ("View Z Depth", (0.1, -0.5)), ("View Distance", (0.1, -0.5))):
    def build_cam(t, output=output, post=post):
        out = t.new("ShaderNodeCameraData").outputs[output]
        if output == "View Vector":
            return t.vscale(out, *post)
        return t.new("ShaderNodeMath", {"operation": 'MULTIPLY_ADD'}, in0=out, in1=post[0], in2=post[1]).outputs[0]
    simple(f"cameradata_{output.lower().replace(' ', '')}", build_cam, obj="Dome", node="camera_data")
simple("lightpath_camera_depth", lambda t: t.new("ShaderNodeCombineXYZ", X=t.new("ShaderNodeLightPath").outputs[
    "Is Camera Ray"], Y=t.new("ShaderNodeLightPath").outputs["Ray Depth"], Z=t.new("ShaderNodeLightPath").outputs[
    "Is Glossy Ray"]).outputs[0], node="light_path")

# -- normals: Bump, Normal Map, Normal (seen through their effect on a normal-reading node: the normal itself)
simple("bump_checker_height", lambda t: t.vscale(t.new("ShaderNodeBump", Strength=0.8, Distance=0.3, Height=t.new(
    "ShaderNodeTexGradient", {"gradient_type": 'SPHERICAL'}, Vector=t.coord("Object")).outputs["Fac"]).outputs[0],
    0.5, 0.5), obj="Dome", node="bump")
simple("bump_invert_noise", lambda t: t.vscale(t.new("ShaderNodeBump", {"invert": True}, Strength=0.5, Distance=0.1,
                                                     Height=t.new("ShaderNodeTexNoise", Scale=2.0, Detail=1.0,
                                                                  Vector=t.coord("Object")).outputs["Fac"]).outputs[0],
                                                 0.5, 0.5), NOISE, obj="Dome", node="bump")
for space in ('TANGENT', 'OBJECT', 'WORLD'):
    def build_nm(t, space=space):
        tex = image_node(t, "normals", 'Linear', vector=t.coord("UV"))
        nm = t.new("ShaderNodeNormalMap", {"space": space}, Strength=0.8)
        if space == 'TANGENT':
            nm.uv_map = "UVMap"
        t.link(tex.outputs["Color"], nm.inputs["Color"])
        return t.vscale(nm.outputs[0], 0.5, 0.5)
    simple(f"normalmap_{space.lower()}", build_nm, obj="Dome", node="normal_map")
def normal_node(t):
    node = t.new("ShaderNodeNormal")
    node.outputs["Normal"].default_value = (0.3, 0.4, 0.866)       # the node's own direction
    t.link(t.new("ShaderNodeNewGeometry").outputs["Normal"], node.inputs["Normal"])
    return t.new("ShaderNodeCombineXYZ", X=node.outputs["Dot"], Y=0.5, Z=t.new(
        "ShaderNodeVectorMath", {"operation": 'DOT_PRODUCT'}, in0=node.outputs["Normal"],
        in1=(0.0, 0.0, 1.0)).outputs["Value"]).outputs[0]


simple("normal_node_dot", normal_node, obj="Dome", node="normal")
simple("bump_wave_height", lambda t: t.vscale(t.new("ShaderNodeBump", Strength=1.0, Distance=0.2, Height=t.new(
    "ShaderNodeTexWave", Scale=1.5, Vector=t.coord("Object")).outputs["Fac"]).outputs[0], 0.5, 0.5), obj="Dome",
       node="bump")
simple("fresnel_of_bumped_normal", lambda t: t.new("ShaderNodeFresnel", IOR=1.5, Normal=t.new(
    "ShaderNodeBump", Strength=1.0, Distance=0.2, Height=t.new("ShaderNodeTexWave", Scale=1.5,
                                                                Vector=t.coord("Object")).outputs["Fac"]).outputs[0]
    ).outputs[0], obj="Dome", node="bump")


# -- implicit conversions between socket types (Cycles' colour -> float is a luminance, vector -> float an average)
simple("convert_color_to_float", lambda t: t.new("ShaderNodeMath", {"operation": 'MULTIPLY'}, in0=uv_color(t),
                                                 in1=1.0).outputs[0], node="conversion")
simple("convert_vector_to_float", lambda t: t.new("ShaderNodeMath", {"operation": 'MULTIPLY'},
                                                  in0=t.mapped("Object", location=(0.5, 0.5, 0.5)),
                                                  in1=1.0).outputs[0], node="conversion")
simple("convert_float_to_vector", lambda t: t.new("ShaderNodeVectorMath", {"operation": 'MULTIPLY'},
                                                  in0=t.axis("UV", 0), in1=(0.3, 0.6, 0.9)).outputs[0],
       node="conversion")


# -- a node group (inlined by the compiler)
def group_case(t):
    group = bpy.data.node_groups.get("NP_Group")
    if group is None:
        group = bpy.data.node_groups.new("NP_Group", "ShaderNodeTree")
        group.inputs.new("NodeSocketVector", "Vector")
        group.inputs.new("NodeSocketFloat", "Scale")
        group.outputs.new("NodeSocketColor", "Color")
        gin, gout = group.nodes.new("NodeGroupInput"), group.nodes.new("NodeGroupOutput")
        checker = group.nodes.new("ShaderNodeTexChecker")
        inv = group.nodes.new("ShaderNodeInvert")
        group.links.new(gin.outputs["Vector"], checker.inputs["Vector"])
        group.links.new(gin.outputs["Scale"], checker.inputs["Scale"])
        group.links.new(checker.outputs["Color"], inv.inputs["Color"])
        group.links.new(inv.outputs[0], gout.inputs["Color"])
    node = t.new("ShaderNodeGroup", {"node_tree": group})
    t.link(t.coord("Object"), node.inputs["Vector"])
    node.inputs["Scale"].default_value = 3.0
    return node.outputs[0]


simple("group_checker_invert", group_case, node="group")


# ---- the scene -------------------------------------------------------------------------------------------------

def make_images():
    """Four small in-memory images: float (opaque, and with alpha varying), byte sRGB, and a Non-Color normal
    map."""
    import numpy as np
    if "grid_float" not in bpy.data.images:
        w, h = 12, 8
        y, x = np.mgrid[0:h, 0:w].astype(np.float32)
        rgba = np.stack([(x + 0.5) / w, (y + 0.5) / h, 0.5 + 0.5 * np.sin(x * 1.3 + y * 2.1),
                         0.3 + 0.7 * ((x + y) % 3) / 2.0], axis=-1)
        rgba[(x.astype(int) + y.astype(int)) % 4 == 0, :3] *= 2.5       # some values above 1 in the float image
        img = bpy.data.images.new("grid_float_alpha", w, h, alpha=True, float_buffer=True)
        img.colorspace_settings.name = "Linear"
        img.pixels.foreach_set(rgba.reshape(-1))
        img.update()
        opaque = rgba.copy()
        opaque[..., 3] = 1.0
        img = bpy.data.images.new("grid_float", w, h, alpha=True, float_buffer=True)
        img.colorspace_settings.name = "Linear"
        img.pixels.foreach_set(opaque.reshape(-1))
        img.update()
        byte = bpy.data.images.new("grid_byte", w, h, alpha=True, float_buffer=False)
        byte.colorspace_settings.name = "sRGB"
        rgba_b = np.clip(rgba, 0.0, 1.0).copy()
        rgba_b[..., 3] = 1.0
        byte.pixels.foreach_set(np.round(rgba_b.reshape(-1) * 255.0) / 255.0)
        byte.update()
        n = 32
        y, x = (np.mgrid[0:n, 0:n].astype(np.float32) + 0.5) / n
        nx = 0.6 * np.cos(2 * math.pi * 2 * x) * np.sin(2 * math.pi * y)
        ny = 0.4 * np.sin(2 * math.pi * 3 * y)
        nz = np.sqrt(np.clip(1.0 - nx * nx - ny * ny, 0.0, 1.0))
        normals = np.stack([nx * 0.5 + 0.5, ny * 0.5 + 0.5, nz * 0.5 + 0.5, np.ones_like(nx)], axis=-1)
        nimg = bpy.data.images.new("normals", n, n, alpha=False, float_buffer=False)
        nimg.colorspace_settings.name = "Non-Color"
        nimg.pixels.foreach_set(np.round(normals.reshape(-1) * 255.0) / 255.0)
        nimg.update()


def grid_mesh(name, dome):
    import numpy as np
    n = GRID
    lin = np.linspace(-1.0, 1.0, n + 1)
    gx, gy = np.meshgrid(lin, lin)
    gz = 0.45 * (1.0 - np.clip(gx * gx + gy * gy, 0.0, 2.0)) if dome else np.zeros_like(gx)
    verts = np.stack([gx, gy, gz], axis=-1).reshape(-1, 3)
    faces = [(j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i)
             for j in range(n) for i in range(n)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts.tolist(), [], faces)
    uv = mesh.uv_layers.new(name="UVMap")
    loop_verts = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", loop_verts)
    uvs = (verts[loop_verts, :2] + 1.0) * 0.5
    uv.data.foreach_set("uv", uvs.reshape(-1))
    col = mesh.color_attributes.new("Col", 'FLOAT_COLOR', 'POINT')
    colors = np.stack([0.5 + 0.5 * np.sin(2.5 * verts[:, 0]), 0.5 + 0.5 * np.cos(3.0 * verts[:, 1]),
                       0.5 + 0.4 * verts[:, 0] * verts[:, 1], np.ones(len(verts))], axis=-1)
    col.data.foreach_set("color", colors.astype(np.float32).reshape(-1))
    mesh.polygons.foreach_set("use_smooth", [dome] * len(mesh.polygons))
    mesh.update()
    return mesh


def new_scene(size):
    # read_homefile, not read_factory_settings: the latter resets the preferences and so disables the add-on
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    scene.render.resolution_x = scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = 'Standard'
    scene.view_settings.look = 'None'
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.film_transparent = False
    world = bpy.data.worlds.new("Black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    world.color = (0.0, 0.0, 0.0)
    scene.world = world
    for name, dome in (("Plane", False), ("Dome", True)):
        obj = bpy.data.objects.new(name, grid_mesh(name, dome))
        obj.location = (CENTER[0], CENTER[1], 0.0)
        obj.rotation_euler = (0.0, 0.0, PLANE_TURN)
        obj.scale = (PLANE_SCALE, PLANE_SCALE, 1.0 if not dome else PLANE_SCALE)
        obj.pass_index = 3
        obj.color = (0.9, 0.5, 0.2, 1.0)
        scene.collection.objects.link(obj)
    cam = bpy.data.cameras.new("Camera")
    cam.type = 'ORTHO'
    cam.ortho_scale = VIEW
    cam.clip_start, cam.clip_end = 0.1, 100.0
    cam_obj = bpy.data.objects.new("Camera", cam)
    cam_obj.location = (CENTER[0], CENTER[1], 10.0)
    scene.collection.objects.link(cam_obj)
    scene.camera = cam_obj
    make_images()
    return scene


# Cases whose values Cycles renders negative on part of the plane, shifted into [0, ...) after the node (scale,
# offset): the core of the first measurement (9275481) clamped a program's emission at 0 (materials.cpp), Cycles
# does not, and these cases are about the node. math_subtract_signed alone keeps its negative values.
SHIFTS = {
    "maprange_linear": (1.0, 0.2), "maprange_stepped": (1.0, 0.2), "maprange_vector_linear": (1.0, 0.05),
    "math_arcsine_out_of_range": (1.0, 1.6), "math_arctan2": (1.0, 3.2), "math_arctangent": (1.0, 1.6),
    "math_ceil": (1.0, 2.0), "math_divide_by_zero": (1.0, 1.0), "math_floor": (1.0, 2.5),
    "math_logarithm_through_zero": (0.1, 1.0), "math_modulo_negative": (1.0, 1.0), "math_sign": (1.0, 1.5),
    "math_snap": (1.0, 2.0), "math_tangent": (1.0, 1.0), "math_tanh": (1.0, 1.0), "math_trunc": (1.0, 1.5),
    "mix_rgba_linear_light": (1.0, 0.5), "mix_rgba_subtract": (1.0, 0.5), "vectorcurves": (1.0, 0.2),
    "vmath_subtract": (1.0, 0.5), "vmath_wrap": (1.0, 0.3), "geometry_position": (0.85, 0.08),
    "texcoord_object_from_camera": (0.35, 0.9),
}


def shifted(t, name, socket):
    if name not in SHIFTS:
        return socket
    scale, offset = SHIFTS[name]
    if socket.type == 'VALUE':
        return t.new("ShaderNodeMath", {"operation": 'MULTIPLY_ADD'}, in0=socket, in1=scale, in2=offset).outputs[0]
    return t.vscale(socket, scale, offset)


def build(size=64, names=None):
    """A new scene with the cases' materials (all of CASES, or those named); returns [(name, class, object, node)]
    in order. Call use_case(name) to put one on its object and show that object alone."""
    scene = new_scene(size)
    chosen = []
    for name, cls, obj, node, builder in CASES:
        if names is not None and name not in names:
            continue
        mat = bpy.data.materials.new(name)
        mat.use_fake_user = True
        t = Tree(mat)
        t.emit(shifted(t, name, builder(t)))
        mat["ps_object"], mat["ps_class"], mat["ps_node"] = obj, cls, node
        chosen.append((name, cls, obj, node))
    if names is not None:
        missing = set(names) - {c[0] for c in chosen}
        if missing:
            raise KeyError(f"no such node case: {sorted(missing)}")
    scene["cases"] = [c[0] for c in chosen]
    return chosen


def use_case(name):
    """Put material `name` on its object (Plane or Dome) and hide the other from the render and the viewport."""
    mat = bpy.data.materials[name]
    for obj_name in ("Plane", "Dome"):
        obj = bpy.data.objects[obj_name]
        shown = obj_name == mat["ps_object"]
        obj.hide_render = not shown
        obj.hide_viewport = not shown      # the tools export the viewport depsgraph, which hide_render leaves alone
        obj.data.materials.clear()
        if shown:
            obj.data.materials.append(mat)
    bpy.context.view_layer.update()


def _check_unique():
    names = [c[0] for c in CASES]
    dup = {n for n in names if names.count(n) > 1}
    assert not dup, dup


_check_unique()

if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    size = int(argv[argv.index("--size") + 1]) if "--size" in argv else 64
    cases = build(size)
    use_case(cases[0][0])
    for img in bpy.data.images:
        img.pack()
    out = REPO / "build" / "node_compare" / "node_planes.blend"
    out.parent.mkdir(parents=True, exist_ok=True)
    bpy.context.preferences.filepaths.save_version = 0
    bpy.ops.wm.save_as_mainfile(filepath=str(out), compress=True)
    print(f"wrote {out}: {len(cases)} cases")
