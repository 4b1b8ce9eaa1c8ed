"""The translation API the add-on (and the viewport) builds scenes with: meshes + instances, textures, spot and
round area lights. Bad input names its field (ValueError)."""
import math

import numpy as np
import pytest

import photonsplat as ps

QUAD_V = np.array([[-0.5, -0.5, 0], [0.5, -0.5, 0], [0.5, 0.5, 0], [-0.5, 0.5, 0]], np.float32)
QUAD_T = np.array([[0, 1, 2], [0, 2, 3]], np.int32)


def translate(x, y, z):
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def top_camera(size=16, height=10.0, extent=6.0):
    """Orthographic camera above the origin looking down, `extent` wide."""
    to_world = translate(0, 0, height)
    projection = np.diag([2.0 / extent, 2.0 / extent, -2.0 / 100.0, 1.0])
    projection[2, 3] = -1.0
    return ps.Camera(to_world=to_world, projection=projection, width=size, height=size)


def test_instances_share_one_mesh_and_move_without_rebuilding():
    scene = ps.Scene()
    scene.add_material(name="white", color=(0.8, 0.8, 0.8))
    mesh_id = scene.add_mesh_data("quad", QUAD_V, QUAD_T)
    ids = [scene.add_instance(mesh_id, translate(2.0 * i, 0, 0)) for i in range(1000)]
    assert ids == list(range(1000))
    assert (scene.mesh_count, scene.instance_count) == (1, 1000)
    assert (scene.stored_triangle_count, scene.triangle_count) == (2, 2000)
    scene.set_background((1.0, 1.0, 1.0))
    settings = ps.RenderSettings(photons=1000)
    image, _ = ps.render(scene, top_camera(), settings)
    covered = image[..., 0] < 0.95
    scene.set_instance_transform(ids[0], translate(0, 100, 0))             # out of the view
    moved, _ = ps.render(scene, top_camera(), settings)
    assert (moved[..., 0] < 0.95).sum() < covered.sum()
    with pytest.raises(ValueError, match="instance"):
        scene.set_instance_transform(5000, np.eye(4))
    with pytest.raises(ValueError, match="mesh"):
        scene.add_instance(7, np.eye(4))
    with pytest.raises(ValueError, match="transform"):
        scene.add_instance(mesh_id, np.full((4, 4), np.nan))


def test_add_mesh_still_places_one_instance():
    scene = ps.Scene()
    scene.add_material(name="white")
    scene.add_mesh(name="quad", vertices=QUAD_V, triangles=QUAD_T, transform=translate(1, 2, 3))
    assert (scene.mesh_count, scene.instance_count, scene.triangle_count) == (1, 1, 2)


def test_uvs_and_textures():
    scene = ps.Scene()
    red_green = np.zeros((1, 2, 3), np.float32)
    red_green[0, 0, 0] = red_green[0, 1, 1] = 1.0
    texture = scene.add_texture("rg", pixels=red_green, color_space="linear")
    scene.add_material(name="textured", texture=texture)
    uvs = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)
    scene.add_mesh(name="quad", vertices=QUAD_V * 6, triangles=QUAD_T, uvs=uvs)
    scene.set_background((1.0, 1.0, 1.0))
    image, _ = ps.render(scene, top_camera(), ps.RenderSettings(photons=1000))
    # Around the two texel centres (u = 0.25, 0.75); bilinear blending elsewhere (and across the repeat seam).
    left, right = image[6:10, 3:5, :3].mean(axis=(0, 1)), image[6:10, 11:13, :3].mean(axis=(0, 1))
    np.testing.assert_allclose(left, (1, 0, 0), atol=0.07)
    np.testing.assert_allclose(right, (0, 1, 0), atol=0.07)
    with pytest.raises(ValueError, match="uvs"):
        scene.add_mesh(name="bad", vertices=QUAD_V, triangles=QUAD_T, uvs=np.zeros((3, 2), np.float32))
    with pytest.raises(ValueError, match="path"):
        scene.add_texture("missing", path="/nonexistent/texture.png")
    with pytest.raises(ValueError, match="color_space"):
        scene.add_texture("odd", pixels=red_green, color_space="ACEScg")
    with pytest.raises(ValueError, match="texture"):
        scene.add_material(name="dangling", texture=9)


