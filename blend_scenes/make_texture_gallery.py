"""Writes texture_gallery.blend next to this script: the probe sphere of the closure gallery and 36 textured
materials (acceptance (b) of the shader node programs issue).

  - the closure gallery's set (make_closure_gallery.py): a UV sphere "Probe" (radius 0.5 m, 64 x 32, smooth, with its
    UV map and a point colour attribute "Col") floating over a grey diffuse floor, a sun (3 W/m², 2°), a 150 W point
    light of 0.2 m radius (both hidden from the camera) and a grey world (0.4); the camera is a 70 mm lens (the probe
    fills more of the frame than in the closure gallery: textures show), 96 x 96;
  - three small images made here and packed into the file: "tex_float" (16 x 16 float, linear), "tex_byte"
    (16 x 16 byte, sRGB), "tex_normal" (32 x 32 byte, Non-Color, a tangent-space normal map of bumps);
  - the materials, every one kept (fake user), the first on the probe. `tools/texture_gallery.py` puts each in turn
    on the probe and renders it with Cycles and Photon Splat. They cover image textures (float and sRGB, Closest and
    Linear), procedural textures (noise, voronoi, musgrave, wave, magic, brick, checker, gradient, white noise),
    node groups (a texture group and a shader group), colour ramps, Mix RGB blends, Bump and Normal Map, the Principled
    BSDF with textured base colour / roughness / metallic / specular / alpha, Glossy with textured roughness, Mix
    Shader with a textured factor, textured Emission, and converters (HSV, curves, separate / combine, map range).
    Only nodes of Blender 3.4.

Run:  blender -b --factory-startup --python blend_scenes/make_texture_gallery.py
"""

import math
import sys
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector

sys.path.insert(0, str(Path(__file__).resolve().parent))
from scene_kit import add_camera, new_empty_scene, save  # noqa: E402
from make_closure_gallery import (WORLD, add_floor, add_lights, diffuse, glossy, mix,  # noqa: E402
                                  PROBE_CENTER, PROBE_RADIUS, ORANGE, GOLD, WHITE)
from make_closure_gallery import Tree as _Tree  # noqa: E402

SIZE = 96
CAMERA_LOCATION = (0.0, -3.3, 1.6)
CAMERA_TARGET = (0.0, 0.0, 0.66)
CAMERA_LENS = 70.0
BLUE = (0.1, 0.25, 0.6)
GREEN = (0.15, 0.5, 0.12)


class Tree(_Tree):
    """The closure gallery's Tree, with inputs also by index (in0=...) and vector values of any length."""

    def set(self, socket, value):
        if isinstance(value, bpy.types.NodeSocket):
            self.tree.links.new(value, socket)
        elif isinstance(value, (tuple, list)):
            n = len(socket.default_value)
            socket.default_value = tuple(value) + (1.0,) * (n - len(value))
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


# ---- images ----------------------------------------------------------------------------------------------------

def make_images():
    n = 16
    y, x = (np.mgrid[0:n, 0:n].astype(np.float32) + 0.5) / n
    rgb = np.stack([0.15 + 0.75 * x, 0.2 + 0.6 * (0.5 + 0.5 * np.sin(6.28 * y)), 0.8 - 0.6 * x * y], axis=-1)
    rgb[((x * 4).astype(int) + (y * 4).astype(int)) % 2 == 0] *= 0.45
    rgba = np.concatenate([rgb, np.ones_like(x)[..., None]], axis=-1).astype(np.float32)
    flt = bpy.data.images.new("tex_float", n, n, alpha=True, float_buffer=True)
    flt.colorspace_settings.name = "Linear"
    flt.pixels.foreach_set(rgba.reshape(-1))
    byte = bpy.data.images.new("tex_byte", n, n, alpha=True, float_buffer=False)
    byte.colorspace_settings.name = "sRGB"
    byte.pixels.foreach_set(np.round(np.clip(rgba, 0, 1).reshape(-1) ** (1 / 2.2) * 255) / 255)
    m = 32
    y, x = (np.mgrid[0:m, 0:m].astype(np.float32) + 0.5) / m
    nx = 0.5 * np.sin(2 * math.pi * 4 * x)
    ny = 0.5 * np.sin(2 * math.pi * 3 * y)
    nz = np.sqrt(np.clip(1 - nx * nx - ny * ny, 0, 1))
    nrm = np.stack([nx * 0.5 + 0.5, ny * 0.5 + 0.5, nz * 0.5 + 0.5, np.ones_like(x)], axis=-1)
    normal = bpy.data.images.new("tex_normal", m, m, alpha=False, float_buffer=False)
    normal.colorspace_settings.name = "Non-Color"
    normal.pixels.foreach_set(np.round(nrm.reshape(-1) * 255) / 255)
    for img in (flt, byte, normal):
        img.pack()


