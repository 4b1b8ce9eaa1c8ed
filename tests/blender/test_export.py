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
from photonsplat.export import materials


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

def test_principled_maps_to_the_dominant_lobe(empty_scene):
    glass, _ = node_material("G", "ShaderNodeBsdfPrincipled", Base_Color=(0.9, 1.0, 0.9, 1.0), Transmission=1.0,
                             IOR=1.5, Roughness=0.0)
    metal, _ = node_material("M", "ShaderNodeBsdfPrincipled", Base_Color=(1.0, 0.8, 0.3, 1.0), Metallic=1.0,
                             Roughness=0.0)
    plain, _ = node_material("D", "ShaderNodeBsdfPrincipled", Base_Color=(0.2, 0.4, 0.6, 1.0),
                             Emission_Color=(1.0, 0.5, 0.0, 1.0), Emission_Strength=4.0)
    g, m, d = (materials.convert_material(x) for x in (glass, metal, plain))
    assert (g.kind, g.ior, g.notes) == ("glass", pytest.approx(1.5), [])
    assert approx(g.color, (0.9, 1.0, 0.9))
    assert m.kind == "mirror" and approx(m.color, (1.0, 0.8, 0.3)) and m.notes == []
    assert d.kind == "diffuse" and approx(d.color, (0.2, 0.4, 0.6))
    assert approx(d.emission, (4.0, 2.0, 0.0))


def test_principled_approximations_are_noted(empty_scene):
    rough_metal, _ = node_material("RM", "ShaderNodeBsdfPrincipled", Metallic=0.7, Roughness=0.4)
    spec = materials.convert_material(rough_metal)
    assert spec.kind == "glossy" and spec.roughness == pytest.approx(0.4)
    assert any("Metallic" in n for n in spec.notes)
    assert not any("Roughness" in n for n in spec.notes), "a rough metal is rendered rough now"


def test_rough_metals_become_glossy_with_their_roughness(empty_scene):
    gold, node = node_material("Gold", "ShaderNodeBsdfPrincipled", Base_Color=(1.0, 0.77, 0.34, 1.0), Metallic=1.0,
                               Roughness=0.35)
    node.distribution = 'GGX'            # the default of Blender 3.4 (4.0 made it Multiscatter GGX, noted)
    brushed, node = node_material("Brushed", "ShaderNodeBsdfGlossy", Color=(0.9, 0.9, 0.9, 1.0), Roughness=0.3)
    node.distribution = 'GGX'
    polished, _ = node_material("Polished", "ShaderNodeBsdfGlossy", Color=(0.9, 0.9, 0.9, 1.0), Roughness=0.05)
    smooth_metal, _ = node_material("Chrome", "ShaderNodeBsdfPrincipled", Metallic=1.0, Roughness=0.05)
    g, b, p, c = (materials.convert_material(x) for x in (gold, brushed, polished, smooth_metal))
    assert g.kind == "glossy" and approx(g.color, (1.0, 0.77, 0.34)) and g.notes == []
    assert g.roughness == pytest.approx(0.35)
    assert b.kind == "glossy" and b.roughness == pytest.approx(0.3) and approx(b.color, (0.9, 0.9, 0.9))
    assert b.notes == []
    assert b.core_arguments()["roughness"] == pytest.approx(0.3) and b.core_arguments()["kind"] == "glossy"
    assert "roughness 0.30" in b.describe()
    # At or below 0.05 a metal is a perfect mirror, as Cycles users expect (alpha <= 0.0025).
    assert (p.kind, p.notes) == ("mirror", []) and (c.kind, c.notes) == ("mirror", [])


