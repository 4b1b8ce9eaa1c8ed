"""scene.photonsplat as the core's settings table builds it: every stored setting with the core's default, range,
choices and description; `passes` still reads and writes `iterations`, also in files saved under the old name;
and the keyword arguments read back from a fresh scene make the core's default settings, bit for bit."""

import warnings

import bpy
import numpy as np
import pytest

from photonsplat import export, settings


def rna(name):
    return bpy.types.Scene.bl_rna.properties["photonsplat"].fixed_type.properties[name]


def test_every_stored_setting_is_a_property_with_the_cores_default_range_and_choices(empty_scene, core):
    props = empty_scene.photonsplat
    for row in settings.stored(core.SETTINGS):
        name, prop = row["name"], rna(row["name"])
        value = getattr(props, name)
        if row["unit"] == "bytes":
            assert value * settings.GIB == row["default"], name
        elif row["type"] in ("float", "double"):
            assert np.float32(value) == np.float32(row["default"]), name
        else:
            assert value == row["default"], name
        assert prop.description == row["description"], name
        if row["type"] == "enum":
            assert tuple(item.identifier for item in prop.enum_items) == row["choices"], name
        if row["type"] in ("uint", "int") and row["max"] is not None:
            assert (prop.hard_min, prop.hard_max) == (row["min"], row["max"]), name
    for name in settings.FROM_BLENDER:
        assert name not in type(props).bl_rna.properties


def test_passes_reads_and_writes_iterations(empty_scene):
    props = empty_scene.photonsplat
    props.iterations = 12
    assert props.passes == 12
    props.passes = 5
    assert props.iterations == 5
    assert rna("passes").description.startswith("Deprecated")
    assert rna("iterations").name == "Iterations"


def test_a_file_saved_with_the_old_name_keeps_its_value(empty_scene, tmp_path):
    empty_scene.photonsplat["passes"] = 9  # what an older add-on stored: an ID property named passes
    path = tmp_path / "old_names.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    bpy.ops.wm.open_mainfile(filepath=str(path), load_ui=False)
    props = bpy.context.scene.photonsplat
    assert props.iterations == 9 and "passes" not in props.keys()


def test_kwargs_of_a_fresh_scene_are_the_cores_defaults_and_what_the_exporter_sent(empty_scene, core):
    props = empty_scene.photonsplat
    kwargs = settings.render_settings_kwargs(props)
    assert repr(core.RenderSettings(**kwargs)) == repr(core.RenderSettings())
    props.photons, props.iterations, props.time_limit, props.memory_budget = 1234, 3, 2.5, 1.5
    props.method, props.radius, props.seed = "gather", 0.125, 77
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        exported = export.render_settings(core, props)
    assert repr(core.RenderSettings(**settings.render_settings_kwargs(props))) == repr(exported)


def test_a_refused_value_names_the_setting(empty_scene, core):
    props = empty_scene.photonsplat
    props["alpha"] = 0.0  # an ID property bypasses the property's limits, as a script or an old file can
    with pytest.raises(ValueError, match="alpha"):
        core.RenderSettings(**settings.render_settings_kwargs(props))
