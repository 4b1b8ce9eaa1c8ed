"""Node programs: the node graphs driving closure inputs, compiled by export/shader_program.py into the op list of
native/include/photonsplat/shader_program.h, and what materials.py makes of them (program outputs, constant folding).

The compiler reads its op table from the core (photonsplat._core.shader_ops()); these tests compile against the
header's own table when the core does not have programs yet, so the compiler is checked either way. End-to-end
renders need the core's interpreter and skip without it.
"""

import math
import re
from pathlib import Path

import bpy
import numpy as np
import pytest

from blender_helpers import enable_nodes
from photonsplat import compat, export
from photonsplat.export import materials, shader_program

HEADER = Path(__file__).resolve().parents[2] / "native" / "include" / "photonsplat" / "shader_program.h"


def header_op_table():
    """The op table of shader_program.h's X-macro, as shader_ops() returns it."""
    text = HEADER.read_text()
    body = text[text.index("#define PS_SHADER_OPS(X)"):text.index("// clang-format on")]
    body = re.sub(r"/\*.*?\*/", "", body, flags=re.S)
    ops = []
    for name, params, inputs, outputs in re.findall(r'X\((\w+),\s*(\d+),\s*"(\w*)",\s*"(\w*)"\)', body):
        ops.append(dict(name=name, id=len(ops), params=int(params), inputs=inputs, outputs=outputs))
    return ops


def core_has_programs():
    try:
        from photonsplat import _core
    except ImportError:
        return False
    return hasattr(_core, "shader_ops")


@pytest.fixture(autouse=True)
def op_table():
    """The core's table when it has one, the header's otherwise."""
    if not core_has_programs():
        shader_program.use_op_table(header_op_table())
    yield shader_program.op_table()
    shader_program.use_op_table(None)


# --- building materials -----------------------------------------------------------------------------------------

def diffuse_material(name="M"):
    """A material whose Surface is a Diffuse BSDF (Color, Roughness free for the test to drive)."""
    mat = bpy.data.materials.new(name)
    enable_nodes(mat)
    nodes = mat.node_tree.nodes
    nodes.clear()
    shader = nodes.new("ShaderNodeBsdfDiffuse")
    output = nodes.new("ShaderNodeOutputMaterial")
    mat.node_tree.links.new(shader.outputs[0], output.inputs["Surface"])
    return mat, mat.node_tree, shader


def decode(program, ops):
    """[(op name, params, inputs, outputs)] of an encoded program."""
    by_id = {op["id"]: op["name"] for op in ops.values()}
    code, i, result = program["code"], 0, []
    while i < len(code):
        op, n_params, n_inputs, n_outputs = code[i:i + 4]
        i += 4
        params = code[i:i + n_params]
        i += n_params
        inputs = code[i:i + n_inputs]
        i += n_inputs
        outputs = code[i:i + n_outputs]
        i += n_outputs
        result.append((by_id[op], params, inputs, outputs))
    return result


def program_of(mat, ops):
    """(spec, encoded program, decoded instructions): textures get core index 0, attributes their order."""
    spec = materials.convert_material(mat)
    program = spec.core_arguments(texture_index=lambda reference: 0).get("program")
    assert program is not None, spec.notes
    return spec, program, decode(program, ops)


def names(instructions):
    return [name for name, *_ in instructions]


def check_encoding(program, ops):
    """Every instruction has its op's counts; registers and tables are in range."""
    size = len(program["registers"])
    for name, params, inputs, outputs in decode(program, ops):
        op = ops[name]
        assert len(params) == op["params"] and len(inputs) == len(op["inputs"])
        assert len(outputs) == len(op["outputs"])
        for index, kind in list(zip(inputs, op["inputs"])) + list(zip(outputs, op["outputs"])):
            assert index == -1 or 0 <= index <= size - (3 if kind == "v" else 1), (name, index)
    for output in program["outputs"]:
        assert 0 <= output["register"] < size


# --- the op table -------------------------------------------------------------------------------------------------

def test_the_core_table_is_the_headers():
    if not core_has_programs():
        pytest.skip("the core has no shader_ops() yet")
    from photonsplat import _core
    assert _core.shader_ops() == header_op_table()


# --- constants ----------------------------------------------------------------------------------------------------

def test_constant_inputs_emit_no_program(empty_scene, op_table):
    mat, tree, shader = diffuse_material()
    rgb = tree.nodes.new("ShaderNodeRGB")
    rgb.outputs[0].default_value = (0.2, 0.4, 0.6, 1.0)
    value = tree.nodes.new("ShaderNodeValue")
    value.outputs[0].default_value = 0.7
    reroute = tree.nodes.new("NodeReroute")
    tree.links.new(rgb.outputs[0], reroute.inputs[0])
    tree.links.new(reroute.outputs[0], shader.inputs["Color"])
    tree.links.new(value.outputs[0], shader.inputs["Roughness"])
    spec = materials.convert_material(mat)
    arguments = spec.core_arguments()
    assert "program" not in arguments and spec.notes == [] and not spec.uses_program
    (d,) = arguments["closures"]
    assert d["color"] == pytest.approx((0.2, 0.4, 0.6)) and d["roughness"] == pytest.approx(0.7)


def test_a_driven_input_becomes_a_program_output(empty_scene, op_table):
    mat, tree, shader = diffuse_material()
    checker = tree.nodes.new("ShaderNodeTexChecker")
    tree.links.new(checker.outputs["Color"], shader.inputs["Color"])
    spec, program, code = program_of(mat, op_table)
    check_encoding(program, op_table)
    assert names(code) == ["texture_coordinate", "checker_texture"]
    (output,) = program["outputs"]
    assert output["target"] == "closure_color" and output["index"] == 0
    assert output["register"] == code[1][3][0]                # the checker's Color
    assert code[1][2][0] == code[0][3][0]                      # its Vector: Generated coordinates
    assert spec.uses_texspace and not spec.notes


# --- every node kind ----------------------------------------------------------------------------------------------

