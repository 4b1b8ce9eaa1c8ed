"""RenderSettings as the core's settings table generates it: photonsplat.SETTINGS, keywords, properties, the
deprecated `passes`, __repr__, and the keyword arguments the add-on derives from scene.photonsplat."""
import math
import types
import warnings

import numpy as np
import pytest

import photonsplat as ps
from photonsplat import settings as blender_settings
from scenes import cornell_box, cornell_camera

NAMES = [row["name"] for row in ps.SETTINGS]


def test_settings_describe_every_property_with_its_default():
    defaults = ps.RenderSettings()
    assert len(NAMES) == len(set(NAMES)) >= 20
    for row in ps.SETTINGS:
        assert set(row) >= {"name", "type", "default", "min", "max", "choices", "description", "aliases"}
        assert getattr(defaults, row["name"]) == row["default"], row["name"]
        assert row["description"] and row["requirement"].startswith("must be"), row["name"]
        assert row["type"] in ("uint", "int", "float", "double", "bool", "enum", "set")
    rows = {row["name"]: row for row in ps.SETTINGS}
    assert rows["outputs"]["choices"] == ps.FILM_OUTPUTS and "caustics" not in rows["outputs"]["default"]
    assert rows["method"]["choices"] == ps.METHODS and rows["kernel"]["choices"] == ps.KERNELS
    assert rows["iterations"]["aliases"] == ("passes",)
    assert (rows["direct_samples"]["min"], rows["direct_samples"]["max"]) == (1, 4096)
    assert rows["alpha"]["min_exclusive"] and not rows["alpha"]["max_exclusive"]


@pytest.mark.parametrize("row", ps.SETTINGS, ids=NAMES)
def test_values_outside_a_range_are_refused_by_keyword_and_by_property_naming_the_setting(row):
    bad = []
    step = 1 if row["type"] in ("uint", "int") else 0.5
    if row["min"] is not None:
        bad.append(row["min"] if row["min_exclusive"] else row["min"] - step)
    if row["max"] is not None:
        bad.append(row["max"] if row["max_exclusive"] else row["max"] + step)
    if row["type"] in ("float", "double"):
        bad += [math.nan, math.inf]
    if row["type"] == "enum":
        bad.append("no such choice")
    settings = ps.RenderSettings()
    for value in bad:
        with pytest.raises(ValueError, match=row["name"]):
            ps.RenderSettings(**{row["name"]: value})
        with pytest.raises(ValueError, match=row["name"]):
            setattr(settings, row["name"], value)
        assert getattr(settings, row["name"]) == row["default"]  # a refused value is not kept


def test_values_of_another_kind_are_type_errors_naming_the_setting():
    for kwargs in (dict(photons="many"), dict(threads=2.5), dict(method=3), dict(radius="wide")):
        with pytest.raises(TypeError, match=next(iter(kwargs))):
            ps.RenderSettings(**kwargs)
    with pytest.raises(TypeError, match="photns"):
        ps.RenderSettings(photns=1000)
    assert ps.RenderSettings(photons=np.int64(7), radius=np.float32(0.5), threads=True).photons == 7


def test_every_setting_round_trips_through_keywords_properties_and_repr():
    changed = dict(photons=1234, radius=0.25, method="gather", max_bounces=3, seed=2**63 + 5, threads=2,
                   direct_samples=2, normal_tolerance=45.0, plane_distance=0.5, kernel="epanechnikov",
                   boundary_correction=False, adaptive_radius=False, directional_level=2, memory_budget=2**40, guide_photons=False,
                   aimed_photons=0.5, caustics_pass=True, transparent=True, iterations=0, time_limit=2.5, alpha=0.5,
                   outputs=("combined", "direct", "depth"))
    assert set(changed) == set(NAMES), "a new setting: add a value for it here"
    settings = ps.RenderSettings(**changed)
    for name, value in changed.items():
        assert getattr(settings, name) == value, name
    again = eval(repr(settings), {"RenderSettings": ps.RenderSettings})
    assert repr(again) == repr(settings)
    assert "aimed_photons=0.1," in repr(ps.RenderSettings()) and "alpha=0.6666667" in repr(ps.RenderSettings())
    by_property = ps.RenderSettings(time_limit=2.5)
    for name, value in changed.items():
        setattr(by_property, name, value)
    assert repr(by_property) == repr(settings)


