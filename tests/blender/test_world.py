"""The world as the add-on exports it (issue 17): its node tree compiled to a program (export/world.py), the constant
world without one, the Cycles world settings read, portals (export/lights.py), and the sync applying world changes
in full exports and in the viewport's incremental path (export/sync.py). Then, where the core has world programs,
the sky an escaped camera ray sees against Cycles' render of the same scene.
"""

import math
import sys
from pathlib import Path

import bpy
import numpy as np
import pytest
from mathutils import Vector

from blender_helpers import enable_nodes, uniform_world
from photonsplat import compat, export
from photonsplat.export import shader_program
from photonsplat.export import world as world_export

REPO = Path(__file__).resolve().parents[2]


# --- a core that records what the sync gives it ----------------------------------------------------------------

class FakeScene:
    """Stands in for the core Scene: records every call, by name, with its arguments."""

    def __init__(self):
        self.calls = []
        self.textures = []
        self.background = None
        self.world_program = None
        self.map_resolution = None
        self.portals = []
        self.lights = []

    def add_texture(self, **kw):
        self.calls.append(("add_texture", kw))
        self.textures.append(kw)
        return len(self.textures) - 1

    def add_material(self, **kw):
        self.calls.append(("add_material", kw))
        return len([c for c in self.calls if c[0] == "add_material"]) - 1

    def add_mesh_data(self, **kw):
        self.calls.append(("add_mesh_data", kw))
        return len([c for c in self.calls if c[0] == "add_mesh_data"]) - 1

    def add_instance(self, **kw):
        self.calls.append(("add_instance", kw))
        return len([c for c in self.calls if c[0] == "add_instance"]) - 1

    def attribute_id(self, name):
        return 0

    def set_background(self, radiance):
        self.calls.append(("set_background", radiance))
        self.background = tuple(radiance)

    def set_world_program(self, program, map_resolution=0):
        self.calls.append(("set_world_program", program))
        self.world_program, self.map_resolution = program, map_resolution

    def add_portal(self, name, corner, edge_u, edge_v):
        self.calls.append(("add_portal", name))
        self.portals.append((name, np.array(corner), np.array(edge_u), np.array(edge_v)))

    def clear_lights(self):
        self.calls.append(("clear_lights", None))
        self.portals, self.lights = [], []

    def __getattr__(self, method):            # add_*_light, set_instance_transform, fit_origin...
        if method.startswith("__"):
            raise AttributeError(method)

        def record(*args, **kw):
            self.calls.append((method, kw))
            if method.startswith("add_") and method.endswith("_light"):
                self.lights.append((method, kw))
        return record

    def count(self, method):
        return sum(1 for name, _ in self.calls if name == method)


class FakeCore:
    Scene = FakeScene


def sync_once(scene=None):
    sync = export.BlenderSync(FakeCore)
    sync.sync(bpy.context.evaluated_depsgraph_get())
    return sync


# --- building worlds ---------------------------------------------------------------------------------------------

def node_world(scene):
    """A new world with its node tree emptied but for the World Output; returns (world, nodes, links, output)."""
    world = bpy.data.worlds.new("Nodes")
    enable_nodes(world)
    tree = world.node_tree
    tree.nodes.clear()
    output = tree.nodes.new("ShaderNodeOutputWorld")
    scene.world = world
    return world, tree.nodes, tree.links, output


def equirect_image(name="Sky", width=8, height=4):
    """A float image whose texels are all different (red along u, green along v, blue 0.25)."""
    image = bpy.data.images.new(name, width, height, float_buffer=True)
    # (Blender 4.x names a float image's space "Linear Rec.709", which textures.py does not know yet: Non-Color is
    # the same data in every version.)
    image.colorspace_settings.name = 'Non-Color'
    pixels = np.zeros((height, width, 4), dtype=np.float32)
    pixels[..., 0] = (np.arange(width) + 0.5)[None, :] / width * 4.0
    pixels[..., 1] = (np.arange(height) + 0.5)[:, None] / height * 2.0
    pixels[..., 2] = 0.25
    pixels[..., 3] = 1.0
    image.pixels.foreach_set(pixels.reshape(-1))
    image.update()
    return image