NODES = [
    ("ShaderNodeTexCoord", "UV", "texture_coordinate"),
    ("ShaderNodeUVMap", "UV", "uv_map"),
    ("ShaderNodeAttribute", "Color", "attribute"),
    ("ShaderNodeVertexColor", "Color", "attribute"),
    ("ShaderNodeNewGeometry", "Normal", "geometry"),
    ("ShaderNodeObjectInfo", "Random", "object_info"),
    ("ShaderNodeLightPath", "Is Camera Ray", "light_path"),
    ("ShaderNodeCameraData", "View Z Depth", "camera_data"),
    ("ShaderNodeFresnel", "Fac", "fresnel"),
    ("ShaderNodeLayerWeight", "Facing", "layer_weight"),
    ("ShaderNodeTexImage", "Alpha", "image_texture"),
    ("ShaderNodeTexEnvironment", "Color", "environment_texture"),
    ("ShaderNodeNormalMap", "Normal", "normal_map"),
    ("ShaderNodeBump", "Normal", "bump"),
    ("ShaderNodeNormal", "Dot", "normal"),
    ("ShaderNodeVectorTransform", "Vector", "vector_transform"),
    ("ShaderNodeTexNoise", "Fac", "noise_texture"),
    ("ShaderNodeTexVoronoi", "Distance", "voronoi_texture"),
    ("ShaderNodeTexMusgrave", "Fac", "musgrave_texture"),
    ("ShaderNodeTexWave", "Color", "wave_texture"),
    ("ShaderNodeTexMagic", "Color", "magic_texture"),
    ("ShaderNodeTexBrick", "Color", "brick_texture"),
    ("ShaderNodeTexChecker", "Fac", "checker_texture"),
    ("ShaderNodeTexGradient", "Color", "gradient_texture"),
    ("ShaderNodeTexWhiteNoise", "Value", "white_noise_texture"),
    ("ShaderNodeMath", "Value", "math"),
    ("ShaderNodeVectorMath", "Vector", "vector_math"),
    ("ShaderNodeMapRange", "Result", "map_range"),
    ("ShaderNodeClamp", "Result", "clamp"),
    ("ShaderNodeValToRGB", "Color", "color_ramp"),
    ("ShaderNodeRGBCurve", "Color", "rgb_curves"),
    ("ShaderNodeVectorCurve", "Vector", "vector_curves"),
    ("ShaderNodeFloatCurve", "Value", "float_curve"),
    ("ShaderNodeMix", "Result_Float", "mix_float"),
    ("ShaderNodeMixRGB", "Color", "mix_color"),
    ("ShaderNodeHueSaturation", "Color", "hue_saturation_value"),
    ("ShaderNodeGamma", "Color", "gamma"),
    ("ShaderNodeBrightContrast", "Color", "bright_contrast"),
    ("ShaderNodeInvert", "Color", "invert"),
    ("ShaderNodeSeparateColor", "Red", "math"),                 # aliased registers: the Math below reads them
    ("ShaderNodeCombineColor", "Color", "combine_xyz"),
    ("ShaderNodeSeparateHSV", "H", "separate_color"),
    ("ShaderNodeCombineHSV", "Color", "combine_color"),
    ("ShaderNodeSeparateXYZ", "X", "math"),
    ("ShaderNodeCombineXYZ", "Vector", "combine_xyz"),
    ("ShaderNodeRGBToBW", "Val", "rgb_to_bw"),
    ("ShaderNodeBlackbody", "Color", "blackbody"),
    ("ShaderNodeWavelength", "Color", "wavelength"),
    ("ShaderNodeMapping", "Vector", "mapping"),
    ("ShaderNodeVectorRotate", "Vector", "vector_rotate"),
]


def _output(node, identifier):
    return next(s for s in node.outputs if s.identifier == identifier)


@pytest.mark.parametrize("idname, output, op", NODES, ids=[n[0] for n in NODES])
def test_each_node_compiles_to_its_op(empty_scene, op_table, idname, output, op):
    mat, tree, shader = diffuse_material(idname)
    try:
        node = tree.nodes.new(idname)
    except RuntimeError:
        pytest.skip(f"{idname} is not a node of Blender {bpy.app.version_string}")
    if idname in ("ShaderNodeTexImage", "ShaderNodeTexEnvironment"):
        node.image = bpy.data.images.new("Tex", 4, 4)
    if idname == "ShaderNodeAttribute":
        node.attribute_name = "Col"
    # A Math node in between, so that constant sources (Combine of constants) still reach a program.
    math_node = tree.nodes.new("ShaderNodeMath")
    math_node.operation = 'MULTIPLY'
    tree.links.new(_output(node, output), math_node.inputs[0])
    if idname in ("ShaderNodeCombineColor", "ShaderNodeCombineXYZ", "ShaderNodeCombineHSV"):
        driver = tree.nodes.new("ShaderNodeNewGeometry")
        tree.links.new(driver.outputs["Pointiness"], node.inputs[0])
    if idname in ("ShaderNodeSeparateColor", "ShaderNodeSeparateXYZ"):
        driver = tree.nodes.new("ShaderNodeNewGeometry")
        tree.links.new(driver.outputs["Position"], node.inputs[0])
    tree.links.new(math_node.outputs[0], shader.inputs["Roughness"])
    spec, program, code = program_of(mat, op_table)
    check_encoding(program, op_table)
    assert op in names(code), (names(code), spec.notes)
    assert not any("not supported" in n or "could not be compiled" in n for n in spec.notes), spec.notes
    assert [o["target"] for o in program["outputs"]] == ["closure_roughness"]


