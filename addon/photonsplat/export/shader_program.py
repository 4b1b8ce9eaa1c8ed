"""Node programs: the node graph that drives a material's closure inputs, compiled to the flat op list the core
interprets at each hit (native/include/photonsplat/shader_program.h), as Cycles' SVM compiler does.

A ProgramBuilder holds the register file (constants and unconnected socket values are registers with initial
values), the instructions, the tables (baked ramps and curves, matrices) and what the program needs of the scene
(mesh attributes by name, Generated coordinates' texture space, Object Info). `value_of(socket)` gives a socket's
symbolic Value: a Python constant (a float, or a 3-tuple for a colour or vector) or a Reg (a register and its type,
'f' one register, 'v' three). It follows links through reroutes, muted nodes (their internal links), node groups
(flattened: Group Output and Group Input sockets are looked through) and Blender's implicit conversions (colour ->
float is the luminance, vector -> float the average, float -> vector a broadcast, colour <-> vector the same
registers). Each node is compiled once per (node, group nesting, bump offset): a Bump node compiles its Height
subgraph three times, with the shading point ops' `bump` param 0, 1 and 2 and its filter width (compat.py).

Every node of Cycles 3.4's SVM that reads the shading point or computes is compiled to its op (NODES lists them);
anything else (Point Density, IES, AO, Bevel, Wireframe, Script, Light Falloff, ...) gives its output
sockets' own default values (black, 0) and a note names the node. Nodes of Blender 4.x/5.x map to the 3.4 ops
where they match exactly and are approximated with a note where they do not (Noise's fractal types and
Lacunarity, Voronoi's Detail, Math's Floored Modulo, Mix's Exclusion...).

The arithmetic helpers (mul, add, sub, one_minus, lerp, clamp01, ...) fold constants in Python and emit math,
vector_math or mix ops otherwise: the material lowering (materials.py) writes its formulas once for both.

The op table (names, ids, param and operand counts) comes from the core, photonsplat._core.shader_ops(), read once.
"""

import math
import struct

import numpy as np

from .. import compat

# Blender's colour -> float conversion (Cycles' linear_rgb_to_gray), as the core's color_to_float.
LUMINANCE = (0.2126, 0.7152, 0.0722)

# Cycles bakes colour ramps and curves into this many entries (RAMP_TABLE_SIZE).
TABLE_SIZE = 256

# The Geometry node's Pointiness (per vertex) and Random Per Island (per face) are mesh attributes that the mesh
# export computes as Cycles' Blender sync does (export/mesh.py), under names no Blender attribute can have.
POINTINESS = "\x01pointiness"
RANDOM_PER_ISLAND = "\x01random_per_island"
# A UV map's MikkTSpace tangents and bitangent signs, per corner (Normal Map in tangent space): this prefix and the
# UV map's name ("" the render UV map).
TANGENT_PREFIX = "\x01tangent:"

# Cycles renders an Image Texture node without an image in magenta.
MISSING_IMAGE_COLOR = (1.0, 0.0, 1.0)

_op_table = None
_op_table_override = None


def use_op_table(ops):
    """Replaces the core's op table (a list as shader_ops() returns it; None: the core's again). For tests of the
    compiler against a core that does not have programs yet."""
    global _op_table_override
    _op_table_override = None if ops is None else {op["name"]: dict(op) for op in ops}


def op_table():
    """{op name: {"name", "id", "params", "inputs", "outputs"}} from the core, read once; None when the core has
    no node programs (then materials are lowered as constants, as before programs)."""
    global _op_table
    if _op_table_override is not None:
        return _op_table_override
    if _op_table is None:
        try:
            from .. import _core
            ops = _core.shader_ops()
        except (ImportError, AttributeError):
            ops = None
        _op_table = {} if not ops else {op["name"]: dict(op) for op in ops}
    return _op_table or None


class Reg:
    """A register operand: `index` is the first register, `type` 'f' (one) or 'v' (three)."""
    __slots__ = ("index", "type")

    def __init__(self, index, type):
        self.index, self.type = index, type

    def __eq__(self, other):
        return isinstance(other, Reg) and (self.index, self.type) == (other.index, other.type)

    def __hash__(self):
        return hash((self.index, self.type))

    def __repr__(self):
        return f"Reg({self.index}, {self.type!r})"

    def component(self, k):
        """Register aliasing: component k of a vector register (Separate XYZ / RGB)."""
        return Reg(self.index + k, "f") if self.type == "v" else self


def is_reg(value):
    return isinstance(value, Reg)


def is_const(value):
    return not isinstance(value, Reg)


class AttributeParam:
    """A param that is a mesh attribute id, known only once the core scene names it (scene.attribute_id)."""
    __slots__ = ("name",)

    def __init__(self, name):
        self.name = name


class TextureParam:
    """A param that is a core texture index (export/textures.py TextureRef, added by the sync)."""
    __slots__ = ("reference",)

    def __init__(self, reference):
        self.reference = reference


# --- socket kinds and conversions ---------------------------------------------------------------------------

_FLOAT_SOCKETS = {"VALUE", "INT", "BOOLEAN"}
_VECTOR_SOCKETS = {"VECTOR", "RGBA", "ROTATION"}


def socket_kind(socket):
    """'f', 'color', 'vector' or None (shader, string, object...: no value)."""
    t = socket.type
    if t in _FLOAT_SOCKETS:
        return "f"
    if t == "RGBA":
        return "color"
    if t in _VECTOR_SOCKETS:
        return "vector"
    return None


def float_bits(value):
    """A float as the int32 param that holds its bits (the core reads it back with OpArgs::param_float)."""
    return struct.unpack("<i", struct.pack("<f", float(value)))[0]


def constant_of(socket):
    """A socket's own value as a constant of its kind (0 where it has none)."""
    kind = socket_kind(socket)
    value = getattr(socket, "default_value", None)
    if kind is None or value is None:
        return 0.0
    if kind == "f":
        try:
            return float(value)
        except (TypeError, ValueError):
            return 0.0
    try:
        values = tuple(float(c) for c in tuple(value)[:3])
    except TypeError:
        return (float(value),) * 3
    return values + (0.0,) * (3 - len(values))


def _finite(value, default):
    if isinstance(value, tuple):
        return tuple(v if math.isfinite(v) else default for v in value)
    return value if math.isfinite(value) else default


# --- the builder --------------------------------------------------------------------------------------------