def hdri_world(scene, rotation_z=0.0, image=None, strength=1.0):
    """Texture Coordinate (Generated) -> Mapping (rotation about Z) -> Environment Texture -> Background."""
    world, nodes, links, output = node_world(scene)
    coordinate = nodes.new("ShaderNodeTexCoord")
    mapping = nodes.new("ShaderNodeMapping")
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, rotation_z)
    environment = nodes.new("ShaderNodeTexEnvironment")
    environment.image = image if image is not None else equirect_image()
    background = nodes.new("ShaderNodeBackground")
    background.inputs["Strength"].default_value = strength
    links.new(coordinate.outputs["Generated"], mapping.inputs["Vector"])
    links.new(mapping.outputs["Vector"], environment.inputs["Vector"])
    links.new(environment.outputs["Color"], background.inputs["Color"])
    links.new(background.outputs[0], output.inputs["Surface"])
    return world, mapping, environment


def op_names(spec):
    return [instruction[0] for instruction in spec.program.instructions] if spec.uses_program else []


# --- compilation -------------------------------------------------------------------------------------------------

def test_constant_world_has_no_program(empty_scene):
    uniform_world(empty_scene, (0.5, 0.25, 1.0), 2.0)
    spec = world_export.convert_world(empty_scene.world)
    assert not spec.uses_program and spec.core_program() is None
    assert spec.radiance == pytest.approx((1.0, 0.5, 2.0))
    assert spec.notes == []


def test_no_world_is_black_and_a_world_without_nodes_its_colour(empty_scene):
    assert world_export.convert_world(None).radiance == (0.0, 0.0, 0.0)
    world = bpy.data.worlds.new("Plain")
    world.color = (0.1, 0.2, 0.3)
    if compat.has_use_nodes_switch(world):         # Blender 5.0: worlds always render their node tree
        world.use_nodes = False
        spec = world_export.convert_world(world)
        assert not spec.uses_program and spec.radiance == pytest.approx((0.1, 0.2, 0.3))


def test_constant_nodes_fold_to_the_constant(empty_scene):
    """A Mix Shader of two Backgrounds whose inputs are constants (an RGB node, a Math node) is a constant world."""
    world, nodes, links, output = node_world(empty_scene)
    rgb = nodes.new("ShaderNodeRGB")
    rgb.outputs[0].default_value = (0.2, 0.4, 0.6, 1.0)
    first = nodes.new("ShaderNodeBackground")
    second = nodes.new("ShaderNodeBackground")
    second.inputs["Color"].default_value = (1.0, 0.0, 0.0, 1.0)
    second.inputs["Strength"].default_value = 3.0
    mix = nodes.new("ShaderNodeMixShader")
    mix.inputs["Fac"].default_value = 0.25
    links.new(rgb.outputs[0], first.inputs["Color"])
    links.new(first.outputs[0], mix.inputs[1])
    links.new(second.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], output.inputs["Surface"])
    spec = world_export.convert_world(world)
    assert not spec.uses_program
    assert spec.radiance == pytest.approx((0.75 * 0.2 + 0.25 * 3.0, 0.75 * 0.4, 0.75 * 0.6))


def test_environment_texture_with_mapping_is_a_program(empty_scene):
    world, mapping, environment = hdri_world(empty_scene, rotation_z=math.radians(90.0))
    spec = world_export.convert_world(world)
    assert spec.uses_program, spec.notes
    names = op_names(spec)
    assert "environment_texture" in names and "mapping" in names and "texture_coordinate" in names
    assert [reference.image.name for reference in spec.textures] == [environment.image.name]
    program = spec.core_program(lambda reference: 7)
    assert [o["target"] for o in program["outputs"]] == ["emission"]
    assert spec.radiance == (0.0, 0.0, 0.0)
    assert spec.notes == []


