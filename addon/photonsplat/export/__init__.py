"""Evaluated Blender depsgraph -> what the native core renders: a Scene, a Camera and RenderSettings.

One module per concept does the conversion (mesh, materials, lights, camera, world); this file walks the
depsgraph and ties them together. The core module is passed in as `core` (the compiled photonsplat._core),
which keeps this code free of import-time dependencies on the native library.

Nothing here raises for a merely unusual scene: whatever is approximated or skipped becomes a line in
`ExportedFrame.warnings`, which the engine shows in the render report. Real errors (no camera) raise
ExportError with a message meant for the user; the core itself raises ValueError for invalid data.
"""

from dataclasses import dataclass, field

from . import camera, lights, materials, mesh, world


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
    meshes: int = 0
    triangles: int = 0
    lights: int = 0
    materials: int = 0


def export_frame(core, depsgraph, camera_override=None):
    """Convert the evaluated scene of `depsgraph` for one frame. `camera_override` replaces scene.camera."""
    scene = depsgraph.scene
    notes = []

    # The camera first: without one there is nothing to render, so fail before the costly geometry export.
    width, height = camera.resolution(scene)
    try:
        core_camera = camera.export_camera(core, depsgraph, camera_override or scene.camera, width, height, notes)
    except camera.CameraError as error:
        raise ExportError(str(error)) from None

    settings = render_settings(core, scene.photonsplat)
    core_scene = core.Scene()
    frame = ExportedFrame(scene=core_scene, camera=core_camera, settings=settings, width=width, height=height)
    table = _MaterialTable(core_scene, notes)

    for instance in depsgraph.object_instances:
        # An instance is only valid during its own iteration step: use it here, keep nothing of it.
        ob = instance.object
        if not instance.show_self:
            continue
        name = _instance_name(instance)
        if ob.type == 'LIGHT':
            if lights.export_light(core_scene, name, ob.data, instance.matrix_world.copy(), notes):
                frame.lights += 1
        elif ob.type == 'MESH':
            triangles = mesh.triangle_mesh(ob)
            if triangles is None:
                continue                      # no faces (only loose edges or points): nothing to hit
            slot_ids = [table.id_for(slot.material) for slot in ob.material_slots] or [table.id_for(None)]
            core_scene.add_mesh(name=name, vertices=triangles.vertices, triangles=triangles.triangles,
                                normals=triangles.normals,
                                material_ids=mesh.scene_material_ids(triangles.slots, slot_ids),
                                transform=camera.matrix_to_numpy(instance.matrix_world))
            frame.meshes += 1
            frame.triangles += len(triangles.triangles)
        elif ob.type in mesh.UNSUPPORTED_TYPES:
            notes.append(f"Object '{name}': {ob.type.lower()} objects are not supported yet, skipped")

    background = world.background_radiance(depsgraph.scene_eval.world, notes)
    core_scene.set_background(radiance=background)
    if frame.lights == 0 and not table.emissive and max(background) <= 0.0:
        notes.append("The scene has no lights, no emissive surfaces and a black world: the image will be black")

    frame.materials = table.count
    frame.warnings = _unique(notes)
    return frame


def render_settings(core, props):
    """scene.photonsplat -> core RenderSettings, field by field (the core validates the values)."""
    return core.RenderSettings(photons=props.photons, radius=props.radius, method=props.method,
                               max_bounces=props.max_bounces, seed=props.seed, threads=props.threads,
                               direct_samples=props.direct_samples, kernel=props.kernel,
                               directional_level=props.directional_level,
                               memory_budget=int(props.memory_budget * 2**30))


class _MaterialTable:
    """Adds every Blender material to the core scene once, and remembers its index there."""

    def __init__(self, core_scene, notes):
        self._core_scene = core_scene
        self._notes = notes
        self._ids = {}
        self.emissive = False          # whether any material emits light

    @property
    def count(self):
        return len(self._ids)

    def id_for(self, material):
        key = None if material is None else material.name_full
        if key not in self._ids:
            spec = materials.convert_material(material)
            self._ids[key] = self._core_scene.add_material(**spec.core_arguments())
            self.emissive = self.emissive or max(spec.emission) > 0.0
            if spec.notes:
                self._notes.append(f"Material '{spec.name}': " + "; ".join(_unique(spec.notes)))
        return self._ids[key]


def _instance_name(instance):
    """A readable name for error messages; instances generated by particles or nodes get their id."""
    ob = instance.object
    if instance.is_instance:
        return f"{ob.name} (instance {instance.persistent_id[0]} of {instance.parent.name})"
    return ob.name


def _unique(lines):
    return list(dict.fromkeys(lines))
