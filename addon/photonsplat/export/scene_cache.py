"""The exported scene kept between viewport updates, so that a change re-exports only what it touched.

The viewport calls sync() on every depsgraph update. Walking depsgraph.object_instances is cheap (a matrix per
instance); what costs is reading geometry, so mesh arrays are cached per object and read again only when the
depsgraph says that object's geometry changed (or it is new). A transform-only change therefore exports no
mesh, a moved light re-exports only the lights, an edited material only that material.

build() then makes a fresh core Scene from the cached arrays. (Once the core can move instances of a
resident mesh, build() becomes an update of the transforms instead of a rebuild.)

Kept apart from export_frame() (the final render's one-shot export) on purpose: a frame render has no previous
state to reuse; both use the same per-concept converters (mesh, lights, materials, world).
"""

from dataclasses import dataclass, field

import numpy as np

from . import camera, lights, materials, mesh, world


@dataclass
class _CachedMesh:
    arrays: object                  # mesh.TriangleMesh, object space
    material_keys: list             # per slot: the material's name_full (None = default material)
    data_name: str                  # the Mesh datablock's name: edits to it dirty this object


@dataclass
class SyncReport:
    """What one sync() exported: the viewport shows it in its stats line and the tests count it."""
    meshes: int = 0
    lights: int = 0
    materials: int = 0
    world: bool = False
    structure: bool = False          # objects appeared, disappeared or moved

    @property
    def changed(self):
        return bool(self.meshes or self.lights or self.materials or self.world or self.structure)


class _CallRecorder:
    """Stands in for a core Scene while lights are exported: records add_*_light calls to replay on each
    build (light export stays the one in lights.py, whatever light kinds it learns)."""

    def __init__(self):
        self.calls = []

    def __getattr__(self, method):
        def record(*args, **kwargs):
            self.calls.append((method, args, kwargs))
        return record


@dataclass
class SceneCache:
    meshes: dict = field(default_factory=dict)      # object name -> _CachedMesh
    instances: dict = field(default_factory=dict)   # instance name -> (object name, (4, 4) transform)
    materials: dict = field(default_factory=dict)   # material key -> core add_material() arguments
    light_calls: list = field(default_factory=list)
    light_count: int = 0
    background: tuple = (0.0, 0.0, 0.0)
    notes: list = field(default_factory=list)
    # Totals since creation: how many times geometry / lights were read from Blender.
    mesh_exports: int = 0
    light_exports: int = 0
    _synced: bool = False

    def sync(self, depsgraph):
        """Brings the cache up to date with `depsgraph` (its updates tell what changed since the last call)."""
        import bpy

        report = SyncReport()
        full = not self._synced
        dirty_objects, dirty_data, dirty_materials = set(), set(), set()
        lights_dirty = world_dirty = full
        for update in depsgraph.updates:
            item = update.id
            if isinstance(item, bpy.types.Object):
                if item.type == 'LIGHT':
                    lights_dirty = True
                elif update.is_updated_geometry:
                    dirty_objects.add(item.name)
            elif isinstance(item, bpy.types.Light):
                lights_dirty = True
            elif isinstance(item, bpy.types.Mesh):
                dirty_data.add(item.name)
            elif isinstance(item, bpy.types.Material):
                dirty_materials.add(item.name_full)
            elif isinstance(item, bpy.types.World):
                world_dirty = True
            elif isinstance(item, (bpy.types.ShaderNodeTree, bpy.types.Scene)):
                # A node tree edit reaches us as the tree (its material may not be listed) and a scene
                # update may be a world swap: re-read materials and world, both cheap.
                dirty_materials.update(self.materials)
                world_dirty = True
        for key in dirty_materials & set(self.materials):
            self.materials[key] = self._convert_material(key)
            report.materials += 1

        seen, present = {}, set()
        recorder = _CallRecorder() if lights_dirty else None
        for instance in depsgraph.object_instances:
            # An instance is only valid during its own iteration step: copy what is kept.
            ob = instance.object
            if not instance.show_self:
                continue
            name = _instance_name(instance)
            if ob.type == 'LIGHT':
                if recorder is not None and lights.export_light(recorder, name, ob.data,
                                                                instance.matrix_world.copy(), self.notes):
                    report.lights += 1
            elif ob.type == 'MESH':
                present.add(ob.name)
                cached = self.meshes.get(ob.name)
                if cached is None or ob.name in dirty_objects or cached.data_name in dirty_data:
                    cached = self._export_mesh(ob)
                    self.meshes[ob.name] = cached
                    report.meshes += 1
                if cached.arrays is not None:
                    seen[name] = (ob.name, camera.matrix_to_numpy(instance.matrix_world))
        if recorder is not None:
            self.light_calls = recorder.calls
            self.light_count = report.lights
            self.light_exports += 1
        if world_dirty:
            self.background = world.background_radiance(depsgraph.scene_eval.world, self.notes)
            report.world = True

        report.structure = not _same_instances(seen, self.instances)
        self.instances = seen
        # Geometry of objects no longer in the scene is dropped.
        for stale in set(self.meshes) - present:
            del self.meshes[stale]
        self._synced = True
        return report

    def build(self, core):
        """A core Scene holding everything cached."""
        scene = core.Scene()
        ids = {key: scene.add_material(**arguments) for key, arguments in self.materials.items()}
        for name, (object_name, transform) in self.instances.items():
            cached = self.meshes[object_name]
            arrays = cached.arrays
            slot_ids = [ids[key] for key in cached.material_keys]
            scene.add_mesh(name=name, vertices=arrays.vertices, triangles=arrays.triangles,
                           normals=arrays.normals, material_ids=mesh.scene_material_ids(arrays.slots, slot_ids),
                           transform=transform)
        for method, args, kwargs in self.light_calls:
            getattr(scene, method)(*args, **kwargs)
        scene.set_background(radiance=self.background)
        return scene

    def _export_mesh(self, ob):
        self.mesh_exports += 1
        arrays = mesh.triangle_mesh(ob)
        keys = [slot.material.name_full if slot.material else None for slot in ob.material_slots] or [None]
        for slot, key in zip(ob.material_slots, keys):
            if key not in self.materials:
                self.materials[key] = self._convert_material(key, slot.material)
        if None in keys and None not in self.materials:
            self.materials[None] = self._convert_material(None)
        return _CachedMesh(arrays=arrays, material_keys=keys, data_name=ob.data.name)

    def _convert_material(self, key, material=None):
        import bpy

        if material is None and key is not None:
            material = bpy.data.materials.get(key)
        spec = materials.convert_material(material)
        if spec.notes:
            self.notes.append(f"Material '{spec.name}': " + "; ".join(dict.fromkeys(spec.notes)))
        return spec.core_arguments()


def _instance_name(instance):
    ob = instance.object
    if instance.is_instance:
        return f"{ob.name} (instance {instance.persistent_id[0]} of {instance.parent.name})"
    return ob.name


def _same_instances(a, b):
    if a.keys() != b.keys():
        return False
    return all(a[k][0] == b[k][0] and np.array_equal(a[k][1], b[k][1]) for k in a)