def test_light_path_camera_ray_mix(empty_scene):
    """The camera sees one background, the scene is lit by another: a Mix Shader by Is Camera Ray."""
    world, nodes, links, output = node_world(empty_scene)
    light_path = nodes.new("ShaderNodeLightPath")
    lighting = nodes.new("ShaderNodeBackground")
    lighting.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    seen = nodes.new("ShaderNodeBackground")
    seen.inputs["Color"].default_value = (0.0, 0.0, 1.0, 1.0)
    mix = nodes.new("ShaderNodeMixShader")
    links.new(light_path.outputs["Is Camera Ray"], mix.inputs["Fac"])
    links.new(lighting.outputs[0], mix.inputs[1])
    links.new(seen.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], output.inputs["Surface"])
    spec = world_export.convert_world(world)
    assert spec.uses_program and "light_path" in op_names(spec)
    assert spec.notes == []


def test_sky_texture_compiles_through_the_node_table(empty_scene):
    """Sky Texture goes through whatever shader_program.NODES has for it: its op when it has one, else a note."""
    world, nodes, links, output = node_world(empty_scene)
    sky = nodes.new("ShaderNodeTexSky")
    background = nodes.new("ShaderNodeBackground")
    links.new(sky.outputs["Color"], background.inputs["Color"])
    links.new(background.outputs[0], output.inputs["Surface"])
    spec = world_export.convert_world(world)
    if "ShaderNodeTexSky" in shader_program.NODES:
        assert spec.uses_program and "sky_texture" in op_names(spec), spec.notes
    else:
        assert any("Sky Texture" in note for note in spec.notes)


def test_world_invisible_to_the_camera_compiles_the_camera_flag(empty_scene):
    world = uniform_world(empty_scene, (1.0, 0.5, 0.25), 1.0)
    world.cycles_visibility.camera = False
    spec = world_export.convert_world(world)
    assert spec.uses_program and "light_path" in op_names(spec)
    # Without world programs in the core it is said, not rendered.
    old = world_export.convert_world(world, programs=False)
    assert not old.uses_program and old.radiance == pytest.approx((1.0, 0.5, 0.25))
    assert any("Camera" in note for note in old.notes)


def test_notes_for_what_is_not_rendered(empty_scene):
    world, nodes, links, output = node_world(empty_scene)
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    links.new(diffuse.outputs[0], output.inputs["Surface"])
    volume = nodes.new("ShaderNodeVolumeScatter")
    links.new(volume.outputs[0], output.inputs["Volume"])
    world.cycles.sampling_method = 'NONE'
    world.cycles_visibility.glossy = False
    spec = world_export.convert_world(world)
    text = " | ".join(spec.notes)
    assert "Volume output ignored" in text
    assert "not supported in the world" in text
    assert "sampling method None" in text
    assert "glossy" in text
    assert all(line.startswith(f"World '{world.name}': ") for line in spec.report_lines())


def test_manual_map_resolution(empty_scene):
    world, _, _ = hdri_world(empty_scene)
    world.cycles.sampling_method = 'MANUAL'
    world.cycles.sample_map_resolution = 512
    assert world_export.convert_world(world).map_resolution == 512
    world.cycles.sampling_method = 'AUTOMATIC'
    assert world_export.convert_world(world).map_resolution == 0


def test_driven_inputs_without_world_programs_take_their_values(empty_scene):
    world, _, environment = hdri_world(empty_scene)
    spec = world_export.convert_world(world, programs=False)
    assert not spec.uses_program
    assert any("Environment Texture" in note for note in spec.notes)


# --- the sync ----------------------------------------------------------------------------------------------------

