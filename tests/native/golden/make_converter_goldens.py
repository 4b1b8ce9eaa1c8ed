# Golden values for the converter ops (native/src/nodes/converter_nodes.cpp), rendered by Cycles itself.
#
#   blender -b --factory-startup --python tests/native/golden/make_converter_goldens.py -- OUT.h
#
# (Blender 3.4; OUT.h defaults to converter_goldens.h next to this script.)
#
# How a value is measured: one mesh, one quad per case, seen square-on by an orthographic camera so that each quad
# is exactly one pixel. Each row of quads is one node set-up (its own material); every input of the node under test
# is driven by an Attribute node reading a face-domain attribute, so each pixel's inputs are exact float32 values
# and Cycles cannot constant-fold the node away (constant folding runs the host's copy of the code, and is not what
# a hit sees). The node's output drives an Emission shader of strength 1, so the pixel is the output: Cycles CPU,
# 1 sample, filter width 0.01 (pixel-centre samples), no denoising, Standard view, written as 32-bit OpenEXR
# (scene-linear, no view transform) and read back through bpy.data.images.load.
#
# Cycles' film zeroes non-finite values (ensure_finite), so a case whose output is inf or NaN reads 0; the cases are
# chosen to stay finite, and the test accepts a non-finite value where the golden is exactly 0.
#
# Tables: colour ramps and curves are baked the way Cycles' Blender sync bakes them (256 entries; ColorRamp.evaluate
# at i/255; curves evaluated with CurveMapping.evaluate over [min x, max x] of the curves' points, the RGB curves
# composing each channel's curve with the combined one), and written out in the op table's layout.
import math
import os
import random
import struct
import sys
import tempfile

import bpy

TABLE_SIZE = 256


def f32(x):
    return struct.unpack("f", struct.pack("f", float(x)))[0]


def cfloat(x):
    x = f32(x)
    if math.isnan(x) or math.isinf(x):
        raise ValueError("non-finite value")
    r = "%.9g" % x  # 9 significant digits round-trip a float32
    if "e" not in r and "." not in r:
        r += ".0"
    return r + "f"


# --- case specifications -------------------------------------------------------------------------------------
#
# A row: dict with
#   label, op, params (our op's params), node (bl_idname), props (node properties), sockets: for each of our op's
#   inputs, (Blender input index, 'f' | 'v'); outs: the Blender output indices with types, in our op's output order
#   (several float outputs are combined into one colour); our_outs: our op's output indices they are; cases: list
#   of input lists (floats, or 3-tuples for vectors); table (optional): the table floats for the op; setup
#   (optional): a function(node) run after the properties are set.
ROWS = []

# Fixed-seed random cases beside the hand-picked ones, so that the hand-picked edges are not all that is checked.
RNG = random.Random(1234)


def rnd(lo, hi):
    return round(RNG.uniform(lo, hi), 4)


def rvec(lo, hi):
    return (rnd(lo, hi), rnd(lo, hi), rnd(lo, hi))


def row(**kw):
    ROWS.append(kw)


MATH_OPS = ["ADD", "SUBTRACT", "MULTIPLY", "DIVIDE", "SINE", "COSINE", "TANGENT", "ARCSINE", "ARCCOSINE",
            "ARCTANGENT", "POWER", "LOGARITHM", "MINIMUM", "MAXIMUM", "ROUND", "LESS_THAN", "GREATER_THAN",
            "MODULO", "ABSOLUTE", "ARCTAN2", "FLOOR", "CEIL", "FRACT", "SQRT", "INVERSE_SQRT", "SIGN", "EXPONENT",
            "RADIANS", "DEGREES", "SINH", "COSH", "TANH", "TRUNC", "SNAP", "WRAP", "COMPARE", "MULTIPLY_ADD",
            "PINGPONG", "SMOOTH_MIN", "SMOOTH_MAX"]
MATH_CASES = [
    [0.5, 2.0, 0.3], [-1.5, 0.7, 0.2], [3.0, 0.0, 0.0], [-2.0, 3.0, -1.0], [-2.0, 0.5, 4.0], [0.0, 0.0, 0.0],
    [2.5, -1.25, 0.5], [7.3, 2.1, -3.2], [-0.3, -0.7, 1.0], [1.0, 1.0001, 0.001], [-4.6, 2.0, 0.0],
    [0.75, -2.0, 3.0], [-0.5, -0.5, -2.0], [1.7, 1.2, 1.2],
]
MATH_CASES += [[rnd(-3.0, 3.0), rnd(-3.0, 3.0), rnd(-1.0, 2.0)] for _ in range(16)]
for i, name in enumerate(MATH_OPS):
    row(label="math " + name, op="math", params=[i, 0], node="ShaderNodeMath",
        props={"operation": name, "use_clamp": False}, sockets=[(0, "f"), (1, "f"), (2, "f")],
        outs=[(0, "f")], our_outs=[0], cases=MATH_CASES)