# ---- node helpers ----------------------------------------------------------------------------------------------

def coord(t, which="UV"):
    return t.new("ShaderNodeTexCoord").outputs[which]


def mapped(t, which="Object", scale=1.0, rotation=(0.0, 0.0, 0.0), location=(0.0, 0.0, 0.0)):
    return t.new("ShaderNodeMapping", Vector=coord(t, which), Location=location, Rotation=rotation,
                 Scale=(scale,) * 3 if isinstance(scale, float) else scale).outputs[0]


def image(t, name, vector=None, interpolation='Linear'):
    node = t.new("ShaderNodeTexImage", {"interpolation": interpolation})
    node.image = bpy.data.images[name]
    if vector is not None:
        t.tree.links.new(vector, node.inputs["Vector"])
    return node


def ramp(t, fac, stops, interpolation='LINEAR'):
    node = t.new("ShaderNodeValToRGB")
    r = node.color_ramp
    r.interpolation = interpolation
    while len(r.elements) < len(stops):
        r.elements.new(0.5)
    for element, (pos, color) in zip(r.elements, stops):
        element.position = pos
        element.color = (*color, 1.0)
    t.tree.links.new(fac, node.inputs["Fac"])
    return node


def principled(t, **inputs):
    inputs.setdefault("Base_Color", ORANGE)
    return t.new("ShaderNodeBsdfPrincipled", **inputs)


def noise(t, scale=4.0, detail=3.0, vector=None):
    return t.new("ShaderNodeTexNoise", Vector=vector or coord(t, "Object"), Scale=scale, Detail=detail,
                 Roughness=0.55)


def checker(t, scale=6.0, c1=ORANGE, c2=BLUE, vector=None):
    return t.new("ShaderNodeTexChecker", Vector=vector or coord(t, "UV"), Color1=c1, Color2=c2, Scale=scale)


def texture_group():
    """A node group "TexGroup": Vector, Scale -> Color (checker x noise, through a ramp) and Fac."""
    group = bpy.data.node_groups.new("TexGroup", "ShaderNodeTree")
    group.inputs.new("NodeSocketVector", "Vector")
    group.inputs.new("NodeSocketFloat", "Scale")
    group.outputs.new("NodeSocketColor", "Color")
    group.outputs.new("NodeSocketFloat", "Fac")
    gin, gout = group.nodes.new("NodeGroupInput"), group.nodes.new("NodeGroupOutput")
    chk = group.nodes.new("ShaderNodeTexChecker")
    chk.inputs["Color1"].default_value = (0.9, 0.8, 0.2, 1.0)
    chk.inputs["Color2"].default_value = (0.2, 0.3, 0.7, 1.0)
    nz = group.nodes.new("ShaderNodeTexNoise")
    nz.inputs["Scale"].default_value = 3.0
    mixn = group.nodes.new("ShaderNodeMixRGB")
    mixn.blend_type = 'MULTIPLY'
    mixn.inputs["Fac"].default_value = 0.6
    group.links.new(gin.outputs["Vector"], chk.inputs["Vector"])
    group.links.new(gin.outputs["Scale"], chk.inputs["Scale"])
    group.links.new(gin.outputs["Vector"], nz.inputs["Vector"])
    group.links.new(chk.outputs["Color"], mixn.inputs["Color1"])
    group.links.new(nz.outputs["Color"], mixn.inputs["Color2"])
    group.links.new(mixn.outputs[0], gout.inputs["Color"])
    group.links.new(nz.outputs["Fac"], gout.inputs["Fac"])