def test_sync_sets_the_program_and_shares_the_texture_table(empty_scene):
    """An HDRI in the world and in a material is one core texture; the constant is black beside a program."""
    world, _, environment = hdri_world(empty_scene)
    world.cycles.sampling_method = 'MANUAL'
    world.cycles.sample_map_resolution = 256
    material = bpy.data.materials.new("Textured")
    enable_nodes(material)
    tree = material.node_tree
    image_node = tree.nodes.new("ShaderNodeTexImage")
    image_node.image = environment.image
    image_node.interpolation = 'Closest'                   # compiled to a program: a program texture
    principled = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    tree.links.new(image_node.outputs["Color"], principled.inputs[0])
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    bpy.context.active_object.data.materials.append(material)

    sync = sync_once()
    scene = sync.scene
    assert scene.count("add_texture") == 1, scene.calls
    assert scene.world_program is not None and scene.map_resolution == 256
    assert scene.background == (0.0, 0.0, 0.0)
    assert shader_program.op_table()["environment_texture"]["id"] in scene.world_program["code"]


def test_constant_world_sync_uses_set_background_only(empty_scene):
    uniform_world(empty_scene, (0.5, 0.5, 0.5), 2.0)
    scene = sync_once().scene
    assert scene.background == pytest.approx((1.0, 1.0, 1.0))
    assert scene.world_program is None


class DepsgraphUpdates:
    """Calls sync.sync(depsgraph) from depsgraph_update_post, as the viewport's view_update does."""

    def __init__(self, sync):
        self.sync, self.reports = sync, []

    def __enter__(self):
        bpy.app.handlers.depsgraph_update_post.append(self.handler)
        return self

    def __exit__(self, *exc):
        bpy.app.handlers.depsgraph_update_post.remove(self.handler)

    def handler(self, scene, depsgraph):
        self.reports.append(self.sync.sync(depsgraph))

    def evaluate(self):
        self.reports.clear()
        bpy.context.view_layer.update()
        return self.reports


def test_viewport_applies_world_changes_in_place(empty_scene):
    world, mapping, environment = hdri_world(empty_scene)
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    sync = export.BlenderSync(FakeCore)
    sync.sync(bpy.context.evaluated_depsgraph_get())
    scene = sync.scene
    first = scene.world_program
    assert first is not None
    with DepsgraphUpdates(sync) as updates:
        mapping.inputs["Rotation"].default_value = (0.0, 0.0, 1.0)
        reports = updates.evaluate()
        assert any(r.world for r in reports) and not any(r.rebuilt for r in reports), reports
        assert sync.scene is scene and scene.world_program["registers"] != first["registers"]
        assert scene.count("add_texture") == 1               # the image was not added again

        # Constant again: the program goes, the constant comes.
        tree = world.node_tree
        tree.links.remove(next(l for l in tree.links if l.to_node.bl_idname == "ShaderNodeBackground"))
        tree.nodes["Background"].inputs["Color"].default_value = (0.0, 0.5, 0.0, 1.0)
        reports = updates.evaluate()
        assert any(r.world for r in reports) and not any(r.rebuilt for r in reports), reports
        assert scene.world_program is None and scene.background == pytest.approx((0.0, 0.5, 0.0))

        # Nothing changed in the world: nothing applied.
        before = scene.count("set_background")
        bpy.context.active_object.location.x += 1.0
        updates.evaluate()
        assert scene.count("set_background") == before


# --- portals -----------------------------------------------------------------------------------------------------

def portal_light(scene, shape='RECTANGLE', size=2.0, size_y=1.0, rotation=(0.0, 0.0, 0.0), scale=(1.0, 1.0, 1.0)):
    data = bpy.data.lights.new("Portal", 'AREA')
    data.shape, data.size, data.size_y = shape, size, size_y
    data.cycles.is_portal = True
    obj = bpy.data.objects.new("Portal", data)
    obj.location = (1.0, 2.0, 3.0)
    obj.rotation_euler = rotation
    obj.scale = scale
    scene.collection.objects.link(obj)
    return obj