@pytest.mark.parametrize("idname, output, op", NODES, ids=[n[0] for n in NODES])
def test_the_core_accepts_each_program(empty_scene, op_table, core, idname, output, op):
    """The core validates what the compiler emits (counts, ranges, texture and attribute ids, outputs)."""
    if not core_has_programs():
        pytest.skip("the core has no node programs yet (photonsplat._core.shader_ops missing)")
    mat, tree, shader = diffuse_material(idname)
    try:
        node = tree.nodes.new(idname)
    except RuntimeError:
        pytest.skip(f"{idname} is not a node of Blender {bpy.app.version_string}")
    if idname in ("ShaderNodeTexImage", "ShaderNodeTexEnvironment"):
        node.image = bpy.data.images.new("Tex", 4, 4)
    if idname == "ShaderNodeAttribute":
        node.attribute_name = "Col"
    if idname == "ShaderNodeTexCoord":
        node.object = bpy.data.objects.new("Empty", None)
    value = _output(node, output)
    tree.links.new(value, shader.inputs["Color" if value.type != "VALUE" else "Roughness"])
    spec = materials.convert_material(mat)
    scene = core.Scene()
    texture = scene.add_texture(name="Tex", pixels=np.ones((4, 4, 4), dtype=np.float32), color_space="linear")
    arguments = spec.core_arguments(texture_index=lambda reference: texture, attribute_id=scene.attribute_id)
    # Separating or combining constants folds: no program at all.
    folded = {"ShaderNodeSeparateColor", "ShaderNodeCombineColor", "ShaderNodeSeparateXYZ", "ShaderNodeCombineXYZ"}
    assert ("program" in arguments) != (idname in folded)
    scene.add_material(**arguments)


def test_node_params_follow_cycles_enums(empty_scene, op_table):
    mat, tree, shader = diffuse_material()
    power = tree.nodes.new("ShaderNodeMath")
    power.operation = 'POWER'
    power.use_clamp = True
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    tree.links.new(geometry.outputs["Pointiness"], power.inputs[0])
    mix = tree.nodes.new("ShaderNodeMixRGB")
    mix.blend_type = 'LINEAR_LIGHT'
    mix.use_clamp = True
    tree.links.new(power.outputs[0], mix.inputs["Fac"])
    wave = tree.nodes.new("ShaderNodeTexWave")
    wave.wave_type, wave.rings_direction, wave.wave_profile = 'RINGS', 'Z', 'TRI'
    tree.links.new(wave.outputs["Color"], mix.inputs["Color2"])
    tree.links.new(mix.outputs[0], shader.inputs["Color"])
    _, program, code = program_of(mat, op_table)
    by_name = {name: params for name, params, _, _ in code}
    assert by_name["math"] == [10, 1]                 # NODE_MATH_POWER, clamp
    assert by_name["mix_color"] == [17, 1, 1]          # NODE_MIX_LINEAR, legacy clamps its factor, clamp result
    assert by_name["wave_texture"] == [1, 0, 2, 2]     # rings, (bands x), rings z, triangle


# --- following links ----------------------------------------------------------------------------------------------

def test_groups_are_flattened_and_reroutes_and_muted_nodes_looked_through(empty_scene, op_table):
    group = bpy.data.node_groups.new("Scale", "ShaderNodeTree")
    if hasattr(group, "interface"):
        group.interface.new_socket("In", in_out='INPUT', socket_type='NodeSocketFloat')
        group.interface.new_socket("Out", in_out='OUTPUT', socket_type='NodeSocketFloat')
    else:
        group.inputs.new("NodeSocketFloat", "In")
        group.outputs.new("NodeSocketFloat", "Out")
    group_in = group.nodes.new("NodeGroupInput")
    group_out = group.nodes.new("NodeGroupOutput")
    inner = group.nodes.new("ShaderNodeMath")
    inner.operation = 'SINE'
    group.links.new(group_in.outputs[0], inner.inputs[0])
    group.links.new(inner.outputs[0], group_out.inputs[0])

    mat, tree, shader = diffuse_material()
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    muted = tree.nodes.new("ShaderNodeMath")
    muted.operation = 'LOGARITHM'
    muted.mute = True
    reroute = tree.nodes.new("NodeReroute")
    tree.links.new(geometry.outputs["Pointiness"], muted.inputs[0])
    tree.links.new(muted.outputs[0], reroute.inputs[0])
    tree.links.new(reroute.outputs[0], node.inputs[0])
    tree.links.new(node.outputs[0], shader.inputs["Roughness"])
    spec, program, code = program_of(mat, op_table)
    math_ops = [c for c in code if c[0] == "math"]
    operations = [params[0] for _, params, _, _ in math_ops]
    # The muted Logarithm passes Pointiness on; the Sine inside the group reads it; the Diffuse clamps it (add 0,
    # clamped).
    assert operations == [shader_program.MATH_OPS.index("SINE"), shader_program.MATH_OPS.index("ADD")]
    assert names(code)[0] == "geometry" and math_ops[0][2][0] == code[0][3][7]     # Pointiness
    # The group unconnected: its input socket's own value is a register.
    tree.links.remove(node.inputs[0].links[0])
    node.inputs[0].default_value = 0.25
    spec, program, code = program_of(mat, op_table)
    assert names(code) == ["math", "math"] and program["registers"][code[0][2][0]] == pytest.approx(0.25)


def test_implicit_conversions(empty_scene, op_table):
    mat, tree, shader = diffuse_material()
    checker = tree.nodes.new("ShaderNodeTexChecker")
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    tree.links.new(checker.outputs["Color"], shader.inputs["Roughness"])          # colour -> float: luminance
    tree.links.new(geometry.outputs["Pointiness"], shader.inputs["Color"])        # float -> colour: broadcast
    _, _, code = program_of(mat, op_table)
    assert "color_to_float" in names(code) and "float_to_vector" in names(code)
    tree.links.new(geometry.outputs["Position"], shader.inputs["Roughness"])      # vector -> float: average
    _, _, code = program_of(mat, op_table)
    assert "vector_to_float" in names(code)


# --- bump, normals ------------------------------------------------------------------------------------------------

