"""The viewport's core Scene, kept between depsgraph updates and changed only where the scene changed.

sync() runs on every view_update. Walking depsgraph.object_instances is cheap (a matrix per instance), and so
are the lights and the world, so those are read every time and compared with what the core scene holds. What
costs is reading geometry and building BVHs, so:
  - mesh arrays are cached per evaluated mesh (instancing.mesh_key) and read from Blender again only when the
    depsgraph says their object's geometry changed (or they are new);
  - a change of transforms only (moved objects, moved instancers) calls Scene.set_instance_transform on the
    existing core scene: the next render refits the top-level BVH, every mesh BVH is kept;
  - changed lights are replaced with Scene.clear_lights + add_*_light, a changed world with set_background:
    no mesh, instance or BVH touched;
  - anything else (an object added, removed, re-meshed or given another material, an edited material or
    texture) builds a new core Scene from the cached arrays: only edited meshes are read from Blender, but
    the core then rebuilds every BVH (it cannot remove instances or replace a mesh's data in place).
In-place changes need the scene to be out of use (the core forbids changing a scene a render reads): sync()
asks the caller through `release()` and builds a new scene instead when it is refused.

Meshes, instances and materials go through export.instancing, as in the final render's export_frame.
"""

from dataclasses import dataclass

import numpy as np

from . import lights, mesh, world
from .instancing import GeometryTable, MaterialTable, instance_name, placement, unique


@dataclass
class SyncReport:
    """What one sync() did: the viewport restarts its refinement when `changed`; the tests count it."""
    meshes: int = 0             # meshes read from Blender
    lights: int = 0             # lights exported (0: the lights did not change)
    moved: int = 0              # set_instance_transform calls
    world: bool = False         # background changed
    rebuilt: bool = False       # a new core Scene was built
    reason: str = ""            # why it was rebuilt

    @property
    def changed(self):
        return bool(self.meshes or self.lights or self.moved or self.world or self.rebuilt)


class _CallRecorder:
    """Stands in for a core Scene while lights are exported: records add_*_light calls to compare with the last
    ones and replay (light export stays the one in lights.py, whatever light kinds it learns)."""

    def __init__(self):
        self.calls = []

    def __getattr__(self, method):
        def record(*args, **kwargs):
            self.calls.append((method, args, kwargs))
        return record


