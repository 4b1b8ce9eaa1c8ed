"""Every bad input raises a clear ValueError naming the field; nothing crashes, nothing is silently wrong."""
import os

import numpy as np
import pytest

import photonsplat as ps
from scenes import cornell_box, cornell_camera, quad

V, T = quad((0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0))


def scene_with_material():
    scene = ps.Scene()
    scene.add_material(name="m")
    return scene


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(vertices=V[:, :2], triangles=T), "vertices"),
        (dict(vertices=V.reshape(-1), triangles=T), "vertices"),
        (dict(vertices=V, triangles=T[:, :2]), "triangles"),
        (dict(vertices=V.astype(str), triangles=T), "vertices"),
        (dict(vertices=V, triangles=T.astype(np.float32)), "triangles"),
        (dict(vertices=np.where(np.arange(12).reshape(4, 3) == 4, np.nan, V), triangles=T), "vertices"),
        (dict(vertices=np.where(np.arange(12).reshape(4, 3) == 4, np.inf, V), triangles=T), "vertices"),
        (dict(vertices=V, triangles=T + 2), "triangles"),
        (dict(vertices=V, triangles=-T - 1), "triangles"),
        (dict(vertices=V, triangles=T.astype(np.int64) + 2**33), "triangles"),
        (dict(vertices=V, triangles=T, material_ids=np.array([0, 5], np.int32)), "material_ids"),
        (dict(vertices=V, triangles=T, material_ids=np.array([0, -1], np.int32)), "material_ids"),
        (dict(vertices=V, triangles=T, material_ids=np.zeros(3, np.int32)), "material_ids"),
        (dict(vertices=V, triangles=T, normals=np.ones((3, 3), np.float32)), "normals"),
        (dict(vertices=V, triangles=T, normals=np.full((4, 3), np.nan, np.float32)), "normals"),
        (dict(vertices=V, triangles=T, transform=np.identity(3)), "transform"),
        (dict(vertices=V, triangles=T, transform=np.full((4, 4), np.nan)), "transform"),
    ],
)
def test_bad_mesh_arrays_name_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        scene_with_material().add_mesh(name="Cube", **kwargs)


def test_mesh_error_names_the_object():
    with pytest.raises(ValueError, match="Cube"):
        scene_with_material().add_mesh(name="Cube", vertices=V, triangles=T + 9)


def test_mesh_without_any_material_is_refused():
    with pytest.raises(ValueError, match="material"):
        ps.Scene().add_mesh(name="Cube", vertices=V, triangles=T)


def test_degenerate_triangles_are_dropped_and_counted():
    scene = scene_with_material()
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], np.float32)  # 0,1,2 collinear
    t = np.array([[0, 1, 2], [0, 1, 3], [0, 0, 3]], np.int32)
    scene.add_mesh(name="m", vertices=v, triangles=t)
    assert scene.triangle_count == 1
    assert scene.dropped_triangles == 2


def test_empty_mesh_is_accepted():
    scene = scene_with_material()
    scene.add_mesh(name="empty", vertices=np.zeros((0, 3), np.float32), triangles=np.zeros((0, 3), np.int32))
    assert scene.triangle_count == 0


