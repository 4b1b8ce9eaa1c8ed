"""Glossy materials from Python: add_material(kind="glossy", roughness=...) renders, bad roughness is refused."""
import math

import numpy as np
import pytest

import photonsplat as ps
from scenes import quad


def glossy_plane_scene(roughness, color=(0.9, 0.7, 0.5)):
    """A 40 m glossy plane at z = 0 under a point light at (0, 0, 1)."""
    scene = ps.Scene()
    index = scene.add_material(name="metal", kind="glossy", color=color, roughness=roughness)
    assert index == 0
    v, t = quad((-20, -20, 0), (20, -20, 0), (20, 20, 0), (-20, 20, 0))
    scene.add_mesh(name="plane", vertices=v, triangles=t)
    scene.add_point_light(name="lamp", position=(0, 0, 1), intensity=(50.0,) * 3)
    return scene


def test_glossy_plane_renders_a_highlight_at_the_mirror_point():
    # Seen from (-2, 0, 1), the light's mirror image (0, 0, -1) lies behind the point (-1, 0, 0) of the plane:
    # the camera looks straight at it, so the highlight is in the middle of the image.
    camera = ps.look_at_camera(eye=(-2, 0, 1), target=(-1, 0, 0), up=(0, 0, 1), width=33, height=33,
                               fov_y_degrees=30)
    image, _ = ps.render(glossy_plane_scene(0.2), camera, ps.RenderSettings(photons=2000))
    assert np.isfinite(image).all() and (image >= 0).all()
    luminance = image[..., :3] @ np.array([0.2126, 0.7152, 0.0722])
    y, x = np.unravel_index(np.argmax(luminance), luminance.shape)
    assert abs(y - 16) <= 1 and abs(x - 16) <= 1
    assert luminance[y, x] > 20 * luminance[0, 0]


def test_rougher_glossy_spreads_the_highlight():
    camera = ps.look_at_camera(eye=(-2, 0, 1), target=(-1, 0, 0), up=(0, 0, 1), width=17, height=17,
                               fov_y_degrees=30)
    sharp, _ = ps.render(glossy_plane_scene(0.15), camera, ps.RenderSettings(photons=1000))
    rough, _ = ps.render(glossy_plane_scene(0.6), camera, ps.RenderSettings(photons=1000))
    assert sharp[8, 8, 0] > 2 * rough[8, 8, 0]
    assert sharp[0, 8, 0] < rough[0, 8, 0]


def test_smooth_glossy_is_a_mirror():
    # At roughness <= 0.05 the plane is a perfect mirror: not a view sample, so no direct light on it at all.
    camera = ps.look_at_camera(eye=(-2, 0, 1), target=(-1, 0, 0), up=(0, 0, 1), width=9, height=9,
                               fov_y_degrees=30)
    _, _, passes = ps.render(glossy_plane_scene(0.05), camera, ps.RenderSettings(photons=1000), passes=True)
    assert passes["direct"].max() == 0.0


def test_default_roughness_is_accepted_for_every_kind():
    scene = ps.Scene()
    for kind in ("diffuse", "mirror", "glass", "glossy"):
        scene.add_material(name=kind, kind=kind)
    assert scene.material_count == 4


@pytest.mark.parametrize("roughness", [math.nan, -1.0, 2.0, math.inf])
def test_bad_roughness_is_refused_naming_it(roughness):
    with pytest.raises(ValueError, match="roughness"):
        ps.Scene().add_material(name="metal", kind="glossy", roughness=roughness)


@pytest.mark.parametrize("clear", [1.0, 0.5])
def test_a_glossy_surface_sees_a_light_through_a_transparent_sheet(clear):
    """A glossy floor (roughness 0.4) under an area light, with a transparent sheet between them: the sheet dims
    the direct light by its colour on the way from the light and again on the way to the camera, no more. Light
    sampling's shadow rays passed the sheet, but the BSDF's own directions stopped at it and lost their share of
    the multiple importance sampling (issue 18: the floor was 0.55 of the same without the sheet)."""
    def direct(sheet):
        scene = ps.Scene()
        scene.add_material(name="floor", kind="glossy", color=(0.5, 0.5, 0.5), roughness=0.4)
        scene.add_material(name="sheet", kind="closures", closures=[dict(kind="transparent", color=(clear,) * 3)])
        v, t = quad((-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0))
        scene.add_mesh(name="floor", vertices=v, triangles=t, material_ids=np.zeros(2, np.int32))
        if sheet:
            v, t = quad((-3, -3, 0.5), (3, -3, 0.5), (3, 3, 0.5), (-3, 3, 0.5))
            scene.add_mesh(name="sheet", vertices=v, triangles=t, material_ids=np.ones(2, np.int32))
        # It emits towards cross(u, v) = -z: down onto the floor.
        scene.add_area_light(name="lamp", center=(0.0, 0.0, 1.0), axis_u=(1.0, 0.0, 0.0), axis_v=(0.0, -1.0, 0.0),
                             radiance=(2.0, 2.0, 2.0))
        camera = ps.look_at_camera(eye=(0, -2, 3), target=(0, 0, 0), up=(0, 0, 1), width=16, height=16,
                                   fov_y_degrees=40)
        _, _, passes = ps.render(scene, camera, ps.RenderSettings(photons=1000, seed=2), passes=True)
        return passes["direct"][..., :3].astype(np.float64).mean()
    assert direct(True) / direct(False) == pytest.approx(clear * clear, rel=1e-3)