class ProgramBuilder:
    """One material's program being compiled; see the module docstring."""

    def __init__(self, ops, notes):
        self.ops = ops
        self.notes = notes
        self.registers = []          # initial values
        self.instructions = []       # [op name, params, input register indices, output register indices]
        self.tables = []
        self.attributes = []         # mesh attribute names the program reads, in first-use order
        self.uses_texspace = False   # Generated coordinates: the mesh's texture space
        self.uses_object_info = False
        self.bump = 0                # the shading point offset of the ops emitted now (Bump's height)
        self.bump_width = 1.0        # and the Bump node's filter width, the offset's length in differentials
        self.material_index = 0      # the material's pass index (Object Info's Material Index)
        self._memo = {}
        self._constants = {}
        self._depth = 0

    # -- registers and instructions --
    def constant(self, value):
        """A register holding `value` (a float or a 3-tuple), shared by equal constants."""
        key = tuple(value) if isinstance(value, tuple) else float(value)
        reg = self._constants.get(key)
        if reg is None:
            if isinstance(key, tuple):
                reg = Reg(len(self.registers), "v")
                self.registers.extend(float(c) for c in key)
            else:
                reg = Reg(len(self.registers), "f")
                self.registers.append(key)
            self._constants[key] = reg
        return reg

    def _fresh(self, type):
        reg = Reg(len(self.registers), type)
        self.registers.extend([0.0] * (3 if type == "v" else 1))
        return reg

    def operand(self, value, type):
        """The register of `value` as an operand of type 'f' or 'v' (emitting a conversion when needed)."""
        if type == "v":
            if isinstance(value, Reg):
                return value if value.type == "v" else self.emit("float_to_vector", [], [value])[0]
            if not isinstance(value, tuple):
                value = (float(value),) * 3
            return self.constant(value)
        if isinstance(value, Reg):
            return value if value.type == "f" else self.emit("vector_to_float", [], [value])[0]
        if isinstance(value, tuple):
            value = sum(value) / 3.0
        return self.constant(value)

    def emit(self, op, params, inputs):
        """Appends op `op`; `inputs` are Values in the op's input order. Returns the output Regs."""
        info = self.ops[op]
        if len(params) != info["params"] or len(inputs) != len(info["inputs"]):
            raise ValueError(f"shader op {op}: {len(params)} params and {len(inputs)} inputs given")
        registers = [self.operand(v, t) for v, t in zip(inputs, info["inputs"])]
        outputs = [self._fresh(t) for t in info["outputs"]]
        self.instructions.append([op, list(params), [r.index for r in registers], [r.index for r in outputs]])
        return outputs

    def table(self, values):
        """Appends `values` to the tables; returns their offset."""
        offset = len(self.tables)
        self.tables.extend(float(v) for v in values)
        return offset

    def attribute(self, name):
        if name not in self.attributes:
            self.attributes.append(name)
        return AttributeParam(name)

    @property
    def empty(self):
        return not self.instructions

    # -- the encoding --
    def encode(self, outputs, texture_index=None, attribute_id=None):
        """The program dict of the core's add_material(program=...): `outputs` are (target, closure index, Reg)
        triples; texture_index(TextureRef) and attribute_id(name) give the core's indices (without them: -1 and
        the attribute's position in self.attributes)."""
        registers = list(self.registers)
        code = []

        def const(value):
            registers.extend(value if isinstance(value, tuple) else (value,))
            return len(registers) - (3 if isinstance(value, tuple) else 1)

        for op, params, inputs, outs in self.instructions:
            resolved = []
            for p in params:
                if isinstance(p, TextureParam):
                    p = -1 if texture_index is None else int(texture_index(p.reference))
                elif isinstance(p, AttributeParam):
                    p = (int(attribute_id(p.name)) if attribute_id is not None
                         else self.attributes.index(p.name))
                resolved.append(int(p))
            if op in ("image_texture", "environment_texture") and resolved[0] < 0:
                # Unreadable image: Cycles' magenta, alpha 1.
                for name, source, target in (("copy_vector", const(MISSING_IMAGE_COLOR), outs[0]),
                                             ("copy_float", const(1.0), outs[1])):
                    code += [self.ops[name]["id"], 0, 1, 1, source, target]
                continue
            code += [self.ops[op]["id"], len(resolved), len(inputs), len(outs), *resolved, *inputs, *outs]
        return {"code": code, "registers": registers, "tables": list(self.tables),
                "outputs": [{"target": t, "index": int(i), "register": r.index} for t, i, r in outputs]}

    # -- values of sockets --
    def value_of(self, socket, stack=()):
        """The Value an input socket receives, converted to the socket's own kind."""
        from .materials import follow
        out, own, inner = follow(socket, stack)
        if out is None:
            value, kind = constant_of(own), socket_kind(own)
        else:
            value, kind = self.output_value(out, inner), socket_kind(out)
        return self.convert(value, kind, socket_kind(socket))

    def convert(self, value, source, target):
        """Blender's implicit conversion of a Value of kind `source` to kind `target`."""
        if target is None or source == target or (source != "f" and target != "f"):
            return value
        if target == "f":
            if isinstance(value, Reg):
                if value.type == "f":
                    return value
                op = "color_to_float" if source == "color" else "vector_to_float"
                return self.emit(op, [], [value])[0]
            if not isinstance(value, tuple):
                return float(value)
            if source == "color":
                return sum(w * c for w, c in zip(LUMINANCE, value))
            return sum(value) / 3.0
        # float -> vector or colour: a broadcast
        if isinstance(value, Reg):
            return value if value.type == "v" else self.emit("float_to_vector", [], [value])[0]
        if isinstance(value, tuple):
            return value
        return (float(value),) * 3

    def output_value(self, out, stack):
        """The Value of output socket `out` of a node inside the group nesting `stack`."""
        node = out.node
        key = (node.as_pointer(), tuple(n.as_pointer() for n in stack), self.bump, self.bump_width)
        results = self._memo.get(key)
        if results is None:
            if self._depth > 200:
                raise RecursionError("node graph too deep")
            self._depth += 1
            try:
                results = compile_node(self, node, stack)
            finally:
                self._depth -= 1
            self._memo[key] = results
        value = results.get(out.identifier)
        if value is None:
            value = constant_of(out)
            if node.bl_idname in NODES:
                self.notes.append(f"{node.bl_label} node's output '{out.name}' is not interpreted: "
                                  f"{_describe(value)} used")
        return value

    def inp(self, node, key, stack, default=0.0):
        """The Value of `node`'s input `key` (identifier, else name); `default` when the node has none."""
        socket = _socket(node.inputs, key)
        if socket is None:
            return default
        return self.value_of(socket, stack)

    def with_bump(self, offset, width, compute):
        # The centre is the point itself whatever the width: one compile serves the height and any other use.
        saved = self.bump, self.bump_width
        self.bump, self.bump_width = offset, (width if offset else 1.0)
        try:
            return compute()
        finally:
            self.bump, self.bump_width = saved

    def point_params(self, *params):
        """The params of an op that reads the shading point: the bump offset, `params`, the filter width."""
        return [self.bump, *params, float_bits(self.bump_width)]


def _socket(sockets, key):
    for s in sockets:
        if s.identifier == key:
            return s
    for s in sockets:
        if s.name == key:
            return s
    return None


def _describe(value):
    if isinstance(value, tuple):
        return "(" + ", ".join(f"{c:g}" for c in value) + ")"
    return f"{value:g}"


# --- arithmetic on Values ------------------------------------------------------------------------------------

