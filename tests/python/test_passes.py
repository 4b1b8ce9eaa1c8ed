"""The per-pass images of render(passes=True): first-hit depth and normal as Cycles defines them, the caustics
pass as exactly the caustic photons' share of the indirect light, and film transparency. Under 5 s."""
import numpy as np

import photonsplat as ps
from scenes import cornell_box, cornell_camera, plane_scene, quad


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


def test_caustics_pass_holds_what_camera_paths_find_beyond_translucency():
    """Cycles' Caustics toggles drop a glossy, mirror or refracting closure met right after a diffuse-labelled
    scatter, and translucency is one: a glossy wall seen through a translucent sheet is wholly in Cycles' caustic
    excess, a diffuse one not at all (differential seed 175: the pass held 0.10 of that excess, the camera path's
    light beyond the sheet missing). A spot between sheet and wall lights the wall alone."""
    def render(wall_kind):
        scene = ps.Scene()
        sheet = scene.add_material(name="sheet", kind="closures",
                                   closures=[dict(kind="translucent", color=(0.8, 0.8, 0.8))])
        wall = scene.add_material(name="wall", kind=wall_kind, color=(0.7, 0.7, 0.7), roughness=0.3)
        for name, corners, material in (("sheet", ((-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)), sheet),
                                        ("wall", ((-3, 1, -3), (3, 1, -3), (3, 1, 3), (-3, 1, 3)), wall)):
            v, t = quad(*corners)
            scene.add_mesh(name=name, vertices=v, triangles=t, material_ids=np.full(2, material, np.int32))
        scene.add_spot_light("spot", position=(0.0, 0.5, 0.0), direction=(0.0, 1.0, 0.0), intensity=(20, 20, 20),
                             spot_size=1.2, radius=0.05)
        camera = ps.look_at_camera(eye=(0, -3, 0), target=(0, 0, 0), width=16, height=16, fov_y_degrees=20.0)
        image, _, passes = ps.render(scene, camera, ps.RenderSettings(photons=5000, caustics_pass=True), passes=True)
        return image[..., :3], passes["caustics"]
    glossy, glossy_caustics = render("glossy")
    assert glossy.mean() > 0.01                            # the wall's highlight, through the sheet
    np.testing.assert_allclose(glossy_caustics, glossy, rtol=1e-5, atol=1e-7)
    diffuse, diffuse_caustics = render("diffuse")
    assert diffuse.mean() > 0.01 and diffuse_caustics.max() == 0.0
