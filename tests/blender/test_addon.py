"""The add-on registers, exposes its engine and settings, and opens Blender's generic panels to it."""

import bpy
import pytest

from photonsplat import compat, engine, ui


def test_engine_is_registered():
    engines = {getattr(cls, "bl_idname", None): cls for cls in bpy.types.RenderEngine.__subclasses__()}
    assert "PHOTONSPLAT" in engines
    cls = engines["PHOTONSPLAT"]
    assert cls.bl_label == "Photon Splat"
    assert cls.bl_use_shading_nodes_custom is False     # else the Shader Editor refuses Cycles nodes
    assert cls.bl_use_eevee_viewport is True
    assert cls.bl_use_preview is False


def test_engine_can_be_selected(empty_scene):
    empty_scene.render.engine = 'PHOTONSPLAT'
    assert empty_scene.render.engine == 'PHOTONSPLAT'


def test_settings_have_the_public_names(empty_scene):
    settings = empty_scene.photonsplat
    expected = {"photons": int, "radius": float, "method": str, "max_bounces": int, "seed": int,
                "direct_samples": int, "threads": int}
    for name, kind in expected.items():
        assert isinstance(getattr(settings, name), kind), name
    assert settings.radius == 0.0                       # 0 = derived from the scene's size
    methods = {item.identifier for item in settings.bl_rna.properties["method"].enum_items}
    assert {"brute", "cluster"} <= methods
    settings.method = "brute"
    assert settings.method == "brute"


def test_methods_match_the_core(core):
    """Every method offered in the panel exists in the core."""
    methods = {item.identifier for item in
               bpy.types.Scene.bl_rna.properties["photonsplat"].fixed_type.properties["method"].enum_items}
    assert methods <= set(core.METHODS)


def test_generic_panels_are_opened():
    for name in ("RENDER_PT_format", "RENDER_PT_output", "RENDER_PT_color_management", "DATA_PT_lens",
                 "DATA_PT_context_light", "EEVEE_MATERIAL_PT_context_material", "WORLD_PT_context_world"):
        assert "PHOTONSPLAT" in getattr(bpy.types, name).COMPAT_ENGINES, name
    # Our own panels exist and are shown for our engine only.
    for cls in (ui.RENDER_PT_photonsplat, ui.DATA_PT_photonsplat_light, ui.MATERIAL_PT_photonsplat_surface):
        assert hasattr(bpy.types, cls.__name__)
        assert cls.COMPAT_ENGINES == {"PHOTONSPLAT"}


def test_core_is_loadable(core):
    assert callable(core.render)


def test_missing_core_is_reported_not_raised(caustics_scene, monkeypatch, tmp_path):
    """With a broken build the add-on still registers; rendering then reports why instead of crashing."""
    import photonsplat
    monkeypatch.setattr(photonsplat, "CORE_IMPORT_ERROR", "simulated: no module photonsplat._core")
    with pytest.raises(engine.CoreUnavailable, match="simulated"):
        engine.load_core()
    caustics_scene.render.engine = 'PHOTONSPLAT'
    caustics_scene.render.resolution_percentage = 5
    caustics_scene.render.filepath = str(tmp_path / "never.exr")
    with pytest.raises(RuntimeError, match="simulated"):   # bpy.ops turns the ERROR report into this
        bpy.ops.render.render(write_still=True)
    assert engine.last_outcome.status == "failed"


class RecordingLayout:
    """Stands in for UILayout (panels cannot draw in background mode): checks every property a panel shows
    exists, and records the labels."""

    def __init__(self):
        self.props, self.labels = [], []

    def prop(self, data, name, **kwargs):
        assert name in data.bl_rna.properties, f"{type(data).__name__} has no property {name!r}"
        self.props.append(name)

    def label(self, text="", **kwargs):
        self.labels.append(text)

    def __getattr__(self, name):                       # column(), row(), box(), separator(), templates...
        return lambda *args, **kwargs: self


class PanelStandIn:
    """What Blender passes a panel's draw() as self: its layout, and the panel class's attributes and methods."""

    def __init__(self, panel_class, layout):
        self.panel_class, self.layout = panel_class, layout

    def __getattr__(self, name):
        value = getattr(self.panel_class, name)
        return value.__get__(self) if callable(value) and hasattr(value, "__get__") else value


def draw(panel_class, **context):
    from types import SimpleNamespace
    layout = RecordingLayout()
    panel_class.draw(PanelStandIn(panel_class, layout), SimpleNamespace(engine="PHOTONSPLAT", **context))
    return layout


def test_panels_draw(caustics_scene):
    settings_panel = draw(ui.RENDER_PT_photonsplat, scene=caustics_scene)
    assert {"photons", "radius", "method", "max_bounces", "seed"} <= set(settings_panel.props)
    assert draw(ui.RENDER_PT_photonsplat_performance, scene=caustics_scene).props == ["threads", "memory_budget"]
    glass = draw(ui.MATERIAL_PT_photonsplat_surface, material=bpy.data.materials["Glass"])
    assert any("glass" in text for text in glass.labels)
    draw(ui.WORLD_PT_photonsplat_surface, world=caustics_scene.world)
    for kind in ("POINT", "SUN", "SPOT", "AREA"):
        bpy.data.lights["Light"].type = kind
        light = bpy.data.lights["Light"]                # changing the type changes the Python class
        # Spot cones and round area lights are rendered as they are: the panel notes nothing for them.
        assert draw(ui.DATA_PT_photonsplat_light, light=light).labels == [], kind
        if kind == "AREA":
            light.shape = "ELLIPSE"
            assert draw(ui.DATA_PT_photonsplat_light, light=light).labels == []
            light.spread = 1.0                          # what the export approximates, the panel says
            assert any("spread" in text for text in draw(ui.DATA_PT_photonsplat_light, light=light).labels)
    # Every light setting this Blender's Cycles reads is in the panel (Blender 4.x: Temperature, Exposure...).
    for kind in ("POINT", "SPOT", "SUN", "AREA"):
        bpy.data.lights["Light"].type = kind
        light = bpy.data.lights["Light"]
        props = draw(ui.DATA_PT_photonsplat_light, light=light).props
        assert {"energy"} | set(compat.light_panel_properties(light)) <= set(props)
        assert ("color" in props) != (getattr(light, "use_temperature", False))
        if compat.CYCLES_4_LIGHTS:
            assert {"exposure", "use_temperature"} <= set(props)
            assert ("use_soft_falloff" in props) == (kind in ("POINT", "SPOT"))
            light.use_temperature = True                  # the colour then comes from the temperature
            props = draw(ui.DATA_PT_photonsplat_light, light=light).props
            assert "temperature" in props and "color" not in props
            light.use_temperature = False
    from types import SimpleNamespace
    assert not ui.DATA_PT_photonsplat_light.poll(SimpleNamespace(engine="PHOTONSPLAT", light=None))
    assert ui.DATA_PT_photonsplat_light.poll(SimpleNamespace(engine="PHOTONSPLAT", light=light))