# Cycles' NodeMathType and NodeVectorMathType (svm/types.h), in order.
MATH_OPS = ["ADD", "SUBTRACT", "MULTIPLY", "DIVIDE", "SINE", "COSINE", "TANGENT", "ARCSINE", "ARCCOSINE",
            "ARCTANGENT", "POWER", "LOGARITHM", "MINIMUM", "MAXIMUM", "ROUND", "LESS_THAN", "GREATER_THAN",
            "MODULO", "ABSOLUTE", "ARCTAN2", "FLOOR", "CEIL", "FRACT", "SQRT", "INVERSE_SQRT", "SIGN", "EXPONENT",
            "RADIANS", "DEGREES", "SINH", "COSH", "TANH", "TRUNC", "SNAP", "WRAP", "COMPARE", "MULTIPLY_ADD",
            "PINGPONG", "SMOOTH_MIN", "SMOOTH_MAX"]
VECTOR_MATH_OPS = ["ADD", "SUBTRACT", "MULTIPLY", "DIVIDE", "CROSS_PRODUCT", "PROJECT", "REFLECT", "DOT_PRODUCT",
                   "DISTANCE", "LENGTH", "SCALE", "NORMALIZE", "SNAP", "FLOOR", "CEIL", "MODULO", "FRACTION",
                   "ABSOLUTE", "MINIMUM", "MAXIMUM", "WRAP", "SINE", "COSINE", "TANGENT", "REFRACT", "FACEFORWARD",
                   "MULTIPLY_ADD"]


def _fold_math(op, a, b):
    if op == "ADD":
        return a + b
    if op == "SUBTRACT":
        return a - b
    if op == "MULTIPLY":
        return a * b
    if op == "DIVIDE":
        return a / b if b != 0.0 else 0.0
    if op == "MINIMUM":
        return min(a, b)
    if op == "MAXIMUM":
        return max(a, b)
    if op == "SQRT":
        return math.sqrt(a) if a > 0.0 else 0.0
    if op == "POWER":
        try:
            return math.pow(a, b) if a >= 0.0 or float(b).is_integer() else 0.0
        except (OverflowError, ValueError):
            return 0.0
    if op == "LOGARITHM":
        return math.log(a) / math.log(b) if a > 0.0 and b > 0.0 and b != 1.0 else 0.0
    raise KeyError(op)


def math_op(b, op, x, y=0.0, clamp=False):
    """Cycles' Math node on two Values (folded when both are constant floats)."""
    if is_const(x) and is_const(y) and not isinstance(x, tuple) and not isinstance(y, tuple):
        try:
            r = _fold_math(op, float(x), float(y))
            return min(max(r, 0.0), 1.0) if clamp else r
        except KeyError:
            pass
    return b.emit("math", [MATH_OPS.index(op), int(clamp)], [x, y, 0.0])[0]


def _vec(v):
    return v if isinstance(v, tuple) else (float(v),) * 3


def _is_vector(v):
    return isinstance(v, tuple) or (isinstance(v, Reg) and v.type == "v")


def _identity(b, const, other, neutral):
    """`other` when the constant `const` is the neutral element (0 for add, 1 for mul), else None; an absorbing 0 of
    mul gives 0. The result keeps the vector kind of either operand."""
    values = const if isinstance(const, tuple) else (const,)
    vector = _is_vector(const) or _is_vector(other)
    if neutral == 1.0 and all(v == 0.0 for v in values):
        return (0.0,) * 3 if vector else 0.0
    if all(v == neutral for v in values):
        return as_vector(b, other) if vector else other
    return None


def mul(b, x, y):
    for const, other in ((x, y), (y, x)):
        if is_const(const) and is_reg(other):
            folded = _identity(b, const, other, 1.0)
            if folded is not None:
                return folded
    if is_const(x) and is_const(y):
        if isinstance(x, tuple) or isinstance(y, tuple):
            if not isinstance(y, tuple):
                return tuple(c * y for c in x)
            if not isinstance(x, tuple):
                return tuple(x * c for c in y)
            return tuple(p * q for p, q in zip(x, y))
        return x * y
    if _is_float(x) and _is_float(y):
        return math_op(b, "MULTIPLY", x, y)
    if _is_float(y):
        return b.emit("vector_math", [VECTOR_MATH_OPS.index("SCALE")], [x, (0.0,) * 3, (0.0,) * 3, y])[0]
    if _is_float(x):
        return b.emit("vector_math", [VECTOR_MATH_OPS.index("SCALE")], [y, (0.0,) * 3, (0.0,) * 3, x])[0]
    return b.emit("vector_math", [VECTOR_MATH_OPS.index("MULTIPLY")], [x, y, (0.0,) * 3, 1.0])[0]


def _is_float(v):
    return (isinstance(v, Reg) and v.type == "f") or isinstance(v, (int, float))


def _binary(b, op, x, y, fold):
    if is_const(x) and is_const(y):
        if isinstance(x, tuple) or isinstance(y, tuple):
            return tuple(fold(p, q) for p, q in zip(_vec(x), _vec(y)))
        return fold(x, y)
    if _is_float(x) and _is_float(y):
        return math_op(b, op, x, y)
    return b.emit("vector_math", [VECTOR_MATH_OPS.index(op)], [x, y, (0.0,) * 3, 1.0])[0]


def add(b, x, y):
    for const, other in ((x, y), (y, x)):
        if is_const(const) and is_reg(other):
            folded = _identity(b, const, other, 0.0)
            if folded is not None:
                return folded
    return _binary(b, "ADD", x, y, lambda p, q: p + q)


def sub(b, x, y):
    return _binary(b, "SUBTRACT", x, y, lambda p, q: p - q)


def minimum(b, x, y):
    return _binary(b, "MINIMUM", x, y, min)


def maximum(b, x, y):
    return _binary(b, "MAXIMUM", x, y, max)


def divide(b, x, y):
    return _binary(b, "DIVIDE", x, y, lambda p, q: p / q if q != 0.0 else 0.0)


def one_minus(b, x):
    return sub(b, (1.0,) * 3 if isinstance(x, tuple) or (is_reg(x) and x.type == "v") else 1.0, x)


def lerp(b, x, y, t):
    """(1 - t) x + t y, as materials' _mix (t not clamped)."""
    if is_const(x) and is_const(y) and is_const(t):
        if isinstance(x, tuple) or isinstance(y, tuple):
            return tuple((1.0 - t) * p + t * q for p, q in zip(_vec(x), _vec(y)))
        return (1.0 - t) * x + t * y
    if _is_float(x) and _is_float(y):
        return b.emit("mix_float", [0], [t, x, y])[0]
    return b.emit("mix_vector", [0], [t, x, y])[0]


def clamp01(b, x):
    if is_const(x):
        if isinstance(x, tuple):
            return tuple(min(max(c, 0.0), 1.0) for c in x)
        return min(max(x, 0.0), 1.0)
    if x.type == "f":
        return math_op(b, "ADD", x, 0.0, clamp=True)
    return maximum(b, minimum(b, x, (1.0,) * 3), (0.0,) * 3)


def clamp_min(b, x, low):
    if is_const(x):
        return max(x, low)
    return math_op(b, "MAXIMUM", x, low)


def sqrt(b, x):
    return math_op(b, "SQRT", x)


def square(b, x):
    return mul(b, x, x)


def dot(b, x, y):
    if is_const(x) and is_const(y):
        return sum(p * q for p, q in zip(_vec(x), _vec(y)))
    return b.emit("vector_math", [VECTOR_MATH_OPS.index("DOT_PRODUCT")], [x, y, (0.0,) * 3, 1.0])[1]


