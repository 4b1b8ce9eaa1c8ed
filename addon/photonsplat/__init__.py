"""Photon Splat: caustics and indirect light by photon splatting onto a view-sample cluster hierarchy.

One package, two uses:
- the scripting API, importable from plain /usr/bin/python3 (no Blender needed):
      import photonsplat as ps
      image, stats = ps.render(scene, camera, ps.RenderSettings(photons=200_000))
      reference, _ = ps.render_reference(scene, camera, samples=256)
      print(ps.ssim(image, reference), ps.psnr(image, reference))
- the Blender add-on: Blender calls register(), which is the only place that imports bpy.
"""

bl_info = {
    "name": "Photon Splat",
    "author": "Photon Splat developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Render > Render Engine",
    "description": "Caustics and indirect light in seconds: photon splatting on a view-sample cluster hierarchy",
    "category": "Render",
}

# The compiled core. When it is missing or broken (wrong Python, missing libraries) the add-on still
# registers and says why in its panel, instead of failing to enable.
try:
    from ._core import (  # noqa: F401  (re-exported scripting API)
        FILM_OUTPUTS,
        IMAGE_FILES,
        KERNELS,
        METHODS,
        Camera,
        Cancelled,
        Progressive,
        RenderSettings,
        SETTINGS,
        Scene,
        RELMSE_EPSILON,
        automatic_radius,
        boundary_loss,
        psnr,
        relmse,
        default_memory_budget,
        ray_floor,
        render,
        render_reference,
        rmse,
        ssim,
        write_image,
    )
    from .cameras import look_at_camera  # noqa: F401
    # Inside Blender: photonsplat.reference.render_reference(depsgraph, ...) renders the current scene's reference
    # through the engine's exporter (the module imports bpy only when called).
    from . import reference  # noqa: F401

    CORE_IMPORT_ERROR = None
except ImportError as error:  # pragma: no cover - exercised only with a broken build
    CORE_IMPORT_ERROR = f"the native module photonsplat._core could not be loaded: {error}"


def _blender_modules():
    from . import engine, properties, ui

    return (properties, engine, ui)


def register():
    for module in _blender_modules():
        module.register()


def unregister():
    for module in reversed(_blender_modules()):
        module.unregister()