@pytest.mark.parametrize("shape", ['RECTANGLE', 'SQUARE', 'DISK'])
def test_portals_are_exported_facing_the_light_direction(empty_scene, shape):
    uniform_world(empty_scene)
    obj = portal_light(empty_scene, shape=shape, rotation=(math.radians(90.0), 0.0, math.radians(30.0)),
                       scale=(1.5, 1.0, 1.0))
    sync = sync_once()
    scene = sync.scene
    assert scene.lights == [] and sync.lights == 0 and sync.portals == 1
    ((name, corner, edge_u, edge_v),) = scene.portals
    basis = obj.matrix_world.to_3x3()
    direction = np.array(basis @ Vector((0.0, 0.0, -1.0))).astype(float)
    direction /= np.linalg.norm(direction)
    normal = np.cross(edge_u, edge_v)
    assert normal / np.linalg.norm(normal) == pytest.approx(direction, abs=1e-6)
    size_x = 2.0
    size_y = 1.0 if shape == 'RECTANGLE' else 2.0
    assert sorted([np.linalg.norm(edge_u), np.linalg.norm(edge_v)]) == pytest.approx(
        sorted([1.5 * size_x, size_y]), rel=1e-6)
    assert corner + 0.5 * edge_u + 0.5 * edge_v == pytest.approx(np.array(obj.matrix_world.translation), abs=1e-6)
    notes = " | ".join(sync.notes)
    assert ("bounding rectangle" in notes) == (shape == 'DISK')
    # A lit scene: no "no lights" note from the portal alone beside a lit world.
    assert "black" not in notes


def test_portal_changes_are_applied_like_lights(empty_scene):
    uniform_world(empty_scene)
    obj = portal_light(empty_scene)
    sync = export.BlenderSync(FakeCore)
    sync.sync(bpy.context.evaluated_depsgraph_get())
    scene = sync.scene
    with DepsgraphUpdates(sync) as updates:
        obj.location.z += 1.0
        reports = updates.evaluate()
        assert any(r.lights for r in reports) and not any(r.rebuilt for r in reports)
        assert scene.count("clear_lights") == 1 and len(scene.portals) == 1
        assert scene.portals[0][1][2] == pytest.approx(4.0)       # a flat portal at the light's new height
        obj.data.cycles.is_portal = False                  # an area light again: it emits
        obj.data.update_tag()                              # (the UI tags the light; Python alone does not)
        updates.evaluate()
        assert scene.portals == [] and [m for m, _ in scene.lights] == ["add_area_light"]


def test_portal_is_not_an_area_light_in_the_real_core(empty_scene, core):
    uniform_world(empty_scene)
    portal_light(empty_scene)
    sync = export.BlenderSync(core)
    sync.sync(bpy.context.evaluated_depsgraph_get())
    assert sync.lights == 0
    if hasattr(sync.scene, "add_portal"):
        assert sync.portals == 1
    else:
        assert any("portals not supported" in note for note in sync.notes)


# --- pixels against Cycles -----------------------------------------------------------------------------------------

def sky_scene(scene):
    """A perspective camera looking up and sideways at the sky of hdri_world (no geometry): every pixel is an escaped
    camera ray."""
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.data.lens = 18.0
    cam.rotation_euler = (math.radians(70.0), 0.0, math.radians(35.0))
    scene.collection.objects.link(cam)
    scene.camera = cam
    return cam


def test_escaped_camera_rays_see_cycles_sky(empty_scene, core, tmp_path):
    if not hasattr(core.Scene, "set_world_program"):
        pytest.skip("this core has no world programs (Scene.set_world_program)")
    sys.path.insert(0, str(REPO / "tools"))
    import node_compare

    world, mapping, environment = hdri_world(empty_scene, rotation_z=math.radians(40.0), strength=1.5,
                                             image=equirect_image("Fine", 32, 16))
    environment.interpolation = 'Closest'         # texel values, not their blends: a sharp comparison
    sky_scene(empty_scene)
    empty_scene.render.resolution_x = empty_scene.render.resolution_y = 32
    empty_scene.render.resolution_percentage = 100
    node_compare.cycles_plane_settings(empty_scene, threads=2)
    cycles = node_compare.render_cycles(tmp_path / "cycles.exr")
    ours, notes, _ = node_compare.photonsplat_case(core, threads=2)
    assert not [n for n in notes if n.startswith("World")], notes
    assert ours.shape == cycles.shape == (32, 32, 4)
    difference = np.abs(ours[..., :3] - cycles[..., :3])
    # Nearest texels: a pixel whose centre lies on a texel edge may take the neighbour; all others are exact.
    close = (difference <= 1e-3 * np.maximum(cycles[..., :3], 1e-3)).all(axis=-1)
    print(f"\nsky: Cycles mean {cycles[..., :3].mean():.4f}, ours {ours[..., :3].mean():.4f}, "
          f"{close.mean() * 100:.1f} % of pixels within 1e-3")
    assert close.mean() >= 0.97
    assert abs(ours[..., :3].mean() / cycles[..., :3].mean() - 1.0) < 0.01


