"""The light options of Blender 4.x/5.x Cycles through the Python API: add_point_light(sphere=...) and
add_spot_light(sphere=..., spot_cosine=...) reach the core and change what a near plane receives, as the closed
forms say. (The core's own checks: tests/native/test_cycles4_lights.cpp; the path tracer's:
test_reference.py::test_sphere_and_disc_lights_near_a_lambert_plane.) Under a second."""
import math

import numpy as np
import pytest

import photonsplat as ps
import scenes

SIZE, EXTENT, HEIGHT = 16, 2.0, 1.0


def direct_light(add_light):
    """The direct pass of a Lambert plane z = 0 under the light add_light(scene) adds, seen from above by an
    orthographic camera EXTENT wide (the pixel centres are the receivers)."""
    scene = ps.Scene()
    scene.add_material(name="plane", color=(0.8, 0.8, 0.8))
    v, t = scenes.quad((-20, -20, 0), (20, -20, 0), (20, 20, 0), (-20, 20, 0))
    scene.add_mesh(name="plane", vertices=v, triangles=t)
    add_light(scene)
    to_world = np.eye(4)
    to_world[2, 3] = 10.0
    projection = np.diag([2.0 / EXTENT, 2.0 / EXTENT, -2.0 / 100.0, 1.0])
    projection[2, 3] = -1.0
    camera = ps.Camera(to_world=to_world, projection=projection, width=SIZE, height=SIZE)
    settings = ps.RenderSettings(photons=1000, seed=1, direct_samples=1024)
    _, _, passes = ps.render(scene, camera, settings, passes=True)
    return passes["direct"][..., 0]


def squared_distance_to_light():
    """d^2 from each pixel's receiver to a light at HEIGHT above the origin (symmetric, so row order is moot)."""
    c = (np.arange(SIZE) + 0.5) / SIZE * EXTENT - EXTENT / 2
    x, y = np.meshgrid(c, c)
    return x ** 2 + y ** 2 + HEIGHT ** 2


def test_sphere_keyword_makes_a_near_point_light_a_sphere():
    """Radius 0.5 at height 1 (d = 2R below it): the sphere gives the point law I cos / d^2, the disc
    I cos / (d^2 + R^2), so sphere / disc = 1 + R^2 / d^2, 1.25 right below the light."""
    radius = 0.5

    def lamp(sphere):
        return lambda s: s.add_point_light("lamp", position=(0, 0, HEIGHT), intensity=(10, 10, 10), radius=radius,
                                           sphere=sphere)

    disc, default = direct_light(lamp(False)), direct_light(
        lambda s: s.add_point_light("lamp", position=(0, 0, HEIGHT), intensity=(10, 10, 10), radius=radius))
    assert np.array_equal(disc, default)                       # sphere=False is the default: Cycles 3.4
    ratio = direct_light(lamp(True)) / disc
    d2 = squared_distance_to_light()
    expected = (d2 + radius ** 2) / d2
    print(f"\nsphere / disc: {ratio.min():.4f}..{ratio.max():.4f}, analytic {expected.min():.4f}..{expected.max():.4f}")
    assert np.abs(ratio / expected - 1.0).max() < 0.01
    assert ratio.max() > 1.2


def test_spot_keywords_drop_the_cosine_and_make_a_sphere():
    spot = dict(position=(0, 0, HEIGHT), direction=(0, 0, -1), intensity=(10, 10, 10), spot_size=math.radians(150))
    with_cosine = direct_light(lambda s: s.add_spot_light("spot", **spot))
    without = direct_light(lambda s: s.add_spot_light("spot", **spot, spot_cosine=False))
    # A point spot (one exact shadow ray): Cycles 4.x's falloff is 1 / cos(theta) of Cycles 3.4's, at every pixel.
    cos_theta = HEIGHT / np.sqrt(squared_distance_to_light())
    np.testing.assert_allclose(without / with_cosine, 1.0 / cos_theta, rtol=1e-4)
    # With a radius, sphere=True brightens the near field as for the point light (the cone, 75 degrees each side,
    # holds every ray from the sphere to the plane under the camera).
    radius = 0.5
    disc = direct_light(lambda s: s.add_spot_light("spot", **spot, radius=radius, spot_cosine=False))
    sphere = direct_light(lambda s: s.add_spot_light("spot", **spot, radius=radius, sphere=True, spot_cosine=False))
    d2 = squared_distance_to_light()
    assert np.abs((sphere / disc) / ((d2 + radius ** 2) / d2) - 1.0).max() < 0.01


def test_new_keywords_are_booleans_with_cycles_34_defaults():
    doc_point, doc_spot = ps.Scene.add_point_light.__doc__, ps.Scene.add_spot_light.__doc__
    assert "sphere: bool = False" in doc_point and "Soft Falloff" in doc_point
    assert "sphere: bool = False" in doc_spot and "spot_cosine: bool = True" in doc_spot and "4.x" in doc_spot
    scene = ps.Scene()
    with pytest.raises(TypeError):
        scene.add_point_light("lamp", position=(0, 0, 1), intensity=(1, 1, 1), sphere="yes")
