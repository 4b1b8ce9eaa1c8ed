"""Evaluated Blender depsgraph -> what the native core renders: a Scene, a Camera and RenderSettings.

One module per concept does the conversion (mesh, materials, lights, camera, world); this file walks the
depsgraph and ties them together. The core module is passed in as `core` (the compiled photonsplat._core),
which keeps this code free of import-time dependencies on the native library.

Nothing here raises for a merely unusual scene: whatever is approximated or skipped becomes a line in
`ExportedFrame.warnings`, which the engine shows in the render report. Real errors (no camera) raise
ExportError with a message meant for the user; the core itself raises ValueError for invalid data.
"""

from dataclasses import dataclass, field

from . import camera, lights, mesh, world
from .instancing import GeometryTable, MaterialTable, instance_name, placement, unique


class ExportError(Exception):
    """The scene cannot be rendered; the message tells the user what to change."""


@dataclass
class ExportedFrame:
    scene: object                  # core Scene
    camera: object                 # core Camera
    settings: object               # core RenderSettings
    width: int
    height: int
    warnings: list = field(default_factory=list)
    meshes: int = 0                # distinct meshes (each stored once in the core)
    instances: int = 0             # placements of them: objects, collection / particle / geometry-node instances
    triangles: int = 0             # triangles in the world, every instance counted
    # Original object name -> core instance ids showing it (its own mesh and every instance it generates or
    # that shows it): what Scene.set_instance_transform needs when only transforms change.
    object_instances: dict = field(default_factory=dict)
    lights: int = 0
    materials: int = 0


def export_frame(core, depsgraph, camera_override=None):
    """Convert the evaluated scene of `depsgraph` for one frame. `camera_override` replaces scene.camera.

    With a render border, the camera covers only the border's pixels and width/height are the border's size."""
    scene = depsgraph.scene
    notes = []

    # The camera first: without one there is nothing to render, so fail before the costly geometry export.
    full_width, full_height = camera.resolution(scene)
    region = camera.border_region(scene, full_width, full_height)
    width, height = region[2] - region[0], region[3] - region[1]
    try:
        core_camera = camera.export_camera(core, depsgraph, camera_override or scene.camera, full_width,
                                           full_height, notes, region=region)
    except camera.CameraError as error:
        raise ExportError(str(error)) from None

    settings = render_settings(core, scene.photonsplat)
    core_scene = core.Scene()
    frame = ExportedFrame(scene=core_scene, camera=core_camera, settings=settings, width=width, height=height)
    table = MaterialTable(core_scene, notes)

    geometry = GeometryTable(core_scene, table)
    for instance in depsgraph.object_instances:
        # An instance is only valid during its own iteration step: use it here, keep nothing of it.
        ob = instance.object
        if not instance.show_self:
            continue
        name = instance_name(instance)
        if ob.type == 'LIGHT':
            if lights.export_light(core_scene, name, ob.data, instance.matrix_world.copy(), notes):
                frame.lights += 1
        elif ob.type == 'MESH' or mesh.needs_to_mesh(instance):
            _, triangles = geometry.add(placement(instance, name), lambda: mesh.triangle_mesh(ob))
            if triangles:
                frame.instances += 1
                frame.triangles += triangles
        elif ob.type in mesh.UNSUPPORTED_TYPES:
            notes.append(f"Object '{name}': {ob.type.lower()} objects are not supported yet, skipped")

    frame.meshes = geometry.count
    frame.object_instances = geometry.instances_by_object
    background = world.background_radiance(depsgraph.scene_eval.world, notes)
    core_scene.set_background(radiance=background)
    if frame.lights == 0 and not table.emissive and max(background) <= 0.0:
        notes.append("The scene has no lights, no emissive surfaces and a black world: the image will be black")

    frame.materials = table.count
    frame.warnings = unique(notes)
    return frame


def render_settings(core, props, **overrides):
    """scene.photonsplat -> core RenderSettings, field by field (the core validates the values). `overrides`
    set fields that do not come from scene.photonsplat (caustics_pass, transparent) or replace some that do."""
    fields = dict(photons=props.photons, radius=props.radius, method=props.method,
                  max_bounces=props.max_bounces, seed=props.seed, threads=props.threads,
                  direct_samples=props.direct_samples, kernel=props.kernel,
                  boundary_correction=props.boundary_correction,
                  directional_level=props.directional_level, passes=props.passes,
                  time_limit=props.time_limit, memory_budget=int(props.memory_budget * 2**30))
    fields.update(overrides)
    return core.RenderSettings(**fields)