@pytest.mark.parametrize(
    "call, field",
    [
        (lambda s: s.add_material(name="m", kind="velvet"), "kind"),
        (lambda s: s.add_material(name="m", color=(1, 2, 0)), "color"),
        (lambda s: s.add_material(name="m", color=(1, 0)), "color"),
        (lambda s: s.add_material(name="m", color=(np.nan, 0, 0)), "color"),
        (lambda s: s.add_material(name="m", emission=(-1, 0, 0)), "emission"),
        (lambda s: s.add_material(name="m", kind="glass", ior=0.0), "ior"),
        (lambda s: s.add_point_light(name="L", position=(0, 0, np.nan), intensity=(1, 1, 1)), "position"),
        (lambda s: s.add_point_light(name="L", position=(0, 0, 1), intensity=(-1, 1, 1)), "value|intensity"),
        (lambda s: s.add_point_light(name="L", position=(0, 0, 1), intensity=(1, 1, 1), radius=-1), "radius"),
        (lambda s: s.add_sun_light(name="S", direction=(0, 0, 0), irradiance=(1, 1, 1)), "direction"),
        (lambda s: s.add_sun_light(name="S", direction=(0, 0, -1), irradiance=(1, 1, 1), angle=4.0), "angle"),
        (lambda s: s.add_area_light(name="A", center=(0, 0, 1), axis_u=(1, 0, 0), axis_v=(2, 0, 0),
                                    radiance=(1, 1, 1)), "axis"),
        (lambda s: s.set_background((np.inf, 0, 0)), "background"),
        # Closures (kind="closures"): every key is checked and named.
        (lambda s: s.add_material(name="m", kind="closures", closures=[dict(kind="toon")]), r"closures\[0\]"),
        (lambda s: s.add_material(name="m", kind="closures", closures=[dict(color=(1, 1, 1))]), r"closures\[0\]\.kind"),
        (lambda s: s.add_material(name="m", kind="closures", closures=[dict(kind="diffuse", colour=(1, 1, 1))]),
         "unknown key 'colour'"),
        (lambda s: s.add_material(name="m", kind="closures", closures=[dict(kind="diffuse", color=(np.nan, 0, 0))]),
         r"closures\[0\]\.color"),
        (lambda s: s.add_material(name="m", kind="closures",
                                  closures=[dict(kind="reflection", alpha_x=2.0, alpha_y=0.1)]), "alpha"),
        (lambda s: s.add_material(name="m", kind="closures",
                                  closures=[dict(kind="refraction", ior=0.0)]), "ior"),
        (lambda s: s.add_material(name="m", kind="closures", closures=[dict(
            kind="reflection", distribution="sharp", reported_alpha=np.nan)]), r"closures\[0\]\.reported_alpha"),
        (lambda s: s.add_material(name="m", kind="closures", closures=[dict(
            kind="reflection", distribution="ggx", alpha_x=0.1, alpha_y=0.1, reported_alpha=0.01)]),
         "sharp reflection only"),
        (lambda s: s.add_material(name="m", kind="closures",
                                  closures=[dict(kind="diffuse", factors_on=[1])], factors=[dict(kind="fresnel")]),
         "factor"),
        (lambda s: s.add_material(name="m", kind="closures", closures=[dict(kind="diffuse", factors_on=[40])]),
         "factors_on"),
        (lambda s: s.add_material(name="m", kind="closures", closures=[],
                                  factors=[dict(kind="fresnel", value=-1.0)]), r"factors\[0\]"),
        (lambda s: s.add_material(name="m", kind="closures",
                                  closures=[dict(kind="velvet", roughness=0.5)] * 9), "closures"),
        (lambda s: s.add_material(name="m", kind="closures", closures=[dict(kind="diffuse")] * 17), "closures"),
        (lambda s: s.add_material(name="m", kind="diffuse", closures=[dict(kind="diffuse")]), "closures"),
        (lambda s: s.add_material(name="m", kind="closures", closures=[dict(kind="diffuse", texture=3)]), "texture"),
    ],
)
def test_bad_materials_lights_background_name_the_field(call, field):
    with pytest.raises(ValueError, match=field):
        call(ps.Scene())


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(photons=-1), "photons"),
        (dict(radius=-0.5), "radius"),
        (dict(radius=float("nan")), "radius"),
        (dict(radius=float("inf")), "radius"),
        (dict(method="fastest"), "method"),
        (dict(max_bounces=-1), "max_bounces"),
        (dict(threads=-2), "threads"),
        (dict(direct_samples=0), "direct_samples"),
        (dict(normal_tolerance=0.0), "normal_tolerance"),
        (dict(photons=10**12), "photons"),
    ],
)
def test_bad_settings_name_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        ps.RenderSettings(**kwargs)


def test_settings_changed_after_construction_are_checked_as_they_are_set_and_at_render():
    settings = ps.RenderSettings()
    with pytest.raises(ValueError, match="radius"):
        settings.radius = -1.0
    assert settings.radius == 0.0  # a refused value is not kept
    with pytest.raises(ValueError, match="method"):
        settings.method = "nope"
    settings.iterations = 0  # valid alone; with no time_limit the render would never end
    with pytest.raises(ValueError, match="iterations"):
        ps.render(cornell_box(), cornell_camera(4, 4), settings)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(width=0), "width"),
        (dict(width=-5), "width"),
        (dict(height=2.5), "height"),
        (dict(to_world=np.zeros((4, 4))), "to_world"),
        (dict(to_world=np.full((4, 4), np.nan)), "to_world"),
        (dict(projection=np.identity(3)), "projection"),
        (dict(projection=np.zeros((4, 4))), "projection"),
    ],
)
def test_bad_cameras_name_the_field(kwargs, field):
    good = cornell_camera(8, 8)
    args = dict(to_world=np.identity(4), projection=np.array([[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1.002, -0.2002],
                                                                [0, 0, -1, 0]]), width=good.width, height=good.height)
    args.update(kwargs)
    with pytest.raises(ValueError, match=field):
        ps.Camera(**args)


def test_progress_must_be_callable():
    with pytest.raises(ValueError, match="progress"):
        ps.render(cornell_box(), cornell_camera(4, 4), ps.RenderSettings(), progress=42)


def test_extreme_but_valid_settings_give_finite_images():
    scene, camera = cornell_box(), cornell_camera(8, 8)
    for settings in (ps.RenderSettings(photons=0), ps.RenderSettings(photons=1), ps.RenderSettings(radius=1e-9),
                     ps.RenderSettings(radius=1e3, photons=2000), ps.RenderSettings(max_bounces=0)):
        image, _ = ps.render(scene, camera, settings)
        assert np.isfinite(image).all(), settings


def test_resolution_beyond_memory_is_refused_before_allocating():
    camera = ps.look_at_camera(eye=(0, -3.9, 1), target=(0, 0, 1), width=65536, height=65536)
    with pytest.raises(ValueError, match="resolution"):
        ps.render(cornell_box(), camera, ps.RenderSettings(photons=1000))


def test_photon_count_beyond_memory_is_refused_before_allocating():
    memory = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    photons = int(memory / 56)  # a photon record is 56 bytes: this much would fill all of memory
    if photons > 500_000_000:
        pytest.skip("this machine has more memory than the largest photon count the settings allow")
    with pytest.raises(ValueError, match="photons"):
        ps.render(cornell_box(), cornell_camera(4, 4), ps.RenderSettings(photons=photons))