class SceneCache:
    def __init__(self):
        self.scene = None            # the core Scene, current after each sync()
        self.notes = []              # approximation notes of the current scene (as export_frame words them)
        self._arrays = {}            # mesh key -> mesh.TriangleMesh (None: no faces), object space
        self._layout = {}            # instance name -> (Placement.signature, (4, 4) matrix) in self.scene
        self._instance_ids = {}      # instance name -> core instance id in self.scene
        self._light_calls = None     # add_*_light calls in self.scene
        self._light_notes = []
        self._background = None
        self._world_notes = []
        self._material_notes = []
        self._materials_dirty = False
        # Totals since creation, for the stats line and the tests.
        self.mesh_exports = 0        # meshes read from Blender
        self.light_exports = 0       # times the lights were replaced
        self.builds = 0              # core Scenes built
        self.transform_updates = 0   # set_instance_transform calls

    def sync(self, core, depsgraph, release=None):
        """Brings self.scene up to date with `depsgraph` (its updates tell which geometry and materials
        changed since the last call). release() is called before changing the current scene in place and must
        return True once no render uses it (None: it is not in use); False makes sync build a new scene."""
        try:
            return self._sync(core, depsgraph, release)
        except Exception:
            self.scene = None        # half-updated: the next sync builds a new scene from scratch
            raise

    def _sync(self, core, depsgraph, release):
        import bpy

        report = SyncReport()
        dirty_objects, dirty_data = set(), set()
        for update in depsgraph.updates:
            item = update.id
            if isinstance(item, bpy.types.Object):
                if update.is_updated_geometry:
                    dirty_objects.add(item.name_full)
            elif isinstance(item, bpy.types.Mesh):
                dirty_data.add(item.name_full)
            elif isinstance(item, (bpy.types.Material, bpy.types.ShaderNodeTree, bpy.types.Image)):
                # A node tree edit may reach us as the tree only (its material not listed): all materials are
                # converted again, which the core can only do in a new scene.
                self._materials_dirty = True

        placements, recorder, light_notes = [], _CallRecorder(), []
        known_objects = {signature[0] for signature, _ in self._layout.values()}
        fresh = set()                # mesh keys read during this sync
        for instance in depsgraph.object_instances:
            # An instance is only valid during its own iteration step: copy what is kept.
            ob = instance.object
            if not instance.show_self:
                continue
            if ob.type == 'LIGHT':
                lights.export_light(recorder, instance_name(instance), ob.data, instance.matrix_world.copy(),
                                    light_notes)
            elif ob.type == 'MESH' or mesh.needs_to_mesh(instance):
                where = placement(instance)
                generator = instance.parent.original.name_full if instance.is_instance else None
                dirty = (where.object_name in dirty_objects or generator in dirty_objects
                         or where.object_name not in known_objects
                         or (ob.data is not None and ob.data.name_full in dirty_data))
                if where.mesh_key not in fresh and (dirty or where.mesh_key not in self._arrays):
                    self._arrays[where.mesh_key] = mesh.triangle_mesh(ob)
                    fresh.add(where.mesh_key)
                    self.mesh_exports += 1
                    report.meshes += 1
                placements.append(where)
        world_notes = []
        background = tuple(world.background_radiance(depsgraph.scene_eval.world, world_notes))
        used = {where.mesh_key for where in placements}
        for stale in set(self._arrays) - used:
            del self._arrays[stale]

        layout = {where.name: (where.signature, where.matrix) for where in placements}
        lights_changed = recorder.calls != self._light_calls
        if lights_changed:
            self._light_calls, self._light_notes = recorder.calls, light_notes
            self.light_exports += 1
            report.lights = max(1, len(recorder.calls))
        world_changed = background != self._background
        if world_changed:
            self._background, self._world_notes = background, world_notes
            report.world = True

        reason = self._rebuild_reason(layout, report)
        # (An instance of a mesh without faces is not in the core scene: its moves change nothing.)
        moved = [name for name, (_, matrix) in layout.items()
                 if name in self._instance_ids and not np.array_equal(matrix, self._layout[name][1])
                 ] if not reason else []
        in_place = bool(moved or lights_changed or world_changed)
        if not reason and in_place and release is not None and not release():
            reason = "the running render did not stop in time"
        if reason:
            self._build(core, placements)
            report.rebuilt, report.reason = True, reason
        elif in_place:
            scene = self.scene
            for name in moved:
                scene.set_instance_transform(self._instance_ids[name], layout[name][1])
            if moved:
                scene.fit_origin()   # objects moved far keep their precision (the core's render origin)
            report.moved = len(moved)
            self.transform_updates += report.moved
            if lights_changed:
                scene.clear_lights()
                self._add_lights(scene)
            if world_changed:
                scene.set_background(radiance=self._background)
        self._layout = layout
        self.notes = self._current_notes()
        return report

    def _rebuild_reason(self, layout, report):
        if self.scene is None:
            return "first export"
        if report.meshes:
            return "geometry changed"
        if self._materials_dirty:
            return "materials changed"
        if {name: signature for name, (signature, _) in layout.items()} != \
                {name: signature for name, (signature, _) in self._layout.items()}:
            return "objects added, removed or changed"
        return ""

    def _build(self, core, placements):
        """A new core Scene from the cached arrays (materials converted again, as export_frame does)."""
        scene = core.Scene()
        material_notes = []
        table = MaterialTable(scene, material_notes)
        geometry = GeometryTable(scene, table)
        ids = {}
        for where in placements:
            instance_id, _ = geometry.add(where, lambda key=where.mesh_key: self._arrays[key])
            if instance_id is not None:
                ids[where.name] = instance_id
        self._add_lights(scene)
        scene.set_background(radiance=self._background)
        if not self._light_calls and not table.emissive and max(self._background) <= 0.0:
            material_notes.append("The scene has no lights, no emissive surfaces and a black world: "
                                  "the image will be black")
        self.scene, self._instance_ids, self._material_notes = scene, ids, material_notes
        self._materials_dirty = False
        self.builds += 1

    def _add_lights(self, scene):
        for method, args, kwargs in self._light_calls:
            getattr(scene, method)(*args, **kwargs)

    def _current_notes(self):
        return unique(self._material_notes + self._light_notes + self._world_notes)

    @property
    def meshes(self):
        """Core meshes in the current scene."""
        return 0 if self.scene is None else self.scene.mesh_count

    @property
    def instances(self):
        return 0 if self.scene is None else self.scene.instance_count
