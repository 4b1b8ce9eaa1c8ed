"""Evaluated Blender depsgraph -> what the native core renders: a Scene, a Camera and RenderSettings.

One module per concept does the conversion (mesh, materials, lights, camera, world); this file walks the
depsgraph and ties them together. The core module is passed in as `core` (the compiled photonsplat._core),
which keeps this code free of import-time dependencies on the native library.

Nothing here raises for a merely unusual scene: whatever is approximated or skipped becomes a line in
`ExportedFrame.warnings`, which the engine shows in the render report. Real errors (no camera) raise
ExportError with a message meant for the user; the core itself raises ValueError for invalid data.
"""

from dataclasses import dataclass, field

from . import camera, lights, materials, mesh, textures, world


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
    table = _MaterialTable(core_scene, notes)

    geometry = _GeometryTable(core_scene, table, notes)
    for instance in depsgraph.object_instances:
        # An instance is only valid during its own iteration step: use it here, keep nothing of it.
        ob = instance.object
        if not instance.show_self:
            continue
        name = _instance_name(instance)
        if ob.type == 'LIGHT':
            if lights.export_light(core_scene, name, ob.data, instance.matrix_world.copy(), notes):
                frame.lights += 1
        elif ob.type == 'MESH' or mesh.needs_to_mesh(instance):
            triangles = geometry.add_instance(instance, name)
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
    frame.warnings = _unique(notes)
    return frame


def render_settings(core, props, **overrides):
    """scene.photonsplat -> core RenderSettings, field by field (the core validates the values). `overrides`
    set fields that do not come from scene.photonsplat (caustics_pass, transparent) or replace some that do."""
    fields = dict(photons=props.photons, radius=props.radius, method=props.method,
                  max_bounces=props.max_bounces, seed=props.seed, threads=props.threads,
                  direct_samples=props.direct_samples, kernel=props.kernel,
                  directional_level=props.directional_level, passes=props.passes,
                  time_limit=props.time_limit, memory_budget=int(props.memory_budget * 2**30))
    fields.update(overrides)
    return core.RenderSettings(**fields)


class _GeometryTable:
    """Adds each distinct evaluated mesh to the core scene once, then one core instance per object or instance
    that shows it. Instances of one mesh (particles, geometry nodes, collection instances, linked duplicates)
    share the same evaluated data block, so they share one core mesh: Embree builds its BVH once."""

    def __init__(self, core_scene, table, notes):
        self._core_scene = core_scene
        self._table = table
        self._notes = notes
        self._ids = {}                 # (data block pointer, material ids) -> (core mesh id, triangles)
        self.instances_by_object = {}  # original object name -> [core instance id]

    @property
    def count(self):
        return sum(1 for mesh_id, _ in self._ids.values() if mesh_id is not None)

    def add_instance(self, instance, name):
        """Export `instance` (mesh first if new); returns its triangle count, 0 when it has nothing to render."""
        ob = instance.object
        slots = [self._table.id_for(slot.material) for slot in ob.material_slots] or [self._table.id_for(None)]
        holdout = _is_holdout(instance)
        if holdout:
            slots = [self._table.holdout_id()] * len(slots)
        key = (ob.data.as_pointer() if ob.type == 'MESH' else ob.original.name_full, tuple(slots))
        if key not in self._ids:
            self._ids[key] = self._add_mesh(ob, name, slots)
        mesh_id, triangles = self._ids[key]
        if mesh_id is None:
            return 0                   # no faces (only loose edges or points): nothing to hit
        visibility = _ray_visibility(ob)
        instance_id = self._core_scene.add_instance(mesh_id=mesh_id,
                                                    transform=camera.matrix_to_numpy(instance.matrix_world),
                                                    name=name, **visibility)
        self.instances_by_object.setdefault(ob.original.name_full, []).append(instance_id)
        return triangles

    def _add_mesh(self, ob, name, slots):
        triangles = mesh.triangle_mesh(ob)
        if triangles is None:
            return None, 0
        mesh_id = self._core_scene.add_mesh_data(name=ob.data.name if ob.data else name,
                                                 vertices=triangles.vertices, triangles=triangles.triangles,
                                                 normals=triangles.normals, uvs=triangles.uvs,
                                                 material_ids=mesh.scene_material_ids(triangles.slots, slots))
        return mesh_id, len(triangles.triangles)


def _ray_visibility(ob):
    """Cycles' object ray visibility, as the core's three ray kinds (diffuse, glossy and transmission rays are
    one kind there: 'indirect', seen if any of the three sees the object)."""
    camera_ray = bool(getattr(ob, "visible_camera", True))
    shadow = bool(getattr(ob, "visible_shadow", True))
    indirect = any(bool(getattr(ob, attr, True))
                   for attr in ("visible_diffuse", "visible_glossy", "visible_transmission"))
    return dict(visible_camera=camera_ray, visible_shadow=shadow, visible_indirect=indirect)


def _is_holdout(instance):
    """Object holdout (Object > Visibility > Holdout), or a holdout collection of the view layer."""
    ob = instance.object
    return bool(getattr(ob, "is_holdout", False))


class _MaterialTable:
    """Adds every Blender material to the core scene once, and remembers its index there."""

    def __init__(self, core_scene, notes):
        self._core_scene = core_scene
        self._notes = notes
        self._ids = {}
        self._textures = {}            # image name -> core texture index
        self._holdout = None
        self.emissive = False          # whether any material emits light

    @property
    def count(self):
        return len(self._ids) + (self._holdout is not None)

    def holdout_id(self):
        """One black material cut out of the image, for objects marked as holdout."""
        if self._holdout is None:
            spec = materials.holdout_material()
            self._holdout = self._core_scene.add_material(**spec.core_arguments())
        return self._holdout

    def id_for(self, material):
        key = None if material is None else material.name_full
        if key not in self._ids:
            spec = materials.convert_material(material)
            arguments = spec.core_arguments()
            if spec.texture is not None:
                arguments["texture"] = self._texture_index(spec)
            self._ids[key] = self._core_scene.add_material(**arguments)
            self.emissive = self.emissive or max(spec.emission) > 0.0
            if spec.notes:
                self._notes.append(f"Material '{spec.name}': " + "; ".join(_unique(spec.notes)))
        return self._ids[key]

    def _texture_index(self, spec):
        """Core index of the image of `spec.texture` (added once per image); a failure to read it becomes a note
        and the material keeps its plain colour."""
        reference = spec.texture
        if reference.key not in self._textures:
            try:
                self._textures[reference.key] = textures.add_texture(self._core_scene, reference)
            except (ValueError, RuntimeError) as error:
                self._notes.append(f"Material '{spec.name}': image '{reference.image.name}' not readable "
                                   f"({error}); its colour is used")
                self._textures[reference.key] = -1
        return self._textures[reference.key]


def _instance_name(instance):
    """A readable name for error messages; instances generated by particles or nodes get their id."""
    ob = instance.object
    if instance.is_instance:
        return f"{ob.name} (instance {instance.persistent_id[0]} of {instance.parent.name})"
    return ob.name


def _unique(lines):
    return list(dict.fromkeys(lines))
