"""Every splatting method the settings offer, through the Python API: the exact ones equal the brute-force
oracle on the same photons; the approximate one stays close; all accept both kernels and bad values fail."""
import numpy as np
import pytest

import photonsplat as ps
from scenes import cornell_box, cornell_camera, quad

EXACT = ("tiled", "cluster", "cluster_cone", "gather")


def test_methods_are_the_designs():
    assert set(ps.METHODS) == {"brute", "tiled", "cluster", "cluster_cone", "directional", "gather"}
    assert set(ps.KERNELS) == {"uniform", "epanechnikov"}


@pytest.fixture(scope="module")
def box():
    return cornell_box(), cornell_camera(40, 40)


@pytest.mark.parametrize("kernel", ["uniform", "epanechnikov"])
@pytest.mark.parametrize("method", EXACT)
def test_exact_method_equals_brute(box, method, kernel):
    scene, camera = box
    common = dict(photons=20000, seed=5, kernel=kernel)
    _, _, oracle = ps.render(scene, camera, ps.RenderSettings(method="brute", **common), passes=True)
    _, stats, result = ps.render(scene, camera, ps.RenderSettings(method=method, **common), passes=True)
    assert oracle["indirect"].sum() > 0
    np.testing.assert_allclose(result["indirect"], oracle["indirect"], rtol=1e-4, atol=1e-6 * oracle["indirect"].max())
    assert stats["counters"]["photon_sample_tests"] >= 0


@pytest.mark.parametrize("radius", [1e-4, 0.05, 10.0])
def test_exact_methods_agree_for_tiny_typical_and_huge_radii(box, radius):
    scene, camera = box
    images = {}
    for method in ("brute",) + EXACT:
        _, _, images[method] = ps.render(scene, camera, ps.RenderSettings(method=method, photons=3000, radius=radius),
                                         passes=True)
    for method in EXACT:
        np.testing.assert_allclose(images[method]["indirect"], images["brute"]["indirect"], rtol=1e-4,
                                   atol=1e-6 * max(images["brute"]["indirect"].max(), 1e-12), err_msg=method)


def test_directional_is_close_to_exact_on_average(box):
    scene, camera = box
    _, _, exact = ps.render(scene, camera, ps.RenderSettings(method="cluster", photons=50000), passes=True)
    _, _, approx = ps.render(scene, camera, ps.RenderSettings(method="directional", photons=50000), passes=True)
    assert np.isfinite(approx["indirect"]).all() and (approx["indirect"] >= 0).all()
    ratio = approx["indirect"].mean() / exact["indirect"].mean()
    assert 0.8 < ratio < 1.2, ratio


@pytest.mark.parametrize("kwargs, field", [(dict(kernel="gaussian"), "kernel"), (dict(directional_level=-2), "directional_level")])
def test_bad_method_settings_name_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        ps.RenderSettings(**kwargs)


def test_exact_methods_equal_brute_on_the_caustics_pass_of_diffuse_and_glossy_walls():
    """The Caustics pass splats its photons twice, with the share of each sample's BRDF Cycles would label diffuse
    and with the rest (photons.h): walls that are both diffuse and glossy take both, in every method."""
    scene = ps.Scene()
    both = scene.add_material(name="both", kind="closures", closures=[
        dict(kind="diffuse", color=(0.7, 0.25, 0.2)),
        dict(kind="reflection", distribution="ggx", alpha_x=0.2, alpha_y=0.2, color=(0.3, 0.3, 0.3))])
    mirror = scene.add_material(name="mirror", kind="mirror", color=(0.9, 0.9, 0.9))
    for name, corners, material in (("floor", ((-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)), both),
                                    ("back", ((-1, 1, 0), (1, 1, 0), (1, 1, 2), (-1, 1, 2)), both),
                                    ("left", ((-1, -1, 0), (-1, 1, 0), (-1, 1, 2), (-1, -1, 2)), mirror)):
        v, t = quad(*corners)
        scene.add_mesh(name=name, vertices=v, triangles=t, material_ids=np.full(2, material, np.int32))
    scene.add_point_light(name="lamp", position=(0.2, 0.0, 1.5), intensity=(10.0,) * 3, radius=0.05)
    camera = ps.look_at_camera(eye=(0.3, -3.0, 1.2), target=(0.0, 0.3, 0.6), width=32, height=32)
    passes = {}
    for method in ("brute",) + EXACT + ("directional",):
        settings = ps.RenderSettings(method=method, photons=20000, seed=2, caustics_pass=True)
        _, _, passes[method] = ps.render(scene, camera, settings, passes=True)
    oracle = passes["brute"]["caustics"]
    assert 0.0 < oracle.sum() < passes["brute"]["indirect"].sum()
    for method in EXACT:
        np.testing.assert_allclose(passes[method]["caustics"], oracle, rtol=1e-4, atol=1e-6 * oracle.max(),
                                   err_msg=method)
    assert 0.8 < passes["directional"]["caustics"].mean() / oracle.mean() < 1.2
