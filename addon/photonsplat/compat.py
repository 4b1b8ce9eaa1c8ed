"""Every difference between the Blender versions the add-on supports, in one place.

Supported: 3.4 (Debian 12's Blender), 4.5 LTS and 5.0 (blender.org, and the `bpy` wheels the tests use). The
rest of the add-on asks this module instead of testing bpy.app.version itself, so that a new Blender version
is one edit here. Each entry says which version changed what.
"""

import math

import bpy
import numpy as np

VERSION = bpy.app.version


def corner_normals_are_vertex_normals(mesh):
    """Whether every corner's split normal is its vertex's normal, bit for bit (all faces smooth, no auto smooth
    or custom normals): then the vertex normals, a quarter of the corner normals' floats, say the same. 4.1
    replaced auto smooth by Mesh.normals_domain ('POINT': exactly this case); 3.4 computes the corner normals of
    such a mesh as copies of the vertex normals (BKE_mesh_normals_loop_split without split normals)."""
    domain = getattr(mesh, "normals_domain", None)
    if domain is not None:
        return domain == 'POINT'
    if mesh.use_auto_smooth or mesh.has_custom_normals:
        return False
    polygons = mesh.polygons
    if len(polygons) == 0:
        return False
    smooth = np.empty(len(polygons), dtype=bool)
    polygons.foreach_get("use_smooth", smooth)
    return bool(smooth.all())


def triangles_shaded_flat(mesh):
    """Which loop triangles Cycles shades with the triangle's own normal: a bool array, or None where none is.
    Blender 4.1+ (Mesh.normals_domain): every triangle of a 'FACE' mesh (all faces flat, no sharp edges or custom
    normals), none otherwise (a 'CORNER' mesh's flat faces take their corner normals, the polygon's normal). Blender
    3.x: the triangles of flat faces, unless Auto Smooth or custom normals make Cycles shade every face by its split
    normals. A flat quad that is not planar has a polygon normal that is neither of its triangles' own."""
    domain = getattr(mesh, "normals_domain", None)
    if domain is not None:
        return np.ones(len(mesh.loop_triangles), dtype=bool) if domain == 'FACE' else None
    if mesh.use_auto_smooth or mesh.has_custom_normals:
        return None
    smooth = np.empty(len(mesh.loop_triangles), dtype=bool)
    mesh.loop_triangles.foreach_get("use_smooth", smooth)
    return None if smooth.all() else ~smooth


def prepare_corner_normals(mesh):
    """Make loop_triangles' split_normals valid. Blender 3.4 computes them on request only
    (Mesh.calc_normals_split, removed in 4.1, where corner normals are always up to date)."""
    calc = getattr(mesh, "calc_normals_split", None)
    if calc is not None:
        calc()


# --- render results -------------------------------------------------------------------------------------------

# RenderPass.rect: Blender 3.4 takes foreach_set as one row of `channels` floats per pixel; 4.x and 5.x take
# one flat run of floats (len(rect) is the pixel count in both).
_FLAT_PASS_RECT = VERSION >= (4, 0, 0)


def write_pass_pixels(render_pass, pixels):
    """Fill `render_pass` from `pixels`, a C-contiguous float32 (pixel count, channels) array."""
    render_pass.rect.foreach_set(pixels.reshape(-1) if _FLAT_PASS_RECT else pixels)


# --- Principled BSDF ------------------------------------------------------------------------------------------

# Principled BSDF v2 (Blender 4.0) renamed or replaced the inputs of v1 (3.x). The export reads them by role;
# roles a version does not have are None there. v1's Subsurface Color is gone in v2 (subsurface uses Base
# Color); v2's Specular IOR Level, Coat Tint and Thin Film have no v1 counterpart.
PRINCIPLED_V2 = VERSION >= (4, 0, 0)
_PRINCIPLED_V1 = {
    "base_color": "Base Color", "metallic": "Metallic", "roughness": "Roughness", "ior": "IOR",
    "alpha": "Alpha", "normal": "Normal", "transmission": "Transmission",
    "subsurface": "Subsurface", "subsurface_color": "Subsurface Color",
    "specular": "Specular", "specular_tint": "Specular Tint", "anisotropic": "Anisotropic",
    "coat": "Clearcoat", "coat_roughness": "Clearcoat Roughness",
    "sheen": "Sheen", "sheen_tint": "Sheen Tint",
    "emission_color": "Emission", "emission_strength": "Emission Strength",
    "transmission_roughness": "Transmission Roughness",
    "specular_ior_level": None, "coat_tint": None, "thin_film": None, "diffuse_roughness": None,
}
_PRINCIPLED_V2 = {
    **_PRINCIPLED_V1,
    "transmission": "Transmission Weight", "subsurface": "Subsurface Weight", "subsurface_color": None,
    "specular": None, "specular_ior_level": "Specular IOR Level", "anisotropic": "Anisotropic",
    "coat": "Coat Weight", "coat_roughness": "Coat Roughness", "coat_tint": "Coat Tint",
    "sheen": "Sheen Weight", "sheen_tint": "Sheen Tint",
    "emission_color": "Emission Color", "transmission_roughness": None, "thin_film": "Thin Film Thickness",
    "diffuse_roughness": "Diffuse Roughness",            # 4.3 and later
}
PRINCIPLED_INPUTS = _PRINCIPLED_V2 if PRINCIPLED_V2 else _PRINCIPLED_V1