def test_bump_compiles_its_height_three_times(empty_scene, op_table):
    mat, tree, shader = diffuse_material()
    coords = tree.nodes.new("ShaderNodeTexCoord")
    noise = tree.nodes.new("ShaderNodeTexNoise")
    bump = tree.nodes.new("ShaderNodeBump")
    tree.links.new(coords.outputs["Object"], noise.inputs["Vector"])
    tree.links.new(noise.outputs["Fac"], bump.inputs["Height"])
    tree.links.new(bump.outputs["Normal"], shader.inputs["Normal"])
    spec, program, code = program_of(mat, op_table)
    check_encoding(program, op_table)
    assert names(code).count("noise_texture") == 3
    # The offsets' length: a whole differential in 3.x, the node's Filter Width (0.1 for a new node) in 4.x.
    width = shader_program.float_bits(0.1 if "Filter Width" in bump.inputs else 1.0)
    unit = shader_program.float_bits(1.0)
    coordinates = sorted((params[0], params[-1]) for name, params, _, _ in code if name == "texture_coordinate")
    assert coordinates == [(0, unit), (1, width), (2, width)]
    (bump_op,) = [c for c in code if c[0] == "bump"]
    noise_facs = [outputs[0] for name, _, _, outputs in code if name == "noise_texture"]
    assert bump_op[2][2:5] == noise_facs                # height at the point, at dx, at dy
    assert bump_op[1] == [0, 0, width]                   # not inverted, Normal unconnected, the filter width
    (output,) = program["outputs"]
    assert output["target"] == "normal" and output["register"] == bump_op[3][0]


@pytest.mark.skipif(bpy.app.version < (4, 1, 0), reason="the Bump node's Filter Width came with Blender 4.1")
@pytest.mark.parametrize("driver, expected", [("ShaderNodeValue", 3.0), ("ShaderNodeTexNoise", 0.25)])
def test_a_linked_filter_width_counts_where_it_is_constant(driver, expected, empty_scene, op_table):
    """Cycles compiles a Bump's Filter Width as a constant of the node: a link into it counts where it folds to a
    constant (a Value node: 3), and otherwise the socket's own value stands (a Noise texture: 0.25), with a note.
    Measured in Cycles 4.5 on tests/blender/test_bump_filter_width.py's scene: each linked case gave the pixels of
    the value used here (0 difference), 0.06-0.26 off the others."""
    mat, tree, shader = diffuse_material()
    noise = tree.nodes.new("ShaderNodeTexNoise")
    bump = tree.nodes.new("ShaderNodeBump")
    bump.inputs["Filter Width"].default_value = 0.25
    source = tree.nodes.new(driver)
    if driver == "ShaderNodeValue":
        source.outputs[0].default_value = 3.0
    tree.links.new(source.outputs[0], bump.inputs["Filter Width"])
    tree.links.new(noise.outputs["Fac"], bump.inputs["Height"])
    tree.links.new(bump.outputs["Normal"], shader.inputs["Normal"])
    spec, program, code = program_of(mat, op_table)
    (bump_op,) = [c for c in code if c[0] == "bump"]
    assert bump_op[1][2] == shader_program.float_bits(expected)
    varies = any("Filter Width varies" in note for note in spec.notes)
    assert varies == (driver != "ShaderNodeValue"), spec.notes


def test_normal_map_registers_its_uv_map(empty_scene, op_table):
    mat, tree, shader = diffuse_material()
    normal_map = tree.nodes.new("ShaderNodeNormalMap")
    normal_map.uv_map = "Detail"
    image = tree.nodes.new("ShaderNodeTexImage")
    image.image = bpy.data.images.new("Normals", 4, 4)
    tree.links.new(image.outputs["Color"], normal_map.inputs["Color"])
    tree.links.new(normal_map.outputs["Normal"], shader.inputs["Normal"])
    spec = materials.convert_material(mat)
    # The UV map, and its MikkTSpace tangents (tangent space reads them, as Cycles does).
    assert sorted(spec.attributes) == sorted(["Detail", shader_program.TANGENT_PREFIX + "Detail"])
    ids = {"Detail": 7, shader_program.TANGENT_PREFIX + "Detail": 8}
    arguments = spec.core_arguments(texture_index=lambda reference: 3, attribute_id=lambda name: ids[name])
    code = decode(arguments["program"], op_table)
    assert [c[1] for c in code if c[0] == "normal_map"] == [[0, 7, 8]]
    assert [c[1][0] for c in code if c[0] == "image_texture"] == [3]
    # An unreadable image: Cycles' magenta, copied in.
    arguments = spec.core_arguments(texture_index=lambda reference: -1, attribute_id=lambda name: ids[name])
    code = decode(arguments["program"], op_table)
    assert "image_texture" not in names(code) and "copy_vector" in names(code)


# --- tables -------------------------------------------------------------------------------------------------------

def test_ramps_and_curves_are_baked(empty_scene, op_table):
    mat, tree, shader = diffuse_material()
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    ramp = tree.nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = (1.0, 0.0, 0.0, 1.0)
    ramp.color_ramp.elements[1].color = (0.0, 0.0, 1.0, 0.5)
    curves = tree.nodes.new("ShaderNodeRGBCurve")
    curves.mapping.curves[3].points[1].location = (2.0, 1.0)       # the combined curve reaches x = 2
    tree.links.new(geometry.outputs["Pointiness"], ramp.inputs["Fac"])
    tree.links.new(ramp.outputs["Color"], curves.inputs["Color"])
    tree.links.new(curves.outputs["Color"], shader.inputs["Color"])
    _, program, code = program_of(mat, op_table)
    check_encoding(program, op_table)
    tables = program["tables"]
    (ramp_params,) = [c[1] for c in code if c[0] == "color_ramp"]
    offset, entries, interpolate = ramp_params
    assert entries == shader_program.TABLE_SIZE and interpolate == 1
    baked = np.array(tables[offset:offset + 4 * entries]).reshape(entries, 4)
    assert baked[0] == pytest.approx((1.0, 0.0, 0.0, 1.0)) and baked[-1] == pytest.approx((0.0, 0.0, 1.0, 0.5))
    assert baked[128] == pytest.approx(tuple(ramp.color_ramp.evaluate(128 / 255)), abs=1e-5)
    (curve_params,) = [c[1] for c in code if c[0] == "rgb_curves"]
    offset, entries = curve_params
    assert tables[offset:offset + 2] == pytest.approx([0.0, 2.0])   # the points' x range
    assert len(tables) >= offset + 2 + 3 * entries


