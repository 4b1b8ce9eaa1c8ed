"""Scene export, checked against a stand-in for the native core that only records what it is given.

These tests pin down the conversions themselves (units, orientations, material mapping, array layouts), so
they do not need the compiled module.
"""

import math

import bpy
import numpy as np
import pytest

from blender_helpers import enable_nodes, uniform_world
from photonsplat import compat, export
from photonsplat.export import materials, shader_program


class RecordingCore:
    """Same construction API as photonsplat._core; keeps every call for inspection."""

    class Scene:
        def __init__(self):
            self.materials, self.meshes, self.lights, self.background = [], [], [], None
            self.mesh_data, self.textures = [], []

        def add_material(self, **kw):
            self.materials.append(kw)
            return len(self.materials) - 1

        def add_mesh_data(self, **kw):
            self.mesh_data.append(kw)
            return len(self.mesh_data) - 1

        def add_instance(self, mesh_id, transform, **kw):
            # `meshes` lists what is placed in the world: each instance with its mesh's arrays.
            self.meshes.append(dict(self.mesh_data[mesh_id], mesh_id=mesh_id, transform=transform, **kw))
            return len(self.meshes) - 1

        def add_texture(self, **kw):
            self.textures.append(kw)
            return len(self.textures) - 1

        def add_spot_light(self, **kw):
            self.lights.append(("spot", kw))

        def add_point_light(self, **kw):
            self.lights.append(("point", kw))

        def add_sun_light(self, **kw):
            self.lights.append(("sun", kw))

        def add_area_light(self, **kw):
            self.lights.append(("area", kw))

        def set_background(self, radiance):
            self.background = radiance

    class Camera:
        def __init__(self, **kw):
            self.__dict__.update(kw)

    class RenderSettings:
        def __init__(self, **kw):
            self.__dict__.update(kw)


def export_current():
    return export.export_frame(RecordingCore, bpy.context.evaluated_depsgraph_get())