def components(x):
    if is_const(x):
        return tuple(_vec(x))
    return tuple(x.component(k) for k in range(3)) if x.type == "v" else (x, x, x)


def max_component(b, x):
    if is_const(x):
        return max(_vec(x))
    r, g, bl = components(x)
    return maximum(b, maximum(b, r, g), bl)


def as_vector(b, x):
    if isinstance(x, Reg):
        return x if x.type == "v" else b.convert(x, "f", "vector")
    return _vec(x)


def positive(value, cutoff):
    """Whether a weight may exceed `cutoff`: known for constants, assumed for registers."""
    if is_reg(value):
        return True
    if isinstance(value, tuple):
        return max(value) > cutoff
    return value > cutoff


# --- nodes ---------------------------------------------------------------------------------------------------

def _dims(value):
    return {"1D": 1, "2D": 2, "3D": 3, "4D": 4}.get(value, 3)


def _outs(names, regs):
    return dict(zip(names, regs))


def _texco_default(b, kind):
    """A texture's unconnected Vector: Generated coordinates (Cycles' LINK_TEXTURE_GENERATED), UV, or the
    position."""
    if kind == "uv":
        return b.emit("uv_map", b.point_params(-1), [])[0]
    if kind == "position":
        return b.emit("geometry", b.point_params(-1, -1), [])[0]
    b.uses_texspace = True
    return b.emit("texture_coordinate", b.point_params(-1), [])[0]


def _vector_input(b, node, stack, default="generated"):
    socket = _socket(node.inputs, "Vector")
    if socket is not None and socket.is_linked:
        from .materials import follow
        out, _, _ = follow(socket, stack)
        if out is not None:
            return b.value_of(socket, stack)
    return _texco_default(b, default)


def _normal_input(b, node, stack, key="Normal"):
    """An unconnected Normal input is the shading normal (LINK_NORMAL)."""
    socket = _socket(node.inputs, key)
    if socket is not None and socket.is_linked:
        from .materials import follow
        out, _, _ = follow(socket, stack)
        if out is not None:
            return b.value_of(socket, stack), True
    return b.emit("geometry", b.point_params(-1, -1), [])[1], False


def _n_value(b, node, stack):
    return {"Value": constant_of(node.outputs[0])}


def _n_rgb(b, node, stack):
    return {"Color": constant_of(node.outputs[0])}


def _n_texture_coordinate(b, node, stack):
    matrix = -1
    ob = getattr(node, "object", None)
    if ob is not None:
        world_to_object = np.array(ob.matrix_world.inverted(), dtype=np.float64)
        matrix = b.table(world_to_object.T.reshape(-1))          # column-major
    if getattr(node, "from_instancer", False):
        b.notes.append("Texture Coordinate 'From Instancer' ignored (the instance's own coordinates used)")
    b.uses_texspace = True
    regs = b.emit("texture_coordinate", b.point_params(matrix), [])
    return _outs(["Generated", "Normal", "UV", "Object", "Camera", "Window", "Reflection"], regs)


def _n_uv_map(b, node, stack):
    if getattr(node, "from_instancer", False):
        b.notes.append("UV Map 'From Instancer' ignored (the instance's own UV map used)")
    name = getattr(node, "uv_map", "")
    return {"UV": b.emit("uv_map", b.point_params(b.attribute(name) if name else -1), [])[0]}


def _n_attribute(b, node, stack):
    kind = getattr(node, "attribute_type", "GEOMETRY")
    name = getattr(node, "attribute_name", "")
    if kind != "GEOMETRY" or not name:
        what = f"{kind.lower()} attribute" if kind != "GEOMETRY" else "attribute without a name"
        b.notes.append(f"Attribute node ({what} '{name}') not supported: black, 0 used")
        return {"Color": (0.0,) * 3, "Vector": (0.0,) * 3, "Fac": 0.0, "Alpha": 0.0}
    regs = b.emit("attribute", b.point_params(b.attribute(name)), [])
    return _outs(["Color", "Vector", "Fac", "Alpha"], regs)


def _n_vertex_color(b, node, stack):
    # An empty name is the mesh's default colour attribute (the mesh export resolves "").
    name = getattr(node, "layer_name", "")
    regs = b.emit("attribute", b.point_params(b.attribute(name)), [])
    return {"Color": regs[0], "Alpha": regs[3]}


def _n_geometry(b, node, stack):
    # Pointiness and Random Per Island cost the mesh export a pass over its edges: asked for only when linked.
    params = []
    for socket, name in (("Pointiness", POINTINESS), ("Random Per Island", RANDOM_PER_ISLAND)):
        output = _socket(node.outputs, socket)
        params.append(b.attribute(name) if output is not None and output.is_linked else -1)
    regs = b.emit("geometry", b.point_params(*params), [])
    return _outs(["Position", "Normal", "Tangent", "True Normal", "Incoming", "Parametric", "Backfacing",
                  "Pointiness", "Random Per Island"], regs)


def _n_object_info(b, node, stack):
    b.uses_object_info = True
    results = _outs(["Location", "Color", "Alpha", "Object Index", "Material Index", "Random"],
                    b.emit("object_info", [], []))
    results["Material Index"] = float(b.material_index)    # the op's is 0: the material's pass index is known here
    return results


_LIGHT_PATH = ["Is Camera Ray", "Is Shadow Ray", "Is Diffuse Ray", "Is Glossy Ray", "Is Singular Ray",
               "Is Reflection Ray", "Is Transmission Ray", "Ray Length", "Ray Depth", "Diffuse Depth",
               "Glossy Depth", "Transparent Depth", "Transmission Depth"]


def _n_light_path(b, node, stack):
    results = _outs(_LIGHT_PATH, b.emit("light_path", [], []))
    for out in node.outputs:
        if out.identifier not in results:
            results[out.identifier] = 0.0
            if out.is_linked:
                b.notes.append(f"Light Path '{out.name}' not supported: 0 used")
    return results


def _n_camera_data(b, node, stack):
    return _outs(["View Vector", "View Z Depth", "View Distance"], b.emit("camera_data", [], []))


def _n_fresnel(b, node, stack):
    normal, _ = _normal_input(b, node, stack)
    return {"Fac": b.emit("fresnel", [], [b.inp(node, "IOR", stack), normal])[0]}


def _n_layer_weight(b, node, stack):
    normal, _ = _normal_input(b, node, stack)
    return _outs(["Fresnel", "Facing"], b.emit("layer_weight", [], [b.inp(node, "Blend", stack), normal]))


_INTERPOLATION = {"Linear": 0, "Closest": 1, "Cubic": 2, "Smart": 3}
_EXTENSION = {"REPEAT": 0, "EXTEND": 1, "CLIP": 2, "MIRROR": 3}
_PROJECTION = {"FLAT": 0, "BOX": 1, "SPHERE": 2, "TUBE": 3}
_DATA_SPACES = {"Non-Color", "Raw", "Generic Data"}