def test_glossy_distributions_other_than_ggx_are_noted(empty_scene):
    beckmann, node = node_material("Beck", "ShaderNodeBsdfGlossy", Roughness=0.4)
    node.distribution = 'BECKMANN'
    multi, node = node_material("Multi", "ShaderNodeBsdfGlossy", Roughness=0.4)
    node.distribution = 'MULTI_GGX'
    principled, node = node_material("PM", "ShaderNodeBsdfPrincipled", Metallic=1.0, Roughness=0.6)
    node.distribution = 'MULTI_GGX'
    for mat, label in ((beckmann, "Beckmann"), (multi, "Multiscatter GGX"), (principled, "Multiscatter GGX")):
        spec = materials.convert_material(mat)
        assert spec.kind == "glossy" and any(label in n and "GGX" in n for n in spec.notes), spec.notes
    # A smooth one is a mirror whatever its distribution: nothing to note.
    smooth, node = node_material("SmoothBeck", "ShaderNodeBsdfGlossy", Roughness=0.0)
    node.distribution = 'BECKMANN'
    assert materials.convert_material(smooth).notes == []


def test_rough_glass_is_still_rendered_smooth_with_a_note(empty_scene):
    glass, _ = node_material("Frosted", "ShaderNodeBsdfGlass", IOR=1.5, Roughness=0.3)
    principled, _ = node_material("PFrosted", "ShaderNodeBsdfPrincipled", Transmission=1.0, Roughness=0.3)
    for mat in (glass, principled):
        spec = materials.convert_material(mat)
        assert spec.kind == "glass" and any("Roughness 0.30" in n and "smooth" in n for n in spec.notes)


def test_glossy_roughness_reaches_the_core(empty_scene):
    add_camera(empty_scene)
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    plane = bpy.context.active_object
    metal, _ = node_material("Brushed", "ShaderNodeBsdfGlossy", Color=(0.8, 0.6, 0.4, 1.0), Roughness=0.45)
    plane.data.materials.append(metal)
    frame = export_current()
    (exported,) = frame.scene.materials
    assert exported["kind"] == "glossy" and exported["roughness"] == pytest.approx(0.45)
    assert approx(exported["color"], (0.8, 0.6, 0.4))


def test_basic_shaders(empty_scene):
    diffuse, _ = node_material("Di", "ShaderNodeBsdfDiffuse", Color=(0.5, 0.25, 0.125, 1.0))
    glossy, _ = node_material("Gl", "ShaderNodeBsdfGlossy", Color=(0.9, 0.9, 0.9, 1.0), Roughness=0.0)
    glass, _ = node_material("Ga", "ShaderNodeBsdfGlass", Color=(1.0, 1.0, 1.0, 1.0), IOR=1.33, Roughness=0.0)
    light, _ = node_material("Em", "ShaderNodeEmission", Color=(1.0, 0.5, 0.25, 1.0), Strength=10.0)
    d, gl, ga, em = (materials.convert_material(x) for x in (diffuse, glossy, glass, light))
    assert d.kind == "diffuse" and approx(d.color, (0.5, 0.25, 0.125)) and d.notes == []
    assert gl.kind == "mirror" and approx(gl.color, (0.9, 0.9, 0.9)) and gl.notes == []
    assert ga.kind == "glass" and ga.ior == pytest.approx(1.33) and ga.notes == []
    # An Emission shader reflects nothing: black diffuse plus the emitted radiance colour x strength.
    assert em.kind == "diffuse" and approx(em.color, (0, 0, 0)) and approx(em.emission, (10.0, 5.0, 2.5))


def test_mix_with_emission_is_exact(empty_scene):
    mat, _ = node_material("Mix", "ShaderNodeMixShader", Fac=0.25)
    tree = mat.node_tree
    mix = tree.nodes["Mix Shader"]
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (0.8, 0.4, 0.2, 1.0)
    emission = tree.nodes.new("ShaderNodeEmission")
    emission.inputs["Strength"].default_value = 8.0
    tree.links.new(diffuse.outputs[0], mix.inputs[1])
    tree.links.new(emission.outputs[0], mix.inputs[2])
    spec = materials.convert_material(mat)
    assert spec.kind == "diffuse" and spec.notes == []
    assert approx(spec.color, (0.6, 0.3, 0.15))              # 0.75 x the diffuse albedo
    assert approx(spec.emission, (2.0, 2.0, 2.0))            # 0.25 x 8