for i, name in enumerate(MATH_OPS):
    if name in ("ADD", "SUBTRACT", "MULTIPLY", "SINE", "POWER", "SMOOTH_MIN"):
        row(label="math clamp " + name, op="math", params=[i, 1], node="ShaderNodeMath",
            props={"operation": name, "use_clamp": True}, sockets=[(0, "f"), (1, "f"), (2, "f")],
            outs=[(0, "f")], our_outs=[0], cases=MATH_CASES)

VMATH_OPS = ["ADD", "SUBTRACT", "MULTIPLY", "DIVIDE", "CROSS_PRODUCT", "PROJECT", "REFLECT", "DOT_PRODUCT",
             "DISTANCE", "LENGTH", "SCALE", "NORMALIZE", "SNAP", "FLOOR", "CEIL", "MODULO", "FRACTION",
             "ABSOLUTE", "MINIMUM", "MAXIMUM", "WRAP", "SINE", "COSINE", "TANGENT", "REFRACT", "FACEFORWARD",
             "MULTIPLY_ADD"]
VMATH_VALUE_OPS = ("DOT_PRODUCT", "DISTANCE", "LENGTH")
VMATH_CASES = [
    [(0.5, -1.0, 2.0), (1.5, 0.25, -0.5), (0.1, 0.2, 0.3), 0.7],
    [(-1.3, 2.7, 0.4), (0.0, 2.0, -3.0), (1.0, -1.0, 0.5), 1.45],
    [(0.0, 0.0, 0.0), (0.3, -0.4, 0.5), (-2.0, 0.0, 1.0), -2.0],
    [(3.3, -4.4, 5.5), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 0.0],
    [(0.2, 0.6, -0.77), (0.0, 0.0, 1.0), (0.5, 0.5, 0.5), 1.33],
    [(0.9, 0.1, -0.4), (0.0, 0.0, 1.0), (0.2, -0.3, -0.9), 2.5],
    [(-0.6, -0.25, 1.9), (-1.5, 0.8, 0.8), (2.0, 2.0, -1.0), 0.5],
    [(7.25, -3.5, 0.125), (2.0, -1.5, 0.75), (-1.0, 0.5, 0.25), 1.0],
]
VMATH_CASES += [[rvec(-3.0, 3.0), rvec(-3.0, 3.0), rvec(-2.0, 2.0), rnd(0.3, 2.0)] for _ in range(10)]
for i, name in enumerate(VMATH_OPS):
    value = name in VMATH_VALUE_OPS
    row(label="vector_math " + name, op="vector_math", params=[i], node="ShaderNodeVectorMath",
        props={"operation": name}, sockets=[(0, "v"), (1, "v"), (2, "v"), (3, "f")],
        outs=[(1, "f")] if value else [(0, "v")], our_outs=[1] if value else [0], cases=VMATH_CASES)

MAP_RANGE_TYPES = ["LINEAR", "STEPPED", "SMOOTHSTEP", "SMOOTHERSTEP"]
MAP_RANGE_CASES = [
    [0.3, 0.0, 1.0, 0.0, 1.0, 4.0], [1.4, 0.0, 1.0, -2.0, 3.0, 4.0], [-0.4, 0.0, 1.0, 5.0, 1.0, 3.0],
    [0.55, 1.0, 0.0, 0.0, 10.0, 5.0], [2.0, 1.0, 1.0, 0.0, 1.0, 4.0], [0.7, 0.2, 1.2, 3.0, -1.0, 0.0],
    [0.37, -1.0, 2.0, 0.5, 0.25, 2.5], [1.25, 2.0, -2.0, -1.0, 1.0, 6.0], [0.999, 0.0, 1.0, 0.0, 1.0, 10.0],
    # an empty source range gives 0, which a clamped map range then clamps into the target range
    [2.0, 1.0, 1.0, 3.0, 5.0, 4.0], [0.5, -0.5, -0.5, -2.0, -1.0, 2.0],
]
for i, name in enumerate(MAP_RANGE_TYPES):
    for clamp in (0, 1):
        row(label="map_range %s clamp %d" % (name, clamp), op="map_range", params=[i, clamp],
            node="ShaderNodeMapRange", props={"data_type": "FLOAT", "interpolation_type": name,
                                              "clamp": bool(clamp)},
            sockets=[(k, "f") for k in range(6)], outs=[(0, "f")], our_outs=[0], cases=MAP_RANGE_CASES)
VMAP_RANGE_CASES = []
for k in range(0, len(MAP_RANGE_CASES) - 2):
    a, b, c = MAP_RANGE_CASES[k], MAP_RANGE_CASES[k + 1], MAP_RANGE_CASES[k + 2]
    VMAP_RANGE_CASES.append([(a[j], b[j], c[j]) for j in range(6)])