def test_spot_and_round_area_lights_validate_their_fields():
    scene = ps.Scene()
    scene.add_spot_light("spot", position=(0, 0, 2), direction=(0, 0, -1), intensity=(1, 1, 1),
                         spot_size=math.radians(45), spot_blend=0.2, radius=0.1)
    scene.add_area_light("disk", center=(0, 0, 2), axis_u=(1, 0, 0), axis_v=(0, 1, 0), radiance=(1, 1, 1),
                         shape="ellipse")
    assert scene.light_count == 2
    with pytest.raises(ValueError, match="spot_size"):
        scene.add_spot_light("bad", position=(0, 0, 2), direction=(0, 0, -1), intensity=(1, 1, 1), spot_size=0.0)
    with pytest.raises(ValueError, match="spot_blend"):
        scene.add_spot_light("bad", position=(0, 0, 2), direction=(0, 0, -1), intensity=(1, 1, 1),
                             spot_size=1.0, spot_blend=1.5)
    with pytest.raises(ValueError, match="shape"):
        scene.add_area_light("bad", center=(0, 0, 2), axis_u=(1, 0, 0), axis_v=(0, 1, 0), radiance=(1, 1, 1),
                             shape="star")


def test_clear_lights_then_new_lights_render_as_a_fresh_scene():
    """What the viewport does when a light moves: the meshes (and their BVH) stay, the lights are replaced."""
    def quad_scene():
        scene = ps.Scene()
        scene.add_material(name="white", color=(0.8, 0.8, 0.8))
        scene.add_instance(scene.add_mesh_data("quad", QUAD_V * 8, QUAD_T), np.eye(4))
        return scene

    settings = ps.RenderSettings(photons=2000, seed=5, threads=1)
    kept = quad_scene()
    kept.add_point_light(name="lamp", position=(1.0, 0.0, 2.0), intensity=(10.0, 10.0, 10.0))
    ps.render(kept, top_camera(), settings)                          # builds the BVH
    kept.clear_lights()
    assert (kept.light_count, kept.mesh_count, kept.instance_count) == (0, 1, 1)
    kept.add_point_light(name="lamp", position=(-1.0, 0.0, 2.0), intensity=(10.0, 10.0, 10.0))
    fresh = quad_scene()
    fresh.add_point_light(name="lamp", position=(-1.0, 0.0, 2.0), intensity=(10.0, 10.0, 10.0))
    image, _ = ps.render(kept, top_camera(), settings)
    expected, _ = ps.render(fresh, top_camera(), settings)
    assert image[..., :3].mean() > 0.01
    np.testing.assert_array_equal(image, expected)


@pytest.mark.parametrize("zero_normal", [False, True])
def test_vertex_normals_shade_as_their_corner_expansion(zero_normal):
    """Normals given per vertex are kept per vertex (a third of the memory of corner normals, issue 19) and shade
    exactly as the same normals given at every corner: the images are bit-identical at the same seed. A zero
    vertex normal (each corner then falls back to its triangle's normal) keeps corner normals."""
    from scenes import cornell_box, cornell_camera, uv_sphere
    v, t, n = uv_sphere(0.35)
    if zero_normal:
        n = n.copy()
        n[40] = 0.0
    images = []
    for normals in (n, np.ascontiguousarray(n[t])):
        scene = cornell_box()
        clay = scene.add_material(name="clay", color=(0.6, 0.45, 0.35))
        scene.add_mesh(name="smooth", vertices=v, triangles=t, normals=normals,
                       material_ids=np.full(len(t), clay, np.int32), transform=translate(0.4, 0.3, 0.5))
        image, _ = ps.render(scene, cornell_camera(32, 32), ps.RenderSettings(photons=2000, seed=3))
        images.append(image)
    assert np.array_equal(images[0], images[1])


def test_bvhs_built_ahead_render_the_same_bits():
    """Scene.build_bvhs_ahead (issue 19: each mesh's BVH built on a thread while the caller adds the next) gives the
    same image at the same seed as BVHs built by the render; a scene dropped while its builds run is safe. Only
    meshes of 262,144 triangles or more are built ahead (smaller ones shown once are placed in render space)."""
    from scenes import cornell_box, cornell_camera, uv_sphere
    v, t, n = uv_sphere(0.3, rings=192, segments=768)
    assert len(t) >= 262144
    images = []
    for ahead in (False, True):
        scene = cornell_box()
        scene.build_bvhs_ahead = ahead
        assert scene.build_bvhs_ahead == ahead
        clay = scene.add_material(name="clay", color=(0.6, 0.45, 0.35))
        mesh_id = scene.add_mesh_data("smooth", v, t, normals=n, material_ids=np.full(len(t), clay, np.int32))
        for i in range(3):
            scene.add_instance(mesh_id, translate(-0.5 + 0.5 * i, 0.3, 0.4))
        image, _ = ps.render(scene, cornell_camera(32, 32), ps.RenderSettings(photons=2000, seed=5))
        images.append(image)
    assert np.array_equal(images[0], images[1])
    for _ in range(3):
        scene = ps.Scene()
        scene.build_bvhs_ahead = True
        scene.add_material(name="white")
        for i in range(4):
            scene.add_mesh_data(f"m{i}", v, t)
        del scene
