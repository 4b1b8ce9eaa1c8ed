"""Reference renders of the current Blender scene, for scripts running inside Blender.

    import bpy, photonsplat
    image, stats = photonsplat.reference.render_reference(bpy.context.evaluated_depsgraph_get(), samples=256)

The scene goes through the engine's own exporter (export.export_frame: the same meshes, materials, lights,
camera and resolution an F12 render sees) and then to the native reference renderer (path tracing with
next-event estimation and MIS, plus progressive photon mapping of point-light and sun caustics; see
docs/reference.md). Needs the add-on registered (the exporter reads scene.photonsplat); imports nothing from
Blender until called, so `import photonsplat` keeps working outside Blender.
"""


def render_reference(depsgraph, samples=64, seed=0, threads=0, max_bounces=16, caustic_photons=100_000,
                     time_limit=0.0, progress=None, camera=None):
    """Render the evaluated scene of `depsgraph` (its camera, or `camera`) with the reference renderer.

    Returns (image, stats) as photonsplat.render_reference does: image float32 (height, width, 4), linear
    radiance, row 0 at the TOP (np.flipud it to compare with Blender's bottom-up pixels); stats a dict of
    "seconds", "counters", "bytes", "values" (values["samples"] = passes done), plus "warnings": what the
    exporter approximated or skipped. Raises export.ExportError (no camera, ...) and ValueError (bad settings).
    """
    from . import export
    from .engine import load_core

    core = load_core()
    frame = export.export_frame(core, depsgraph, camera_override=camera)
    image, stats = core.render_reference(frame.scene, frame.camera, samples=samples, seed=seed, threads=threads,
                                         max_bounces=max_bounces, caustic_photons=caustic_photons,
                                         time_limit=time_limit, progress=progress)
    stats["warnings"] = list(frame.warnings)
    return image, stats