for i, name in enumerate(MAP_RANGE_TYPES):
    for clamp in (0, 1):
        row(label="map_range_vector %s clamp %d" % (name, clamp), op="map_range_vector", params=[i, clamp],
            node="ShaderNodeMapRange", props={"data_type": "FLOAT_VECTOR", "interpolation_type": name,
                                              "clamp": bool(clamp)},
            sockets=[(k, "v") for k in range(6, 12)], outs=[(1, "v")], our_outs=[0], cases=VMAP_RANGE_CASES)

CLAMP_CASES = [[0.5, 0.0, 1.0], [-0.5, 0.0, 1.0], [1.5, 0.0, 1.0], [0.5, 1.0, 0.0], [2.0, 1.0, -1.0],
               [-3.0, 1.0, -1.0], [0.25, 0.3, 0.3], [7.0, -2.0, 5.0]]
for i, name in enumerate(["MINMAX", "RANGE"]):
    row(label="clamp " + name, op="clamp", params=[i], node="ShaderNodeClamp", props={"clamp_type": name},
        sockets=[(0, "f"), (1, "f"), (2, "f")], outs=[(0, "f")], our_outs=[0], cases=CLAMP_CASES)

# Mix: Cycles' NodeMix order, and Blender's names for it.
MIX_BLENDS = ["MIX", "ADD", "MULTIPLY", "SUBTRACT", "SCREEN", "DIVIDE", "DIFFERENCE", "DARKEN", "LIGHTEN",
              "OVERLAY", "DODGE", "BURN", "HUE", "SATURATION", "VALUE", "COLOR", "SOFT_LIGHT", "LINEAR_LIGHT"]
MIX_CASES = [
    [0.5, (0.2, 0.4, 0.6), (0.8, 0.3, 0.1)], [0.25, (0.9, 0.1, 0.5), (0.0, 0.5, 1.0)],
    [1.0, (0.3, 0.7, 0.2), (0.6, 0.6, 0.6)], [0.8, (0.05, 0.95, 0.4), (0.7, 0.2, 0.0)],
    [1.4, (0.6, 0.2, 0.8), (0.1, 0.9, 0.4)], [-0.3, (0.5, 0.5, 0.5), (0.9, 0.2, 0.3)],
    [0.6, (1.5, -0.2, 0.0), (2.0, 0.5, -0.5)], [0.7, (0.0, 0.0, 0.0), (0.4, 0.8, 0.2)],
    [0.35, (0.8, 0.8, 0.8), (0.2, 0.2, 0.2)], [0.9, (0.25, 0.55, 0.75), (1.0, 0.0, 0.5)],
]
MIX_CASES += [[rnd(-0.2, 1.2), rvec(-0.1, 1.2), rvec(-0.1, 1.2)] for _ in range(10)]
for i, name in enumerate(MIX_BLENDS):
    for cf, cr in ((1, 0), (0, 1)) if name in ("MIX", "ADD", "DIVIDE", "DODGE", "BURN", "LINEAR_LIGHT",
                                               "OVERLAY", "HUE") else ((1, 0), (0, 0)):
        row(label="mix_color %s clamp_factor %d clamp_result %d" % (name, cf, cr), op="mix_color",
            params=[i, cf, cr], node="ShaderNodeMix",
            props={"data_type": "RGBA", "blend_type": name, "clamp_factor": bool(cf), "clamp_result": bool(cr)},
            sockets=[(0, "f"), (6, "v"), (7, "v")], outs=[(2, "v")], our_outs=[0], cases=MIX_CASES)
for cf in (0, 1):
    row(label="mix_float clamp %d" % cf, op="mix_float", params=[cf], node="ShaderNodeMix",
        props={"data_type": "FLOAT", "clamp_factor": bool(cf)}, sockets=[(0, "f"), (2, "f"), (3, "f")],
        outs=[(0, "f")], our_outs=[0], cases=[[c[0], c[1][0], c[2][1]] for c in MIX_CASES])
    row(label="mix_vector clamp %d" % cf, op="mix_vector", params=[cf], node="ShaderNodeMix",
        props={"data_type": "VECTOR", "factor_mode": "UNIFORM", "clamp_factor": bool(cf)},
        sockets=[(0, "f"), (4, "v"), (5, "v")], outs=[(1, "v")], our_outs=[0], cases=MIX_CASES)
    row(label="mix_vector_nonuniform clamp %d" % cf, op="mix_vector_nonuniform", params=[cf],
        node="ShaderNodeMix", props={"data_type": "VECTOR", "factor_mode": "NON_UNIFORM", "clamp_factor": bool(cf)},
        sockets=[(1, "v"), (4, "v"), (5, "v")], outs=[(1, "v")], our_outs=[0],
        cases=[[(c[0], 1.0 - c[0], c[0] * 2.0), c[1], c[2]] for c in MIX_CASES])