def add_camera(scene, location=(0.0, -5.0, 1.0)):
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.location = location
    cam.rotation_euler = (math.radians(90.0), 0.0, 0.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    return cam


def node_material(name, shader_type, **inputs):
    """A material whose Surface is one shader node of `shader_type` with the given input values."""
    mat = bpy.data.materials.new(name)
    enable_nodes(mat)
    nodes = mat.node_tree.nodes
    nodes.clear()
    shader = nodes.new(shader_type)
    for key, value in inputs.items():
        name = key.replace("_", " ")
        if shader_type == "ShaderNodeBsdfPrincipled" and key.lower() in compat.PRINCIPLED_INPUTS:
            name = compat.principled_input(key.lower())       # v1 and v2 name some inputs differently
        shader.inputs[name].default_value = value
    output = nodes.new("ShaderNodeOutputMaterial")
    mat.node_tree.links.new(shader.outputs[0], output.inputs["Surface"])
    return mat, shader


def approx(values, expected, rel=1e-5):
    return tuple(values) == pytest.approx(tuple(expected), rel=rel, abs=1e-6)


# --- materials ------------------------------------------------------------------------------------------------

def closures_of(spec, kind=None, label=None):
    """The closure dicts the core gets, those of `kind` (and `label`) only when given."""
    found = []
    for d, c in zip(spec.core_arguments()["closures"], spec.closures):
        if (kind is None or d["kind"] == kind) and (label is None or c.label == label):
            found.append(d)
    return found


def one(spec, kind, label=None):
    (d,) = closures_of(spec, kind, label)
    return d


v1_only = pytest.mark.skipif(compat.PRINCIPLED_V2, reason="Principled BSDF v1 is Blender 3.x's")


@v1_only
def test_principled_v1_lowers_as_cycles_3_4(empty_scene):
    base = (0.8, 0.4, 0.2)
    mat, node = node_material("P", "ShaderNodeBsdfPrincipled", Base_Color=(*base, 1.0), Metallic=0.25,
                              Transmission=0.5, Specular=0.5, Specular_Tint=0.5, Roughness=0.3, Sheen=0.5,
                              Sheen_Tint=0.5, Clearcoat=0.4, Clearcoat_Roughness=0.1, IOR=1.5,
                              Transmission_Roughness=0.2)
    node.distribution = 'GGX'
    spec = materials.convert_material(mat)
    assert spec.notes == []
    args = spec.core_arguments()
    assert args["kind"] == "closures" and args["factors"] == [dict(kind="fresnel", value=pytest.approx(1.5))]
    # svm_closure.h's weights.
    diffuse_weight, transmission, specular_weight = 0.75 * 0.5, 0.5 * 0.75, 1.0 - 0.5 * 0.75
    d = one(spec, "principled_diffuse")
    assert approx(d["color"], tuple(b * diffuse_weight for b in base)) and d["roughness"] == pytest.approx(0.3)
    lum = 0.2126729 * 0.8 + 0.7151522 * 0.4 + 0.0721750 * 0.2
    sheen = one(spec, "sheen")
    assert approx(sheen["color"], tuple(0.5 * diffuse_weight * (0.5 + 0.5 * b / lum) for b in base), rel=1e-4)
    s = one(spec, "reflection", "specular")
    tint = tuple(0.5 + 0.5 * b / 0.5 for b in base)              # luminance approx 0.3/0.6/0.1 of base = 0.5
    cspec0 = tuple(0.5 * 0.08 * t * 0.75 + b * 0.25 for t, b in zip(tint, base))
    assert approx(s["color"], (specular_weight,) * 3) and approx(s["specular_color"], cspec0)
    assert (s["fresnel"], s["distribution"]) == ("principled", "ggx")
    assert s["ior"] == pytest.approx(2.0 / (1.0 - math.sqrt(0.08 * 0.5)) - 1.0)
    assert s["alpha_x"] == pytest.approx(0.09) and s["alpha_y"] == pytest.approx(0.09)
    r = one(spec, "reflection", "glass reflection")
    assert approx(r["color"], (transmission,) * 3) and r["factors_on"] == [0] and r["fresnel"] == "principled"
    assert approx(r["specular_color"], tuple(b * 0.5 + 0.5 for b in base)) and r["ior"] == pytest.approx(1.5)
    t = one(spec, "refraction")
    assert approx(t["color"], tuple(b * transmission for b in base)) and t["factors_off"] == [0]
    refraction_roughness = 1.0 - (1.0 - 0.3) * (1.0 - 0.2)                # 3.4's Transmission Roughness
    assert t["alpha_x"] == pytest.approx(refraction_roughness ** 2) and t["ior"] == pytest.approx(1.5)
    c = one(spec, "reflection", "clearcoat")
    assert approx(c["color"], (0.25 * 0.4,) * 3) and (c["distribution"], c["fresnel"]) == ("gtr1", "dielectric")
    assert c["alpha_x"] == pytest.approx(0.01) and c["ior"] == pytest.approx(1.5)
    assert "principled" in spec.describe() and "clearcoat" in spec.describe()


@v1_only
def test_principled_v1_alpha_anisotropy_emission_subsurface(empty_scene):
    mat, node = node_material("A", "ShaderNodeBsdfPrincipled", Base_Color=(0.5, 0.5, 0.5, 1.0), Alpha=0.25,
                              Emission=(1.0, 0.5, 0.0, 1.0), Emission_Strength=4.0, Roughness=0.5,
                              Anisotropic=0.5, Anisotropic_Rotation=0.1, Subsurface=0.5,
                              Subsurface_Color=(1.0, 0.0, 0.0, 1.0))
    node.distribution = 'MULTI_GGX'
    spec = materials.convert_material(mat)
    assert approx(one(spec, "transparent")["color"], (0.75,) * 3)
    assert approx(one(spec, "principled_diffuse")["color"], (0.25 * 0.75, 0.25 * 0.25, 0.25 * 0.25))
    assert approx(spec.emission, (1.0, 0.5, 0.0))                         # x alpha
    s = one(spec, "reflection", "specular")
    aspect = math.sqrt(1.0 - 0.5 * 0.9)
    assert s["alpha_x"] == pytest.approx(0.25 / aspect) and s["alpha_y"] == pytest.approx(0.25 * aspect)
    assert s["distribution"] == "multi_ggx" and approx(s["color"], (0.25,) * 3)
    assert any("rotation" in n for n in spec.notes) and any("subsurface" in n for n in spec.notes)


def test_principled_metal_and_glass(empty_scene):
    metal, node = node_material("M", "ShaderNodeBsdfPrincipled", Base_Color=(1.0, 0.8, 0.3, 1.0), Metallic=1.0,
                                Roughness=0.0)
    glass, gnode = node_material("G", "ShaderNodeBsdfPrincipled", Base_Color=(0.9, 1.0, 0.9, 1.0),
                                 Transmission=1.0, IOR=1.5, Roughness=0.0)
    m, g = materials.convert_material(metal), materials.convert_material(glass)
    (r,) = closures_of(m)
    assert r["kind"] == "reflection" and r["distribution"] == "sharp"
    assert approx(r["specular_color"], (1.0, 0.8, 0.3))
    t = one(g, "refraction")
    assert t["distribution"] == "sharp" and approx(t["color"], (0.9, 1.0, 0.9)) and t["factors_off"] == [0]
    assert g.core_arguments()["factors"][0]["kind"] == "fresnel"
    assert not closures_of(g, "diffuse") and not closures_of(g, "principled_diffuse")


def test_glossy_distributions_and_sharp_threshold(empty_scene):
    specs = {}
    for dist in ("GGX", "BECKMANN", "MULTI_GGX", "ASHIKHMIN_SHIRLEY"):
        mat, node = node_material("Gl" + dist, "ShaderNodeBsdfGlossy", Color=(0.9, 0.8, 0.7, 1.0), Roughness=0.3)
        node.distribution = dist
        specs[dist] = materials.convert_material(mat)
    for dist, expected in (("GGX", "ggx"), ("BECKMANN", "beckmann"), ("MULTI_GGX", "multi_ggx")):
        r = one(specs[dist], "reflection")
        assert (r["distribution"], r["fresnel"]) == (expected, "none") and specs[dist].notes == []
        assert r["alpha_x"] == pytest.approx(0.09) and approx(r["color"], (0.9, 0.8, 0.7))
    # Multiscatter GGX tints its bounces after the first by the colour: the core needs it, or the lobe scatters once
    # only (a rough Multiscatter floor was 0.84 of Cycles' light). The others have no use for it.
    assert approx(one(specs["MULTI_GGX"], "reflection")["specular_color"], (0.9, 0.8, 0.7))
    assert "specular_color" not in one(specs["GGX"], "reflection")
    assert one(specs["ASHIKHMIN_SHIRLEY"], "reflection")["distribution"] == "ggx"
    assert any("Ashikhmin" in n for n in specs["ASHIKHMIN_SHIRLEY"].notes)
    polished, node = node_material("Polished", "ShaderNodeBsdfGlossy", Roughness=0.05)
    assert one(materials.convert_material(polished), "reflection")["distribution"] == "sharp"


def test_a_near_mirror_multiscatter_glossy_keeps_the_alpha_cycles_3_reports(empty_scene):
    """Cycles 3.x renders a Glossy of Multiscatter GGX at roughness 0.02 as a microfacet lobe whose clamped D all
    but drops the lights it reflects: the export's mirror keeps its alpha (reported_alpha) for the core to weigh
    them so. A true mirror to Cycles (alpha^2 < 1e-7), GGX, and Cycles 4.x (which fixed it) keep none."""
    specs = {}
    for name, dist, roughness in (("Multi", 'MULTI_GGX', 0.02), ("Ggx", 'GGX', 0.02), ("Polished", 'MULTI_GGX', 0.015)):
        mat, node = node_material(name, "ShaderNodeBsdfGlossy", Roughness=roughness)
        node.distribution = dist
        specs[name] = one(materials.convert_material(mat), "reflection")
    assert all(d["distribution"] == "sharp" for d in specs.values())
    if compat.MULTISCATTER_LIGHT_ESTIMATE == "light_sample":
        assert specs["Multi"]["reported_alpha"] == pytest.approx(0.02 ** 2, rel=1e-5)
    else:
        assert "reported_alpha" not in specs["Multi"]
    assert "reported_alpha" not in specs["Ggx"] and "reported_alpha" not in specs["Polished"]


def test_anisotropic_glossy_alphas(empty_scene):
    idname = "ShaderNodeBsdfAnisotropic" if not compat.PRINCIPLED_V2 else "ShaderNodeBsdfGlossy"
    for anisotropy in (0.5, -0.5):
        mat, node = node_material("An", idname, Roughness=0.4, Anisotropy=anisotropy)
        node.distribution = 'GGX'
        r = one(materials.convert_material(mat), "reflection")
        a = 0.16
        expected = (a * 0.5, a / 0.5) if anisotropy > 0 else (a / 0.5, a * 0.5)
        assert (r["alpha_x"], r["alpha_y"]) == pytest.approx(expected)


def test_glass_splits_by_a_fresnel_factor(empty_scene):
    smooth, node = node_material("Ga", "ShaderNodeBsdfGlass", Color=(1.0, 0.9, 0.8, 1.0), IOR=1.33, Roughness=0.0)
    node.distribution = 'GGX'
    frosted, node = node_material("Frosted", "ShaderNodeBsdfGlass", IOR=1.5, Roughness=0.3)
    node.distribution = 'GGX'
    s, f = materials.convert_material(smooth), materials.convert_material(frosted)
    assert s.notes == [] and f.notes == []
    assert s.core_arguments()["factors"] == [dict(kind="fresnel", value=pytest.approx(1.33))]
    r, t = one(s, "reflection"), one(s, "refraction")
    assert (r["distribution"], t["distribution"]) == ("sharp", "sharp") and r["fresnel"] == "none"
    assert r["factors_on"] == [0] and t["factors_off"] == [0] and approx(t["color"], (1.0, 0.9, 0.8))
    r, t = one(f, "reflection"), one(f, "refraction")
    assert (r["distribution"], t["distribution"]) == ("ggx", "ggx") and t["alpha_x"] == pytest.approx(0.09)
    assert "IOR 1.50" in f.describe() and "rough" in f.describe()
    refraction, node = node_material("Re", "ShaderNodeBsdfRefraction", IOR=1.5, Roughness=0.0)
    r = materials.convert_material(refraction)
    assert [d["kind"] for d in closures_of(r)] == ["refraction"] and r.core_arguments()["factors"] == []


def test_a_multiscatter_glass_is_the_walk_on_both_sides(empty_scene):
    """A rough Glass of Multiscatter GGX: one multi_ggx_glass closure per side, unweighted by a Fresnel factor (the
    walk's microfacets pick reflection or refraction), its colour passed on as the tint of the later scatterings,
    and the approximation noted. A smooth one stays a split sharp glass."""
    rough, node = node_material("Mg", "ShaderNodeBsdfGlass", Color=(1.0, 0.9, 0.8, 1.0), IOR=1.4, Roughness=0.5)
    node.distribution = 'MULTI_GGX'
    spec = materials.convert_material(rough)
    r, t = one(spec, "reflection"), one(spec, "refraction")
    assert (r["distribution"], t["distribution"]) == ("multi_ggx_glass", "multi_ggx_glass")
    assert spec.core_arguments()["factors"] == [] and "factors_on" not in r and "factors_off" not in t
    assert r["alpha_x"] == pytest.approx(0.25) and t["ior"] == pytest.approx(1.4)
    assert approx(t["color"], (1.0, 0.9, 0.8)) and approx(t["specular_color"], (1.0, 0.9, 0.8))
    assert any("multiscatter GGX glass" in n for n in spec.notes)
    smooth, node = node_material("Ms", "ShaderNodeBsdfGlass", IOR=1.4, Roughness=0.02)
    node.distribution = 'MULTI_GGX'
    spec = materials.convert_material(smooth)
    assert one(spec, "refraction")["distribution"] == "sharp" and spec.notes == []


def test_basic_shaders(empty_scene):
    made = {
        "diffuse": node_material("Di", "ShaderNodeBsdfDiffuse", Color=(0.5, 0.25, 0.125, 1.0), Roughness=0.5),
        "translucent": node_material("Tr", "ShaderNodeBsdfTranslucent", Color=(0.3, 0.3, 0.3, 1.0)),
        "transparent": node_material("Tp", "ShaderNodeBsdfTransparent", Color=(0.9, 0.9, 0.9, 1.0)),
        "emission": node_material("Em", "ShaderNodeEmission", Color=(1.0, 0.5, 0.25, 1.0), Strength=10.0),
        "holdout": node_material("Ho", "ShaderNodeHoldout"),
        "subsurface": node_material("Ss", "ShaderNodeSubsurfaceScattering", Color=(0.7, 0.6, 0.5, 1.0)),
    }
    if not compat.PRINCIPLED_V2:
        made["velvet"] = node_material("Ve", "ShaderNodeBsdfVelvet", Color=(0.4, 0.4, 0.4, 1.0), Sigma=0.7)
    spec = {k: materials.convert_material(m) for k, (m, _) in made.items()}
    d = one(spec["diffuse"], "diffuse")
    assert approx(d["color"], (0.5, 0.25, 0.125)) and d["roughness"] == pytest.approx(0.5)
    assert spec["diffuse"].notes == []
    assert approx(one(spec["translucent"], "translucent")["color"], (0.3,) * 3)
    assert approx(one(spec["transparent"], "transparent")["color"], (0.9,) * 3)
    # An Emission shader reflects nothing: a black surface plus the emitted radiance colour x strength.
    assert approx(spec["emission"].emission, (10.0, 5.0, 2.5))
    assert all(max(d["color"]) == 0.0 for d in closures_of(spec["emission"]))
    assert spec["holdout"].core_arguments()["holdout"] is True
    assert any("subsurface" in n for n in spec["subsurface"].notes)
    if "velvet" in spec:
        v = one(spec["velvet"], "velvet")
        assert v["roughness"] == pytest.approx(0.7) and approx(v["color"], (0.4,) * 3)


def _mix_material(name, fac=0.5):
    mat, mix = node_material(name, "ShaderNodeMixShader", Fac=fac)
    tree = mat.node_tree
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (0.8, 0.4, 0.2, 1.0)
    glossy = tree.nodes.new("ShaderNodeBsdfGlossy")
    glossy.inputs["Roughness"].default_value = 0.3
    tree.links.new(diffuse.outputs[0], mix.inputs[1])
    tree.links.new(glossy.outputs[0], mix.inputs[2])
    return mat, mix, tree


def test_mix_and_add_with_constant_factors(empty_scene):
    mat, mix, tree = _mix_material("DiffGloss", 0.3)
    spec = materials.convert_material(mat)
    assert spec.notes == [] and spec.core_arguments()["factors"] == []
    assert approx(one(spec, "diffuse")["color"], (0.56, 0.28, 0.14))
    assert approx(one(spec, "reflection")["color"], (0.3 * 0.8,) * 3)      # Glossy's default colour 0.8
    add = tree.nodes.new("ShaderNodeAddShader")
    emission = tree.nodes.new("ShaderNodeEmission")
    emission.inputs["Strength"].default_value = 8.0
    tree.links.new(mix.outputs[0], add.inputs[0])
    tree.links.new(emission.outputs[0], add.inputs[1])
    tree.links.new(add.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    spec = materials.convert_material(mat)
    assert approx(spec.emission, (8.0, 8.0, 8.0)) and approx(one(spec, "diffuse")["color"], (0.56, 0.28, 0.14))
    # Two diffuse shaders mixed are one closure.
    twin, mix = node_material("Twin", "ShaderNodeMixShader", Fac=0.25)
    for i, c in ((1, 0.4), (2, 0.8)):
        node = twin.node_tree.nodes.new("ShaderNodeBsdfDiffuse")
        node.inputs["Color"].default_value = (c, c, c, 1.0)
        twin.node_tree.links.new(node.outputs[0], mix.inputs[i])
    (d,) = closures_of(materials.convert_material(twin))
    assert approx(d["color"], (0.75 * 0.4 + 0.25 * 0.8,) * 3)


def test_mix_by_fresnel_and_layer_weight_is_view_dependent(empty_scene):
    mat, mix, tree = _mix_material("Coated")
    fresnel = tree.nodes.new("ShaderNodeFresnel")
    fresnel.inputs["IOR"].default_value = 1.6
    reroute = tree.nodes.new("NodeReroute")
    tree.links.new(fresnel.outputs[0], reroute.inputs[0])
    tree.links.new(reroute.outputs[0], mix.inputs["Fac"])
    spec = materials.convert_material(mat)
    assert spec.notes == []
    assert spec.core_arguments()["factors"] == [dict(kind="fresnel", value=pytest.approx(1.6))]
    d, r = one(spec, "diffuse"), one(spec, "reflection")
    assert d["factors_off"] == [0] and r["factors_on"] == [0] and approx(d["color"], (0.8, 0.4, 0.2))
    for output, kind in (("Fresnel", "layer_fresnel"), ("Facing", "layer_facing")):
        layer = tree.nodes.new("ShaderNodeLayerWeight")
        layer.inputs["Blend"].default_value = 0.3
        tree.links.new(layer.outputs[output], mix.inputs["Fac"])
        spec = materials.convert_material(mat)
        assert spec.core_arguments()["factors"] == [dict(kind=kind, value=pytest.approx(0.3))]
    # Nested: the same Fresnel node above two mixes shares one factor; bits combine.
    outer = tree.nodes.new("ShaderNodeMixShader")
    tree.links.new(fresnel.outputs[0], mix.inputs["Fac"])
    tree.links.new(fresnel.outputs[0], outer.inputs["Fac"])
    tree.links.new(mix.outputs[0], outer.inputs[1])
    tree.links.new(tree.nodes.new("ShaderNodeBsdfTransparent").outputs[0], outer.inputs[2])
    tree.links.new(outer.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    spec = materials.convert_material(mat)
    assert len(spec.core_arguments()["factors"]) == 1
    assert one(spec, "diffuse")["factors_off"] == [0] and one(spec, "transparent")["factors_on"] == [0]
    r = one(spec, "reflection")
    assert r["factors_on"] == [0] and r["factors_off"] == [0]
    assert any("applied once" in n for n in spec.notes)        # the diffuse's (1 - F)^2: bits OR together
    # Anything else driving Fac: compiled into the node program (without programs in the core: its unconnected
    # value, noted).
    mat, mix, tree = _mix_material("Math", 0.3)
    tree.links.new(tree.nodes.new("ShaderNodeMath").outputs[0], mix.inputs["Fac"])
    spec = materials.convert_material(mat)
    if shader_program.op_table() is None:
        assert any("Math" in n for n in spec.notes) and approx(one(spec, "diffuse")["color"], (0.56, 0.28, 0.14))
    else:
        assert spec.notes == [] and spec.core_arguments()["factors"] == []
        targets = {(o["target"], o["index"]) for o in spec.core_arguments()["program"]["outputs"]}
        assert targets == {("closure_color", 0), ("closure_color", 1)}


def _group(name, inner_type):
    """A node group around one shader node of `inner_type` whose Color comes from the group's input."""
    group = bpy.data.node_groups.new(name, "ShaderNodeTree")
    compat.new_group_socket(group, "INPUT", "NodeSocketColor", "Tint")
    compat.new_group_socket(group, "OUTPUT", "NodeSocketShader", "Shader")
    group_in = group.nodes.new("NodeGroupInput")
    group_out = group.nodes.new("NodeGroupOutput")
    shader = group.nodes.new(inner_type)
    group.links.new(group_in.outputs["Tint"], shader.inputs["Color"])
    group.links.new(shader.outputs[0], group_out.inputs["Shader"])
    return group


def test_shaders_inside_nested_groups_are_converted(empty_scene):
    inner = _group("InnerDiffuse", "ShaderNodeBsdfDiffuse")
    outer = bpy.data.node_groups.new("Outer", "ShaderNodeTree")
    compat.new_group_socket(outer, "INPUT", "NodeSocketColor", "Tint")
    compat.new_group_socket(outer, "OUTPUT", "NodeSocketShader", "Shader")
    o_in, o_out = outer.nodes.new("NodeGroupInput"), outer.nodes.new("NodeGroupOutput")
    node = outer.nodes.new("ShaderNodeGroup")
    node.node_tree = inner
    outer.links.new(o_in.outputs["Tint"], node.inputs["Tint"])
    outer.links.new(node.outputs["Shader"], o_out.inputs["Shader"])

    mat = bpy.data.materials.new("Grouped")
    enable_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    group_node = tree.nodes.new("ShaderNodeGroup")
    group_node.node_tree = outer
    rgb = tree.nodes.new("ShaderNodeRGB")
    rgb.outputs[0].default_value = (0.1, 0.6, 0.3, 1.0)
    tree.links.new(rgb.outputs[0], group_node.inputs["Tint"])
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(group_node.outputs["Shader"], output.inputs["Surface"])
    spec = materials.convert_material(mat)
    assert spec.notes == [] and approx(one(spec, "diffuse")["color"], (0.1, 0.6, 0.3))
    # Unlinked, the Group node's own input value.
    tree.links.remove(group_node.inputs["Tint"].links[0])
    group_node.inputs["Tint"].default_value = (0.2, 0.2, 0.9, 1.0)
    assert approx(one(materials.convert_material(mat), "diffuse")["color"], (0.2, 0.2, 0.9))


def test_unsupported_setups_fall_back_with_a_note(empty_scene):
    textured, shader = node_material("Tex", "ShaderNodeBsdfPrincipled")
    textured.node_tree.links.new(textured.node_tree.nodes.new("ShaderNodeTexChecker").outputs["Color"],
                                 shader.inputs["Base Color"])
    toon, _ = node_material("Toon", "ShaderNodeBsdfToon", Color=(0.1, 0.2, 0.3, 1.0))
    t = materials.convert_material(textured)
    if shader_program.op_table() is None:      # a core without node programs: the unconnected value, noted
        assert any("Checker" in n for n in t.notes)
    else:                                       # compiled: the diffuse colour is a program output
        assert t.uses_program and not any("Checker" in n for n in t.notes)
        outputs = t.core_arguments()["program"]["outputs"]
        assert any(o["target"] == "closure_color" for o in outputs)
    o = materials.convert_material(toon)
    assert approx(one(o, "diffuse")["color"], (0.1, 0.2, 0.3)) and any("Toon" in n for n in o.notes)


def test_material_without_nodes_uses_its_viewport_colour(empty_scene):
    mat = bpy.data.materials.new("Plain")
    mat.diffuse_color = (0.3, 0.6, 0.9, 1.0)
    if compat.has_use_nodes_switch(mat):
        mat.use_nodes = False
        spec = materials.convert_material(mat)
        assert approx(one(spec, "diffuse")["color"], (0.3, 0.6, 0.9))
    else:   # Blender 5.0: every material renders its node tree (a new one: Principled, Base Color 0.8)
        spec = materials.convert_material(mat)
        assert max(one(spec, "diffuse")["color"]) > 0.0
    assert materials.convert_material(None).name == materials.DEFAULT_MATERIAL_NAME


def test_colours_are_clamped_and_nans_replaced(empty_scene):
    mat, _ = node_material("Hot", "ShaderNodeBsdfDiffuse", Color=(2.0, 0.5, -1.0, 1.0))
    spec = materials.convert_material(mat)
    assert approx(one(spec, "diffuse")["color"], (1.0, 0.5, 0.0)) and any("clamped" in n for n in spec.notes)
    nan, _ = node_material("NaN", "ShaderNodeBsdfGlossy", Roughness=float("nan"))
    spec = materials.convert_material(nan)
    r = one(spec, "reflection")
    assert all(math.isfinite(v) for v in (r["alpha_x"], r["alpha_y"])) and any("not a number" in n
                                                                              for n in spec.notes)


def test_too_many_closures_are_reduced_with_a_note(empty_scene):
    mat = bpy.data.materials.new("Many")
    enable_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    previous = None
    for i in range(12):
        glossy = tree.nodes.new("ShaderNodeBsdfGlossy")
        glossy.inputs["Roughness"].default_value = 0.1 + 0.05 * i       # all different: no merging
        if previous is None:
            previous = glossy
            continue
        add = tree.nodes.new("ShaderNodeAddShader")
        tree.links.new(previous.outputs[0], add.inputs[0])
        tree.links.new(glossy.outputs[0], add.inputs[1])
        previous = add
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(previous.outputs[0], output.inputs["Surface"])
    spec = materials.convert_material(mat)
    assert len(closures_of(spec)) == materials.MAX_DIRECTIONAL and any("dropped" in n for n in spec.notes)


def test_closures_reach_the_core(empty_scene):
    add_camera(empty_scene)
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    plane = bpy.context.active_object
    metal, node = node_material("Brushed", "ShaderNodeBsdfGlossy", Color=(0.8, 0.6, 0.4, 1.0), Roughness=0.45)
    node.distribution = 'GGX'
    plane.data.materials.append(metal)
    frame = export_current()
    (exported,) = frame.scene.materials
    assert exported["kind"] == "closures"
    (closure,) = exported["closures"]
    assert closure["kind"] == "reflection" and closure["alpha_x"] == pytest.approx(0.45 ** 2)
    assert approx(closure["color"], (0.8, 0.6, 0.4))


def test_meshes_are_exported_evaluated_with_their_slots(empty_scene):
    add_camera(empty_scene)
    bpy.ops.mesh.primitive_cube_add(size=2.0, location=(1.0, 2.0, 3.0))
    cube = bpy.context.active_object
    cube.scale = (2.0, 1.0, 1.0)
    cube.modifiers.new("Subdivision", 'SUBSURF').levels = 1          # 6 faces -> 24 quads -> 48 triangles
    red, _ = node_material("Red", "ShaderNodeBsdfDiffuse", Color=(1.0, 0.0, 0.0, 1.0))
    cube.data.materials.append(red)
    cube.data.materials.append(None)                                  # an empty slot
    cube.data.polygons[0].material_index = 1
    cube.data.polygons[1].material_index = 7                          # beyond the last slot: clamped

    frame = export_current()
    (mesh,) = frame.scene.meshes
    assert mesh["vertices"].dtype == np.float32 and mesh["vertices"].shape[1] == 3
    assert mesh["triangles"].dtype == np.int32 and mesh["triangles"].shape == (48, 3)
    assert mesh["normals"].dtype == np.float32 and mesh["normals"].shape == (48, 3, 3)
    ids = mesh["material_ids"]
    assert ids.dtype == np.int32 and ids.shape == (48,)
    names = [frame.scene.materials[i]["name"] for i in np.unique(ids)]
    assert sorted(names) == sorted(["Red", materials.DEFAULT_MATERIAL_NAME])
    np.testing.assert_allclose(mesh["transform"], np.array(cube.matrix_world), atol=1e-6)
    assert np.allclose(np.linalg.norm(mesh["normals"], axis=2), 1.0, atol=1e-4)
    assert frame.triangles == 48


def test_each_material_is_exported_once_and_faceless_objects_are_skipped(empty_scene):
    add_camera(empty_scene)
    shared, _ = node_material("Shared", "ShaderNodeBsdfDiffuse")
    for x in (-2.0, 2.0):
        bpy.ops.mesh.primitive_uv_sphere_add(segments=8, ring_count=4, location=(x, 0.0, 0.0))
        bpy.context.active_object.data.materials.append(shared)
    bpy.ops.curve.primitive_bezier_curve_add()                        # no bevel: no faces
    bpy.ops.object.text_add(location=(0.0, 0.0, 2.0))                # text: its mesh comes as an instance
    frame = export_current()
    assert len(frame.scene.meshes) == 3                                # two spheres and the text, once
    assert [m["name"] for m in frame.scene.materials].count("Shared") == 1


# --- lights -----------------------------------------------------------------------------------------------

def light_object(scene, kind, energy, location=(0.0, 0.0, 3.0), rotation=(0.0, 0.0, 0.0),
                 scale=(1.0, 1.0, 1.0), color=(1.0, 0.5, 0.25), **props):
    data = bpy.data.lights.new(kind, kind)
    data.energy = energy
    data.color = color
    for key, value in props.items():
        setattr(data, key, value)
    obj = bpy.data.objects.new(kind, data)
    obj.location, obj.rotation_euler, obj.scale = location, rotation, scale
    scene.collection.objects.link(obj)
    return obj


def exported_lights(scene):
    return export_current().scene.lights


def test_point_light_units_follow_cycles(empty_scene):
    add_camera(empty_scene)
    light_object(empty_scene, 'POINT', 100.0, location=(1.0, 2.0, 3.0), shadow_soft_size=0.25)
    ((kind, kw),) = exported_lights(empty_scene)
    assert kind == "point"
    assert approx(kw["intensity"], tuple(c * 100.0 / (4.0 * math.pi) for c in (1.0, 0.5, 0.25)))
    assert approx(kw["position"], (1.0, 2.0, 3.0)) and kw["radius"] == pytest.approx(0.25)


def test_spot_light_keeps_its_cone(empty_scene):
    add_camera(empty_scene)
    light_object(empty_scene, 'SPOT', 50.0, rotation=(math.radians(90.0), 0.0, 0.0), scale=(3.0, 3.0, 3.0),
                 spot_size=math.radians(60.0), spot_blend=0.25, shadow_soft_size=0.1)
    frame = export_current()
    ((kind, kw),) = frame.scene.lights
    assert kind == "spot" and approx(kw["intensity"], tuple(c * 50.0 / (4 * math.pi) for c in (1, .5, .25)))
    assert approx(kw["direction"], (0.0, 1.0, 0.0))      # local -Z turned 90 degrees about X, scale ignored
    assert kw["spot_size"] == pytest.approx(math.radians(60.0)) and kw["spot_blend"] == pytest.approx(0.25)
    assert kw["radius"] == pytest.approx(0.1)
    assert not frame.warnings


def test_sun_light(empty_scene):
    add_camera(empty_scene)
    light_object(empty_scene, 'SUN', 3.0, rotation=(math.radians(90.0), 0.0, 0.0), angle=0.1)
    ((kind, kw),) = exported_lights(empty_scene)
    assert kind == "sun"
    assert approx(kw["irradiance"], (3.0, 1.5, 0.75))
    assert approx(kw["direction"], (0.0, 1.0, 0.0))      # local -Z turned 90 degrees about X
    assert kw["angle"] == pytest.approx(0.1)


@pytest.mark.parametrize("rotation", [(0.0, 0.0, 0.0), (0.3, -1.1, 2.0)])
def test_rectangular_area_light(empty_scene, rotation):
    add_camera(empty_scene)
    obj = light_object(empty_scene, 'AREA', 200.0, rotation=rotation, scale=(1.0, 2.0, 1.0),
                       shape='RECTANGLE', size=2.0, size_y=1.5)
    ((kind, kw),) = exported_lights(empty_scene)
    assert kind == "area"
    u, v = np.array(kw["axis_u"]), np.array(kw["axis_v"])
    area = 2.0 * 1.0 * 1.5 * 2.0                             # sizes times the object scale
    assert np.linalg.norm(np.cross(u, v)) == pytest.approx(area, rel=1e-5)
    facing = -np.array(obj.matrix_world.to_3x3().col[2])      # Blender's area lights shine along local -Z
    normal = np.cross(u, v) / area
    assert normal @ (facing / np.linalg.norm(facing)) == pytest.approx(1.0, abs=1e-5)
    # Cycles 3.4: L = P / (4 A); 4.x: P / (π A).
    divisor = math.pi if compat.CYCLES_4_LIGHTS else 4.0
    assert approx(kw["radiance"], tuple(c * 200.0 / (divisor * area) for c in (1.0, 0.5, 0.25)))
    assert approx(kw["center"], tuple(obj.matrix_world.translation))


@pytest.mark.parametrize("shape", ['DISK', 'ELLIPSE'])
def test_round_area_lights_are_ellipses(empty_scene, shape):
    add_camera(empty_scene)
    light_object(empty_scene, 'AREA', 100.0, shape=shape, size=1.0, size_y=2.0)
    frame = export_current()
    ((kind, kw),) = frame.scene.lights
    size_y = 2.0 if shape == 'ELLIPSE' else 1.0
    area = math.pi / 4.0 * size_y
    assert kw["shape"] == "ellipse"
    assert np.linalg.norm(kw["axis_u"]) * np.linalg.norm(kw["axis_v"]) == pytest.approx(size_y, rel=1e-5)
    divisor = math.pi if compat.CYCLES_4_LIGHTS else 4.0
    assert kw["radiance"][0] == pytest.approx(100.0 / (divisor * area), rel=1e-5)
    assert not frame.warnings


# --- camera, world, settings ---------------------------------------------------------------------------------

def test_camera_matches_blender(empty_scene):
    cam = add_camera(empty_scene)
    cam.scale = (2.0, 2.0, 2.0)                                # Cycles ignores the camera's scale
    cam.data.shift_x = 0.1
    empty_scene.render.resolution_x, empty_scene.render.resolution_y = 320, 180
    empty_scene.render.resolution_percentage = 50
    frame = export_current()
    assert (frame.width, frame.height) == (160, 90)
    camera = frame.camera
    assert (camera.width, camera.height) == (160, 90)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    expected = cam.evaluated_get(depsgraph).calc_matrix_camera(depsgraph, x=160, y=90)
    np.testing.assert_allclose(camera.projection, np.array(expected), rtol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(camera.to_world[:3, :3], axis=0), 1.0, rtol=1e-6)
    np.testing.assert_allclose(camera.to_world[:3, 3], (0.0, -5.0, 1.0), atol=1e-6)


def test_no_camera_is_an_export_error(empty_scene):
    with pytest.raises(export.ExportError, match="camera"):
        export_current()


def test_world_background(empty_scene):
    add_camera(empty_scene)
    world = uniform_world(empty_scene, (0.5, 0.25, 1.0), 2.0)
    assert approx(export_current().scene.background, (1.0, 0.5, 2.0))
    if compat.has_use_nodes_switch(world):      # Blender 5.0: worlds always render their node tree
        world.use_nodes = False
        world.color = (0.1, 0.2, 0.3)
        assert approx(export_current().scene.background, (0.1, 0.2, 0.3))


def test_settings_go_to_the_core_unchanged(empty_scene):
    add_camera(empty_scene)
    props = empty_scene.photonsplat
    props.photons, props.radius, props.method, props.max_bounces, props.seed = 1234, 0.05, "brute", 3, 7
    settings = export_current().settings
    assert (settings.photons, settings.method, settings.max_bounces, settings.seed) == (1234, "brute", 3, 7)
    assert settings.radius == pytest.approx(0.05)


def test_collection_instances_are_exported_with_their_own_transforms(empty_scene):
    add_camera(empty_scene)
    group = bpy.data.collections.new("Group")                     # not linked to the scene: only instanced
    bpy.ops.mesh.primitive_cube_add(size=1.0)
    cube = bpy.context.active_object
    for collection in cube.users_collection:
        collection.objects.unlink(cube)
    group.objects.link(cube)
    for x in (-3.0, 3.0):
        empty = bpy.data.objects.new(f"Instance{x}", None)
        empty.instance_type = 'COLLECTION'
        empty.instance_collection = group
        empty.location = (x, 0.0, 0.0)
        empty_scene.collection.objects.link(empty)
    meshes = export_current().scene.meshes
    assert sorted(m["transform"][0, 3] for m in meshes) == pytest.approx([-3.0, 3.0])
    assert all(len(m["triangles"]) == 12 for m in meshes)


def test_principled_inputs_of_this_blender_are_read(empty_scene):
    """Principled v1 (3.x) and v2 (4.0+) name inputs differently; the export reads the running version's."""
    coat, node = node_material("Coated", "ShaderNodeBsdfPrincipled", Base_Color=(0.2, 0.3, 0.4, 1.0),
                               Subsurface=0.5, Coat=0.5, Sheen=0.5)
    spec = materials.convert_material(coat)
    labels = [c.label for c in spec.closures]
    assert any(label in ("clearcoat", "coat") for label in labels) and "sheen" in labels
    assert any("subsurface" in n for n in spec.notes)
    diffuse = [d for d in closures_of(spec) if d["kind"] in ("diffuse", "principled_diffuse")]
    assert len(diffuse) == 1 and max(diffuse[0]["color"]) > 0.0


@pytest.mark.skipif(bpy.app.version < (4, 3, 0), reason="the Metallic BSDF node came with Blender 4.3")
def test_metallic_bsdf_is_a_metal(empty_scene):
    f82, node = node_material("F82", "ShaderNodeBsdfMetallic", Base_Color=(0.9, 0.6, 0.3, 1.0), Roughness=0.3,
                              Edge_Tint=(1.0, 1.0, 1.0, 1.0))
    node.distribution = 'GGX'
    spec = materials.convert_material(f82)
    r = one(spec, "reflection")
    assert (r["fresnel"], r["distribution"]) == ("schlick", "ggx") and spec.notes == []
    assert approx(r["specular_color"], (0.9, 0.6, 0.3)) and r["alpha_x"] == pytest.approx(0.09)
    conductor, node = node_material("Gold", "ShaderNodeBsdfMetallic", Roughness=0.0)
    node.fresnel_type = 'PHYSICAL_CONDUCTOR'
    node.inputs["IOR"].default_value = (0.18, 0.42, 1.37)
    node.inputs["Extinction"].default_value = (3.42, 2.35, 1.77)
    spec = materials.convert_material(conductor)
    expected = tuple(((n - 1) ** 2 + k * k) / ((n + 1) ** 2 + k * k)
                     for n, k in zip((0.18, 0.42, 1.37), (3.42, 2.35, 1.77)))
    r = one(spec, "reflection")
    assert r["distribution"] == "sharp" and approx(r["specular_color"], expected, rel=1e-4)
    assert any("conductor" in n for n in spec.notes)


def test_base_colour_texture_goes_to_the_diffuse_closure(empty_scene):
    add_camera(empty_scene)
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    plane = bpy.context.active_object
    mat, shader = node_material("Textured", "ShaderNodeBsdfPrincipled", Metallic=0.0)
    image = bpy.data.images.new("Checker", 4, 4)
    texture = mat.node_tree.nodes.new("ShaderNodeTexImage")
    texture.image = image
    mat.node_tree.links.new(texture.outputs["Color"], shader.inputs[compat.principled_input("base_color")])
    plane.data.materials.append(mat)
    frame = export_current()
    (exported,) = frame.scene.materials
    assert len(frame.scene.textures) == 1
    diffuse = [d for d in exported["closures"] if d["kind"] in ("diffuse", "principled_diffuse")]
    assert len(diffuse) == 1 and diffuse[0]["texture"] == 0 and diffuse[0]["texture_target"] == "color"
    assert all("texture" not in d for d in exported["closures"] if d not in diffuse)


def _split_normals(mesh_data, count):
    """Every triangle corner's split normal, read as the export read them before issue 19 (the reference)."""
    compat.prepare_corner_normals(mesh_data)
    normals = np.empty(count * 9, dtype=np.float32)
    mesh_data.loop_triangles.foreach_get("split_normals", normals)
    return normals.reshape(-1, 3, 3)


@pytest.mark.parametrize("shading", ["smooth", "flat", "mixed", "auto_smooth"])
def test_normals_are_the_split_normals_bit_for_bit(empty_scene, shading):
    """A smooth mesh's normals are read per vertex (issue 19: a quarter of the floats); expanded to the corners they
    are exactly the split normals, so images do not change. Other meshes keep per-corner split normals, except
    the triangles Cycles shades flat (compat.triangles_shaded_flat: this subdivided Suzanne's quads are not
    planar), which take their own normal: perpendicular to their edges, on their split normals' side."""
    from photonsplat.export import mesh as mesh_export
    bpy.ops.mesh.primitive_monkey_add()
    ob = bpy.context.active_object
    ob.modifiers.new("Subdivision", 'SUBSURF').levels = 1
    for i, polygon in enumerate(ob.data.polygons):
        polygon.use_smooth = shading in ("smooth", "auto_smooth") or (shading == "mixed" and i % 2 == 0)
    if shading == "auto_smooth":
        if not hasattr(ob.data, "use_auto_smooth"):
            pytest.skip("auto smooth is a modifier since Blender 4.1")
        ob.data.use_auto_smooth = True
    evaluated = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
    arrays = mesh_export.triangle_mesh(evaluated, mesh_export.MeshNeeds(uvs=True, slots=True))
    expected = _split_normals(evaluated.data, len(arrays.triangles))
    assert (arrays.normals.ndim == 2) == (shading == "smooth")
    corners = arrays.normals[arrays.triangles] if arrays.normals.ndim == 2 else arrays.normals
    assert corners.shape == expected.shape
    flat = compat.triangles_shaded_flat(evaluated.data)
    if flat is None:
        flat = np.zeros(len(arrays.triangles), dtype=bool)
    assert flat.any() == (shading == "flat" or (shading == "mixed" and not hasattr(ob.data, "normals_domain")))
    assert np.array_equal(corners[~flat].view(np.uint32), expected[~flat].view(np.uint32))
    points = arrays.vertices[arrays.triangles[flat]].astype(np.float64)
    own = corners[flat].astype(np.float64)
    for edge in (points[:, 1] - points[:, 0], points[:, 2] - points[:, 0]):
        edge /= np.linalg.norm(edge, axis=1, keepdims=True)
        assert np.all(np.abs(np.einsum("tcj,tj->tc", own, edge)) < 1e-5)
    assert np.allclose(np.linalg.norm(own, axis=2), 1.0, atol=1e-6)
    assert np.all(np.einsum("tcj,tcj->tc", own, expected[flat]) > 0.0)
    assert arrays.uvs.shape == (len(arrays.triangles), 3, 2) and arrays.slots.shape == (len(arrays.triangles),)


def test_plain_materials_export_no_uvs_and_no_slots(empty_scene):
    """Only what a material reads is exported (issue 19): a plain diffuse mesh has neither its UV map nor its
    slots in the core (its one material everywhere); an image texture brings the UV map back."""
    add_camera(empty_scene)
    bpy.ops.mesh.primitive_monkey_add()
    ob = bpy.context.active_object
    plain, diffuse = node_material("Plain", "ShaderNodeBsdfDiffuse")
    ob.data.materials.append(plain)
    ob.data.materials.append(plain)
    ob.data.polygons[0].material_index = 1
    (mesh,) = export_current().scene.meshes
    assert mesh["uvs"] is None
    assert np.array_equal(mesh["material_ids"], np.zeros(len(mesh["triangles"]), np.int32))
    image = bpy.data.images.new("Checker", 4, 4)
    texture = plain.node_tree.nodes.new("ShaderNodeTexImage")
    texture.image = image
    plain.node_tree.links.new(texture.outputs["Color"], diffuse.inputs["Color"])
    (mesh,) = export_current().scene.meshes
    assert mesh["uvs"].shape == (len(mesh["triangles"]), 3, 2)