def test_camera_sees_one_background_while_another_lights_the_scene(empty_scene, core, tmp_path):
    """A Light Path Is Camera Ray mix: the camera sees blue, the grey plane is lit by white (against Cycles)."""
    if not hasattr(core.Scene, "set_world_program"):
        pytest.skip("this core has no world programs (Scene.set_world_program)")
    sys.path.insert(0, str(REPO / "tools"))
    import node_compare

    world, nodes, links, output = node_world(empty_scene)
    light_path = nodes.new("ShaderNodeLightPath")
    lighting = nodes.new("ShaderNodeBackground")
    lighting.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    seen = nodes.new("ShaderNodeBackground")
    seen.inputs["Color"].default_value = (0.1, 0.2, 0.9, 1.0)
    mix = nodes.new("ShaderNodeMixShader")
    links.new(light_path.outputs["Is Camera Ray"], mix.inputs["Fac"])
    links.new(lighting.outputs[0], mix.inputs[1])
    links.new(seen.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], output.inputs["Surface"])
    bpy.ops.mesh.primitive_plane_add(size=2.0)               # no material: grey 0.8 diffuse in both renderers
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.data.type = 'ORTHO'
    cam.data.ortho_scale = 4.0
    cam.location = (0.0, 0.0, 5.0)                           # looking down: the plane in the middle, sky around
    empty_scene.collection.objects.link(cam)
    empty_scene.camera = cam
    empty_scene.render.resolution_x = empty_scene.render.resolution_y = 32
    empty_scene.render.resolution_percentage = 100
    node_compare.cycles_plane_settings(empty_scene, threads=2)
    empty_scene.cycles.samples = 128
    cycles = node_compare.render_cycles(tmp_path / "cycles.exr")[..., :3]
    ours, notes, _ = node_compare.photonsplat_case(core, threads=2)
    ours = ours[..., :3]
    assert not [n for n in notes if n.startswith("World")], notes
    sky = cycles[..., 2] > 3.0 * cycles[..., 0]
    plane = ~sky
    assert 0.2 < plane.mean() < 0.3, plane.mean()            # the plane covers a quarter of the view
    print(f"\nplane: Cycles {cycles[plane].mean():.4f}, ours {ours[plane].mean():.4f}; sky ours "
          f"{ours[sky].mean(axis=0)}")
    np.testing.assert_allclose(ours[sky], np.broadcast_to((0.1, 0.2, 0.9), ours[sky].shape), rtol=1e-4)
    assert abs(ours[plane].mean() / cycles[plane].mean() - 1.0) < 0.02


# --- the real core ---------------------------------------------------------------------------------------------------

def world_programs(core):
    if not hasattr(core.Scene, "set_world_program"):
        pytest.skip("this core has no world programs (Scene.set_world_program)")
    return core


def real_sync(core):
    sync = export.BlenderSync(core)
    sync.sync(bpy.context.evaluated_depsgraph_get())
    return sync


def test_camera_invisible_world_in_the_core(empty_scene, core):
    world_programs(core)
    world = uniform_world(empty_scene, (1.0, 0.5, 0.25), 2.0)
    world.cycles_visibility.camera = False
    scene = real_sync(core).scene
    assert scene.world_programmed
    up = (0.0, 0.0, 1.0)
    assert scene.world_radiance(up, camera=True) == pytest.approx((0.0, 0.0, 0.0))
    assert scene.world_radiance(up, camera=False) == pytest.approx((2.0, 1.0, 0.5), rel=1e-5)


