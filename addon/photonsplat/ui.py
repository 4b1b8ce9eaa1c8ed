"""Properties-editor panels for Photon Splat.

Our own panels: the render settings (scene.photonsplat), and light / material / world panels that show only
what Photon Splat renders (EEVEE's panels show EEVEE-only options, Cycles' need the Cycles add-on). Blender's
generic panels (output, dimensions, format, colour management, camera...) are opened to our engine by adding
its id to their COMPAT_ENGINES, the way Cycles does it.
"""

import bpy
from bpy.types import Panel

from . import compat, engine
from .export import lights, materials, world

ENGINE_ID = engine.PhotonSplatRenderEngine.bl_idname


class PhotonSplatPanel:
    """Mix-in: a Properties-editor panel shown only while Photon Splat is the render engine (and, with
    `context_member`, only when the context has that data block: a light, a material, a world)."""
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    COMPAT_ENGINES = {ENGINE_ID}
    context_member = None

    @classmethod
    def poll(cls, context):
        if cls.context_member is not None and getattr(context, cls.context_member, None) is None:
            return False
        return context.engine in cls.COMPAT_ENGINES


class DataBlockPanel(PhotonSplatPanel):
    """Mix-in: a panel of the context's `context_member` data block, drawn by draw_block(layout, block)."""

    def draw(self, context):
        self.draw_block(self.layout, getattr(context, self.context_member))


def _draw_core_status(layout):
    """An error box when the native module cannot be loaded (the add-on stays usable otherwise)."""
    try:
        engine.load_core()
    except engine.CoreUnavailable as error:
        box = layout.box()
        box.alert = True
        box.label(text="Photon Splat cannot render:", icon='ERROR')
        for line in _wrap(str(error), 60):        # labels do not wrap by themselves
            box.label(text=line)


def _wrap(text, width):
    lines, line = [], ""
    for word in text.split():
        if line and len(line) + 1 + len(word) > width:
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}" if line else word
    return lines + [line] if line else lines


def _property_split(layout):
    """`layout` in Blender's property-split style: labels on the left, values on the right, no keyframe dots."""
    layout.use_property_split = True
    layout.use_property_decorate = False
    return layout


def _draw_notes(layout, notes):
    for note in notes:
        layout.label(text=note, icon='INFO')


# --- render settings -----------------------------------------------------------------------------------------

class RENDER_PT_photonsplat(PhotonSplatPanel, Panel):
    bl_label = "Photon Splat"
    bl_context = "render"

    def draw(self, context):
        layout = _property_split(self.layout)
        _draw_core_status(layout)
        settings = context.scene.photonsplat
        col = layout.column()
        col.prop(settings, "photons")
        col.prop(settings, "radius")
        col.prop(settings, "method")
        col.prop(settings, "kernel")
        col.prop(settings, "boundary_correction")
        col.prop(settings, "adaptive_radius")
        if settings.method == "directional":
            col.prop(settings, "directional_level")
        col = layout.column()
        col.prop(settings, "iterations")
        col.prop(settings, "time_limit")
        col = layout.column()
        col.prop(settings, "max_bounces")
        col.prop(settings, "direct_samples")
        col.prop(settings, "seed")


class RENDER_PT_photonsplat_performance(PhotonSplatPanel, Panel):
    bl_label = "Performance"
    bl_context = "render"
    bl_parent_id = "RENDER_PT_photonsplat"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        layout = _property_split(self.layout)
        layout.prop(context.scene.photonsplat, "threads")
        layout.prop(context.scene.photonsplat, "memory_budget")


class RENDER_PT_photonsplat_viewport(PhotonSplatPanel, Panel):
    bl_label = "Viewport"
    bl_context = "render"
    bl_parent_id = "RENDER_PT_photonsplat"

    def draw(self, context):
        layout = _property_split(self.layout)
        settings = context.scene.photonsplat
        col = layout.column(heading="First Image")
        col.prop(settings, "viewport_preview_photons", text="Photons")
        col.prop(settings, "viewport_preview_divider", text="Pixel Size")
        col = layout.column(heading="Refinement")
        col.prop(settings, "viewport_photons", text="Photons per Pass")
        col.prop(settings, "viewport_iterations", text="Iterations")
        col.prop(settings, "viewport_time_limit", text="Time Limit")


class RENDER_PT_photonsplat_film(PhotonSplatPanel, Panel):
    bl_label = "Film"
    bl_context = "render"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        layout = _property_split(self.layout)
        layout.prop(context.scene.render, "film_transparent", text="Transparent")


class VIEWLAYER_PT_photonsplat_passes(PhotonSplatPanel, Panel):
    bl_label = "Passes"
    bl_context = "view_layer"

    def draw(self, context):
        layout = _property_split(self.layout)
        view_layer = context.view_layer
        col = layout.column(heading="Data", align=True)
        col.prop(view_layer, "use_pass_combined")
        col.prop(view_layer, "use_pass_z", text="Depth")
        col.prop(view_layer, "use_pass_normal")
        col = layout.column(heading="Light", align=True)
        col.prop(view_layer, "use_pass_emit", text="Emission")
        col.prop(view_layer.photonsplat, "use_pass_direct")
        col.prop(view_layer.photonsplat, "use_pass_indirect")
        col.prop(view_layer.photonsplat, "use_pass_caustics")


