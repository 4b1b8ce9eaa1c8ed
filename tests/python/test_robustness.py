"""Robustness through the bindings: the memory budget setting, hard cases for every method, no crash."""
import numpy as np
import pytest

import photonsplat as ps
from scenes import cornell_box, cornell_camera, quad


def test_memory_budget_is_a_setting_and_refuses_before_allocating_naming_the_structure():
    settings = ps.RenderSettings(memory_budget=300_000)
    assert settings.memory_budget == 300_000
    assert "memory_budget=300000" in repr(settings)
    with pytest.raises(ValueError, match=r"view_samples.*over the memory budget.*lower resolution"):
        ps.render(cornell_box(), cornell_camera(64, 64), settings)


def test_default_memory_budget_is_reported_and_predictions_come_with_the_stats():
    assert ps.default_memory_budget() > 0
    _, stats = ps.render(cornell_box(), cornell_camera(16, 16), ps.RenderSettings(photons=2000))
    assert stats["values"]["memory_budget"] == ps.default_memory_budget()
    for structure, measured in stats["bytes"].items():
        assert stats["predicted_bytes"][structure] >= measured, structure


def test_negative_memory_budget_is_refused():
    with pytest.raises(ValueError, match="memory_budget"):
        ps.RenderSettings(memory_budget=-1)


@pytest.mark.parametrize("method", ps.METHODS)
def test_one_pixel_and_nan_free_output_for_every_method(method):
    image, stats = ps.render(cornell_box(), cornell_camera(1, 1), ps.RenderSettings(photons=2000, method=method))
    assert image.shape == (1, 1, 4) and np.isfinite(image).all()


@pytest.mark.parametrize("method", ps.METHODS)
def test_mesh_with_nan_transform_is_refused_naming_the_object(method):
    scene = ps.Scene()
    scene.add_material(name="m")
    v, t = quad((0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0))
    transform = np.identity(4)
    transform[0, 3] = np.nan
    with pytest.raises(ValueError, match="Suzanne"):
        scene.add_mesh(name="Suzanne", vertices=v, triangles=t, transform=transform)
    image, _ = ps.render(scene, cornell_camera(4, 4), ps.RenderSettings(photons=100, method=method))
    assert np.isfinite(image).all()