def shader_group():
    """A node group "ShaderGroup": Color, Roughness -> a Principled BSDF (metallic 0.3) bumped by a wave texture."""
    group = bpy.data.node_groups.new("ShaderGroup", "ShaderNodeTree")
    group.inputs.new("NodeSocketColor", "Color")
    group.inputs.new("NodeSocketFloat", "Roughness")
    group.outputs.new("NodeSocketShader", "BSDF")
    gin, gout = group.nodes.new("NodeGroupInput"), group.nodes.new("NodeGroupOutput")
    bsdf = group.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.inputs["Metallic"].default_value = 0.3
    wave = group.nodes.new("ShaderNodeTexWave")
    wave.inputs["Scale"].default_value = 4.0
    bump = group.nodes.new("ShaderNodeBump")
    bump.inputs["Strength"].default_value = 0.3
    group.links.new(wave.outputs["Fac"], bump.inputs["Height"])
    group.links.new(bump.outputs["Normal"], bsdf.inputs["Normal"])
    group.links.new(gin.outputs["Color"], bsdf.inputs["Base Color"])
    group.links.new(gin.outputs["Roughness"], bsdf.inputs["Roughness"])
    group.links.new(bsdf.outputs["BSDF"], gout.inputs["BSDF"])


def group_node(t, name, **inputs):
    node = t.new("ShaderNodeGroup", {"node_tree": bpy.data.node_groups[name]})
    for key, value in inputs.items():
        t.set(node.inputs[key.replace("_", " ")], value)
    return node


def bump(t, height, strength=0.5, distance=0.1, normal=None):
    node = t.new("ShaderNodeBump", Strength=strength, Distance=distance)
    t.tree.links.new(height, node.inputs["Height"])
    if normal is not None:
        t.tree.links.new(normal, node.inputs["Normal"])
    return node.outputs["Normal"]


def mix_rgb(t, blend, fac, a, b):
    node = t.new("ShaderNodeMix", {"data_type": 'RGBA', "blend_type": blend}, in0=fac)
    for index, value in ((6, a), (7, b)):
        if isinstance(value, bpy.types.NodeSocket):
            t.tree.links.new(value, node.inputs[index])
        else:
            node.inputs[index].default_value = (*value, 1.0)
    return node.outputs[2]


# ---- the gallery -----------------------------------------------------------------------------------------------

def m_image_float(t):
    return principled(t, Base_Color=image(t, "tex_float", coord(t, "UV")).outputs["Color"])


def m_image_byte_closest(t):
    vec = mapped(t, "UV", scale=(2.0, 2.0, 1.0))
    return principled(t, Base_Color=image(t, "tex_byte", vec, 'Closest').outputs["Color"], Roughness=0.3)


def m_image_emission(t):
    tex = image(t, "tex_byte", coord(t, "UV"))
    return t.new("ShaderNodeAddShader", in0=t.new("ShaderNodeEmission", Color=tex.outputs["Color"],
                                                  Strength=0.8).outputs[0],
                 in1=diffuse(t, color=(0.3, 0.3, 0.3)).outputs[0])


def m_noise_ramp(t):
    n = noise(t, 5.0)
    r = ramp(t, n.outputs["Fac"], [(0.35, ORANGE), (0.5, (0.9, 0.85, 0.7)), (0.65, BLUE)])
    return principled(t, Base_Color=r.outputs["Color"])


def m_noise_roughness(t):
    n = noise(t, 6.0, 2.0)
    rough = t.new("ShaderNodeMapRange", From_Min=0.3, From_Max=0.7, To_Min=0.05, To_Max=0.8,
                  Value=n.outputs["Fac"]).outputs[0]
    return principled(t, Base_Color=GOLD, Metallic=1.0, Roughness=rough)