def test_passes_is_a_deprecated_name_of_iterations():
    with pytest.warns(DeprecationWarning, match="iterations"):
        settings = ps.RenderSettings(passes=5)
    assert settings.iterations == 5
    with pytest.warns(DeprecationWarning):
        assert settings.passes == 5
    with pytest.warns(DeprecationWarning):
        settings.passes = 7
    assert settings.iterations == 7
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ps.RenderSettings(iterations=5).iterations = 6  # the new name does not warn
    with pytest.raises(TypeError, match="iterations"), pytest.warns(DeprecationWarning):
        ps.RenderSettings(passes=2, iterations=3)
    with pytest.raises(ValueError, match="iterations"), pytest.warns(DeprecationWarning):
        ps.RenderSettings(passes=-1)


def test_progressive_counts_iterations_done():
    progressive = ps.Progressive(cornell_box(), cornell_camera(4, 4), ps.RenderSettings(photons=100, iterations=2))
    progressive.step()
    assert progressive.iterations_done == progressive.passes_done == 1


# --- the add-on's side, without Blender ------------------------------------------------------------------------

def blender_defaults():
    """A stand-in for a fresh scene.photonsplat: every stored setting at its Blender property's default."""
    return types.SimpleNamespace(**{name: kwargs["default"] for name, kind, kwargs in blender_settings.property_specs()
                                    if "default" in kwargs})


def test_blender_properties_cover_the_table_with_its_defaults_ranges_and_choices():
    specs = {name: (kind, kwargs) for name, kind, kwargs in blender_settings.property_specs()}
    assert set(specs) == (set(NAMES) - blender_settings.FROM_BLENDER) | {"passes"}
    assert specs["method"][1]["items"][0][0] == ps.METHODS[0] and len(specs["method"][1]["items"]) == len(ps.METHODS)
    assert specs["direct_samples"] == ("int", specs["direct_samples"][1])
    assert (specs["direct_samples"][1]["min"], specs["direct_samples"][1]["max"]) == (1, 4096)
    assert specs["memory_budget"][0] == "float" and specs["memory_budget"][1]["name"] == "Memory Budget (GiB)"
    assert 0.0 < specs["alpha"][1]["min"] < 1e-3
    passes = specs["passes"][1]
    assert "Deprecated" in passes["description"] and "default" not in passes
    props = types.SimpleNamespace(iterations=3)
    passes["set"](props, 9)
    assert passes["get"](props) == 9 == props.iterations


def test_kwargs_from_default_blender_properties_render_the_same_bits_as_default_settings():
    kwargs = blender_settings.render_settings_kwargs(blender_defaults())
    assert set(kwargs) == set(NAMES) - blender_settings.FROM_BLENDER
    from_blender = ps.RenderSettings(**kwargs)
    assert repr(from_blender) == repr(ps.RenderSettings())
    for row in ps.SETTINGS:
        assert getattr(from_blender, row["name"]) == row["default"], row["name"]
    scene, camera = cornell_box(), cornell_camera(16, 16)
    a, _ = ps.render(scene, camera, ps.RenderSettings(photons=2000, seed=3))
    b, _ = ps.render(scene, camera, ps.RenderSettings(**dict(kwargs, photons=2000, seed=3)))
    assert np.array_equal(a, b)


def test_kwargs_convert_gib_to_bytes():
    props = blender_defaults()
    props.memory_budget = 1.5
    assert blender_settings.render_settings_kwargs(props)["memory_budget"] == 3 * 2**29