def test_unsupported_setups_fall_back_with_a_note(empty_scene):
    mix, _ = node_material("DiffGloss", "ShaderNodeMixShader", Fac=0.3)
    tree = mix.node_tree
    tree.links.new(tree.nodes.new("ShaderNodeBsdfDiffuse").outputs[0], tree.nodes["Mix Shader"].inputs[1])
    tree.links.new(tree.nodes.new("ShaderNodeBsdfGlossy").outputs[0], tree.nodes["Mix Shader"].inputs[2])
    textured, shader = node_material("Tex", "ShaderNodeBsdfPrincipled")
    textured.node_tree.links.new(textured.node_tree.nodes.new("ShaderNodeTexChecker").outputs["Color"],
                                 shader.inputs["Base Color"])
    toon, _ = node_material("Toon", "ShaderNodeBsdfToon", Color=(0.1, 0.2, 0.3, 1.0))

    m = materials.convert_material(mix)
    assert m.kind == "diffuse" and any("Mix Shader" in n for n in m.notes)
    t = materials.convert_material(textured)
    assert t.kind == "diffuse" and any("Checker" in n for n in t.notes)
    o = materials.convert_material(toon)
    assert o.kind == "diffuse" and approx(o.color, (0.1, 0.2, 0.3)) and any("Toon" in n for n in o.notes)


def test_material_without_nodes_uses_its_viewport_colour(empty_scene):
    mat = bpy.data.materials.new("Plain")
    mat.diffuse_color = (0.3, 0.6, 0.9, 1.0)
    if compat.has_use_nodes_switch(mat):
        mat.use_nodes = False
        spec = materials.convert_material(mat)
        assert spec.kind == "diffuse" and approx(spec.color, (0.3, 0.6, 0.9))
    else:   # Blender 5.0: every material renders its node tree (a new one: Principled, Base Color 0.8)
        spec = materials.convert_material(mat)
        assert spec.kind == "diffuse" and approx(spec.color, (0.8, 0.8, 0.8))
    assert materials.convert_material(None).name == materials.DEFAULT_MATERIAL_NAME


def test_colours_are_clamped_for_the_core(empty_scene):
    mat, _ = node_material("Hot", "ShaderNodeBsdfDiffuse", Color=(2.0, 0.5, -1.0, 1.0))
    spec = materials.convert_material(mat)
    assert approx(spec.color, (1.0, 0.5, 0.0)) and any("clamped" in n for n in spec.notes)


# --- meshes -------------------------------------------------------------------------------------------------

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
    assert spec.kind == "diffuse"
    assert any(compat.principled_input("coat") in n for n in spec.notes)
    assert any(compat.principled_input("sheen") in n for n in spec.notes)
    assert any("subsurface" in n for n in spec.notes)
    if compat.principled_input("subsurface_color") is None:   # v2: subsurface scatters Base Color itself
        assert approx(spec.color, (0.2, 0.3, 0.4))


@pytest.mark.skipif(bpy.app.version < (4, 3, 0), reason="the Metallic BSDF node came with Blender 4.3")
def test_metallic_bsdf_is_a_metal(empty_scene):
    f82, node = node_material("F82", "ShaderNodeBsdfMetallic", Base_Color=(0.9, 0.6, 0.3, 1.0), Roughness=0.3,
                              Edge_Tint=(1.0, 1.0, 1.0, 1.0))
    node.distribution = 'GGX'
    spec = materials.convert_material(f82)
    assert spec.kind == "glossy" and approx(spec.color, (0.9, 0.6, 0.3)) and spec.notes == []
    conductor, node = node_material("Gold", "ShaderNodeBsdfMetallic", Roughness=0.0)
    node.fresnel_type = 'PHYSICAL_CONDUCTOR'
    node.inputs["IOR"].default_value = (0.18, 0.42, 1.37)
    node.inputs["Extinction"].default_value = (3.42, 2.35, 1.77)
    spec = materials.convert_material(conductor)
    expected = tuple(((n - 1) ** 2 + k * k) / ((n + 1) ** 2 + k * k)
                     for n, k in zip((0.18, 0.42, 1.37), (3.42, 2.35, 1.77)))
    assert spec.kind == "mirror" and approx(spec.color, expected, rel=1e-4)
    assert any("conductor" in n for n in spec.notes)