# The legacy MixRGB node clamps its factor always and its result when use_clamp is set (Cycles adds a clamp).
for name in ("MIX", "OVERLAY", "SOFT_LIGHT"):
    for use_clamp in (0, 1):
        row(label="legacy mix_rgb %s use_clamp %d" % (name, use_clamp), op="mix_color",
            params=[MIX_BLENDS.index(name), 1, use_clamp], node="ShaderNodeMixRGB",
            props={"blend_type": name, "use_clamp": bool(use_clamp)}, sockets=[(0, "f"), (1, "v"), (2, "v")],
            outs=[(0, "v")], our_outs=[0], cases=MIX_CASES)

COLOR_CASES = [(0.2, 0.4, 0.6), (0.9, 0.1, 0.5), (0.0, 0.0, 0.0), (0.5, 0.5, 0.5), (1.5, 0.3, -0.2),
               (0.05, 0.95, 0.4), (0.7, 0.2, 0.2), (0.3, 0.3, 0.8), (2.0, 1.0, 0.5), (0.6, 0.6, 0.1)]
COLOR_CASES += [rvec(0.0, 1.2) for _ in range(8)]
HSV_CASES = [[0.5, 1.0, 1.0, 1.0, COLOR_CASES[0]], [0.2, 1.3, 0.8, 1.0, COLOR_CASES[1]],
             [0.9, 0.5, 1.2, 0.6, COLOR_CASES[2]], [0.0, 2.0, 1.0, 1.0, COLOR_CASES[3]],
             [0.75, 1.0, 1.0, 0.5, COLOR_CASES[4]], [-0.3, 0.7, 0.9, 1.0, COLOR_CASES[5]],
             [1.4, 1.0, 2.0, 1.0, COLOR_CASES[6]], [0.6, 0.0, 1.0, 0.8, COLOR_CASES[7]],
             [0.45, 1.5, 0.5, 1.3, COLOR_CASES[8]]]
HSV_CASES += [[rnd(0.0, 1.0), rnd(0.0, 2.0), rnd(0.0, 2.0), rnd(0.0, 1.0), rvec(0.0, 1.2)] for _ in range(8)]
row(label="hue_saturation_value", op="hue_saturation_value", params=[], node="ShaderNodeHueSaturation", props={},
    sockets=[(0, "f"), (1, "f"), (2, "f"), (3, "f"), (4, "v")], outs=[(0, "v")], our_outs=[0], cases=HSV_CASES)
row(label="gamma", op="gamma", params=[], node="ShaderNodeGamma", props={}, sockets=[(0, "v"), (1, "f")],
    outs=[(0, "v")], our_outs=[0],
    cases=[[c, g] for c, g in zip(COLOR_CASES, [1.0, 2.2, 0.45, 0.0, 2.0, -1.0, 3.0, 0.5, 1.7, 0.0])])
row(label="bright_contrast", op="bright_contrast", params=[], node="ShaderNodeBrightContrast", props={},
    sockets=[(0, "v"), (1, "f"), (2, "f")], outs=[(0, "v")], our_outs=[0],
    cases=[[c, b, k] for c, b, k in zip(COLOR_CASES, [0.0, 0.2, -0.3, 0.5, 0.1, 0.0, -0.1, 1.0, 0.3, 0.0],
                                         [0.0, 0.5, 1.0, -0.5, 0.2, -1.5, 0.7, 0.0, -0.2, 2.0])])
row(label="invert", op="invert", params=[], node="ShaderNodeInvert", props={}, sockets=[(0, "f"), (1, "v")],
    outs=[(0, "v")], our_outs=[0],
    cases=[[f, c] for f, c in zip([1.0, 0.5, 0.0, 0.3, 1.2, -0.4, 0.8, 1.0, 0.25, 0.9], COLOR_CASES)])
for i, name in enumerate(["RGB", "HSV", "HSL"]):
    row(label="separate_color " + name, op="separate_color", params=[i], node="ShaderNodeSeparateColor",
        props={"mode": name}, sockets=[(0, "v")], outs=[(0, "f"), (1, "f"), (2, "f")], our_outs=[0, 1, 2],
        cases=[[c] for c in COLOR_CASES])
    row(label="combine_color " + name, op="combine_color", params=[i], node="ShaderNodeCombineColor",
        props={"mode": name}, sockets=[(0, "f"), (1, "f"), (2, "f")], outs=[(0, "v")], our_outs=[0],
        cases=[list(c) for c in COLOR_CASES] + [[1.0, 0.5, 0.5], [0.999, 0.8, 0.3], [-0.2, 0.5, 0.7],
                                                [0.6, 1.5, 0.4]])
row(label="rgb_to_bw", op="rgb_to_bw", params=[], node="ShaderNodeRGBToBW", props={}, sockets=[(0, "v")],
    outs=[(0, "f")], our_outs=[0], cases=[[c] for c in COLOR_CASES + [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0),
                                                                      (0.0, 0.0, 1.0)]])