def _n_image_texture(b, node, stack):
    from . import textures
    reference, color = textures.texture_reference(node, b.notes, program=True)
    if reference is None:
        return {"Color": color, "Alpha": 1.0}
    vector = _vector_input(b, node, stack, default="uv")
    params = [TextureParam(reference), _INTERPOLATION.get(node.interpolation, 0),
              _EXTENSION.get(node.extension, 0), _PROJECTION.get(node.projection, 0), _alpha_mode(node)]
    regs = b.emit("image_texture", params, [vector, float(getattr(node, "projection_blend", 0.0))])
    return _outs(["Color", "Alpha"], regs)


def _alpha_mode(node):
    """The image op's alpha param as Cycles' ImageTextureNode decides it: channel-packed or ignored alpha, and data
    images, give the stored colour (2); otherwise Cycles holds the image associated and unassociates it only when
    the Alpha output is linked (0, the straight colour), else the colour is the associated colour x alpha (1)."""
    image = node.image
    if (getattr(image, "alpha_mode", "STRAIGHT") in ("CHANNEL_PACKED", "NONE")
            or image.colorspace_settings.name in _DATA_SPACES):
        return 2
    return 0 if _socket(node.outputs, "Alpha").is_linked else 1


def _n_environment_texture(b, node, stack):
    from . import textures
    reference, color = textures.texture_reference(node, b.notes, program=True)
    if reference is None:
        return {"Color": color, "Alpha": 1.0}
    vector = _vector_input(b, node, stack, default="position")
    projection = {"EQUIRECTANGULAR": 0, "MIRROR_BALL": 1}.get(node.projection, 0)
    regs = b.emit("environment_texture", [TextureParam(reference), _INTERPOLATION.get(node.interpolation, 0),
                                          projection], [vector])
    return _outs(["Color", "Alpha"], regs)


_NORMAL_MAP_SPACES = {"TANGENT": 0, "OBJECT": 1, "WORLD": 2, "BLENDER_OBJECT": 3, "BLENDER_WORLD": 4}


def _n_normal_map(b, node, stack):
    name = getattr(node, "uv_map", "")
    space = _NORMAL_MAP_SPACES.get(node.space, 0)
    # Tangent space reads the UV map's MikkTSpace tangents, as Cycles does.
    tangent = b.attribute(TANGENT_PREFIX + name) if space == 0 else -1
    params = [space, b.attribute(name) if name else -1, tangent]
    return {"Normal": b.emit("normal_map", params,
                             [b.inp(node, "Strength", stack), b.inp(node, "Color", stack)])[0]}


def _n_bump(b, node, stack):
    normal, connected = _normal_input(b, node, stack)
    height_socket = _socket(node.inputs, "Height")
    width_socket = _socket(node.inputs, "Filter Width")
    folded = None
    if width_socket is not None and width_socket.is_linked:
        value = b.value_of(width_socket, stack)      # not read where it varies: the core drops what nothing reads
        folded = value if is_const(value) else None
    width, note = compat.bump_filter_width(node, folded)
    if note:
        b.notes.append(note)
    heights = [b.with_bump(k, width, lambda: b.value_of(height_socket, stack)) for k in (0, 1, 2)]
    params = [int(getattr(node, "invert", False)), int(connected), float_bits(width)]
    inputs = [b.inp(node, "Strength", stack), b.inp(node, "Distance", stack), *heights, normal]
    return {"Normal": b.emit("bump", params, inputs)[0]}


def _n_normal(b, node, stack):
    direction = constant_of(_socket(node.outputs, "Normal"))
    regs = b.emit("normal", [], [direction, b.inp(node, "Normal", stack)])
    return _outs(["Normal", "Dot"], regs)


_SPACES = {"WORLD": 0, "OBJECT": 1, "CAMERA": 2}


def _n_vector_transform(b, node, stack):
    params = [{"VECTOR": 0, "POINT": 1, "NORMAL": 2}.get(node.vector_type, 0), _SPACES.get(node.convert_from, 0),
              _SPACES.get(node.convert_to, 0)]
    return {"Vector": b.emit("vector_transform", params, [b.inp(node, "Vector", stack)])[0]}


_MUSGRAVE_TYPES = {"MULTIFRACTAL": 0, "FBM": 1, "HYBRID_MULTIFRACTAL": 2, "RIDGED_MULTIFRACTAL": 3,
                   "HETERO_TERRAIN": 4}


def _n_noise(b, node, stack):
    dims = _dims(getattr(node, "noise_dimensions", "3D"))
    vector = _vector_input(b, node, stack)
    v = lambda key, default=0.0: b.inp(node, key, stack, default)      # noqa: E731
    noise_type = getattr(node, "noise_type", "FBM")
    normalize = getattr(node, "normalize", True)
    lacunarity = v("Lacunarity", 2.0)
    if noise_type == "FBM" and normalize and is_const(lacunarity) and lacunarity == 2.0:
        regs = b.emit("noise_texture", [dims], [vector, v("W"), v("Scale"), v("Detail"), v("Roughness"),
                                                 v("Distortion")])
        return _outs(["Fac", "Color"], regs)
    # Blender 4.1+: fractal types other than normalized fBM of lacunarity 2 are 3.4's Musgrave, whose Dimension
    # H gives the amplitude factor roughness = lacunarity^-H; Distortion and the colour output are not there.
    b.notes.append(f"Noise Texture ({noise_type.lower().replace('_', ' ')}"
                   + ("" if normalize or noise_type != "FBM" else ", not normalized")
                   + ") approximated by Cycles 3.4's Musgrave (no distortion, grey colour)")
    dimension = divide(b, math_op(b, "LOGARITHM", v("Roughness"), math.e),
                       math_op(b, "LOGARITHM", lacunarity, math.e))
    dimension = mul(b, dimension, -1.0)
    fac = b.emit("musgrave_texture", [dims, _MUSGRAVE_TYPES.get(noise_type, 1)],
                 [vector, v("W"), v("Scale"), v("Detail"), dimension, lacunarity, v("Offset"), v("Gain", 1.0)])[0]
    return {"Fac": fac, "Color": as_vector(b, fac)}


def _n_musgrave(b, node, stack):
    dims = _dims(node.musgrave_dimensions)
    vector = _vector_input(b, node, stack)
    inputs = [vector] + [b.inp(node, k, stack) for k in ("W", "Scale", "Detail", "Dimension", "Lacunarity",
                                                         "Offset", "Gain")]
    return {"Fac": b.emit("musgrave_texture", [dims, _MUSGRAVE_TYPES.get(node.musgrave_type, 1)], inputs)[0]}


_VORONOI_FEATURES = {"F1": 0, "F2": 1, "SMOOTH_F1": 2, "DISTANCE_TO_EDGE": 3, "N_SPHERE_RADIUS": 4}
_VORONOI_METRICS = {"EUCLIDEAN": 0, "MANHATTAN": 1, "CHEBYCHEV": 2, "MINKOWSKI": 3}


def _n_voronoi(b, node, stack):
    detail = b.inp(node, "Detail", stack, 0.0)
    if is_reg(detail) or detail > 0.0:
        b.notes.append("Voronoi Texture's Detail (fractal octaves) ignored: one octave, as Blender 3.4")
    params = [_dims(node.voronoi_dimensions), _VORONOI_FEATURES.get(node.feature, 0),
              _VORONOI_METRICS.get(node.distance, 0)]
    inputs = [_vector_input(b, node, stack)] + [b.inp(node, k, stack) for k in ("W", "Scale", "Smoothness",
                                                                               "Exponent", "Randomness")]
    return _outs(["Distance", "Color", "Position", "W", "Radius"], b.emit("voronoi_texture", params, inputs))