def test_multiscatter_light_samples_follow_the_cycles_version():
    """Scene.multiscatter_light_estimate: Cycles 3.x evaluates a Multiscatter GGX lobe towards a light sample with
    each bounce after the first tinted twice ('light_sample', the default), 4.x once as its sampled directions do
    ('walk'). Under a point light only the tinted channels' multiple scattering differs: the red channel of colour
    (1, 0.45, 0.15) keeps all of it either way, green and blue lose part of it towards a light sample (measured
    0.92 and 0.96 of the walk's direct light)."""
    def plane(estimate):
        scene = ps.Scene()
        if estimate is not None:
            scene.multiscatter_light_estimate = estimate
        scene.add_material(name="floor", kind="closures", closures=[dict(
            kind="reflection", distribution="multi_ggx", color=(1.0, 0.45, 0.15), specular_color=(1.0, 0.45, 0.15),
            alpha_x=0.58, alpha_y=0.58)])
        v, t = quad((-20, -20, 0), (20, -20, 0), (20, 20, 0), (-20, 20, 0))
        scene.add_mesh(name="plane", vertices=v, triangles=t)
        scene.add_point_light(name="lamp", position=(0, 0, 1), intensity=(50.0,) * 3)
        return scene
    assert ps.Scene().multiscatter_light_estimate == "light_sample"
    with pytest.raises(ValueError, match="multiscatter_light_estimate"):
        ps.Scene().multiscatter_light_estimate = "mf_eval"
    camera = ps.look_at_camera(eye=(-2, 0, 1), target=(-1, 0, 0), up=(0, 0, 1), width=9, height=9,
                               fov_y_degrees=30)
    settings = ps.RenderSettings(photons=1000, seed=3)
    direct = {}
    for estimate in (None, "light_sample", "walk"):
        _, _, passes = ps.render(plane(estimate), camera, settings, passes=True)
        direct[estimate] = passes["direct"].reshape(-1, 3).mean(0)
    assert np.array_equal(direct[None], direct["light_sample"])
    red, green, blue = direct["light_sample"] / direct["walk"]
    assert red == pytest.approx(1.0, abs=1e-6)
    assert green < 0.95 and blue < 0.98


def test_a_cycles3_multiscatter_mirror_keeps_little_of_the_lights_it_reflects():
    """A sharp reflection with reported_alpha is a Glossy of Multiscatter GGX at roughness 0.02 as Cycles 3.4 renders
    it: a mirror whose directions report the density of a clamped D (0.4 / cos θ at alpha 0.0004), so a light it
    reflects, met by a camera path or by photons on their way to a wall, weighs power_heuristic(that density, the
    light's) and is all but gone (measured: the lamp seen in the floor 5e-5 of a mirror's, the wall's caustic 0)."""
    def scene(reported_alpha):
        s = ps.Scene()
        s.add_material(name="floor", kind="closures", closures=[dict(
            kind="reflection", distribution="sharp", color=(0.9, 0.9, 0.9), reported_alpha=reported_alpha)])
        s.add_material(name="wall", color=(0.7, 0.7, 0.7))
        v, t = quad((-4, -4, 0), (4, -4, 0), (4, 4, 0), (-4, 4, 0))
        s.add_mesh(name="floor", vertices=v, triangles=t, material_ids=np.zeros(len(t), np.int32))
        v, t = quad((-4, 3, 0), (4, 3, 0), (4, 3, 3), (-4, 3, 3))
        s.add_mesh(name="wall", vertices=v, triangles=t, material_ids=np.ones(len(t), np.int32))
        # A small area light facing down at the floor, which reflects it to the camera and to the wall.
        s.add_area_light(name="lamp", center=(0, 0.5, 1.5), axis_u=(0.3, 0, 0), axis_v=(0, -0.3, 0),
                         radiance=(60.0,) * 3)
        return s
    camera = ps.look_at_camera(eye=(0, -3, 1.5), target=(0, 1.5, 0), up=(0, 0, 1), width=24, height=24,
                               fov_y_degrees=60)
    settings = ps.RenderSettings(photons=40000, iterations=4, seed=2)
    mirror, _, mirror_passes = ps.render(scene(0.0), camera, settings, passes=True)
    near, _, near_passes = ps.render(scene(0.0004), camera, settings, passes=True)
    # The lamp seen in the floor: Cycles' weight there is (0.4/cos)² against its density (a few hundred).
    seen = mirror_passes["emission"].sum()
    assert seen > 0.0 and near_passes["emission"].sum() < 0.01 * seen
    # The wall's caustic of the lamp (light -> floor -> wall) is gone too.
    assert near_passes["indirect"].sum() < 0.2 * mirror_passes["indirect"].sum()
    # The wall's direct light stays; the floor's own light samples add a dim glow of the lamp (near_mirror_light,
    # in the direct pass): measured 0.61 against the 243 a mirror shows of the lamp.
    glow = near_passes["direct"].sum() - mirror_passes["direct"].sum()
    assert 0.0 < glow < 0.01 * seen