# --- closures -----------------------------------------------------------------------------------------------------

def test_programmed_roughness_keeps_a_microfacet_lobe(empty_scene, op_table):
    mat = bpy.data.materials.new("Glossy")
    enable_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    glossy = tree.nodes.new("ShaderNodeBsdfGlossy")
    glossy.distribution = 'GGX'
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(glossy.outputs[0], output.inputs["Surface"])
    noise = tree.nodes.new("ShaderNodeTexNoise")
    tree.links.new(noise.outputs["Fac"], glossy.inputs["Roughness"])
    spec, program, code = program_of(mat, op_table)
    (d,) = spec.core_arguments()["closures"]
    assert d["distribution"] == "ggx"
    targets = {o["target"] for o in program["outputs"]}
    assert {"closure_alpha_x", "closure_alpha_y"} <= targets


def test_a_multiscatter_glossy_with_a_computed_colour_programs_its_bounces_tint(empty_scene, op_table):
    mat = bpy.data.materials.new("Multiscatter")
    enable_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    glossy = tree.nodes.new("ShaderNodeBsdfGlossy")
    glossy.distribution = 'MULTI_GGX'
    glossy.inputs["Roughness"].default_value = 0.7
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(glossy.outputs[0], output.inputs["Surface"])
    noise = tree.nodes.new("ShaderNodeTexNoise")
    tree.links.new(noise.outputs["Color"], glossy.inputs["Color"])
    spec, program, code = program_of(mat, op_table)
    (d,) = spec.core_arguments()["closures"]
    assert d["distribution"] == "multi_ggx"
    # The tint of the walk's extra bounces is the colour the program computes (clamped to [0, 1]): without it the
    # core's lobe scatters once only.
    targets = {o["target"] for o in program["outputs"]}
    assert {"closure_color", "closure_specular_color"} <= targets


def test_glass_with_a_computed_ior_splits_by_a_fresnel_op(empty_scene, op_table):
    mat = bpy.data.materials.new("Glass")
    enable_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    glass = tree.nodes.new("ShaderNodeBsdfGlass")
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(glass.outputs[0], output.inputs["Surface"])
    ior = tree.nodes.new("ShaderNodeMath")
    ior.operation = 'ADD'
    ior.inputs[0].default_value, ior.inputs[1].default_value = 1.0, 0.5
    tree.links.new(tree.nodes.new("ShaderNodeNewGeometry").outputs["Pointiness"], ior.inputs[1])
    tree.links.new(ior.outputs[0], glass.inputs["IOR"])
    spec, program, code = program_of(mat, op_table)
    arguments = spec.core_arguments()
    assert arguments["factors"] == [] and "fresnel" in names(code)
    targets = sorted((o["target"], o["index"]) for o in program["outputs"])
    assert targets == [("closure_color", 0), ("closure_color", 1), ("closure_ior", 0), ("closure_ior", 1)]


def test_mix_shader_fac_scales_the_weights_and_emission_is_an_output(empty_scene, op_table):
    mat = bpy.data.materials.new("Mixed")
    enable_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    mix = tree.nodes.new("ShaderNodeMixShader")
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(mix.outputs[0], output.inputs["Surface"])
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    emission = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(diffuse.outputs[0], mix.inputs[1])
    tree.links.new(emission.outputs[0], mix.inputs[2])
    checker = tree.nodes.new("ShaderNodeTexChecker")
    tree.links.new(checker.outputs["Fac"], mix.inputs["Fac"])
    spec, program, code = program_of(mat, op_table)
    check_encoding(program, op_table)
    targets = sorted(o["target"] for o in program["outputs"])
    assert targets == ["closure_color", "emission"] and spec.emits
    assert spec.core_arguments()["emission"] == (0.0, 0.0, 0.0)    # the program sets it


@pytest.mark.skipif(compat.PRINCIPLED_V2, reason="Principled BSDF v1 is Blender 3.x's")
def test_principled_v1_with_a_programmed_base_colour(empty_scene, op_table):
    mat = bpy.data.materials.new("P")
    enable_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    principled = tree.nodes.new("ShaderNodeBsdfPrincipled")
    principled.inputs["Sheen"].default_value = 0.5
    principled.inputs["Transmission"].default_value = 0.5
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(principled.outputs[0], output.inputs["Surface"])
    ramp = tree.nodes.new("ShaderNodeValToRGB")
    tree.links.new(tree.nodes.new("ShaderNodeTexNoise").outputs["Fac"], ramp.inputs["Fac"])
    tree.links.new(ramp.outputs["Color"], principled.inputs["Base Color"])
    spec, program, code = program_of(mat, op_table)
    check_encoding(program, op_table)
    labels = [c.label for c in spec.closures]
    assert {"diffuse", "sheen", "specular", "glass reflection", "refraction"} <= set(labels)
    targets = {(o["target"], labels[o["index"]]) for o in program["outputs"]}
    assert ("closure_color", "diffuse") in targets and ("closure_specular_color", "specular") in targets
    assert ("closure_color", "refraction") in targets and ("closure_color", "sheen") in targets


def test_principled_of_this_blender_compiles(empty_scene, op_table):
    mat = bpy.data.materials.new("P")
    enable_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    principled = tree.nodes.new("ShaderNodeBsdfPrincipled")
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(principled.outputs[0], output.inputs["Surface"])
    noise = tree.nodes.new("ShaderNodeTexNoise")
    for role in ("base_color", "roughness", "metallic", "coat", "transmission", "alpha", "emission_color"):
        name = compat.principled_input(role)
        if name is not None and name in principled.inputs:
            tree.links.new(noise.outputs["Fac"], principled.inputs[name])
    spec, program, code = program_of(mat, op_table)
    check_encoding(program, op_table)
    assert any(o["target"] == "closure_color" for o in program["outputs"])


# --- the Sky Texture ---------------------------------------------------------------------------------------------