def m_checker_metallic(t):
    c = checker(t, 5.0, (1, 1, 1), (0, 0, 0))
    return principled(t, Base_Color=GOLD, Metallic=c.outputs["Fac"], Roughness=0.35)


def m_all_textured(t):
    v = t.new("ShaderNodeTexVoronoi", Vector=coord(t, "Object"), Scale=4.0)
    g = t.new("ShaderNodeTexGradient", {"gradient_type": 'SPHERICAL'}, Vector=coord(t, "Object"))
    w = t.new("ShaderNodeTexWave", Vector=coord(t, "Object"), Scale=3.0)
    return principled(t, Base_Color=v.outputs["Color"], Roughness=g.outputs["Fac"], Metallic=w.outputs["Fac"])


def m_bump_noise(t):
    n = noise(t, 8.0, 4.0)
    return principled(t, Roughness=0.35, Normal=bump(t, n.outputs["Fac"], 0.6, 0.2))


def m_normal_map(t):
    tex = image(t, "tex_normal", mapped(t, "UV", scale=(3.0, 2.0, 1.0)))
    nm = t.new("ShaderNodeNormalMap", {"space": 'TANGENT', "uv_map": "UVMap"}, Strength=1.0,
               Color=tex.outputs["Color"])
    return principled(t, Base_Color=(0.6, 0.6, 0.65), Roughness=0.3, Normal=nm.outputs[0])


def m_glossy_musgrave_roughness(t):
    mg = t.new("ShaderNodeTexMusgrave", Vector=coord(t, "Object"), Scale=4.0, Detail=3.0)
    rough = t.new("ShaderNodeMapRange", Value=mg.outputs[0], From_Min=-0.5, From_Max=1.0, To_Min=0.1,
                  To_Max=0.6).outputs[0]
    return t.new("ShaderNodeBsdfGlossy", {"distribution": 'GGX'}, Color=GOLD, Roughness=rough)


def m_diffuse_brick(t):
    b = t.new("ShaderNodeTexBrick", Vector=coord(t, "UV"), Color1=ORANGE, Color2=(0.6, 0.2, 0.1),
              Mortar=(0.8, 0.8, 0.75), Scale=8.0)
    return diffuse(t, color=b.outputs["Color"])


def m_diffuse_magic(t):
    mg = t.new("ShaderNodeTexMagic", {"turbulence_depth": 3}, Vector=coord(t, "Object"), Scale=2.0)
    return diffuse(t, color=mg.outputs["Color"], roughness=0.5)


def m_diffuse_wave_rings(t):
    w = t.new("ShaderNodeTexWave", {"wave_type": 'RINGS', "rings_direction": 'SPHERICAL', "wave_profile": 'SAW'},
              Vector=coord(t, "Object"), Scale=3.0)
    r = ramp(t, w.outputs["Fac"], [(0.0, (0.9, 0.7, 0.3)), (1.0, (0.3, 0.12, 0.05))])
    return diffuse(t, color=r.outputs["Color"])


def m_mix_checker_factor(t):
    return mix(t, checker(t, 6.0).outputs["Fac"], diffuse(t), glossy(t, 0.2, WHITE))


def m_mix_noise_factor(t):
    n = noise(t, 4.0)
    fac = t.new("ShaderNodeMapRange", {"interpolation_type": 'SMOOTHSTEP'}, Value=n.outputs["Fac"], From_Min=0.4,
                From_Max=0.6).outputs[0]
    return mix(t, fac, principled(t, Base_Color=GOLD, Metallic=1.0, Roughness=0.25), diffuse(t, color=BLUE))


def m_emission_gradient(t):
    g = t.new("ShaderNodeTexGradient", Vector=mapped(t, "Object", scale=1.0, location=(0.5, 0.5, 0.5)))
    r = ramp(t, g.outputs["Fac"], [(0.2, (1.0, 0.3, 0.05)), (0.8, (0.1, 0.3, 1.0))])
    return t.new("ShaderNodeEmission", Color=r.outputs["Color"], Strength=1.5)