row(label="blackbody", op="blackbody", params=[], node="ShaderNodeBlackbody", props={}, sockets=[(0, "f")],
    outs=[(0, "v")], our_outs=[0],
    cases=[[t] for t in [500.0, 800.0, 900.0, 965.0, 1000.0, 1300.0, 1500.0, 2000.0, 2700.0, 3500.0, 4500.0,
                         6500.0, 8000.0, 11999.0, 12000.0, 25000.0, 799.9,
                         1167.0, 1449.0, 1902.0, 3315.0, 6365.0, 6364.9]])
row(label="wavelength", op="wavelength", params=[], node="ShaderNodeWavelength", props={}, sockets=[(0, "f")],
    outs=[(0, "v")], our_outs=[0],
    cases=[[w] for w in [300.0, 374.0, 377.5, 380.0, 382.5, 450.0, 500.2, 555.0, 590.0, 610.0, 650.0, 700.0,
                         779.0, 780.0, 784.0, 786.0, 375.0, 375.5,
                         779.99, 420.3, 530.7]])

MAPPING_CASES = [
    [(0.5, -1.0, 2.0), (0.1, 0.2, 0.3), (0.3, -0.6, 1.2), (1.0, 2.0, 0.5)],
    [(1.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 1.5707964), (1.0, 1.0, 1.0)],
    [(-0.7, 0.4, 0.9), (1.5, -0.5, 0.0), (2.5, 0.1, -0.8), (0.0, 3.0, -1.0)],
    [(0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)],
    [(2.0, 3.0, -1.0), (-1.0, 0.25, 0.5), (-0.4, 0.9, 0.2), (-2.0, 0.5, 1.5)],
]
MAPPING_CASES += [[rvec(-2.0, 2.0), rvec(-1.0, 1.0), rvec(-3.2, 3.2), rvec(-2.0, 2.0)] for _ in range(8)]
for i, name in enumerate(["POINT", "TEXTURE", "VECTOR", "NORMAL"]):
    row(label="mapping " + name, op="mapping", params=[i], node="ShaderNodeMapping", props={"vector_type": name},
        sockets=[(0, "v"), (1, "v"), (2, "v"), (3, "v")], outs=[(0, "v")], our_outs=[0], cases=MAPPING_CASES)

ROTATE_CASES = [
    [(0.5, -1.0, 2.0), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 0.7, (0.3, -0.6, 1.2)],
    [(1.0, 2.0, 3.0), (0.5, 0.5, 0.5), (1.0, 1.0, 0.0), -1.3, (1.0, 0.5, -0.25)],
    [(-0.7, 0.4, 0.9), (1.0, -2.0, 0.0), (0.0, 0.0, 0.0), 2.0, (0.0, 0.0, 0.0)],
    [(2.0, 0.0, -1.0), (0.0, 1.0, 0.0), (0.3, -2.0, 0.6), 3.5, (2.5, 0.1, -0.8)],
    [(0.1, 0.2, 0.3), (-0.3, 0.2, 0.1), (0.0, 1.0, 0.0), 0.0, (-1.0, 2.0, 0.4)],
]
ROTATE_CASES += [[rvec(-2.0, 2.0), rvec(-1.0, 1.0), rvec(-1.0, 1.0), rnd(-6.3, 6.3), rvec(-3.2, 3.2)]
                 for _ in range(8)]
for i, name in enumerate(["AXIS_ANGLE", "X_AXIS", "Y_AXIS", "Z_AXIS", "EULER_XYZ"]):
    for inv in (0, 1):
        row(label="vector_rotate %s invert %d" % (name, inv), op="vector_rotate", params=[i, inv],
            node="ShaderNodeVectorRotate", props={"rotation_type": name, "invert": bool(inv)},
            sockets=[(0, "v"), (1, "v"), (2, "v"), (3, "f"), (4, "v")], outs=[(0, "v")], our_outs=[0],
            cases=ROTATE_CASES)

# --- colour ramps and curves (tables baked after the node exists) ------------------------------------------------
RAMP_FACS = [[x] for x in [-0.5, 0.0, 0.05, 0.2, 0.333, 0.4, 0.5, 0.61, 0.75, 0.9, 0.999, 1.0, 1.3]]


def ramp_setup(interp, color_mode="RGB", hue="NEAR"):
    def setup(node):
        r = node.color_ramp
        r.interpolation = interp
        r.color_mode = color_mode
        r.hue_interpolation = hue
        e = r.elements
        e[0].position = 0.1
        e[0].color = (0.9, 0.2, 0.1, 1.0)
        e[1].position = 0.85
        e[1].color = (0.1, 0.3, 1.0, 0.5)
        m = e.new(0.45)
        m.color = (0.2, 1.0, 0.4, 0.25)
        return [(0, 0)]  # filled in by bake_ramp
    return setup