def _sky_material(sky_type, sun_disc=True, mapping=False):
    mat, tree, shader = diffuse_material("sky")
    sky = tree.nodes.new("ShaderNodeTexSky")
    types = {item.identifier for item in sky.bl_rna.properties["sky_type"].enum_items}
    if sky_type not in types:
        pytest.skip(f"Sky Texture has no type {sky_type} in Blender {bpy.app.version_string}")
    sky.sky_type = sky_type
    sky.sun_disc = sun_disc
    if mapping and sky.inputs.get("Vector") is not None:  # Blender 5.0 drops the socket with the sun disc
        coords = tree.nodes.new("ShaderNodeTexCoord")
        rotate = tree.nodes.new("ShaderNodeMapping")
        rotate.inputs["Rotation"].default_value = (0.0, 0.0, 0.7)
        tree.links.new(coords.outputs["Object"], rotate.inputs["Vector"])
        tree.links.new(rotate.outputs["Vector"], sky.inputs["Vector"])
    tree.links.new(sky.outputs["Color"], shader.inputs["Color"])
    return mat, sky


@pytest.mark.parametrize("sky_type,expected", [("NISHITA", 2), ("SINGLE_SCATTERING", 2), ("PREETHAM", 0),
                                               ("HOSEK_WILKIE", 1)])
def test_sky_texture_compiles_to_its_op(empty_scene, op_table, sky_type, expected):
    mat, sky = _sky_material(sky_type, sun_disc=False, mapping=True)
    spec, program, code = program_of(mat, op_table)
    check_encoding(program, op_table)
    skies = [params for name, params, _, _ in code if name == "sky_texture"]
    assert len(skies) == 1 and skies[0][0] == expected and skies[0][3] == -1
    assert "mapping" in names(code)  # the Vector's link is followed
    settings = program["tables"][skies[0][2]:skies[0][2] + 13]
    assert settings[7] == pytest.approx(sky.sun_elevation) and settings[3] == pytest.approx(sky.turbidity)
    assert any("Hosek" in n for n in spec.notes) == (sky_type == "HOSEK_WILKIE")
    assert any("Single Scattering" in n for n in spec.notes) == (sky_type == "SINGLE_SCATTERING")


def test_sky_texture_with_sun_disc_ignores_its_vector(empty_scene, op_table):
    mat, sky = _sky_material("NISHITA" if "NISHITA" in {i.identifier for i in bpy.types.ShaderNodeTexSky.bl_rna
                                                          .properties["sky_type"].enum_items} else "SINGLE_SCATTERING",
                             sun_disc=True, mapping=True)
    spec, program, code = program_of(mat, op_table)
    vector = sky.inputs.get("Vector")
    disabled = vector is None or not vector.enabled
    assert ("mapping" in names(code)) != disabled
    assert [params[1] for name, params, _, _ in code if name == "sky_texture"] == [1]


# --- what is not supported ------------------------------------------------------------------------------------

@pytest.mark.parametrize("idname", ["ShaderNodeTexPointDensity", "ShaderNodeTexIES",
                                    "ShaderNodeAmbientOcclusion", "ShaderNodeBevel", "ShaderNodeWireframe",
                                    "ShaderNodeLightFalloff", "ShaderNodeScript", "ShaderNodeTangent",
                                    "ShaderNodeParticleInfo"])
def test_unsupported_nodes_fall_back_with_a_note(empty_scene, op_table, idname):
    mat, tree, shader = diffuse_material(idname)
    try:
        node = tree.nodes.new(idname)
    except RuntimeError:
        pytest.skip(f"{idname} is not a node of Blender {bpy.app.version_string}")
    value_output = next((s for s in node.outputs if s.type in ("VALUE", "RGBA", "VECTOR")), None)
    if value_output is None:
        pytest.skip(f"{idname} has no value output")
    tree.links.new(value_output, shader.inputs["Color"])
    spec = materials.convert_material(mat)
    assert any(node.bl_label in n for n in spec.notes), spec.notes
    spec.core_arguments()


def test_displacement_is_ignored_with_a_note(empty_scene, op_table):
    mat, tree, shader = diffuse_material()
    displacement = tree.nodes.new("ShaderNodeDisplacement")
    tree.links.new(displacement.outputs[0], tree.nodes["Material Output"].inputs["Displacement"])
    spec = materials.convert_material(mat)
    assert any("Displacement" in n for n in spec.notes)


def test_attribute_kinds_other_than_geometry_fall_back(empty_scene, op_table):
    mat, tree, shader = diffuse_material()
    attribute = tree.nodes.new("ShaderNodeAttribute")
    attribute.attribute_type = 'OBJECT'
    attribute.attribute_name = "color"
    tree.links.new(attribute.outputs["Color"], shader.inputs["Color"])
    spec = materials.convert_material(mat)
    assert any("Attribute" in n for n in spec.notes) and not spec.uses_program


# --- the mesh data programs read -------------------------------------------------------------------------------

def _export(core_class):
    return export.export_frame(core_class, bpy.context.evaluated_depsgraph_get())


def _attribute_recording_core():
    """test_export's RecordingCore with the core's attribute_id."""
    from test_export import RecordingCore

    class Core(RecordingCore):
        class Scene(RecordingCore.Scene):
            def __init__(self):
                super().__init__()
                self.attribute_names = []

            def attribute_id(self, name):
                if name not in self.attribute_names:
                    self.attribute_names.append(name)
                return self.attribute_names.index(name)
    return Core


def _paint_material(name="Painted"):
    mat, tree, shader = diffuse_material(name)
    attribute = tree.nodes.new("ShaderNodeAttribute")
    attribute.attribute_name = "Paint"
    tree.links.new(attribute.outputs["Color"], shader.inputs["Color"])
    return mat, tree, shader


