"""Writes closure_gallery.blend next to this script: one probe sphere and every material of the closure gallery.

  - a UV sphere "Probe" (radius 0.5 m, 64 x 32, smooth shaded) floating 0.2 m over a neutral grey diffuse floor
    (Lambert, albedo 0.5, 40 m square), centre (0, 0, 0.7);
  - lit by a sun (3 W/m², 2° wide) from the front left, a 150 W point light of radius 0.2 m to the front right
    (both hidden from the camera: Photon Splat never shows lights to camera rays) and a uniform grey world
    (0.4, strength 1);
  - a 50 mm camera looking at the sphere from the front and above, 96 x 96 pixels;
  - the gallery's materials, every one kept in the file (fake user), the first one on the probe's only slot.
    `tools/closure_gallery.py` puts each in turn on that slot and renders it with Cycles, Photon Splat and the
    reference renderer. Their names say what they test: each closure alone, the Principled BSDF with one input
    changed from the base, Mix and Add with constant factors and with Fresnel / Layer Weight factors, a nested
    mix and a node group holding a Principled BSDF. Only nodes of Blender 3.4 are used.

Run:  blender -b --factory-startup --python blend_scenes/make_closure_gallery.py

The file opens in Cycles (CPU, view transform Standard, denoising off, no clamping). GALLERY lists the materials
in order; the tool reads the order from the file (the custom property "gallery" of the scene).
"""

import math
import sys
from pathlib import Path

import bpy
from mathutils import Vector

sys.path.insert(0, str(Path(__file__).resolve().parent))  # for scene_kit
from scene_kit import add_camera, diffuse_material, new_empty_scene, save  # noqa: E402

SIZE = 96
PROBE_CENTER = (0.0, 0.0, 0.7)
PROBE_RADIUS = 0.5
FLOOR = (0.5, 0.5, 0.5)
WORLD = (0.4, 0.4, 0.4)
SUN_STRENGTH = 3.0
SUN_ANGLE = math.radians(2.0)
SUN_DIRECTION = Vector((0.55, 0.45, -0.7)).normalized()     # light travels along this: from front left, above
POINT_POWER = 150.0
POINT_RADIUS = 0.2
POINT_LOCATION = (1.6, -1.4, 2.0)
CAMERA_LOCATION = (0.0, -3.3, 1.6)
CAMERA_TARGET = (0.0, 0.0, 0.62)
CAMERA_LENS = 50.0

ORANGE = (0.8, 0.32, 0.12)     # the coloured base of most materials: chromaticity errors show
GOLD = (0.95, 0.68, 0.35)
TINT = (0.85, 0.95, 0.7)       # glass / transparent tint
WHITE = (1.0, 1.0, 1.0)


# ---- node helpers -----------------------------------------------------------------------------------------------

class Tree:
    """A material's node tree being built: nodes are made with new(type, **inputs, props={...})."""

    def __init__(self, material):
        material.use_nodes = True
        self.tree = material.node_tree
        self.tree.nodes.clear()
        self.output = self.tree.nodes.new("ShaderNodeOutputMaterial")

    def new(self, node_type, props=None, **inputs):
        node = self.tree.nodes.new(node_type)
        for key, value in (props or {}).items():
            setattr(node, key, value)
        for key, value in inputs.items():
            name = key.replace("_", " ")
            socket = node.inputs[name]
            if isinstance(value, bpy.types.NodeSocket):
                self.tree.links.new(value, socket)
            elif isinstance(value, tuple) and len(value) == 3:
                socket.default_value = (*value, 1.0)
            else:
                socket.default_value = value
        return node

    def surface(self, node):
        self.tree.links.new(node.outputs[0], self.output.inputs["Surface"])


def material(name, build, color=None):
    mat = bpy.data.materials.new(name)
    mat.use_fake_user = True
    tree = Tree(mat)
    tree.surface(build(tree))
    if color is not None:
        mat.diffuse_color = (*color, 1.0)
    return mat


def principled(t, **inputs):
    """A Principled BSDF (3.4's defaults) on the orange base unless Base_Color is given."""
    inputs.setdefault("Base_Color", ORANGE)
    return t.new("ShaderNodeBsdfPrincipled", **inputs)


def diffuse(t, color=ORANGE, roughness=0.0):
    return t.new("ShaderNodeBsdfDiffuse", Color=color, Roughness=roughness)


def glossy(t, roughness, color=GOLD, distribution='GGX'):
    return t.new("ShaderNodeBsdfGlossy", props={"distribution": distribution}, Color=color, Roughness=roughness)


def mix(t, factor, first, second):
    node = t.new("ShaderNodeMixShader")
    if isinstance(factor, bpy.types.NodeSocket):
        t.tree.links.new(factor, node.inputs[0])
    else:
        node.inputs[0].default_value = factor
    t.tree.links.new(first.outputs[0], node.inputs[1])
    t.tree.links.new(second.outputs[0], node.inputs[2])
    return node