def _n_wave(b, node, stack):
    params = [{"BANDS": 0, "RINGS": 1}.get(node.wave_type, 0),
              {"X": 0, "Y": 1, "Z": 2, "DIAGONAL": 3}.get(node.bands_direction, 0),
              {"X": 0, "Y": 1, "Z": 2, "SPHERICAL": 3}.get(node.rings_direction, 3),
              {"SIN": 0, "SAW": 1, "TRI": 2}.get(node.wave_profile, 0)]
    inputs = [_vector_input(b, node, stack)] + [b.inp(node, k, stack) for k in (
        "Scale", "Distortion", "Detail", "Detail Scale", "Detail Roughness", "Phase Offset")]
    return _outs(["Color", "Fac"], b.emit("wave_texture", params, inputs))


def _n_magic(b, node, stack):
    inputs = [_vector_input(b, node, stack), b.inp(node, "Scale", stack), b.inp(node, "Distortion", stack)]
    return _outs(["Color", "Fac"], b.emit("magic_texture", [int(node.turbulence_depth)], inputs))


def _n_brick(b, node, stack):
    inputs = [_vector_input(b, node, stack)] + [b.inp(node, k, stack) for k in (
        "Color1", "Color2", "Mortar", "Scale", "Mortar Size", "Mortar Smooth", "Bias", "Brick Width",
        "Row Height")] + [float(node.offset), float(node.squash)]
    params = [int(node.offset_frequency), int(node.squash_frequency)]
    return _outs(["Color", "Fac"], b.emit("brick_texture", params, inputs))


def _n_checker(b, node, stack):
    inputs = [_vector_input(b, node, stack)] + [b.inp(node, k, stack) for k in ("Color1", "Color2", "Scale")]
    return _outs(["Color", "Fac"], b.emit("checker_texture", [], inputs))


# The op's gradient codes, as shader_program.h lists them (4 spherical, 6 radial).
_GRADIENTS = {"LINEAR": 0, "QUADRATIC": 1, "EASING": 2, "DIAGONAL": 3, "SPHERICAL": 4, "QUADRATIC_SPHERE": 5,
              "RADIAL": 6}


def _n_gradient(b, node, stack):
    regs = b.emit("gradient_texture", [_GRADIENTS.get(node.gradient_type, 0)], [_vector_input(b, node, stack)])
    return _outs(["Color", "Fac"], regs)


def _n_white_noise(b, node, stack):
    inputs = [_vector_input(b, node, stack, default="position"), b.inp(node, "W", stack)]
    return _outs(["Value", "Color"], b.emit("white_noise_texture", [_dims(node.noise_dimensions)], inputs))


# Sky Texture: the core's sky types (shader_program.h's sky_texture). Blender 5.0 names Nishita's variants
# 'SINGLE_SCATTERING' (3.4's Nishita above the horizon) and 'MULTIPLE_SCATTERING' (no 3.4 equivalent: single
# scattering is used); both are noted.
_SKY_TYPES = {"PREETHAM": 0, "HOSEK_WILKIE": 1, "NISHITA": 2, "SINGLE_SCATTERING": 2, "MULTIPLE_SCATTERING": 2}


def _prop(node, names, default):
    """The first of `names` that the node has (properties renamed between Blender versions)."""
    for name in names:
        value = getattr(node, name, None)
        if value is not None:
            return value
    return default


def _n_sky_texture(b, node, stack):
    kind = getattr(node, "sky_type", "NISHITA")
    sky = _SKY_TYPES.get(kind)
    if sky is None:
        b.notes.append(f"Sky Texture type '{kind}' not known: the Nishita sky used")
        sky = 2
    if kind == "HOSEK_WILKIE":
        b.notes.append("Hosek / Wilkie sky approximated by Preetham (same sun direction and turbidity; the ground "
                       "albedo is not used)")
    elif kind == "MULTIPLE_SCATTERING":
        b.notes.append("Sky Texture 'Multiple Scattering' approximated by Blender 3.4's single-scattering Nishita "
                       "sky")
    elif kind == "SINGLE_SCATTERING":
        # Blender 5.0 precomputes its texture over the whole sphere (black below the horizon) and folds sun
        # elevations beyond 90 degrees: the sky above the horizon is 3.4's, the rest may differ.
        b.notes.append("Sky Texture 'Single Scattering' evaluated as Blender 3.4's Nishita sky (the ground below "
                       "the horizon may differ)")
    disc = bool(getattr(node, "sun_disc", True)) and sky == 2
    direction = tuple(float(c) for c in _prop(node, ("sun_direction",), (0.0, 0.0, 1.0)))
    settings = list(direction[:3]) + [
        float(_prop(node, ("turbidity",), 2.2)),
        float(_prop(node, ("ground_albedo",), 0.3)),
        float(_prop(node, ("sun_size",), 0.545 * math.pi / 180.0)),
        float(_prop(node, ("sun_intensity",), 1.0)),
        float(_prop(node, ("sun_elevation",), 15.0 * math.pi / 180.0)),
        float(_prop(node, ("sun_rotation",), 0.0)),
        float(_prop(node, ("altitude",), 0.0)),
        float(_prop(node, ("air_density",), 1.0)),
        float(_prop(node, ("dust_density", "aerosol_density"), 1.0)),
        float(_prop(node, ("ozone_density",), 1.0)),
    ]
    settings = [_finite(v, 0.0) for v in settings]
    # With Nishita's sun disc Blender makes the Vector socket unavailable and Cycles ignores its link: the
    # default, Generated coordinates (the direction, in a world), is used.
    socket = _socket(node.inputs, "Vector")
    if socket is not None and not getattr(socket, "enabled", True):
        vector = _texco_default(b, "generated")
    else:
        vector = _vector_input(b, node, stack)
    regs = b.emit("sky_texture", [sky, int(disc), b.table(settings), -1], [vector])
    return {"Color": regs[0]}


def _n_math(b, node, stack):
    op = node.operation
    if op == "FLOORED_MODULO":
        b.notes.append("Math 'Floored Modulo' rendered as Cycles 3.4's truncated Modulo")
        op = "MODULO"
    if op not in MATH_OPS:
        b.notes.append(f"Math '{op}' not supported: 0 used")
        return {"Value": 0.0}
    inputs = [b.value_of(s, stack) for s in list(node.inputs)[:3]]
    inputs += [0.0] * (3 - len(inputs))
    return {"Value": b.emit("math", [MATH_OPS.index(op), int(node.use_clamp)], inputs)[0]}


def _n_vector_math(b, node, stack):
    op = node.operation
    if op not in VECTOR_MATH_OPS:
        b.notes.append(f"Vector Math '{op}' not supported: 0 used")
        return {"Vector": (0.0,) * 3, "Value": 0.0}
    inputs = [b.inp(node, k, stack) for k in ("Vector", "Vector_001", "Vector_002", "Scale")]
    return _outs(["Vector", "Value"], b.emit("vector_math", [VECTOR_MATH_OPS.index(op)], inputs))