def principled_input(role):
    """The name of the Principled BSDF input playing `role` in this Blender, or None where it has none."""
    return PRINCIPLED_INPUTS[role]


# --- shader nodes ---------------------------------------------------------------------------------------------

# Blender 4.0 merged Anisotropic BSDF into Glossy BSDF: nodes.new("ShaderNodeBsdfGlossy") makes a node whose
# bl_idname is ShaderNodeBsdfAnisotropic, and files from 3.x load that way. The default distribution of Glossy
# and Principled became Multiscatter GGX at the same time (GGX before).
GLOSSY_BSDF_IDNAME = "ShaderNodeBsdfAnisotropic" if VERSION >= (4, 0, 0) else "ShaderNodeBsdfGlossy"


def bump_map_correction(material):
    """A material's Bump Map Correction (4.x, on by default), which softens Cycles 4.x's bump shadowing term;
    Blender 3.x has no such setting (its term is another one: BUMP_SHADOWING)."""
    return bool(getattr(getattr(material, "cycles", None), "use_bump_map_correction", True))


# Cycles' bump shadowing term on diffuse closures under a bumped normal: 3.x's after Chiang et al., 4.x's after Conty
# Estevez et al. (read in 4.5's and 5.0's kernels). The core's Scene.bump_shadowing.
BUMP_SHADOWING = "cycles4" if VERSION >= (4, 0, 0) else "cycles3"


def bump_filter_width(node, folded=None):
    """A Bump node's filter width and a note, or None: how many ray differentials apart it samples its Height
    (the core's bump offsets). Blender 3.x samples one whole differential away. 4.x gave the node a Filter Width
    input (0.1 for a new node; files from before it load with 1, 3.x's step), which Cycles compiles as a constant
    of the node (svm_node_bump_P_dx): a link into it counts where it folds to a constant (`folded`: measured in
    Cycles 4.5 with a Value node and a Math node of constants), and otherwise the socket's own value stands (a
    Noise texture's link: the same pixels as the socket's value alone)."""
    socket = node.inputs.get("Filter Width")
    if socket is None:
        return 1.0, None
    note = None
    if socket.is_linked and folded is not None:
        width = float(folded)
    else:
        width = float(socket.default_value)
        if socket.is_linked:
            note = f"Bump node's Filter Width varies over the surface: its own value {width:g} used, as Cycles does"
    if not math.isfinite(width) or width < 0.0:
        return 0.0, f"Bump node's Filter Width {width} read as 0"
    return width, note


# --- node groups ----------------------------------------------------------------------------------------------

def new_group_socket(tree, in_out, socket_type, name):
    """Add an input ('INPUT') or output ('OUTPUT') socket to the node group `tree`: Blender 4.0 replaced
    tree.inputs / tree.outputs by tree.interface."""
    interface = getattr(tree, "interface", None)
    if interface is not None:
        return interface.new_socket(name, in_out=in_out, socket_type=socket_type)
    return (tree.inputs if in_out == 'INPUT' else tree.outputs).new(socket_type, name)


# --- lights ---------------------------------------------------------------------------------------------------

# How Cycles reads a light's settings, measured per version with tools/cycles_light_units.py (figures in
# docs/blender-versions.md). Cycles 4.0 changed three things:
#   - an area light's radiance is P / (π A) (flux P), where 3.4 gave P / (4 A) (flux π P / 4);
#   - a spot's intensity is I · smoothstep(...) across the cone, without 3.4's extra cos θ;
#   - a point or spot light of radius R with Soft Falloff off is a true sphere (on, the default, it is 3.4's
#     disc facing the receiver).
# and added settings that scale the light: Exposure (× 2^exposure), Temperature (× its blackbody colour) and
# Normalize (off: the strength is not divided by the light's area, so it is radiance-like).
CYCLES_4_LIGHTS = VERSION >= (4, 0, 0)
SPOT_COSINE = not CYCLES_4_LIGHTS


# Cycles 3.x evaluates a Multiscatter GGX lobe towards a light sample by a random walk that tints each bounce after
# the first twice (its sampled directions once); 4.x's Multiscatter GGX is the same lobe both ways. The core's
# Scene.multiscatter_light_estimate.
MULTISCATTER_LIGHT_ESTIMATE = "walk" if VERSION >= (4, 0, 0) else "light_sample"


def light_color_power(light):
    """(r, g, b) colour × power as Cycles multiplies them (W; W/m² for a sun), before any unit conversion."""
    power = float(light.energy)
    color = [float(c) for c in light.color]
    if CYCLES_4_LIGHTS:
        power *= 2.0 ** float(light.exposure)
        if light.use_temperature:
            color = [c * float(t) for c, t in zip(color, light.temperature_color)]
    return tuple(c * power for c in color)