def m_mix_multiply(t):
    c = mix_rgb(t, 'MULTIPLY', 0.8, checker(t, 4.0).outputs["Color"], noise(t, 3.0).outputs["Color"])
    return principled(t, Base_Color=c)


def m_mix_overlay(t):
    c = mix_rgb(t, 'OVERLAY', 0.7, image(t, "tex_float", coord(t, "UV")).outputs["Color"],
                t.new("ShaderNodeTexWave", Vector=coord(t, "Object"), Scale=5.0).outputs["Color"])
    return principled(t, Base_Color=c, Roughness=0.4)


def m_legacy_mixrgb_screen(t):
    node = t.new("ShaderNodeMixRGB", {"blend_type": 'SCREEN'}, Fac=0.6, Color1=ORANGE,
                 Color2=checker(t, 5.0, (0.2, 0.4, 0.7), (0.0, 0.0, 0.0)).outputs["Color"])
    return diffuse(t, color=node.outputs[0])


def m_group_texture(t):
    g = group_node(t, "TexGroup", Vector=coord(t, "Object"), Scale=5.0)
    return principled(t, Base_Color=g.outputs["Color"], Roughness=g.outputs["Fac"])


def m_group_shader(t):
    n = noise(t, 3.0)
    return group_node(t, "ShaderGroup", Color=n.outputs["Color"], Roughness=0.4)


def m_hsv_image(t):
    tex = image(t, "tex_float", coord(t, "UV"))
    hsv = t.new("ShaderNodeHueSaturation", Hue=0.65, Saturation=1.3, Value=0.9, Fac=1.0, Color=tex.outputs["Color"])
    return principled(t, Base_Color=hsv.outputs[0])


def m_ramp_constant_voronoi(t):
    v = t.new("ShaderNodeTexVoronoi", {"feature": 'F2', "distance": 'MANHATTAN'}, Vector=coord(t, "Object"),
              Scale=5.0)
    r = ramp(t, v.outputs["Distance"], [(0.0, ORANGE), (0.4, GREEN), (0.7, BLUE)], 'CONSTANT')
    return diffuse(t, color=r.outputs["Color"])


def m_bright_contrast_invert(t):
    tex = image(t, "tex_byte", coord(t, "UV"))
    bc = t.new("ShaderNodeBrightContrast", Color=tex.outputs["Color"], Bright=0.05, Contrast=0.3)
    inv = t.new("ShaderNodeInvert", Fac=0.3, Color=bc.outputs[0])
    return principled(t, Base_Color=inv.outputs[0])


def m_separate_combine_hsv(t):
    sep = t.new("ShaderNodeSeparateColor", {"mode": 'HSV'}, Color=noise(t, 3.0).outputs["Color"])
    comb = t.new("ShaderNodeCombineColor", {"mode": 'HSV'}, Red=sep.outputs[0], Green=0.7, Blue=sep.outputs[2])
    return principled(t, Base_Color=comb.outputs[0])


def m_vertex_color(t):
    attr = t.new("ShaderNodeAttribute", {"attribute_name": "Col"})
    return principled(t, Base_Color=attr.outputs["Color"], Roughness=0.45)


def m_object_mapping_checker(t):
    vec = mapped(t, "Object", scale=(1.0, 1.0, 2.0), rotation=(0.3, 0.0, 0.6))
    return principled(t, Base_Color=checker(t, 3.0, vector=vec).outputs["Color"])


def m_fresnel_textured_mix(t):
    fres = t.new("ShaderNodeFresnel", IOR=1.5)
    return mix(t, fres.outputs[0], diffuse(t, color=checker(t, 6.0).outputs["Color"]),
               glossy(t, 0.15, WHITE))


def m_layer_weight_ramp(t):
    lw = t.new("ShaderNodeLayerWeight", Blend=0.4)
    r = ramp(t, lw.outputs["Facing"], [(0.0, ORANGE), (1.0, BLUE)])
    return principled(t, Base_Color=r.outputs["Color"], Roughness=0.5)