def test_camera_ray_mix_in_the_core(empty_scene, core):
    world_programs(core)
    world, nodes, links, output = node_world(empty_scene)
    light_path = nodes.new("ShaderNodeLightPath")
    lighting = nodes.new("ShaderNodeBackground")
    lighting.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    seen = nodes.new("ShaderNodeBackground")
    seen.inputs["Color"].default_value = (0.1, 0.2, 0.9, 1.0)
    mix = nodes.new("ShaderNodeMixShader")
    links.new(light_path.outputs["Is Camera Ray"], mix.inputs["Fac"])
    links.new(lighting.outputs[0], mix.inputs[1])
    links.new(seen.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], output.inputs["Surface"])
    scene = real_sync(core).scene
    direction = (0.3, -0.4, 0.5)
    assert scene.world_radiance(direction, camera=True) == pytest.approx((0.1, 0.2, 0.9), rel=1e-5)
    assert scene.world_radiance(direction, camera=False) == pytest.approx((1.0, 1.0, 1.0), rel=1e-5)


def test_constant_world_is_not_programmed_in_the_core(empty_scene, core):
    world_programs(core)
    uniform_world(empty_scene, (0.5, 0.5, 0.5), 1.0)
    scene = real_sync(core).scene
    assert not scene.world_programmed
    assert scene.world_map_info()["constant"]


def test_map_resolution_reaches_the_core(empty_scene, core):
    world_programs(core)
    world, _, _ = hdri_world(empty_scene)
    world.cycles.sampling_method = 'MANUAL'
    world.cycles.sample_map_resolution = 64
    info = real_sync(core).scene.world_map_info()
    assert (info["map_width"], info["map_height"]) == (64, 32)
    # Automatic: twice the Environment Texture's width (8), cells of half a texel (docs/world.md).
    world.cycles.sampling_method = 'AUTOMATIC'
    world.update_tag()                                    # (the UI tags the world; Python alone does not)
    info = real_sync(core).scene.world_map_info()
    assert info["map_width"] == 16


def test_portals_reach_the_core(empty_scene, core):
    world_programs(core)
    uniform_world(empty_scene)
    portal_light(empty_scene)
    sync = real_sync(core)
    assert sync.scene.portal_count == 1 and sync.scene.light_count == 0


def test_portal_at_the_open_front_matches_cycles(diffuse_scene, core, tmp_path):
    """The diffuse box lit by a uniform world through its open front, a portal filling the opening (light passing
    along +Y into the box): the same mean radiance as Cycles' render with the same portal, within 2.5 %."""
    world_programs(core)
    from test_translation_lights import compare

    bpy.data.objects.remove(bpy.data.objects["Light"])
    uniform_world(diffuse_scene, (0.4, 0.6, 1.0), 2.0)
    data = bpy.data.lights.new("Window", 'AREA')
    data.shape, data.size = 'SQUARE', 2.0
    data.cycles.is_portal = True
    portal = bpy.data.objects.new("Window", data)
    portal.location = (0.0, -1.0, 1.0)
    portal.rotation_euler = (math.radians(90.0), 0.0, 0.0)      # local -Z -> +Y: into the box
    diffuse_scene.collection.objects.link(portal)
    diffuse_scene.camera.location.y = -3.0
    sync = real_sync(core)
    assert sync.scene.portal_count == 1 and sync.lights == 0
    # (2.5 %: the same portal turned the other way, out of the box, renders 3 % darker.)
    assert abs(compare(diffuse_scene, tmp_path, "WORLD through a portal") - 1.0) < 0.025