_MAP_RANGE = {"LINEAR": 0, "STEPPED": 1, "SMOOTHSTEP": 2, "SMOOTHERSTEP": 3}


def _n_map_range(b, node, stack):
    params = [_MAP_RANGE.get(node.interpolation_type, 0), int(node.clamp)]
    sockets = list(node.inputs)
    if getattr(node, "data_type", "FLOAT") == "FLOAT_VECTOR":
        inputs = [b.value_of(s, stack) for s in sockets[6:12]]
        return {"Vector": b.emit("map_range_vector", params, inputs)[0]}
    inputs = [b.value_of(s, stack) for s in sockets[0:6]]
    return {"Result": b.emit("map_range", params, inputs)[0]}


def _n_clamp(b, node, stack):
    inputs = [b.inp(node, k, stack) for k in ("Value", "Min", "Max")]
    return {"Result": b.emit("clamp", [{"MINMAX": 0, "RANGE": 1}.get(node.clamp_type, 0)], inputs)[0]}


def _n_color_ramp(b, node, stack):
    ramp = node.color_ramp
    values = []
    for i in range(TABLE_SIZE):
        values.extend(tuple(ramp.evaluate(i / (TABLE_SIZE - 1)))[:4])
    offset = b.table(values)
    interpolate = int(ramp.interpolation != "CONSTANT")
    regs = b.emit("color_ramp", [offset, TABLE_SIZE, interpolate], [b.inp(node, "Fac", stack)])
    return _outs(["Color", "Alpha"], regs)


def _curve_range(curves):
    xs = [p.location[0] for c in curves for p in c.points]
    low, high = (min(xs), max(xs)) if xs else (0.0, 1.0)
    if high - low < 1e-8:
        high = low + 1.0
    return low, high


def _bake_curves(b, mapping, curves, compose=None):
    """min x, max x, then TABLE_SIZE entries of each curve (composed with `compose` first when given)."""
    mapping.initialize()
    low, high = _curve_range(list(curves) + ([compose] if compose is not None else []))
    values = [low, high]
    for i in range(TABLE_SIZE):
        x = low + (high - low) * i / (TABLE_SIZE - 1)
        for c in curves:
            t = mapping.evaluate(compose, x) if compose is not None else x
            values.append(mapping.evaluate(c, t))
    return b.table(values)


def _n_rgb_curves(b, node, stack):
    mapping = node.mapping
    curves = mapping.curves
    offset = _bake_curves(b, mapping, [curves[0], curves[1], curves[2]], compose=curves[3])
    inputs = [b.inp(node, "Fac", stack), b.inp(node, "Color", stack)]
    return {"Color": b.emit("rgb_curves", [offset, TABLE_SIZE], inputs)[0]}


def _n_vector_curves(b, node, stack):
    mapping = node.mapping
    offset = _bake_curves(b, mapping, list(mapping.curves)[:3])
    inputs = [b.inp(node, "Fac", stack), b.inp(node, "Vector", stack)]
    return {"Vector": b.emit("vector_curves", [offset, TABLE_SIZE], inputs)[0]}


def _n_float_curve(b, node, stack):
    mapping = node.mapping
    offset = _bake_curves(b, mapping, [mapping.curves[0]])
    inputs = [b.inp(node, "Factor", stack), b.inp(node, "Value", stack)]
    return {"Value": b.emit("float_curve", [offset, TABLE_SIZE], inputs)[0]}


# Blender's blend_type names -> Cycles' NodeMix.
_BLENDS = {"MIX": 0, "ADD": 1, "MULTIPLY": 2, "SUBTRACT": 3, "SCREEN": 4, "DIVIDE": 5, "DIFFERENCE": 6,
           "DARKEN": 7, "LIGHTEN": 8, "OVERLAY": 9, "DODGE": 10, "BURN": 11, "HUE": 12, "SATURATION": 13,
           "VALUE": 14, "COLOR": 15, "SOFT_LIGHT": 16, "LINEAR_LIGHT": 17}


def _blend(b, node):
    blend = node.blend_type
    if blend not in _BLENDS:
        b.notes.append(f"Mix blend '{blend.lower()}' rendered as Difference (Blender 3.4 has no such mode)")
        return _BLENDS["DIFFERENCE"]
    return _BLENDS[blend]


def _n_mix(b, node, stack):
    data_type = node.data_type
    clamp_factor = int(getattr(node, "clamp_factor", True))
    if data_type == "FLOAT":
        inputs = [b.inp(node, k, stack) for k in ("Factor_Float", "A_Float", "B_Float")]
        return {"Result_Float": b.emit("mix_float", [clamp_factor], inputs)[0]}
    if data_type == "VECTOR":
        if getattr(node, "factor_mode", "UNIFORM") == "NON_UNIFORM":
            inputs = [b.inp(node, k, stack) for k in ("Factor_Vector", "A_Vector", "B_Vector")]
            return {"Result_Vector": b.emit("mix_vector_nonuniform", [clamp_factor], inputs)[0]}
        inputs = [b.inp(node, k, stack) for k in ("Factor_Float", "A_Vector", "B_Vector")]
        return {"Result_Vector": b.emit("mix_vector", [clamp_factor], inputs)[0]}
    if data_type == "RGBA":
        inputs = [b.inp(node, k, stack) for k in ("Factor_Float", "A_Color", "B_Color")]
        params = [_blend(b, node), clamp_factor, int(getattr(node, "clamp_result", False))]
        return {"Result_Color": b.emit("mix_color", params, inputs)[0]}
    b.notes.append(f"Mix node of {data_type.lower()} not supported: its outputs are 0")
    return {}


def _n_mix_rgb(b, node, stack):
    # Cycles' legacy MixRGB clamps its factor (svm_mix_clamped_factor); Clamp is the result's.
    inputs = [b.inp(node, k, stack) for k in ("Fac", "Color1", "Color2")]
    params = [_blend(b, node), 1, int(node.use_clamp)]
    return {"Color": b.emit("mix_color", params, inputs)[0]}


def _n_hue_saturation(b, node, stack):
    inputs = [b.inp(node, k, stack) for k in ("Hue", "Saturation", "Value", "Fac", "Color")]
    return {"Color": b.emit("hue_saturation_value", [], inputs)[0]}


def _n_gamma(b, node, stack):
    return {"Color": b.emit("gamma", [], [b.inp(node, "Color", stack), b.inp(node, "Gamma", stack)])[0]}


def _n_bright_contrast(b, node, stack):
    inputs = [b.inp(node, k, stack) for k in ("Color", "Bright", "Contrast")]
    return {"Color": b.emit("bright_contrast", [], inputs)[0]}


def _n_invert(b, node, stack):
    return {"Color": b.emit("invert", [], [b.inp(node, "Fac", stack), b.inp(node, "Color", stack)])[0]}


_COLOR_MODES = {"RGB": 0, "HSV": 1, "HSL": 2}