def m_sheen_velvet_textured(t):
    v = t.new("ShaderNodeBsdfVelvet", Sigma=0.5, Color=noise(t, 4.0).outputs["Color"])
    return t.new("ShaderNodeAddShader", in0=v.outputs[0], in1=diffuse(t, color=(0.2, 0.05, 0.02)).outputs[0])


def m_alpha_checker(t):
    c = checker(t, 5.0, (1, 1, 1), (0, 0, 0))
    alpha = t.new("ShaderNodeMath", {"operation": 'MULTIPLY_ADD'}, in0=c.outputs["Fac"], in1=0.7, in2=0.3).outputs[0]
    return principled(t, Alpha=alpha)


def m_clearcoat_bump(t):
    w = t.new("ShaderNodeTexWave", Vector=coord(t, "Object"), Scale=6.0, Distortion=2.0, Detail=2.0)
    return principled(t, Base_Color=BLUE, Clearcoat=1.0, Clearcoat_Roughness=0.1,
                      Normal=bump(t, w.outputs["Fac"], 0.4, 0.1))


def m_diffuse_bump_image(t):
    tex = image(t, "tex_float", mapped(t, "UV", scale=(2.0, 2.0, 1.0)))
    bw = t.new("ShaderNodeRGBToBW", Color=tex.outputs["Color"]).outputs[0]
    return t.new("ShaderNodeBsdfDiffuse", Color=(0.7, 0.6, 0.5), Normal=bump(t, bw, 0.8, 0.05))


def m_anisotropic_textured(t):
    g = t.new("ShaderNodeTexGradient", {"gradient_type": 'RADIAL'}, Vector=coord(t, "Object"))
    rough = t.new("ShaderNodeMath", {"operation": 'MULTIPLY_ADD'}, in0=g.outputs["Fac"], in1=0.4, in2=0.15).outputs[0]
    return t.new("ShaderNodeBsdfAnisotropic", {"distribution": 'GGX'}, Color=GOLD, Roughness=rough, Anisotropy=0.5)


def m_specular_texture(t):
    c = checker(t, 8.0, (1, 1, 1), (0, 0, 0))
    return principled(t, Base_Color=(0.3, 0.3, 0.35), Specular=c.outputs["Fac"], Roughness=0.2)


def m_blackbody_emission(t):
    n = noise(t, 3.0)
    temp = t.new("ShaderNodeMapRange", Value=n.outputs["Fac"], From_Min=0.3, From_Max=0.7, To_Min=1500.0,
                 To_Max=7000.0).outputs[0]
    bb = t.new("ShaderNodeBlackbody", Temperature=temp)
    return t.new("ShaderNodeEmission", Color=bb.outputs[0], Strength=1.0)


def m_white_noise_cells(t):
    v = t.new("ShaderNodeTexVoronoi", Vector=coord(t, "Object"), Scale=6.0)
    wn = t.new("ShaderNodeTexWhiteNoise", Vector=v.outputs["Position"])
    return principled(t, Base_Color=wn.outputs["Color"], Roughness=0.5)


def m_curves(t):
    tex = image(t, "tex_float", coord(t, "UV"))
    node = t.new("ShaderNodeRGBCurve", Fac=1.0, Color=tex.outputs["Color"])
    c = node.mapping.curves[3]
    c.points.new(0.4, 0.6)
    node.mapping.curves[0].points.new(0.5, 0.3)
    node.mapping.update()
    return principled(t, Base_Color=node.outputs[0])


def m_musgrave_ridged_ramp(t):
    mg = t.new("ShaderNodeTexMusgrave", {"musgrave_type": 'RIDGED_MULTIFRACTAL'}, Vector=coord(t, "Object"),
               Scale=3.0, Detail=4.0, Offset=1.0, Gain=1.5)
    r = ramp(t, mg.outputs[0], [(0.0, (0.05, 0.1, 0.3)), (0.6, (0.8, 0.6, 0.3)), (1.0, (1.0, 1.0, 0.9))], 'EASE')
    return principled(t, Base_Color=r.outputs["Color"], Roughness=0.6)