def test_viewport_world_edits_render_in_place(empty_scene, core):
    """In the viewport's incremental path with the real core: a rotated mapping, then another image, change what the
    camera sees in the same core scene (no rebuild), and the image is added once."""
    world_programs(core)
    world, mapping, environment = hdri_world(empty_scene, image=equirect_image("Fine", 32, 16))
    environment.interpolation = 'Closest'
    sky_scene(empty_scene)
    empty_scene.render.resolution_x = empty_scene.render.resolution_y = 16
    empty_scene.render.resolution_percentage = 100
    props = empty_scene.photonsplat
    props.photons, props.iterations, props.time_limit, props.threads = 1000, 1, 0.0, 2
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())

    def render(scene):
        image, _ = core.render(scene, frame.camera, frame.settings)
        return np.asarray(image, dtype=np.float32)[..., :3]

    sync = export.BlenderSync(core)
    sync.sync(bpy.context.evaluated_depsgraph_get())
    scene = sync.scene
    first = render(scene)
    np.testing.assert_allclose(first, render(frame.scene), rtol=1e-6)
    textures = scene.texture_count if hasattr(scene, "texture_count") else None
    with DepsgraphUpdates(sync) as updates:
        mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(90.0))
        reports = updates.evaluate()
        assert any(r.world for r in reports) and not any(r.rebuilt for r in reports), reports
        assert sync.scene is scene
        rotated = render(scene)
        assert np.abs(rotated - first).max() > 0.1
        if textures is not None:
            assert scene.texture_count == textures

        environment.image = equirect_image("Other", 16, 8)
        reports = updates.evaluate()
        assert any(r.world for r in reports), reports
        other = render(sync.scene)
        assert np.abs(other - rotated).max() > 0.01


def test_hdri_file_reaches_the_core_as_blender_reads_it(empty_scene, core, tmp_path):
    """An OpenEXR file in the world (read by the core from its path where it can): the radiance is the texel Blender
    (and so Cycles) reads, in every Blender's naming of the linear colour space."""
    world_programs(core)
    image = bpy.data.images.new("File", 8, 4, float_buffer=True)
    pixels = np.full((4, 8, 4), 0.25, dtype=np.float32)
    pixels[..., 3] = 1.0
    image.pixels.foreach_set(pixels.reshape(-1))
    image.filepath_raw = str(tmp_path / "sky.exr")
    image.file_format = 'OPEN_EXR'
    image.save()
    bpy.data.images.remove(image)
    loaded = bpy.data.images.load(str(tmp_path / "sky.exr"))
    texels = np.empty(8 * 4 * 4, dtype=np.float32)
    loaded.pixels.foreach_get(texels)
    hdri_world(empty_scene, image=loaded)
    sync = real_sync(core)
    radiance = sync.scene.world_radiance((0.0, 0.0, 1.0), camera=True)
    print(f"\n{loaded.colorspace_settings.name}: Blender's texel {texels[:3]}, the core's {radiance}; {sync.notes}")
    assert not [n for n in sync.notes if n.startswith("World")], sync.notes
    assert radiance == pytest.approx(tuple(texels[:3]), rel=1e-4)


def test_gradient_over_the_direction_in_the_core(empty_scene, core):
    """A Gradient Texture on the unconnected (Generated) coordinates: the world's Generated is the direction."""
    world_programs(core)
    world, nodes, links, output = node_world(empty_scene)
    gradient = nodes.new("ShaderNodeTexGradient")                # linear: x, clamped to [0, 1]
    background = nodes.new("ShaderNodeBackground")
    background.inputs["Strength"].default_value = 2.0
    links.new(gradient.outputs["Color"], background.inputs["Color"])
    links.new(background.outputs[0], output.inputs["Surface"])
    scene = real_sync(core).scene
    assert scene.world_programmed
    assert scene.world_radiance((1.0, 0.0, 0.0)) == pytest.approx((2.0, 2.0, 2.0), rel=1e-5)
    assert scene.world_radiance((0.6, 0.8, 0.0)) == pytest.approx((1.2, 1.2, 1.2), rel=1e-5)
    assert scene.world_radiance((-1.0, 0.0, 0.0)) == pytest.approx((0.0, 0.0, 0.0), abs=1e-6)