def _n_separate_color(b, node, stack):
    mode = _COLOR_MODES.get(getattr(node, "mode", "RGB"), 0)
    color = b.inp(node, "Color", stack)
    if mode == 0:
        channels = components(color)
    else:
        channels = b.emit("separate_color", [mode], [color])
    return _outs(["Red", "Green", "Blue"], channels)


def _n_combine_color(b, node, stack):
    mode = _COLOR_MODES.get(getattr(node, "mode", "RGB"), 0)
    inputs = [b.inp(node, k, stack) for k in ("Red", "Green", "Blue")]
    if mode == 0:
        return {"Color": _combine(b, inputs)}
    return {"Color": b.emit("combine_color", [mode], inputs)[0]}


def _combine(b, inputs):
    if all(is_const(v) for v in inputs):
        return tuple(float(v) for v in inputs)
    return b.emit("combine_xyz", [], inputs)[0]


def _n_separate_rgb(b, node, stack):
    return _outs(["R", "G", "B"], components(b.inp(node, "Image", stack)))


def _n_combine_rgb(b, node, stack):
    return {"Image": _combine(b, [b.inp(node, k, stack) for k in ("R", "G", "B")])}


def _n_separate_hsv(b, node, stack):
    return _outs(["H", "S", "V"], b.emit("separate_color", [1], [b.inp(node, "Color", stack)]))


def _n_combine_hsv(b, node, stack):
    return {"Color": b.emit("combine_color", [1], [b.inp(node, k, stack) for k in ("H", "S", "V")])[0]}


def _n_separate_xyz(b, node, stack):
    return _outs(["X", "Y", "Z"], components(b.inp(node, "Vector", stack)))


def _n_combine_xyz(b, node, stack):
    return {"Vector": _combine(b, [b.inp(node, k, stack) for k in ("X", "Y", "Z")])}


def _n_rgb_to_bw(b, node, stack):
    return {"Val": b.emit("rgb_to_bw", [], [b.inp(node, "Color", stack)])[0]}


def _n_blackbody(b, node, stack):
    return {"Color": b.emit("blackbody", [], [b.inp(node, "Temperature", stack)])[0]}


def _n_wavelength(b, node, stack):
    return {"Color": b.emit("wavelength", [], [b.inp(node, "Wavelength", stack)])[0]}


def _n_mapping(b, node, stack):
    vector_type = {"POINT": 0, "TEXTURE": 1, "VECTOR": 2, "NORMAL": 3}.get(node.vector_type, 0)
    inputs = [b.inp(node, k, stack) for k in ("Vector", "Location", "Rotation", "Scale")]
    return {"Vector": b.emit("mapping", [vector_type], inputs)[0]}


_ROTATIONS = {"AXIS_ANGLE": 0, "X_AXIS": 1, "Y_AXIS": 2, "Z_AXIS": 3, "EULER_XYZ": 4}


def _n_vector_rotate(b, node, stack):
    params = [_ROTATIONS.get(node.rotation_type, 0), int(node.invert)]
    inputs = [b.inp(node, k, stack) for k in ("Vector", "Center", "Axis", "Angle", "Rotation")]
    return {"Vector": b.emit("vector_rotate", params, inputs)[0]}


NODES = {
    "ShaderNodeValue": _n_value,
    "ShaderNodeRGB": _n_rgb,
    "ShaderNodeTexCoord": _n_texture_coordinate,
    "ShaderNodeUVMap": _n_uv_map,
    "ShaderNodeAttribute": _n_attribute,
    "ShaderNodeVertexColor": _n_vertex_color,
    "ShaderNodeNewGeometry": _n_geometry,
    "ShaderNodeObjectInfo": _n_object_info,
    "ShaderNodeLightPath": _n_light_path,
    "ShaderNodeCameraData": _n_camera_data,
    "ShaderNodeFresnel": _n_fresnel,
    "ShaderNodeLayerWeight": _n_layer_weight,
    "ShaderNodeTexImage": _n_image_texture,
    "ShaderNodeTexEnvironment": _n_environment_texture,
    "ShaderNodeNormalMap": _n_normal_map,
    "ShaderNodeBump": _n_bump,
    "ShaderNodeNormal": _n_normal,
    "ShaderNodeVectorTransform": _n_vector_transform,
    "ShaderNodeTexNoise": _n_noise,
    "ShaderNodeTexVoronoi": _n_voronoi,
    "ShaderNodeTexMusgrave": _n_musgrave,
    "ShaderNodeTexWave": _n_wave,
    "ShaderNodeTexMagic": _n_magic,
    "ShaderNodeTexBrick": _n_brick,
    "ShaderNodeTexChecker": _n_checker,
    "ShaderNodeTexGradient": _n_gradient,
    "ShaderNodeTexWhiteNoise": _n_white_noise,
    "ShaderNodeTexSky": _n_sky_texture,
    "ShaderNodeMath": _n_math,
    "ShaderNodeVectorMath": _n_vector_math,
    "ShaderNodeMapRange": _n_map_range,
    "ShaderNodeClamp": _n_clamp,
    "ShaderNodeValToRGB": _n_color_ramp,
    "ShaderNodeRGBCurve": _n_rgb_curves,
    "ShaderNodeVectorCurve": _n_vector_curves,
    "ShaderNodeFloatCurve": _n_float_curve,
    "ShaderNodeMix": _n_mix,
    "ShaderNodeMixRGB": _n_mix_rgb,
    "ShaderNodeHueSaturation": _n_hue_saturation,
    "ShaderNodeGamma": _n_gamma,
    "ShaderNodeBrightContrast": _n_bright_contrast,
    "ShaderNodeInvert": _n_invert,
    "ShaderNodeSeparateColor": _n_separate_color,
    "ShaderNodeCombineColor": _n_combine_color,
    "ShaderNodeSeparateRGB": _n_separate_rgb,
    "ShaderNodeCombineRGB": _n_combine_rgb,
    "ShaderNodeSeparateHSV": _n_separate_hsv,
    "ShaderNodeCombineHSV": _n_combine_hsv,
    "ShaderNodeSeparateXYZ": _n_separate_xyz,
    "ShaderNodeCombineXYZ": _n_combine_xyz,
    "ShaderNodeRGBToBW": _n_rgb_to_bw,
    "ShaderNodeBlackbody": _n_blackbody,
    "ShaderNodeWavelength": _n_wavelength,
    "ShaderNodeMapping": _n_mapping,
    "ShaderNodeVectorRotate": _n_vector_rotate,
}


def compile_node(b, node, stack):
    """{output identifier: Value} of `node`; unsupported nodes give their outputs' own values, noted."""
    handler = NODES.get(node.bl_idname)
    if handler is None:
        b.notes.append(f"{node.bl_label} node not supported: its outputs use their default values "
                       "(usually black or 0)")
        return {out.identifier: constant_of(out) for out in node.outputs}
    try:
        results = handler(b, node, stack)
    except (AttributeError, KeyError, IndexError, TypeError, ValueError) as error:
        # A node of a Blender version whose properties or sockets differ from those mapped here.
        b.notes.append(f"{node.bl_label} node could not be compiled ({error}): its outputs use their "
                       "default values")
        return {out.identifier: constant_of(out) for out in node.outputs}
    return {key: _finite(value, 0.0) if is_const(value) else value for key, value in results.items()}