def add(t, first, second):
    node = t.new("ShaderNodeAddShader")
    t.tree.links.new(first.outputs[0], node.inputs[0])
    t.tree.links.new(second.outputs[0], node.inputs[1])
    return node


def principled_group():
    """A node group "PrincipledGroup" holding a Principled BSDF (metallic 0.5, roughness 0.3) whose Base Color and
    Roughness are the group's inputs."""
    group = bpy.data.node_groups.new("PrincipledGroup", "ShaderNodeTree")
    group.inputs.new("NodeSocketColor", "Base Color")
    group.inputs.new("NodeSocketFloat", "Roughness")
    group.outputs.new("NodeSocketShader", "BSDF")
    inside_in = group.nodes.new("NodeGroupInput")
    inside_out = group.nodes.new("NodeGroupOutput")
    bsdf = group.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.inputs["Metallic"].default_value = 0.5
    group.links.new(inside_in.outputs["Base Color"], bsdf.inputs["Base Color"])
    group.links.new(inside_in.outputs["Roughness"], bsdf.inputs["Roughness"])
    group.links.new(bsdf.outputs["BSDF"], inside_out.inputs["BSDF"])
    return group


def grouped(t):
    node = t.new("ShaderNodeGroup", props={"node_tree": bpy.data.node_groups["PrincipledGroup"]})
    node.inputs["Base Color"].default_value = (*ORANGE, 1.0)
    node.inputs["Roughness"].default_value = 0.3
    return node


def fresnel_mix(t, ior=1.45):
    fresnel = t.new("ShaderNodeFresnel", IOR=ior)
    return mix(t, fresnel.outputs["Fac"], diffuse(t), glossy(t, 0.2, WHITE))


def layer_weight_mix(t, output):
    weight = t.new("ShaderNodeLayerWeight", Blend=0.3)
    return mix(t, weight.outputs[output], diffuse(t), glossy(t, 0.2, WHITE))


# ---- the gallery ------------------------------------------------------------------------------------------------

GALLERY = [
    # each closure alone
    ("diffuse_lambert", lambda t: diffuse(t)),
    ("diffuse_oren_nayar_0.5", lambda t: diffuse(t, roughness=0.5)),
    ("diffuse_oren_nayar_1.0", lambda t: diffuse(t, roughness=1.0)),
    ("glossy_ggx_0.2", lambda t: glossy(t, 0.2)),
    ("glossy_ggx_0.5", lambda t: glossy(t, 0.5)),
    ("glossy_beckmann_0.3", lambda t: glossy(t, 0.3, distribution='BECKMANN')),
    ("glossy_multiggx_0.5", lambda t: glossy(t, 0.5, distribution='MULTI_GGX')),
    ("glossy_sharp", lambda t: glossy(t, 0.0, distribution='SHARP')),
    ("anisotropic_ggx_0.3_aniso_0.5", lambda t: t.new("ShaderNodeBsdfAnisotropic", props={"distribution": 'GGX'},
                                                       Color=GOLD, Roughness=0.3, Anisotropy=0.5)),
    ("glass_sharp", lambda t: t.new("ShaderNodeBsdfGlass", props={"distribution": 'SHARP'}, Color=TINT,
                                    Roughness=0.0, IOR=1.5)),
    ("glass_ggx_0.3", lambda t: t.new("ShaderNodeBsdfGlass", props={"distribution": 'GGX'}, Color=TINT,
                                      Roughness=0.3, IOR=1.5)),
    ("refraction_sharp", lambda t: t.new("ShaderNodeBsdfRefraction", props={"distribution": 'SHARP'}, Color=TINT,
                                         Roughness=0.0, IOR=1.5)),
    ("translucent", lambda t: t.new("ShaderNodeBsdfTranslucent", Color=ORANGE)),
    ("transparent", lambda t: t.new("ShaderNodeBsdfTransparent", Color=TINT)),
    ("velvet_0.5", lambda t: t.new("ShaderNodeBsdfVelvet", Color=ORANGE, Sigma=0.5)),
    ("emission_2_plus_diffuse", lambda t: add(t, t.new("ShaderNodeEmission", Color=ORANGE, Strength=2.0),
                                              diffuse(t, color=(0.5, 0.5, 0.5)))),
    # the Principled BSDF: factory defaults, then the orange base with one input changed
    ("principled_default", lambda t: t.new("ShaderNodeBsdfPrincipled")),
    ("principled_base", lambda t: principled(t)),
    ("principled_metallic_1_rough_0.3", lambda t: principled(t, Base_Color=GOLD, Metallic=1.0, Roughness=0.3)),
    ("principled_metallic_0.5", lambda t: principled(t, Metallic=0.5)),
    ("principled_roughness_0", lambda t: principled(t, Roughness=0.0)),
    ("principled_roughness_1", lambda t: principled(t, Roughness=1.0)),
    ("principled_specular_0", lambda t: principled(t, Specular=0.0)),
    ("principled_specular_1", lambda t: principled(t, Specular=1.0)),
    ("principled_specular_tint_1", lambda t: principled(t, Specular_Tint=1.0)),
    ("principled_sheen_1", lambda t: principled(t, Sheen=1.0)),
    ("principled_sheen_1_tint_1", lambda t: principled(t, Sheen=1.0, Sheen_Tint=1.0)),
    ("principled_clearcoat_1", lambda t: principled(t, Clearcoat=1.0)),
    ("principled_clearcoat_1_rough_0.3", lambda t: principled(t, Clearcoat=1.0, Clearcoat_Roughness=0.3)),
    ("principled_transmission_1_rough_0", lambda t: principled(t, Base_Color=TINT, Transmission=1.0,
                                                               Roughness=0.0)),
    ("principled_transmission_1_rough_0.3", lambda t: principled(t, Base_Color=TINT, Transmission=1.0,
                                                                 Roughness=0.3)),
    ("principled_transmission_1_transrough_0.3", lambda t: principled(t, Base_Color=TINT, Transmission=1.0,
                                                                      Roughness=0.0, Transmission_Roughness=0.3)),
    ("principled_subsurface_0.5", lambda t: principled(t, Subsurface=0.5, Subsurface_Color=ORANGE)),
    ("principled_alpha_0.5", lambda t: principled(t, Alpha=0.5)),
    ("principled_emission_white_1", lambda t: principled(t, Emission=WHITE, Emission_Strength=1.0)),
    ("principled_anisotropic_0.5", lambda t: principled(t, Anisotropic=0.5)),
    ("principled_ior_1.1", lambda t: principled(t, IOR=1.1)),
    ("principled_ior_2.0", lambda t: principled(t, IOR=2.0)),
    # mixes
    ("mix_0.3_diffuse_glossy", lambda t: mix(t, 0.3, diffuse(t), glossy(t, 0.2, WHITE))),
    ("add_diffuse_glossy", lambda t: add(t, diffuse(t, color=(0.5, 0.2, 0.08)), glossy(t, 0.2, (0.3, 0.3, 0.3)))),
    ("mix_fresnel_1.45_diffuse_glossy", lambda t: fresnel_mix(t)),
    ("mix_layer_fresnel_0.3_diffuse_glossy", lambda t: layer_weight_mix(t, "Fresnel")),
    ("mix_layer_facing_0.3_diffuse_glossy", lambda t: layer_weight_mix(t, "Facing")),
    ("mix_nested_0.4_fresnelmix_velvet", lambda t: mix(t, 0.4, fresnel_mix(t),
                                                       t.new("ShaderNodeBsdfVelvet", Color=(0.2, 0.4, 0.8),
                                                             Sigma=0.5))),
    ("group_principled_metallic_0.5", lambda t: grouped(t)),
]