def bake_ramp(node):
    r = node.color_ramp
    table = []
    for i in range(TABLE_SIZE):
        c = r.evaluate(i / (TABLE_SIZE - 1))
        table += [c[0], c[1], c[2], c[3]]
    interp = 0 if r.interpolation == "CONSTANT" else 1
    return table, [0, TABLE_SIZE, interp]


for interp in ("LINEAR", "CONSTANT", "EASE", "B_SPLINE"):
    row(label="color_ramp " + interp, op="color_ramp", params=None, node="ShaderNodeValToRGB", props={},
        sockets=[(0, "f")], outs=[(0, "v")], our_outs=[0], cases=RAMP_FACS, setup=ramp_setup(interp), bake=bake_ramp)
    row(label="color_ramp alpha " + interp, op="color_ramp", params=None, node="ShaderNodeValToRGB", props={},
        sockets=[(0, "f")], outs=[(1, "f")], our_outs=[1], cases=RAMP_FACS, setup=ramp_setup(interp), bake=bake_ramp)
row(label="color_ramp HSV", op="color_ramp", params=None, node="ShaderNodeValToRGB", props={},
    sockets=[(0, "f")], outs=[(0, "v")], our_outs=[0], cases=RAMP_FACS, setup=ramp_setup("LINEAR", "HSV", "FAR"),
    bake=bake_ramp)


def set_curve(curve, pts):
    p = curve.points
    while len(p) > 2:
        p.remove(p[len(p) - 1])
    p[0].location = pts[0]
    p[1].location = pts[1]
    for xy in pts[2:]:
        p.new(xy[0], xy[1])


def curves_setup(kind, extend="EXTRAPOLATED"):
    def setup(node):
        m = node.mapping
        m.extend = extend
        if kind == "rgb":
            set_curve(m.curves[0], [(0.0, 0.1), (0.5, 0.7), (1.0, 0.9)])
            set_curve(m.curves[1], [(0.1, 0.0), (0.9, 1.0)])
            set_curve(m.curves[2], [(0.0, 0.8), (0.6, 0.3), (1.0, 0.5)])
            set_curve(m.curves[3], [(0.05, 0.0), (0.4, 0.6), (0.95, 1.0)])
        elif kind == "vector":
            set_curve(m.curves[0], [(-1.0, -0.5), (0.0, 0.3), (1.0, 1.0)])
            set_curve(m.curves[1], [(-0.8, 1.0), (0.8, -1.0)])
            set_curve(m.curves[2], [(-1.0, 0.0), (-0.2, 0.6), (0.5, -0.3), (1.0, 0.2)])
        else:
            set_curve(m.curves[0], [(0.0, 0.2), (0.3, 0.9), (0.7, 0.1), (1.0, 0.6)])
        m.update()
    return setup


def curve_minmax(m, n):
    lo, hi = float("inf"), float("-inf")
    for i in range(n):
        pts = m.curves[i].points
        lo = min(lo, pts[0].location[0])
        hi = max(hi, pts[len(pts) - 1].location[0])
    return f32(lo), f32(hi)


def bake_curves(kind):
    def bake(node):
        m = node.mapping
        m.update()
        if kind == "rgb":
            lo, hi = curve_minmax(m, 4)
            table = [lo, hi]
            for i in range(TABLE_SIZE):
                t = f32(lo + f32(i / (TABLE_SIZE - 1)) * f32(hi - lo))
                ti = m.evaluate(m.curves[3], t)
                table += [m.evaluate(m.curves[c], ti) for c in range(3)]
        elif kind == "vector":
            lo, hi = curve_minmax(m, 3)
            table = [lo, hi]
            for i in range(TABLE_SIZE):
                t = f32(lo + f32(i / (TABLE_SIZE - 1)) * f32(hi - lo))
                table += [m.evaluate(m.curves[c], t) for c in range(3)]
        else:
            lo, hi = curve_minmax(m, 1)
            table = [lo, hi]
            for i in range(TABLE_SIZE):
                t = f32(lo + f32(i / (TABLE_SIZE - 1)) * f32(hi - lo))
                table.append(m.evaluate(m.curves[0], t))
        return table, [0, TABLE_SIZE]
    return bake


CURVE_CASES = [[1.0, (0.3, 0.6, 0.9)], [1.0, (-0.2, 1.2, 0.5)], [0.5, (0.0, 0.25, 1.0)], [1.0, (0.45, 0.05, 0.7)],
               [0.8, (1.5, -0.6, 0.1)], [1.0, (0.999, 0.001, 0.5)], [0.0, (0.2, 0.3, 0.4)], [1.3, (0.6, 0.7, 0.8)]]
