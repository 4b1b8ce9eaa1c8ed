"""Scene translation with the real core: textures, instancing, every object type that becomes a mesh, camera
framing against Cycles, holdout / hidden objects, and notes for what is approximated.

Images are tiny (16-64 pixels).
"""

import math

import bpy
import numpy as np
import pytest

from blender_helpers import enable_nodes, render_pixels, uniform_world, use_photonsplat
from photonsplat import compat, engine, export


def add_camera(scene, location=(0.0, 0.0, 10.0), rotation=(0.0, 0.0, 0.0), ortho_scale=None):
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.location, cam.rotation_euler = location, rotation
    if ortho_scale is not None:
        cam.data.type, cam.data.ortho_scale = 'ORTHO', ortho_scale
    scene.collection.objects.link(cam)
    scene.camera = cam
    return cam


def material(name, shader="ShaderNodeBsdfDiffuse"):
    mat = bpy.data.materials.new(name)
    enable_nodes(mat)
    tree = mat.node_tree
    tree.nodes.clear()
    node = tree.nodes.new(shader)
    tree.links.new(node.outputs[0], tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    return mat, node


def export_with_core(core):
    return export.export_frame(core, bpy.context.evaluated_depsgraph_get())


# --- textures --------------------------------------------------------------------------------------------------

def two_colour_image(name, left, right, size=8):
    """An image whose left half is `left` and right half `right` (RGB, as stored)."""
    image = bpy.data.images.new(name, size, size)
    pixels = np.zeros((size, size, 4), dtype=np.float32)
    pixels[:, : size // 2, :3] = left
    pixels[:, size // 2:, :3] = right
    pixels[..., 3] = 1.0
    image.pixels.foreach_set(pixels.ravel())
    return image


@pytest.mark.parametrize("source", ["file", "file-without-oiio", "pixels"])
def test_texture_colour_lands_in_the_image(source, empty_scene, tmp_path, core, monkeypatch):
    """A plane textured half red, half (sRGB 0.5) grey under a white world of radiance 1 shows its albedo: the
    left half renders red, the right half the grey decoded from sRGB (0.214), through the file (OpenImageIO) or
    through Blender's pixels: of a generated image, or of the file's image when the core reads no files (the
    extension's module, IMAGE_FILES False; test_extension.py renders this with the real one)."""
    if source == "file-without-oiio":
        monkeypatch.setattr(export.textures, "core_reads_image_files", lambda: False)
    image = two_colour_image("Halves", (1.0, 0.0, 0.0), (0.5, 0.5, 0.5))
    if source.startswith("file"):
        image.filepath_raw = str(tmp_path / "halves.png")
        image.file_format = 'PNG'
        image.save()
        image = bpy.data.images.load(str(tmp_path / "halves.png"))
    assert image.colorspace_settings.name == "sRGB"
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    plane = bpy.context.active_object
    mat, shader = material("Textured")
    texture = mat.node_tree.nodes.new("ShaderNodeTexImage")
    texture.image = image
    mat.node_tree.links.new(texture.outputs["Color"], shader.inputs["Color"])
    plane.data.materials.append(mat)
    add_camera(empty_scene, ortho_scale=2.0)
    uniform_world(empty_scene)
    use_photonsplat(empty_scene, 16, 1000)
    pixels = render_pixels(tmp_path / "textured.exr")
    assert engine.last_outcome.status == "finished", engine.last_outcome.message
    assert not engine.last_outcome.warnings
    left, right = pixels[4:12, 1:6, :3].mean(axis=(0, 1)), pixels[4:12, 10:15, :3].mean(axis=(0, 1))
    grey = ((0.5 + 0.055) / 1.055) ** 2.4
    print(f"\n{source}: left {np.round(left, 4)}, right {np.round(right, 4)} (expected 1,0,0 and {grey:.4f})")
    np.testing.assert_allclose(left, (1.0, 0.0, 0.0), atol=0.04)
    np.testing.assert_allclose(right, (grey,) * 3, rtol=0.05)


def test_nodes_behind_inputs_are_compiled_and_unsupported_ones_noted(empty_scene, tmp_path, core):
    """A Noise Texture and a Mapping node in front of an image are compiled into the material's program (no note);
    a node the core cannot evaluate (Ambient Occlusion) is named in the render report with its fallback."""
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    plane = bpy.context.active_object
    mat, shader = material("Noisy", "ShaderNodeBsdfPrincipled")
    noise = mat.node_tree.nodes.new("ShaderNodeTexNoise")
    mat.node_tree.links.new(noise.outputs["Color"], shader.inputs["Base Color"])
    plane.data.materials.append(mat)
    mapped, diffuse = material("Mapped")
    texture = mapped.node_tree.nodes.new("ShaderNodeTexImage")
    texture.image = two_colour_image("Mapped", (1, 1, 1), (0, 0, 0))
    mapping = mapped.node_tree.nodes.new("ShaderNodeMapping")
    mapped.node_tree.links.new(mapping.outputs[0], texture.inputs["Vector"])
    mapped.node_tree.links.new(texture.outputs["Color"], diffuse.inputs["Color"])
    plane.data.materials.append(mapped)
    plane.data.polygons[0].material_index = 0
    bpy.ops.mesh.primitive_cube_add(location=(0, 0, -2))
    occluded, occluded_diffuse = material("Occluded")
    ao = occluded.node_tree.nodes.new("ShaderNodeAmbientOcclusion")
    occluded.node_tree.links.new(ao.outputs["Color"], occluded_diffuse.inputs["Color"])
    bpy.context.active_object.data.materials.append(mapped)
    bpy.context.active_object.data.materials.append(occluded)
    bpy.context.active_object.data.polygons[0].material_index = 1
    add_camera(empty_scene, ortho_scale=2.0)
    uniform_world(empty_scene)
    use_photonsplat(empty_scene, 16, 1000)
    render_pixels(tmp_path / "noted.exr")
    warnings = engine.last_outcome.warnings
    print("\n" + "\n".join(warnings))
    assert not any(w.startswith("Material 'Noisy'") for w in warnings)
    assert not any(w.startswith("Material 'Mapped'") for w in warnings)
    assert any(w.startswith("Material 'Occluded'") and "Ambient Occlusion" in w for w in warnings)


# --- instancing ----------------------------------------------------------------------------------------------

def points_grid_with_instances(count_x, count_y):
    """A grid of count_x × count_y points, each instancing one ico sphere through geometry nodes."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=count_x - 1, y_subdivisions=count_y - 1, size=20.0)
    grid = bpy.context.active_object
    tree = bpy.data.node_groups.new("Scatter", "GeometryNodeTree")
    compat.new_group_socket(tree, 'INPUT', "NodeSocketGeometry", "Geometry")
    compat.new_group_socket(tree, 'OUTPUT', "NodeSocketGeometry", "Geometry")
    group_in, group_out = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
    on_points = tree.nodes.new("GeometryNodeInstanceOnPoints")
    sphere = tree.nodes.new("GeometryNodeMeshIcoSphere")
    sphere.inputs["Radius"].default_value = 0.2
    sphere.inputs["Subdivisions"].default_value = 3
    tree.links.new(group_in.outputs[0], on_points.inputs["Points"])
    tree.links.new(sphere.outputs[0], on_points.inputs["Instance"])
    tree.links.new(on_points.outputs[0], group_out.inputs[0])
    grid.modifiers.new("Scatter", 'NODES').node_group = tree
    return grid


def test_thousand_instances_are_one_mesh(empty_scene, tmp_path, core):
    points_grid_with_instances(25, 40)
    add_camera(empty_scene, location=(0.0, 0.0, 30.0))
    uniform_world(empty_scene)
    frame = export_with_core(core)
    scene = frame.scene
    per_sphere = 320                                          # ico sphere, 3 subdivisions
    print(f"\n1000 instances: {scene.mesh_count} mesh, {scene.instance_count} instances, "
          f"{scene.stored_triangle_count} triangles stored for {scene.triangle_count} in the world, "
          f"{scene.scene_bytes} bytes")
    assert (frame.meshes, frame.instances) == (1, 1000)
    assert (scene.mesh_count, scene.instance_count) == (1, 1000)
    assert scene.stored_triangle_count == per_sphere
    assert scene.triangle_count == 1000 * per_sphere
    # One sphere's arrays plus one transform (and a name) per instance; realized geometry would take ~ 60 MB.
    assert scene.scene_bytes < 400_000
    assert sorted(sum(frame.object_instances.values(), [])) == list(range(1000))

    use_photonsplat(empty_scene, 24, 2000)
    pixels = render_pixels(tmp_path / "instances.exr")
    assert engine.last_outcome.status == "finished", engine.last_outcome.message
    # Spheres (albedo 0.8, partly shadowed by their neighbours) and the white sky (radiance 1) between them.
    on_spheres = pixels[..., :3].mean(axis=2) < 0.95
    assert 0.05 < on_spheres.mean() < 0.95 and np.isfinite(pixels).all()


# --- object types ---------------------------------------------------------------------------------------------

def _curve():
    bpy.ops.curve.primitive_bezier_circle_add(radius=1.5)
    bpy.context.active_object.data.bevel_depth = 0.3


def _text():
    bpy.ops.object.text_add(location=(-2.0, -0.5, 0.0))
    bpy.context.active_object.data.extrude = 0.1
    bpy.context.active_object.data.size = 2.0


def _metaball():
    bpy.ops.object.metaball_add(radius=1.5)


def _surface():
    bpy.ops.surface.primitive_nurbs_surface_sphere_add(radius=1.5)


def _geometry_nodes():
    points_grid_with_instances(3, 3).scale = (0.2, 0.2, 0.2)
    bpy.data.node_groups["Scatter"].nodes["Ico Sphere"].inputs["Radius"].default_value = 3.0


def _particles():
    """Particle hair rendered as a text object: the depsgraph lists only the text object for these."""
    bpy.ops.object.text_add(location=(50.0, 0.0, 0.0))
    text = bpy.context.active_object
    bpy.ops.mesh.primitive_plane_add(size=3.0)
    emitter = bpy.context.active_object
    system = emitter.modifiers.new("Hair", 'PARTICLE_SYSTEM').particle_system
    system.settings.type, system.settings.count = 'HAIR', 20
    system.settings.render_type, system.settings.instance_object = 'OBJECT', text
    system.settings.particle_size = 1.0
    # Only the particle copies show (the tests export the viewport depsgraph, hence the viewport switches).
    text.hide_viewport = text.hide_render = True
    emitter.show_instancer_for_viewport = emitter.show_instancer_for_render = False


def _collection():
    group = bpy.data.collections.new("Group")
    bpy.ops.object.text_add(location=(-2.0, -0.5, 0.0))
    text = bpy.context.active_object
    text.data.size = 2.0
    for collection in text.users_collection:
        collection.objects.unlink(text)
    group.objects.link(text)
    empty = bpy.data.objects.new("Instancer", None)
    empty.instance_type, empty.instance_collection = 'COLLECTION', group
    bpy.context.scene.collection.objects.link(empty)


@pytest.mark.parametrize("make, instances", [(_curve, 1), (_text, 1), (_metaball, 1), (_surface, 1),
                                              (_geometry_nodes, 9), (_particles, 20), (_collection, 1)],
                         ids=["curve", "text", "metaball", "surface", "geometry_nodes", "particles", "collection"])
def test_every_object_type_renders(make, instances, empty_scene, tmp_path, core):
    """Each kind of object that evaluates to a mesh is exported once per instance (never twice) and is seen."""
    make()
    # Seen along (-1, 1, -1): flat things (text) show whichever axis-aligned way their instances turn them.
    add_camera(empty_scene, location=(6.0, -6.0, 6.0), rotation=(math.radians(54.7356), 0.0, math.radians(45.0)),
               ortho_scale=8.0)
    uniform_world(empty_scene)
    frame = export_with_core(core)
    assert frame.instances == instances and frame.triangles > 0, (frame.instances, frame.triangles)
    use_photonsplat(empty_scene, 48, 1000)                  # enough pixels to catch a text's strokes
    pixels = render_pixels(tmp_path / "object.exr")
    assert engine.last_outcome.status == "finished", engine.last_outcome.message
    # The object (albedo 0.8, lit by the white sky) against the sky itself (radiance 1).
    assert (pixels[..., :3].mean(axis=2) < 0.95).sum() >= 20 and np.isfinite(pixels).all()


# --- visibility --------------------------------------------------------------------------------------------------

def test_hidden_camera_invisible_and_holdout_objects(empty_scene, tmp_path, core):
    """hide_render: gone. visible_camera off: unseen but still shadows. Holdout: black where seen (its alpha 0
    is in the core's view samples, tests/native/test_translation.cpp; the final image is opaque unless Film >
    Transparent is on)."""
    add_camera(empty_scene, ortho_scale=4.0)
    bpy.ops.mesh.primitive_plane_add(size=10.0)                                  # the floor, lit by a sun
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", 'SUN'))
    sun.data.energy, sun.data.angle = 3.0, 0.0
    empty_scene.collection.objects.link(sun)
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(-1.0, 1.0, 1.0))       # hidden from the camera
    bpy.context.active_object.visible_camera = False
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(1.0, 1.0, 1.0))        # hidden from rendering
    bpy.context.active_object.hide_render = bpy.context.active_object.hide_viewport = True
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0.0, -1.0, 1.0))       # holdout
    bpy.context.active_object.is_holdout = True
    use_photonsplat(empty_scene, 16, 1000)
    pixels = render_pixels(tmp_path / "visibility.exr")
    luminance = pixels[..., :3].mean(axis=2)
    lit = luminance[1:3, 1:3].mean()                                             # an open corner of the floor
    shadow_of_invisible = luminance[10:14, 2:6].mean()                           # rows count from the bottom
    under_hidden = luminance[10:14, 10:14].mean()
    print(f"\nlit {lit:.3f}, shadow of camera-invisible {shadow_of_invisible:.3f}, under hide_render "
          f"{under_hidden:.3f}, holdout {pixels[2:6, 6:10, :3].max():.3f}")
    assert lit > 0.5
    assert shadow_of_invisible < 0.1 * lit
    assert under_hidden == pytest.approx(lit, rel=0.05)
    assert pixels[2:6, 6:10, :3].max() == 0.0
    assert luminance[7, 4:12].mean() > 0.5 * lit                                # next to it: the lit floor


# --- camera -------------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("kind, fit, clip_end", [("PERSP", 'VERTICAL', 100.0), ("PERSP", 'AUTO', 100.0),
                                                 ("ORTHO", 'HORIZONTAL', 100.0), ("PERSP", 'AUTO', 5.0)])
def test_camera_framing_matches_cycles(kind, fit, clip_end, empty_scene, tmp_path, core):
    """An emissive square seen through a shifted camera with a sensor fit lands on the same pixels as in
    Cycles; a clip end before it hides it in both."""
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0.7, -0.4, 0.0))
    glow, node = material("Glow", "ShaderNodeEmission")
    bpy.context.active_object.data.materials.append(glow)
    cam = add_camera(empty_scene, location=(0.0, 0.0, 8.0))
    cam.data.type, cam.data.ortho_scale, cam.data.sensor_fit = kind, 5.0, fit
    cam.data.shift_x, cam.data.shift_y, cam.data.clip_end = 0.12, -0.08, clip_end
    empty_scene.render.resolution_x, empty_scene.render.resolution_y = 48, 32
    empty_scene.render.resolution_percentage = 100
    empty_scene.render.engine = 'CYCLES'
    empty_scene.cycles.samples = 16
    empty_scene.cycles.use_denoising = False
    empty_scene.cycles.pixel_filter_type = 'BOX'                     # no pixel filter: same coverage as ours
    empty_scene.cycles.filter_width = 0.01
    reference = render_pixels(tmp_path / "cycles.exr")[..., 0] > 0.5
    use_photonsplat(empty_scene, 48, 1000)
    empty_scene.render.resolution_y = 32
    ours = render_pixels(tmp_path / "ours.exr")[..., 0] > 0.5
    assert ours.shape == reference.shape == (32, 48)
    if clip_end < 8.0:
        assert not reference.any() and not ours.any()
        return
    assert reference.sum() > 4
    overlap = (reference & ours).sum() / (reference | ours).sum()
    centre = lambda mask: np.argwhere(mask).mean(axis=0)
    print(f"\n{kind} {fit}: {reference.sum()} pixels in Cycles, {ours.sum()} ours, overlap {overlap:.3f}")
    assert overlap > 0.85
    np.testing.assert_allclose(centre(ours), centre(reference), atol=0.5)
