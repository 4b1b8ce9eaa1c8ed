"""Render settings of Photon Splat, stored per scene as ``scene.photonsplat``.

The render settings are built from the core's settings table (settings.py: names, defaults, ranges, choices and
descriptions of ``photonsplat.SETTINGS``), so each property is a field of the core's ``RenderSettings`` under the
same name, and ``settings.render_settings_kwargs(scene.photonsplat)`` gives them back to the core. The viewport's
own settings follow. The names are part of the public interface: scripts and render farms set them; a setting's
old name (``passes`` for ``iterations``) stays as a property that reads and writes the new one.
"""

import bpy
from bpy.app.handlers import persistent
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty

from . import settings

PROPERTY = {"int": IntProperty, "float": FloatProperty, "bool": BoolProperty, "enum": EnumProperty}

# The Rendered viewport's settings (not the core's): a fast first image after a change, then refinement.
VIEWPORT = (
    ("viewport_preview_photons", "int", dict(name="First Image Photons", default=20_000, min=0, soft_max=1_000_000,
        description="Photons of the first, fast image after any change in the viewport")),
    ("viewport_preview_divider", "int", dict(name="First Image Pixel Size", default=4, min=1, max=16,
        description="The first image after a change is rendered at 1/N of the viewport's resolution")),
    ("viewport_photons", "int", dict(name="Photons per Iteration", default=100_000, min=0, soft_max=10_000_000,
        description="Photons of each refinement iteration in the viewport (at full viewport resolution)")),
    ("viewport_iterations", "int", dict(name="Iterations", default=32, min=0, soft_max=1024,
        description="Refinement iterations averaged in the viewport before it stops; 0 = no limit")),
    ("viewport_time_limit", "float", dict(name="Time Limit", default=30.0, min=0.0, soft_max=600.0, unit='TIME_ABSOLUTE',
        description="Seconds of refinement after a change before the viewport stops; 0 = no limit")),
)

# Viewport settings stored under an older name by files of earlier versions: {old name: new name}.
VIEWPORT_RENAMED = {"viewport_passes": "viewport_iterations"}


def _scene_settings_class():
    annotations = {name: PROPERTY[kind](**kwargs) for name, kind, kwargs in (*settings.property_specs(), *VIEWPORT)}
    return type("PhotonSplatSceneSettings", (bpy.types.PropertyGroup,), {"__annotations__": annotations})


PhotonSplatSceneSettings = _scene_settings_class()


@persistent
def migrate_renamed_settings(_=None):
    """A file saved when a setting had its old name stores the value under that name: move it to the new one."""
    for scene in bpy.data.scenes:
        props = scene.photonsplat
        for old, new in {**settings.renamed(), **VIEWPORT_RENAMED}.items():
            if old in props.keys():
                props[new] = props[old]
                del props[old]


def _passes_changed(settings, context):
    # Blender refreshes the passes (and the compositor's sockets) by itself only for its own toggles.
    for view_layer in settings.id_data.view_layers:
        if view_layer.photonsplat == settings:
            view_layer.update_render_passes()


class PhotonSplatViewLayerSettings(bpy.types.PropertyGroup):
    """Photon Splat's own render passes of a view layer. Combined, Depth, Normal and Emission use Blender's
    own toggles (view_layer.use_pass_combined / use_pass_z / use_pass_normal / use_pass_emit), as Cycles does."""
    use_pass_direct: BoolProperty(
        name="Direct", default=False, update=_passes_changed,
        description="Light reaching the first diffuse surface straight from the lights (shadow rays)",
    )
    use_pass_indirect: BoolProperty(
        name="Indirect", default=False, update=_passes_changed,
        description="Light that bounced at least once: the splatted photons, caustics included",
    )
    use_pass_caustics: BoolProperty(
        name="Caustics", default=False, update=_passes_changed,
        description="The light Cycles' Caustics toggles remove: what met glass, a mirror or a glossy surface "
                    "after a diffuse bounce (part of Indirect); costs two more splats of those photons",
    )


def register():
    bpy.utils.register_class(PhotonSplatSceneSettings)
    bpy.utils.register_class(PhotonSplatViewLayerSettings)
    bpy.types.Scene.photonsplat = PointerProperty(type=PhotonSplatSceneSettings, name="Photon Splat")
    bpy.types.ViewLayer.photonsplat = PointerProperty(type=PhotonSplatViewLayerSettings, name="Photon Splat")
    bpy.app.handlers.load_post.append(migrate_renamed_settings)


def unregister():
    if migrate_renamed_settings in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(migrate_renamed_settings)
    del bpy.types.ViewLayer.photonsplat
    del bpy.types.Scene.photonsplat
    bpy.utils.unregister_class(PhotonSplatViewLayerSettings)
    bpy.utils.unregister_class(PhotonSplatSceneSettings)
