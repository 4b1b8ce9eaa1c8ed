"""Render settings of Photon Splat, stored per scene as ``scene.photonsplat``.

Each property maps one-to-one onto a field of the core's ``RenderSettings`` (see export/__init__.py), so a value
can be followed in a straight line: this panel -> scene.photonsplat.<name> -> export -> the native core.
The names are part of the public interface: scripts and render farms set them.
"""

import bpy
from bpy.props import EnumProperty, FloatProperty, IntProperty, PointerProperty


# The splatting methods of the design (docs/design.md section 2). Only these two exist in the core so far;
# the others ("tiled", "cluster_cone", "directional", "gather") are added here when the core offers them.
METHOD_ITEMS = (
    ("cluster", "Cluster",
     "Photons walk a hierarchy of view-sample clusters; exact and fast (the default)"),
    ("brute", "Brute Force",
     "Every photon against every view sample; exact but slow, meant as a reference for small images"),
)


class PhotonSplatSceneSettings(bpy.types.PropertyGroup):
    photons: IntProperty(
        name="Photons",
        description="Number of photon paths traced from the lights per frame. "
                    "More photons give less noise in indirect light and caustics",
        default=200_000, min=0, soft_max=10_000_000,
    )
    radius: FloatProperty(
        name="Radius",
        description="Splatting radius of each photon, in world units. "
                    "0 lets the renderer derive it from the size of the scene and the photon count",
        default=0.0, min=0.0, soft_max=1.0, precision=4, unit='LENGTH',
    )
    method: EnumProperty(
        name="Method",
        description="How photons are splatted onto the pixels they light",
        items=METHOD_ITEMS, default="cluster",
    )
    max_bounces: IntProperty(
        name="Max Bounces",
        description="Longest photon path, and the deepest chain of mirror/glass bounces followed from the camera",
        default=8, min=0, soft_max=32,
    )
    seed: IntProperty(
        name="Seed",
        description="Random seed; the same seed gives the same image whatever the number of threads",
        default=0, min=0,
    )
    direct_samples: IntProperty(
        name="Direct Samples",
        description="Shadow rays per light and pixel for direct light (soft shadows of lights with a size)",
        default=4, min=1, soft_max=64,
    )
    threads: IntProperty(
        name="Threads",
        description="Number of CPU threads; 0 uses all cores",
        default=0, min=0, soft_max=256,
    )


def register():
    bpy.utils.register_class(PhotonSplatSceneSettings)
    bpy.types.Scene.photonsplat = PointerProperty(type=PhotonSplatSceneSettings, name="Photon Splat")


def unregister():
    del bpy.types.Scene.photonsplat
    bpy.utils.unregister_class(PhotonSplatSceneSettings)
