"""The per-pass images of render(passes=True): first-hit depth and normal as Cycles defines them, the caustics
pass as exactly the caustic photons' share of the indirect light, and film transparency. Under 5 s."""
import numpy as np

import photonsplat as ps
from scenes import cornell_box, cornell_camera, plane_scene


def test_depth_and_normal_of_a_plane_seen_from_above():
    scene = plane_scene()
    camera = ps.look_at_camera(eye=(0.3, -0.2, 3.0), target=(0.3, -0.2, 0.0), width=16, height=16, up=(0, 1, 0))
    _, _, passes = ps.render(scene, camera, ps.RenderSettings(photons=1000), passes=True)
    depth, normal = passes["depth"][..., 0], passes["normal"]
    # Depth is measured along the camera's axis, not along the ray: 3 at every pixel of a plane facing it.
    assert np.allclose(depth, 3.0, atol=1e-4)
    assert np.allclose(normal, (0.0, 0.0, 1.0), atol=1e-5)


def test_background_pixels_have_no_depth_or_normal_and_transparency_clears_them():
    scene = plane_scene()
    scene.set_background(radiance=(0.25, 0.25, 0.25))
    camera = ps.look_at_camera(eye=(0, -10, 2), target=(0, 10, 0), width=24, height=24)  # plane edge in view
    opaque, _, passes = ps.render(scene, camera, ps.RenderSettings(photons=2000), passes=True)
    sky = passes["depth"][..., 0] == 1e10
    assert 0.2 < sky.mean() < 0.8
    assert (passes["normal"][sky] == 0.0).all()
    assert np.allclose(opaque[sky][:, :3], 0.25) and (opaque[..., 3] == 1.0).all()
    clear, _ = ps.render(scene, camera, ps.RenderSettings(photons=2000, transparent=True))
    assert (clear[sky] == 0.0).all()                       # premultiplied: no colour, no alpha
    assert np.array_equal(clear[~sky], opaque[~sky])       # the plane itself is untouched


def test_caustics_pass_is_the_caustic_photons_share_and_costs_nothing_when_off():
    scene, camera = cornell_box(), cornell_camera(32, 32)
    settings = ps.RenderSettings(photons=20000, method="brute")
    image, _, without = ps.render(scene, camera, settings, passes=True)
    assert "caustics" not in without
    settings.caustics_pass = True
    image_with, stats, passes = ps.render(scene, camera, settings, passes=True)
    assert np.array_equal(image, image_with)               # the pass changes nothing else
    caustics, indirect = passes["caustics"], passes["indirect"]
    assert stats["counters"]["caustic_photons_stored"] > 0
    assert caustics.max() > 0.0 and (caustics <= indirect + 1e-6).all()
    assert caustics.sum() < indirect.sum()                 # the box's walls also bounce light diffusely


def test_no_specular_surface_no_caustics():
    scene = plane_scene()
    camera = ps.look_at_camera(eye=(0, -4, 3), target=(0, 0, 0), width=16, height=16)
    _, stats, passes = ps.render(scene, camera, ps.RenderSettings(photons=5000, caustics_pass=True), passes=True)
    assert stats["counters"].get("caustic_photons_stored", 0) == 0 and passes["caustics"].max() == 0.0
