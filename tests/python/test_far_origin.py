"""Positions and transforms reach the core in double (issue 6): a light 1 cm above a quad, both moved by 1e5,
lights the quad as at the origin. In float32 the light's height at 1e5 would round to 7.8 mm or 15.6 mm (the
spacing of float32 there), and the irradiance under it would change by 64 % or −59 %."""
import numpy as np
import pytest

import photonsplat as ps

QUAD_V = np.array([[-0.5, -0.5, 0], [0.5, -0.5, 0], [0.5, 0.5, 0], [-0.5, 0.5, 0]], np.float32)
QUAD_T = np.array([[0, 1, 2], [0, 2, 3]], np.int32)
FAR = np.array([1e5, -1e5, 1e5])


def translate(offset):
    m = np.eye(4)
    m[:3, 3] = offset
    return m


def direct_light(kind, offset):
    scene = ps.Scene()
    scene.add_material(name="white", color=(0.8, 0.8, 0.8))
    scene.add_instance(scene.add_mesh_data("quad", QUAD_V, QUAD_T), translate(offset))
    above = offset + np.array([0.0, 0.0, 0.01])          # float64 throughout
    if kind == "point":
        scene.add_point_light("lamp", position=above, intensity=(1.0, 1.0, 1.0))
    elif kind == "spot":
        scene.add_spot_light("lamp", position=above, direction=(0, 0, -1), intensity=(1.0, 1.0, 1.0), spot_size=3.0)
    else:
        # It emits towards cross(u, v) = −z: down onto the quad.
        scene.add_area_light("lamp", center=above, axis_u=(0.002, 0, 0), axis_v=(0, -0.002, 0),
                             radiance=(1e5, 1e5, 1e5))
    projection = np.diag([2.0, 2.0, -2.0 / 100.0, 1.0])
    projection[2, 3] = -1.0
    camera = ps.Camera(to_world=translate(offset + np.array([0.0, 0.0, 10.0])), projection=projection,
                       width=16, height=16)
    _, _, passes = ps.render(scene, camera, ps.RenderSettings(photons=1000, radius=0.05, seed=2), passes=True)
    return passes["direct"].astype(np.float64)


@pytest.mark.parametrize("kind", ["point", "spot", "area"])
def test_a_light_1cm_above_a_quad_moved_by_1e5_lights_it_as_at_the_origin(kind):
    at_origin, far = direct_light(kind, np.zeros(3)), direct_light(kind, FAR)
    assert at_origin.max() > 0.0
    assert np.abs(far - at_origin).sum() / np.abs(at_origin).sum() < 1e-3


# An emissive box 0.2 above a 4 x 4 quad, its bottom face parallel to the quad (issue 18, seed 122 of the random
# scenes: an emissive Suzanne on a floor 4e4 from the origin). A shadow ray leaves the quad stepped off it along
# its normal, by more where coordinates are larger; aimed along the direction sampled from the unmoved point, it
# ended that step beyond the light's point, behind the box's bottom face at grazing angles, and the face hid its
# own light: moved up by 1, 4 or 30, the quad's direct light was 0.69 of the same scene at the origin (the
# reference's image 0.93).
BOX_V = np.array([[x, y, z] for x in (-0.3, 0.3) for y in (-0.3, 0.3) for z in (0.2, 0.8)], np.float32)
BOX_FACES = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
BOX_T = np.array([t for a, b, c, d in BOX_FACES for t in ((a, b, c), (a, c, d))], np.int32)


def lit_by_an_emissive_box(offset, reference):
    scene = ps.Scene()
    scene.add_material(name="white", color=(0.8, 0.8, 0.8))
    scene.add_material(name="lamp", color=(0.0, 0.0, 0.0), emission=(5.0, 5.0, 5.0))
    scene.add_instance(scene.add_mesh_data("quad", 4.0 * QUAD_V, QUAD_T, material_ids=np.zeros(2, np.int32)),
                       translate(offset))
    scene.add_instance(scene.add_mesh_data("box", BOX_V, BOX_T, material_ids=np.ones(12, np.int32)), translate(offset))
    projection = np.diag([0.5, 0.5, -2.0 / 100.0, 1.0])
    projection[2, 3] = -1.0
    camera = ps.Camera(to_world=translate(offset + np.array([0.0, 0.0, 10.0])), projection=projection,
                       width=32, height=32)
    if reference:
        image, _ = ps.render_reference(scene, camera, samples=16, seed=3)
        return np.asarray(image)[..., :3].astype(np.float64)
    _, _, passes = ps.render(scene, camera, ps.RenderSettings(photons=1000, radius=0.05, seed=2), passes=True)
    return passes["direct"].astype(np.float64)


@pytest.mark.parametrize("reference", [False, True], ids=["direct_light", "reference"])
@pytest.mark.parametrize("height", [1.0, 4.0, 30.0])
def test_an_emissive_surface_lights_a_floor_it_rests_on_as_at_the_origin(reference, height):
    offset = np.array([0.0, 0.0, height])
    at_origin, moved = lit_by_an_emissive_box(np.zeros(3), reference), lit_by_an_emissive_box(offset, reference)
    assert at_origin.mean() > 0.0
    assert moved.mean() / at_origin.mean() == pytest.approx(1.0, abs=1e-3)
    assert np.abs(moved - at_origin).sum() / np.abs(at_origin).sum() < 1e-2