def test_only_the_attributes_programs_read_are_exported(empty_scene):
    from test_export import add_camera
    Core = _attribute_recording_core()
    add_camera(empty_scene)
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    plane = bpy.context.active_object
    mesh = plane.data
    mesh.uv_layers.new(name="Second")
    colors = mesh.color_attributes.new("Paint", 'FLOAT_COLOR', 'POINT')
    colors.data.foreach_set("color", np.tile([0.1, 0.2, 0.3, 1.0], len(mesh.vertices)).astype(np.float32))
    plane.pass_index = 5
    plain, _, _ = diffuse_material("Plain")
    plane.data.materials.append(plain)
    frame = _export(Core)
    (exported,) = frame.scene.meshes
    assert not exported.get("attributes") and "object_info" not in exported and "texspace" not in exported

    mat, tree, shader = diffuse_material("Painted")
    attribute = tree.nodes.new("ShaderNodeAttribute")
    attribute.attribute_name = "Paint"
    info = tree.nodes.new("ShaderNodeObjectInfo")
    mix = tree.nodes.new("ShaderNodeMixRGB")
    tree.links.new(attribute.outputs["Color"], mix.inputs["Color1"])
    tree.links.new(info.outputs["Random"], mix.inputs["Fac"])
    tree.links.new(mix.outputs[0], shader.inputs["Color"])
    plane.data.materials[0] = mat
    frame = _export(Core)
    (exported,) = frame.scene.meshes
    paint_id = frame.scene.attribute_names.index("Paint")
    assert set(exported["attributes"]) == {paint_id}          # keyed by the core's attribute ids
    paint = exported["attributes"][paint_id]
    assert paint.shape == (len(mesh.vertices), 4) and paint.dtype == np.float32
    assert paint[0] == pytest.approx((0.1, 0.2, 0.3, 1.0))
    info = exported["object_info"]
    assert info["pass_index"] == 5 and 0.0 <= info["random"] <= 1.0 and len(info["color"]) == 4
    (material,) = frame.scene.materials
    code = decode(material["program"], shader_program.op_table())
    assert [c[1] for c in code if c[0] == "attribute"] == [
        [0, frame.scene.attribute_names.index("Paint"), shader_program.float_bits(1.0)]]


# --- rendering through the core ----------------------------------------------------------------------------------

def test_a_program_renders_two_colours(empty_scene, core):
    """Generated x > 0.5 picks red or blue: half the plane each, through the core's interpreter."""
    if not core_has_programs():
        pytest.skip("the core has no node programs yet (photonsplat._core.shader_ops missing)")
    from test_export import add_camera
    from blender_helpers import uniform_world
    add_camera(empty_scene, location=(0.0, 0.0, 3.0))
    empty_scene.camera.rotation_euler = (0.0, 0.0, 0.0)
    bpy.ops.mesh.primitive_plane_add(size=4.0)
    plane = bpy.context.active_object
    mat, tree, shader = diffuse_material("Halves")
    coords = tree.nodes.new("ShaderNodeTexCoord")
    separate = tree.nodes.new("ShaderNodeSeparateXYZ")
    greater = tree.nodes.new("ShaderNodeMath")
    greater.operation = 'GREATER_THAN'
    greater.inputs[1].default_value = 0.5
    mix = tree.nodes.new("ShaderNodeMixRGB")
    mix.inputs["Color1"].default_value = (0.9, 0.1, 0.1, 1.0)
    mix.inputs["Color2"].default_value = (0.1, 0.1, 0.9, 1.0)
    tree.links.new(coords.outputs["Generated"], separate.inputs["Vector"])
    tree.links.new(separate.outputs["X"], greater.inputs[0])
    tree.links.new(greater.outputs[0], mix.inputs["Fac"])
    tree.links.new(mix.outputs[0], shader.inputs["Color"])
    plane.data.materials.append(mat)
    uniform_world(empty_scene)
    empty_scene.render.resolution_x = empty_scene.render.resolution_y = 32
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    assert not any("not" in w for w in frame.warnings), frame.warnings
    image, _ = core.render(frame.scene, frame.camera, frame.settings)
    rgb = np.asarray(image)[..., :3]
    left, right = rgb[:, :14].reshape(-1, 3).mean(axis=0), rgb[:, 18:].reshape(-1, 3).mean(axis=0)
    assert left[0] > 4.0 * left[2] and right[2] > 4.0 * right[0], (left, right)


@pytest.mark.skipif(compat.PRINCIPLED_V2, reason="Principled BSDF v1 is Blender 3.x's")
def test_an_image_in_principled_formulas_is_compiled(empty_scene, op_table):
    mat = bpy.data.materials.new("Tinted")
    enable_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    principled = tree.nodes.new("ShaderNodeBsdfPrincipled")
    principled.inputs["Metallic"].default_value = 0.5
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(principled.outputs[0], output.inputs["Surface"])
    image = tree.nodes.new("ShaderNodeTexImage")
    image.image = bpy.data.images.new("Base", 4, 4)
    tree.links.new(image.outputs["Color"], principled.inputs["Base Color"])
    spec, program, code = program_of(mat, op_table)
    assert "image_texture" in names(code) and not spec.textures
    assert not any("not applied" in n for n in spec.notes), spec.notes
    # Metallic 0: a plain closure texture, as before programs.
    principled.inputs["Metallic"].default_value = 0.0
    spec = materials.convert_material(mat)
    assert spec.textures and not spec.uses_program


# --- Blender 4.x and 5.x nodes --------------------------------------------------------------------------------

def _roughness_from(tree, shader, node, output):
    tree.links.new(_output(node, output), shader.inputs["Roughness"])


@pytest.mark.skipif(bpy.app.version < (4, 1, 0), reason="Noise's fractal types came with Blender 4.1")
def test_noise_fractal_types_of_4x(empty_scene, op_table):
    mat, tree, shader = diffuse_material()
    noise = tree.nodes.new("ShaderNodeTexNoise")
    _roughness_from(tree, shader, noise, "Fac")
    spec, program, code = program_of(mat, op_table)
    assert "noise_texture" in names(code) and spec.notes == []     # normalized fBM, lacunarity 2: 3.4's Noise
    noise.noise_type = 'RIDGED_MULTIFRACTAL'
    spec, program, code = program_of(mat, op_table)
    (params,) = [c[1] for c in code if c[0] == "musgrave_texture"]
    assert params == [3, 3] and any("Noise Texture" in n for n in spec.notes)


