"""Render settings of Photon Splat, stored per scene as ``scene.photonsplat``.

Each property maps one-to-one onto a field of the core's ``RenderSettings`` (see export/__init__.py), so a value
can be followed in a straight line: this panel -> scene.photonsplat.<name> -> export -> the native core.
The names are part of the public interface: scripts and render farms set them.
"""

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty


# The splatting methods of the design (docs/design.md section 2), named as the core names them.
METHOD_ITEMS = (
    ("cluster_cone", "Cluster + Cones",
     "The paper's cluster-trivial: the cluster hierarchy with normal-cone trivial reject and accept; exact"),
    ("cluster", "Cluster",
     "Photons walk a hierarchy of view-sample clusters, culled by bounding boxes; exact"),
    ("directional", "Directional (approximate)",
     "Flux gathered per cluster of one level in 8 direction bins: faster, approximate"),
    ("tiled", "Tiled",
     "Mara et al. 2013: photons binned into 32x32-pixel screen tiles with depth bounds; exact"),
    ("gather", "Gather",
     "Each pixel gathers photons from a hashed uniform grid; exact"),
    ("brute", "Brute Force",
     "Every photon against every view sample; exact but slow, meant as a reference for small images"),
)

KERNEL_ITEMS = (
    ("uniform", "Uniform", "Constant weight inside the radius (keeps the cone method's trivial accept exact)"),
    ("epanechnikov", "Epanechnikov", "Weight falling off as 1 - d^2/r^2: smoother photon footprints"),
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
                    "0 lets the renderer choose it from the size of the scene and the photon count (without Boundary "
                    "Correction, or with the Directional method, a progressive render starts smaller where what the "
                    "camera sees has details thinner than that, which a wide kernel darkens)",
        default=0.0, min=0.0, soft_max=1.0, precision=4, unit='LENGTH',
    )
    method: EnumProperty(
        name="Method",
        description="How photons are splatted onto the pixels they light",
        items=METHOD_ITEMS, default="cluster_cone",
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
    kernel: EnumProperty(
        name="Kernel",
        description="Density-estimation kernel: how a photon's light is spread over its radius",
        items=KERNEL_ITEMS, default="uniform",
    )
    boundary_correction: BoolProperty(
        name="Boundary Correction",
        description="Divide each pixel's bounced light by the part of its kernel that lies on a surface like its "
                    "own, so corners, edges, columns and ledges are not darkened by a kernel that reaches past "
                    "them (glossy surfaces and Directional's approximate passes excepted). Off gives the paper's plain "
                    "estimate",
        default=True,
    )
    directional_level: IntProperty(
        name="Directional Level",
        description="Directional method only: hierarchy level (from the leaves) where photons stop; "
                    "-1 chooses it from the radius",
        default=-1, min=-1, soft_max=16,
    )
    passes: IntProperty(
        name="Passes",
        description="Progressive passes: each traces new photons with a smaller radius and jittered pixels, and the "
                    "image is their mean, which converges to the exact answer. 1 = the one-shot method; "
                    "0 = as many as fit in the time limit",
        default=1, min=0, soft_max=1000,
    )
    time_limit: FloatProperty(
        name="Time Limit",
        description="Seconds of progressive rendering (no pass is started that would end past it); 0 = no limit",
        default=0.0, min=0.0, soft_max=600.0, unit='TIME_ABSOLUTE',
    )
    threads: IntProperty(
        name="Threads",
        description="Number of CPU threads; 0 uses all cores",
        default=0, min=0, soft_max=256,
    )

    memory_budget: FloatProperty(
        name="Memory Budget (GiB)",
        description="Memory a render may hold, in GiB. A render whose structures would not fit is refused before "
                    "allocating, with a message naming the structure and what to lower. "
                    "0 uses three quarters of this machine's memory",
        default=0.0, min=0.0, soft_max=256.0, precision=1,
    )

    # --- viewport (Rendered shading): a fast first image, then refinement in the background ---------------
    viewport_preview_photons: IntProperty(
        name="First Pass Photons",
        description="Photons of the first, fast image after any change in the viewport",
        default=20_000, min=0, soft_max=1_000_000,
    )
    viewport_preview_divider: IntProperty(
        name="First Pass Pixel Size",
        description="The first image after a change is rendered at 1/N of the viewport's resolution",
        default=4, min=1, max=16,
    )
    viewport_photons: IntProperty(
        name="Photons per Pass",
        description="Photons of each refinement pass in the viewport (at full viewport resolution)",
        default=100_000, min=0, soft_max=10_000_000,
    )
    viewport_passes: IntProperty(
        name="Passes",
        description="Refinement passes averaged in the viewport before it stops; 0 = no limit",
        default=32, min=0, soft_max=1024,
    )
    viewport_time_limit: FloatProperty(
        name="Time Limit",
        description="Seconds of refinement after a change before the viewport stops; 0 = no limit",
        default=30.0, min=0.0, soft_max=600.0, unit='TIME_ABSOLUTE',
    )


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
        description="Only the photons whose path was light, then mirrors/glass, then a diffuse surface "
                    "(part of Indirect); costs a second splat of those photons",
    )


def register():
    bpy.utils.register_class(PhotonSplatSceneSettings)
    bpy.utils.register_class(PhotonSplatViewLayerSettings)
    bpy.types.Scene.photonsplat = PointerProperty(type=PhotonSplatSceneSettings, name="Photon Splat")
    bpy.types.ViewLayer.photonsplat = PointerProperty(type=PhotonSplatViewLayerSettings, name="Photon Splat")


def unregister():
    del bpy.types.ViewLayer.photonsplat
    del bpy.types.Scene.photonsplat
    bpy.utils.unregister_class(PhotonSplatViewLayerSettings)
    bpy.utils.unregister_class(PhotonSplatSceneSettings)