row(label="rgb_curves", op="rgb_curves", params=None, node="ShaderNodeRGBCurve", props={},
    sockets=[(0, "f"), (1, "v")], outs=[(0, "v")], our_outs=[0], cases=CURVE_CASES, setup=curves_setup("rgb"),
    bake=bake_curves("rgb"))
row(label="vector_curves", op="vector_curves", params=None, node="ShaderNodeVectorCurve", props={},
    sockets=[(0, "f"), (1, "v")], outs=[(0, "v")], our_outs=[0],
    cases=[[f, (2 * c[0] - 1, 2 * c[1] - 1, 2 * c[2] - 1)] for f, c in CURVE_CASES], setup=curves_setup("vector"),
    bake=bake_curves("vector"))
row(label="float_curve", op="float_curve", params=None, node="ShaderNodeFloatCurve", props={},
    sockets=[(0, "f"), (1, "f")], outs=[(0, "f")], our_outs=[0],
    cases=[[f, v] for f, v in [(1.0, 0.1), (1.0, 0.5), (1.0, -0.3), (1.0, 1.4), (0.5, 0.8), (1.0, 0.999),
                               (0.0, 0.3), (1.0, 0.65), (-0.5, 0.2)]],
    setup=curves_setup("float"), bake=bake_curves("float"))

# Blender's other curve extension, "extended horizontally", which Cycles gives by not extrapolating: the op's table
# layout always extrapolates (it has no flag for this), so only positions inside the curves' range are checked.
def inside(lo, hi):
    return lambda c: all(lo <= x <= hi for x in (c[1] if isinstance(c[1], tuple) else (c[1],)))


row(label="rgb_curves horizontal", op="rgb_curves", params=None, node="ShaderNodeRGBCurve", props={},
    sockets=[(0, "f"), (1, "v")], outs=[(0, "v")], our_outs=[0], cases=list(filter(inside(0.0, 1.0), CURVE_CASES)),
    setup=curves_setup("rgb", "HORIZONTAL"), bake=bake_curves("rgb"))
row(label="float_curve horizontal", op="float_curve", params=None, node="ShaderNodeFloatCurve", props={},
    sockets=[(0, "f"), (1, "f")], outs=[(0, "f")], our_outs=[0],
    cases=[[f, v] for f, v in [(1.0, 0.1), (1.0, 0.5), (0.5, 0.8), (1.0, 0.999), (1.0, 0.65), (1.0, 0.0)]],
    setup=curves_setup("float", "HORIZONTAL"), bake=bake_curves("float"))