# --- lights, materials, world ---------------------------------------------------------------------------------

class DATA_PT_photonsplat_light(DataBlockPanel, Panel):
    bl_label = "Light"
    bl_context = "data"
    context_member = "light"

    def draw_block(self, layout, light):
        layout.row().prop(light, "type", expand=True)
        _property_split(layout)
        col = layout.column()
        extra = compat.light_panel_properties(light)     # Blender 4.x: Temperature, Exposure, Normalize...
        if "color" not in extra and "temperature" not in extra:
            col.prop(light, "color")
        for name in extra:
            col.prop(light, name)
        col.prop(light, "energy")
        if light.type in {'POINT', 'SPOT'}:
            col.prop(light, "shadow_soft_size", text="Radius")
        elif light.type == 'SUN':
            col.prop(light, "angle")
        elif light.type == 'AREA':
            col.prop(light, "shape")
            if light.shape in {'SQUARE', 'DISK'}:
                col.prop(light, "size")
            else:
                col.prop(light, "size", text="Size X")
                col.prop(light, "size_y", text="Y")
        (mis_owner, mis_name), (shadow_owner, shadow_name) = compat.light_switch_owners(light)
        if shadow_owner is not None:
            col.prop(shadow_owner, shadow_name, text="Cast Shadow")
        if mis_owner is not None:
            col.prop(mis_owner, mis_name, text="Multiple Importance")
        # What the export approximates or skips of this light, in the words of the render report.
        _draw_notes(layout, lights.conversion_notes(light))


def _draw_surface_nodes(layout, id_block, fallback_property):
    """The Surface input of a material's or world's Cycles output node, as Cycles' own panels show it."""
    if compat.has_use_nodes_switch(id_block):
        layout.prop(id_block, "use_nodes", icon='NODETREE')
    if compat.uses_nodes(id_block):
        output = id_block.node_tree.get_output_node('CYCLES')
        if output is not None:
            layout.template_node_view(id_block.node_tree, output, output.inputs["Surface"])
    else:
        layout.prop(id_block, fallback_property, text="Color")


class SurfacePanel(DataBlockPanel):
    """Mix-in: the Surface of a material or a world as Cycles' panel shows it, then what Photon Splat makes of it
    (draw_interpretation)."""
    bl_label = "Surface"
    fallback_property = None  # what the panel shows without nodes

    def draw_block(self, layout, block):
        _draw_surface_nodes(layout, block, fallback_property=self.fallback_property)
        self.draw_interpretation(layout, block)


class MATERIAL_PT_photonsplat_surface(SurfacePanel, Panel):
    bl_context = "material"
    context_member = "material"
    fallback_property = "diffuse_color"

    def draw_interpretation(self, layout, material):
        # Say how Photon Splat interprets this material, with what it had to approximate.
        spec = materials.convert_material(material)
        layout.separator()
        layout.label(text=f"Photon Splat renders it as: {spec.describe()}")
        _draw_notes(layout, spec.notes)


class WORLD_PT_photonsplat_surface(SurfacePanel, Panel):
    bl_context = "world"
    context_member = "world"
    fallback_property = "color"

    def draw_interpretation(self, layout, world_block):
        # What the export approximates of this world (environment textures, sky models...).
        notes = []
        world.background_radiance(world_block, notes)
        _draw_notes(layout, notes)


# --- Blender's own panels ------------------------------------------------------------------------------------

# Panels made for every engine ('BLENDER_RENDER' in their COMPAT_ENGINES) that do not apply to us:
# our own light panel replaces the light ones, and we render neither Freestyle nor previews.
_EXCLUDED_PANELS = {
    "DATA_PT_light", "DATA_PT_area", "DATA_PT_preview", "DATA_PT_falloff_curve",
    "RENDER_PT_freestyle", "MATERIAL_PT_freestyle_line",
}
# EEVEE panels that are engine-neutral in fact: the material slot list.
_EXTRA_PANELS = {"EEVEE_MATERIAL_PT_context_material"}

_opened_panels = []


def _generic_panels():
    for panel in bpy.types.Panel.__subclasses__():
        engines = getattr(panel, "COMPAT_ENGINES", None)
        if engines is None or ENGINE_ID in engines:
            continue
        name = panel.__name__
        if name in _EXTRA_PANELS or ('BLENDER_RENDER' in engines and name not in _EXCLUDED_PANELS
                                     and not name.startswith("VIEWLAYER_PT_freestyle")):
            yield panel


_classes = (
    RENDER_PT_photonsplat,
    RENDER_PT_photonsplat_performance,
    RENDER_PT_photonsplat_viewport,
    RENDER_PT_photonsplat_film,
    VIEWLAYER_PT_photonsplat_passes,
    DATA_PT_photonsplat_light,
    MATERIAL_PT_photonsplat_surface,
    WORLD_PT_photonsplat_surface,
)


def register():
    for cls in _classes:
        bpy.utils.register_class(cls)
    for panel in _generic_panels():
        panel.COMPAT_ENGINES.add(ENGINE_ID)
        _opened_panels.append(panel)


def unregister():
    for panel in _opened_panels:
        panel.COMPAT_ENGINES.discard(ENGINE_ID)
    _opened_panels.clear()
    for cls in reversed(_classes):
        bpy.utils.unregister_class(cls)