def add_floor(scene):
    mesh = bpy.data.meshes.new("Floor")
    h = 20.0
    mesh.from_pydata([(-h, -h, 0.0), (h, -h, 0.0), (h, h, 0.0), (-h, h, 0.0)], [], [(0, 1, 2, 3)])
    mesh.materials.append(diffuse_material("Floor", FLOOR))
    obj = bpy.data.objects.new("Floor", mesh)
    scene.collection.objects.link(obj)


def add_probe(scene, first_material):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=PROBE_RADIUS, location=PROBE_CENTER)
    obj = bpy.context.active_object
    obj.name = obj.data.name = "Probe"
    obj.data.polygons.foreach_set("use_smooth", [True] * len(obj.data.polygons))
    obj.data.materials.append(first_material)
    return obj


def add_lights(scene):
    sun = bpy.data.lights.new("Sun", type='SUN')
    sun.energy = SUN_STRENGTH
    sun.angle = SUN_ANGLE
    sun_obj = bpy.data.objects.new("Sun", sun)
    sun_obj.rotation_euler = SUN_DIRECTION.to_track_quat('-Z', 'Y').to_euler()
    point = bpy.data.lights.new("Point", type='POINT')
    point.energy = POINT_POWER
    point.shadow_soft_size = POINT_RADIUS
    point_obj = bpy.data.objects.new("Point", point)
    point_obj.location = POINT_LOCATION
    for obj in (sun_obj, point_obj):
        obj.visible_camera = False
        scene.collection.objects.link(obj)


def make_closure_gallery():
    scene = new_empty_scene(SIZE, SIZE, "Grey", WORLD)
    principled_group()
    materials = [material(name, build) for name, build in GALLERY]
    add_floor(scene)
    add_probe(scene, materials[0])
    add_lights(scene)
    aim = Vector(CAMERA_TARGET) - Vector(CAMERA_LOCATION)
    add_camera(scene, CAMERA_LENS, CAMERA_LOCATION, aim.to_track_quat('-Z', 'Y').to_euler())
    scene["gallery"] = [name for name, _ in GALLERY]
    scene["probe_center"] = PROBE_CENTER
    scene["probe_radius"] = PROBE_RADIUS
    save("closure_gallery.blend")


if __name__ == "__main__":
    make_closure_gallery()