# --- the scene -----------------------------------------------------------------------------------------------
def build_and_render(rows, path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    W = max(len(r["cases"]) for r in rows)
    H = len(rows)
    n_f = max(sum(1 for s in r["sockets"] if s[1] == "f") for r in rows)
    verts, faces, mat_index = [], [], []
    fattr = {k: [] for k in range(6)}
    vattr = {k: [] for k in range(6)}
    mesh = bpy.data.meshes.new("cases")
    for ri, r in enumerate(rows):
        mat = bpy.data.materials.new(r["label"])
        mat.use_nodes = True
        nt = mat.node_tree
        nt.nodes.clear()
        out = nt.nodes.new("ShaderNodeOutputMaterial")
        em = nt.nodes.new("ShaderNodeEmission")
        em.inputs["Strength"].default_value = 1.0
        nt.links.new(em.outputs[0], out.inputs["Surface"])
        node = nt.nodes.new(r["node"])
        for k, v in r["props"].items():
            setattr(node, k, v)
        if "setup" in r:
            r["setup"](node)
        if "bake" in r:
            r["table"], r["params"] = r["bake"](node)
        for k, (si, t) in enumerate(r["sockets"]):
            a = nt.nodes.new("ShaderNodeAttribute")
            a.attribute_type = "GEOMETRY"
            a.attribute_name = ("f%d" if t == "f" else "v%d") % k
            nt.links.new(a.outputs["Fac" if t == "f" else "Vector"], node.inputs[si])
        if len(r["outs"]) == 1:
            nt.links.new(node.outputs[r["outs"][0][0]], em.inputs["Color"])
        else:
            comb = nt.nodes.new("ShaderNodeCombineXYZ")
            for j, (oi, t) in enumerate(r["outs"]):
                nt.links.new(node.outputs[oi], comb.inputs[j])
            nt.links.new(comb.outputs[0], em.inputs["Color"])
        mesh.materials.append(mat)
        for ci, case in enumerate(r["cases"]):
            x0, y0 = -W / 2 + ci, -H / 2 + ri
            b = len(verts)
            verts += [(x0, y0, 0.0), (x0 + 1, y0, 0.0), (x0 + 1, y0 + 1, 0.0), (x0, y0 + 1, 0.0)]
            faces.append((b, b + 1, b + 2, b + 3))
            mat_index.append(ri)
            for k in range(6):
                val = case[k] if k < len(case) else 0.0
                if isinstance(val, (tuple, list)):
                    vattr[k].append(tuple(val))
                    fattr[k].append(0.0)
                else:
                    fattr[k].append(val)
                    vattr[k].append((val, val, val))
    mesh.from_pydata(verts, [], faces)
    mesh.polygons.foreach_set("material_index", mat_index)
    for k in range(6):
        a = mesh.attributes.new("f%d" % k, "FLOAT", "FACE")
        a.data.foreach_set("value", fattr[k])
        b = mesh.attributes.new("v%d" % k, "FLOAT_VECTOR", "FACE")
        b.data.foreach_set("vector", [c for v in vattr[k] for c in v])
    mesh.update()
    obj = bpy.data.objects.new("cases", mesh)
    scene.collection.objects.link(obj)

    cam_data = bpy.data.cameras.new("cam")
    cam_data.type = "ORTHO"
    cam_data.ortho_scale = max(W, H)
    cam = bpy.data.objects.new("cam", cam_data)
    cam.location = (0.0, 0.0, 10.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    world = bpy.data.worlds.new("w")
    world.use_nodes = False
    world.color = (0.0, 0.0, 0.0)
    scene.world = world

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 1
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.filter_width = 0.01
    scene.cycles.sample_clamp_direct = 0.0
    scene.cycles.sample_clamp_indirect = 0.0
    scene.render.resolution_x = W
    scene.render.resolution_y = H
    scene.render.resolution_percentage = 100
    scene.render.use_compositing = False
    scene.render.use_sequencer = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(path)
    px = list(img.pixels)
    assert img.size[0] == W and img.size[1] == H, img.size
    results = []
    for ri, r in enumerate(rows):
        rr = []
        for ci in range(len(r["cases"])):
            p = (ri * W + ci) * 4
            rgb = px[p:p + 3]
            vals = []
            if len(r["outs"]) == 1:
                vals = [rgb[0]] if r["outs"][0][1] == "f" else list(rgb)
            else:
                vals = list(rgb)
            rr.append(vals)
        results.append(rr)
    return results


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    out_path = argv[0] if argv else os.path.join(os.path.dirname(os.path.abspath(__file__)), "converter_goldens.h")
    tmp = tempfile.mkdtemp()
    results = build_and_render(ROWS, os.path.join(tmp, "goldens.exr"))
    lines = ["// Generated by tests/native/golden/make_converter_goldens.py from Blender %s's Cycles; do not edit."
             % bpy.app.version_string,
             "// Each case: the op, its params, its inputs (floats in the op's input order, a vector as three), the",
             "// outputs compared (indices), the values Cycles rendered for them (concatenated), the table (-1: none)",
             "// and a label. The tables follow the layouts in native/src/nodes/converter_nodes.cpp.",
             "#pragma once", "", "#include \"photonsplat/shader_program.h\"", "",
             "namespace ps {", "",
             "struct ConverterGolden {",
             "    ShaderOp op;",
             "    int n_params;",
             "    int params[3];",
             "    int n_in;",
             "    float in[18];",
             "    int n_outs;",
             "    int outs[3];",
             "    int n_expect;",
             "    float expect[9];",
             "    int table;",
             "    const char* label;",
             "};", "", "// clang-format off"]
    tables = []
    cases = []
    for r, res in zip(ROWS, results):
        table = -1
        if "table" in r:
            table = len(tables)
            tables.append(r["table"])
        for ci, (case, vals) in enumerate(zip(r["cases"], res)):
            flat = []
            for v in case:
                flat += list(v) if isinstance(v, (tuple, list)) else [v]
            cases.append("    {ShaderOp::%s, %d, {%s}, %d, {%s}, %d, {%s}, %d, {%s}, %d, \"%s #%d\"}," % (
                r["op"], len(r["params"]), ", ".join(str(p) for p in r["params"]), len(flat),
                ", ".join(cfloat(v) for v in flat), len(r["our_outs"]), ", ".join(str(o) for o in r["our_outs"]),
                len(vals), ", ".join(cfloat(v) for v in vals), table, r["label"], ci))
    for i, t in enumerate(tables):
        lines.append("inline const float kConverterGoldenTable%d[] = {%s};" % (i, ", ".join(cfloat(v) for v in t)))
    lines.append("inline const float* const kConverterGoldenTables[] = {%s};" % ", ".join(
        "kConverterGoldenTable%d" % i for i in range(len(tables))))
    lines.append("inline const ConverterGolden kConverterGoldens[] = {")
    lines += cases
    lines.append("};")
    lines.append("// clang-format on")
    lines.append("")
    lines.append("}  // namespace ps")
    with open(out_path, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("wrote %s: %d rows, %d cases, %d tables" % (out_path, len(ROWS),
                                                      sum(len(r["cases"]) for r in ROWS), len(tables)))


main()