def _normalized(light):
    return not CYCLES_4_LIGHTS or light.normalize


def point_intensity(light, rgb):
    """Intensity (W/sr) of a point or spot light of colour × power `rgb`: P / (4π). Without Normalize (4.x) a
    light of radius R is not divided by its surface: 4π R² times brighter (measured: 1.131× at R = 0.3)."""
    scale = 1.0 / (4.0 * math.pi)
    radius = float(light.shadow_soft_size)
    if not _normalized(light):
        scale *= 4.0 * math.pi * radius * radius
    return tuple(c * scale for c in rgb)


def point_light_shape(light):
    """Keyword arguments of the core's add_point_light / add_spot_light beyond 3.4's, for this light:
    sphere=True where Cycles renders it as a sphere (4.x, Soft Falloff off), spot_cosine=False for a 4.x spot.
    Empty for 3.4's conventions (the core's defaults)."""
    shape = {}
    if CYCLES_4_LIGHTS and not light.use_soft_falloff and float(light.shadow_soft_size) > 0.0:
        shape["sphere"] = True
    if light.type == 'SPOT' and not SPOT_COSINE:
        shape["spot_cosine"] = False
    return shape


def area_radiance(light, rgb, area):
    """Radiance (W/(sr m²)) of an area light of colour × power `rgb` and surface `area` (m², scale included)."""
    if not CYCLES_4_LIGHTS:
        return tuple(c / (4.0 * area) for c in rgb)
    divisor = math.pi * (area if light.normalize else 1.0)
    return tuple(c / divisor for c in rgb)


def light_panel_properties(light):
    """The settings of `light` beyond colour, power, size and shape that this Blender's Cycles reads, for the
    light panel: Temperature, Exposure, Normalize and Soft Falloff in 4.x (each changes the render: see
    above); none in 3.4."""
    if not CYCLES_4_LIGHTS:
        return []
    names = ["use_temperature", "temperature" if light.use_temperature else "color", "exposure"]
    if light.type != 'SUN':
        names.append("normalize")
    if light.type in {'POINT', 'SPOT'}:
        names.append("use_soft_falloff")
    return names


# Cycles' per-light switches. Multiple Importance is light.cycles.use_multiple_importance_sampling in 3.4 and 4.5;
# Cast Shadow is light.cycles.cast_shadow in 3.4 and light.use_shadow from 4.0 (3.4's use_shadow is EEVEE's, which
# Cycles 3.4 ignores). light.cycles is the Cycles add-on's: absent without it, then both read as on (the default).
def light_switch_owners(light):
    """(owner, property name) of the light's Multiple Importance and Cast Shadow switches as this Blender's Cycles
    keeps them (for the light panel); an owner is None where the Cycles add-on is not loaded."""
    cycles = getattr(light, "cycles", None)
    shadow_owner = light if CYCLES_4_LIGHTS else cycles
    return ((cycles, "use_multiple_importance_sampling"),
            (shadow_owner, "use_shadow" if CYCLES_4_LIGHTS else "cast_shadow"))


def light_switches(light):
    """The core's multiple_importance and cast_shadow keyword arguments for `light` (add_*_light)."""
    (mis_owner, mis_name), (shadow_owner, shadow_name) = light_switch_owners(light)
    return {"multiple_importance": bool(getattr(mis_owner, mis_name, True)),
            "cast_shadow": bool(getattr(shadow_owner, shadow_name, True))}


def spot_cone_follows_scale():
    """Whether a non-uniform object scale squeezes a spot's cone into an ellipse (Cycles 4.x); 3.4 reads only
    the direction."""
    return CYCLES_4_LIGHTS


# --- node trees -----------------------------------------------------------------------------------------------

# Blender 5.0 always renders a material's and a world's node tree: their use_nodes is deprecated (reading it
# warns, setting it does nothing). Lights keep their use_nodes switch.
_NODES_ALWAYS = VERSION >= (5, 0, 0)


def has_use_nodes_switch(id_block):
    """Whether `id_block` (material, world or light) has a working Use Nodes switch in this Blender."""
    return not (_NODES_ALWAYS and isinstance(id_block, (bpy.types.Material, bpy.types.World)))


def uses_nodes(id_block):
    """Whether Cycles renders `id_block` through its node tree (else through its plain colour)."""
    if id_block.node_tree is None:
        return False
    return id_block.use_nodes if has_use_nodes_switch(id_block) else True


# --- image output -----------------------------------------------------------------------------------------------

def set_multilayer_exr(image_settings):
    """Make `image_settings` write a multilayer OpenEXR. Blender 5.0 offers that format only once the media
    type is multi-layer (3.4 and 4.5 have no media type)."""
    if VERSION >= (5, 0, 0):
        image_settings.media_type = 'MULTI_LAYER_IMAGE'
    image_settings.file_format = 'OPEN_EXR_MULTILAYER'