def m_glossy_image_roughness(t):
    tex = image(t, "tex_float", coord(t, "UV"))
    sep = t.new("ShaderNodeSeparateColor", Color=tex.outputs["Color"])
    return t.new("ShaderNodeBsdfGlossy", {"distribution": 'BECKMANN'}, Color=(0.9, 0.9, 0.9),
                 Roughness=sep.outputs["Red"])


def m_math_stripes(t):
    sep = t.new("ShaderNodeSeparateXYZ", Vector=coord(t, "Object"))
    s = t.new("ShaderNodeMath", {"operation": 'SINE'}, in0=t.new("ShaderNodeMath", {"operation": 'MULTIPLY'},
                                                              in0=sep.outputs[2], in1=20.0).outputs[0])
    fac = t.new("ShaderNodeMath", {"operation": 'MULTIPLY_ADD', "use_clamp": True}, in0=s.outputs[0], in1=0.5,
                in2=0.5).outputs[0]
    return principled(t, Base_Color=mix_rgb(t, 'MIX', fac, ORANGE, GREEN))


GALLERY = [
    ("image_float_base", m_image_float),
    ("image_byte_closest_base", m_image_byte_closest),
    ("image_emission_plus_diffuse", m_image_emission),
    ("noise_ramp_base", m_noise_ramp),
    ("noise_roughness_metal", m_noise_roughness),
    ("checker_metallic", m_checker_metallic),
    ("voronoi_gradient_wave_all", m_all_textured),
    ("bump_noise", m_bump_noise),
    ("normal_map_tangent", m_normal_map),
    ("glossy_musgrave_roughness", m_glossy_musgrave_roughness),
    ("diffuse_brick", m_diffuse_brick),
    ("diffuse_magic", m_diffuse_magic),
    ("diffuse_wave_rings_ramp", m_diffuse_wave_rings),
    ("mix_shader_checker_factor", m_mix_checker_factor),
    ("mix_shader_noise_factor", m_mix_noise_factor),
    ("emission_gradient_ramp", m_emission_gradient),
    ("mix_multiply_checker_noise", m_mix_multiply),
    ("mix_overlay_image_wave", m_mix_overlay),
    ("mixrgb_legacy_screen", m_legacy_mixrgb_screen),
    ("group_texture", m_group_texture),
    ("group_shader_bump", m_group_shader),
    ("hsv_image", m_hsv_image),
    ("ramp_constant_voronoi_f2", m_ramp_constant_voronoi),
    ("bright_contrast_invert_image", m_bright_contrast_invert),
    ("separate_combine_hsv", m_separate_combine_hsv),
    ("vertex_color_attribute", m_vertex_color),
    ("object_mapping_checker", m_object_mapping_checker),
    ("fresnel_mix_textured", m_fresnel_textured_mix),
    ("layer_weight_ramp", m_layer_weight_ramp),
    ("velvet_textured", m_sheen_velvet_textured),
    ("alpha_checker", m_alpha_checker),
    ("clearcoat_wave_bump", m_clearcoat_bump),
    ("diffuse_bump_image", m_diffuse_bump_image),
    ("anisotropic_textured_roughness", m_anisotropic_textured),
    ("specular_checker", m_specular_texture),
    ("blackbody_emission_noise", m_blackbody_emission),
    ("white_noise_voronoi_cells", m_white_noise_cells),
    ("rgb_curves_image", m_curves),
    ("musgrave_ridged_ramp_ease", m_musgrave_ridged_ramp),
    ("glossy_image_roughness", m_glossy_image_roughness),
    ("math_stripes", m_math_stripes),
]


def material(name, build):
    mat = bpy.data.materials.new(name)
    mat.use_fake_user = True
    t = Tree(mat)
    t.surface(build(t))
    return mat