@pytest.mark.skipif(bpy.app.version < (4, 0, 0), reason="Blender 4.x's operations")
def test_operations_of_4x_are_approximated_with_a_note(empty_scene, op_table):
    mat, tree, shader = diffuse_material()
    modulo = tree.nodes.new("ShaderNodeMath")
    modulo.operation = 'FLOORED_MODULO'
    tree.links.new(tree.nodes.new("ShaderNodeNewGeometry").outputs["Pointiness"], modulo.inputs[0])
    _roughness_from(tree, shader, modulo, "Value")
    mix = tree.nodes.new("ShaderNodeMix")
    mix.data_type = 'RGBA'
    mix.blend_type = 'EXCLUSION'
    tree.links.new(modulo.outputs[0], next(s for s in mix.inputs if s.identifier == "Factor_Float"))
    tree.links.new(_output(mix, "Result_Color"), shader.inputs["Color"])
    spec, program, code = program_of(mat, op_table)
    assert any("Floored Modulo" in n for n in spec.notes) and any("exclusion" in n for n in spec.notes)
    assert {"math", "mix_color"} <= set(names(code))


def test_object_info_random_is_cycles(empty_scene):
    """Object Info's Random as Blender 3.4's Cycles renders it (values read from Cycles renders of an emission of
    Random): an object's from its name's hash, an instance's from the depsgraph's random_id."""
    from photonsplat.export import instancing
    bpy.ops.mesh.primitive_plane_add()
    plane = bpy.context.active_object
    plane.name = "Plané Ünïcode"
    # A depsgraph instance is valid only during its own iteration step.
    (random,) = [instancing.object_info(i)["random"] for i in bpy.context.evaluated_depsgraph_get().object_instances
                 if i.object.type == 'MESH']
    assert random == pytest.approx(0.5442667007446289, abs=1e-7)


def test_viewport_reads_a_mesh_again_when_its_materials_need_an_attribute(empty_scene):
    from test_viewport import DepsgraphUpdates
    Core = _attribute_recording_core()
    bpy.ops.mesh.primitive_plane_add()
    plane = bpy.context.active_object
    plane.data.color_attributes.new("Paint", 'FLOAT_COLOR', 'CORNER')
    plain, tree, shader = diffuse_material("Plain")
    plane.data.materials.append(plain)
    sync = export.BlenderSync(Core)
    sync.sync(bpy.context.evaluated_depsgraph_get())
    assert not sync.scene.mesh_data[0].get("attributes")
    with DepsgraphUpdates(sync) as updates:
        attribute = tree.nodes.new("ShaderNodeAttribute")
        attribute.attribute_name = "Paint"
        tree.links.new(attribute.outputs["Color"], shader.inputs["Color"])
        reports = updates.evaluate()
    assert any(r.rebuilt for r in reports)
    (exported,) = sync.scene.mesh_data
    paint = exported["attributes"][sync.scene.attribute_names.index("Paint")]
    assert paint.shape == (2, 3, 4)                      # per triangle corner


def test_a_material_of_every_program_output_renders(empty_scene, core):
    """Principled with a programmed base colour, roughness and bump, a glass of programmed IOR, an emission: the
    core takes every program output and renders a finite image."""
    if not core_has_programs():
        pytest.skip("the core has no node programs yet (photonsplat._core.shader_ops missing)")
    from test_export import add_camera
    from blender_helpers import uniform_world
    add_camera(empty_scene, location=(0.0, 0.0, 3.0))
    empty_scene.camera.rotation_euler = (0.0, 0.0, 0.0)
    bpy.ops.mesh.primitive_plane_add(size=4.0)
    plane = bpy.context.active_object
    mat = bpy.data.materials.new("Everything")
    enable_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    add = tree.nodes.new("ShaderNodeAddShader")
    mix = tree.nodes.new("ShaderNodeMixShader")
    principled = tree.nodes.new("ShaderNodeBsdfPrincipled")
    glass = tree.nodes.new("ShaderNodeBsdfGlass")
    emission = tree.nodes.new("ShaderNodeEmission")
    coords = tree.nodes.new("ShaderNodeTexCoord")
    noise = tree.nodes.new("ShaderNodeTexNoise")
    ramp = tree.nodes.new("ShaderNodeValToRGB")
    bump = tree.nodes.new("ShaderNodeBump")
    ior = tree.nodes.new("ShaderNodeMath")
    links = tree.links
    links.new(coords.outputs["Object"], noise.inputs["Vector"])
    links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    links.new(ramp.outputs["Color"], principled.inputs[compat.principled_input("base_color")])
    links.new(noise.outputs["Fac"], principled.inputs[compat.principled_input("roughness")])
    links.new(noise.outputs["Fac"], bump.inputs["Height"])
    links.new(bump.outputs["Normal"], principled.inputs["Normal"])
    links.new(noise.outputs["Fac"], ior.inputs[1])
    ior.inputs[0].default_value = 1.2
    links.new(ior.outputs[0], glass.inputs["IOR"])
    links.new(noise.outputs["Color"], emission.inputs["Color"])
    links.new(noise.outputs["Fac"], mix.inputs["Fac"])
    links.new(principled.outputs[0], mix.inputs[1])
    links.new(glass.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], add.inputs[0])
    links.new(emission.outputs[0], add.inputs[1])
    links.new(add.outputs[0], output.inputs["Surface"])
    plane.data.materials.append(mat)
    uniform_world(empty_scene)
    empty_scene.render.resolution_x = empty_scene.render.resolution_y = 16
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    spec = materials.convert_material(mat)
    targets = {o["target"] for o in spec.core_arguments()["program"]["outputs"]}
    assert {"closure_color", "closure_alpha_x", "closure_ior", "emission", "normal"} <= targets
    image, _ = core.render(frame.scene, frame.camera, frame.settings)
    assert np.isfinite(np.asarray(image)).all() and np.asarray(image)[..., :3].max() > 0.0