def set_sphere_uvs(mesh, co):
    """Latitude-longitude UVs (u = longitude / 2 pi, v = latitude / pi + 1/2; a face across the seam gets u > 1 on
    its far side, a pole's corner the u of its face's centre)."""
    loops = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", loops)
    start = np.empty(len(mesh.polygons), dtype=np.int32)
    total = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("loop_start", start)
    mesh.polygons.foreach_get("loop_total", total)
    lon = (np.arctan2(co[:, 1], co[:, 0]) / (2 * math.pi)) % 1.0
    lat = np.arcsin(np.clip(co[:, 2], -1.0, 1.0)) / math.pi + 0.5
    pole = np.abs(co[:, 2]) > 0.999999
    uv = np.zeros((len(loops), 2), dtype=np.float32)
    for s0, n in zip(start, total):
        idx = loops[s0:s0 + n]
        u = lon[idx].copy()
        body = ~pole[idx]
        if u[body].max() - u[body].min() > 0.5:
            u[body & (u < 0.5)] += 1.0
        u[~body] = u[body].mean()
        uv[s0:s0 + n, 0] = u
        uv[s0:s0 + n, 1] = lat[idx]
    mesh.uv_layers[0].data.foreach_set("uv", uv.reshape(-1))


def add_probe(first_material):
    # the sphere built here rather than by primitive_uv_sphere_add, whose face order was found to differ from one
    # run of the script to the next in Blender 3.4 (the same surface, but every cache key would change)
    segments, rings = 64, 32
    verts = [(0.0, 0.0, PROBE_RADIUS)]
    for i in range(1, rings):
        theta = math.pi * i / rings
        for j in range(segments):
            phi = 2 * math.pi * j / segments
            verts.append((PROBE_RADIUS * math.sin(theta) * math.cos(phi), PROBE_RADIUS * math.sin(theta) * math.sin(phi),
                          PROBE_RADIUS * math.cos(theta)))
    verts.append((0.0, 0.0, -PROBE_RADIUS))
    bottom = len(verts) - 1
    ring = lambda i, j: 1 + (i - 1) * segments + j % segments  # noqa: E731
    faces = [(0, ring(1, j), ring(1, j + 1)) for j in range(segments)]
    faces += [(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1))
              for i in range(1, rings - 1) for j in range(segments)]
    faces += [(ring(rings - 1, j + 1), ring(rings - 1, j), bottom) for j in range(segments)]
    mesh = bpy.data.meshes.new("Probe")
    mesh.from_pydata(verts, [], faces)
    mesh.uv_layers.new(name="UVMap")
    obj = bpy.data.objects.new("Probe", mesh)
    obj.location = PROBE_CENTER
    bpy.context.scene.collection.objects.link(obj)
    mesh.polygons.foreach_set("use_smooth", [True] * len(mesh.polygons))
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3) / PROBE_RADIUS
    set_sphere_uvs(mesh, co)
    col = mesh.color_attributes.new("Col", 'FLOAT_COLOR', 'POINT')
    colors = np.stack([0.5 + 0.45 * np.sin(3 * co[:, 0] + 1), 0.5 + 0.45 * np.sin(4 * co[:, 2]),
                       0.5 + 0.45 * np.cos(3 * co[:, 1]), np.ones(len(co))], axis=-1)
    col.data.foreach_set("color", colors.astype(np.float32).reshape(-1))
    mesh.materials.append(first_material)
    mesh.update()
    return obj


def make_texture_gallery():
    scene = new_empty_scene(SIZE, SIZE, "Grey", WORLD)
    make_images()
    texture_group()
    shader_group()
    materials = [material(name, build) for name, build in GALLERY]
    add_floor(scene)
    add_probe(materials[0])
    add_lights(scene)
    aim = Vector(CAMERA_TARGET) - Vector(CAMERA_LOCATION)
    add_camera(scene, CAMERA_LENS, CAMERA_LOCATION, aim.to_track_quat('-Z', 'Y').to_euler())
    scene["gallery"] = [name for name, _ in GALLERY]
    scene["probe_center"] = PROBE_CENTER
    scene["probe_radius"] = PROBE_RADIUS
    save("texture_gallery.blend")


if __name__ == "__main__":
    make_texture_gallery()
