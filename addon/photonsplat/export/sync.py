"""The one Blender sync: an evaluated depsgraph -> the core Scene (meshes, instances, materials, textures, lights,
world), for the final render and the Rendered viewport alike, as Cycles' BlenderSync serves both.

The final render (export_frame) syncs a new BlenderSync once. The viewport keeps one between redraws and calls
sync() on every view_update. Walking depsgraph.object_instances is cheap (a matrix per instance), and so are the
lights and the world, so those are read every time and compared with what the core scene holds. What costs is
reading geometry and building BVHs, so:
  - mesh arrays are kept per evaluated mesh (instancing.mesh_key) and read from Blender again only when the
    depsgraph says their object's geometry changed (or they are new);
  - a change of transforms only (moved objects, moved instancers) calls Scene.set_instance_transform on the
    existing core scene: the next render refits the top-level BVH, every mesh BVH is kept;
  - changed lights (and portals) are replaced with Scene.clear_lights + add_*_light / add_portal, a changed
    world (its constant, its node program, an image or a rotation in it) with set_background and
    set_world_program: no mesh, instance or BVH touched; the world's images go into the scene's one texture
    table, the materials' (an image both use is added once);
  - anything else (an object added, removed, re-meshed or given another material, an edited material or
    texture) builds a new core Scene from the kept arrays: only edited meshes are read from Blender, but
    the core then rebuilds every BVH (it cannot remove instances or replace a mesh's data in place).
In-place changes need the scene to be out of use (the core forbids changing a scene a render reads): sync()
asks the caller through `release()` and builds a new scene instead when it is refused.

The first sync fills its new core Scene while it walks the depsgraph, one mesh read at a time; a sync for one
render (keep_arrays=False) keeps no arrays at all, so a final render holds each mesh's arrays only until the
core has copied them.

Nothing here raises for a merely unusual scene: whatever is approximated or skipped becomes a line in
`BlenderSync.notes`, the one list the final render and the viewport both report (warning_lines). Real errors
(no camera) raise ExportError with a message meant for the user; the core itself raises ValueError for invalid
data.
"""

from dataclasses import dataclass, field

import numpy as np

from .. import compat
from .. import settings as settings_table
from . import camera, lights, mesh, world
from .instancing import GeometryTable, MaterialTable, instance_name, mesh_needs, placement, unique

# Notes beyond this many are summarised in one line: a scene with 500 odd materials should not bury the report.
MAX_WARNINGS_SHOWN = 20


class ExportError(Exception):
    """The scene cannot be rendered; the message tells the user what to change."""


def render_settings(core, props, **overrides):
    """Core RenderSettings of scene.photonsplat `props`; `overrides` set fields that do not come from it
    (caustics_pass, transparent) or replace some that do."""
    return core.RenderSettings(**dict(render_settings_kwargs(props), **overrides))


def render_settings_kwargs(props):
    """scene.photonsplat -> core RenderSettings keyword arguments: the one conversion, used by the final render
    and the viewport alike, from the core's settings table."""
    return settings_table.render_settings_kwargs(props)


def warning_lines(notes):
    """The lines a render engine reports for `notes`, at most MAX_WARNINGS_SHOWN of them and a count of the rest."""
    lines = [f"Photon Splat: {note}" for note in notes[:MAX_WARNINGS_SHOWN]]
    if len(notes) > MAX_WARNINGS_SHOWN:
        lines.append(f"Photon Splat: {len(notes) - MAX_WARNINGS_SHOWN} more warnings not shown")
    return lines


@dataclass
class SyncReport:
    """What one sync() did: the viewport restarts its refinement when `changed`; the tests count it."""
    meshes: int = 0             # meshes read from Blender
    lights: int = 0             # lights exported (0: the lights did not change)
    moved: int = 0              # set_instance_transform calls
    world: bool = False         # the world (background constant or program) changed
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


class _Build:
    """A new core Scene being filled: materials, meshes and instances as placements come (lights and the world
    are added by BlenderSync once the depsgraph walk is over)."""

    def __init__(self, core, specs=None):
        self.scene = core.Scene()
        # Each mesh's BVH is built by the core on a thread of its own while the next mesh is read from Blender.
        if hasattr(self.scene, "build_bvhs_ahead"):
            self.scene.build_bvhs_ahead = True
        self.scene.multiscatter_light_estimate = compat.MULTISCATTER_LIGHT_ESTIMATE
        self.scene.bump_shadowing = compat.BUMP_SHADOWING
        self.material_notes = []
        self.materials = MaterialTable(self.scene, self.material_notes, specs)
        self.geometry = GeometryTable(self.scene, self.materials)
        self.instance_ids = {}       # instance name -> core instance id
        self.triangles = 0           # triangles in the world, every instance counted

    def add(self, where, read_mesh):
        instance_id, triangles = self.geometry.add(where, read_mesh)
        if instance_id is not None:
            self.instance_ids[where.name] = instance_id
            self.triangles += triangles


class BlenderSync:
    """The core Scene of a depsgraph, kept up to date by sync(). `scene` and `notes` are current after each call."""

    def __init__(self, core, keep_arrays=True):
        self.core = core
        self.scene = None            # the core Scene
        self.notes = []              # what was approximated or skipped, one line each
        self._keep_arrays = keep_arrays
        self._arrays = {}            # mesh key -> mesh.TriangleMesh (None: no faces), object space
        self._read = set()           # mesh keys read during the running sync
        self._layout = {}            # instance name -> (Placement.signature, (4, 4) matrix) in self.scene
        self._build = None           # the _Build of self.scene: its tables, instance ids and counts
        self._light_calls = None     # add_*_light calls in self.scene
        self._light_notes = []
        self._object_notes = []
        self._world = None           # world.WorldSpec in self.scene
        self._world_signature = None
        self._world_notes = []
        self._materials_dirty = False
        self._specs = {}             # material name -> MaterialSpec, converted again when materials change
        # Totals since creation, for the stats line and the tests.
        self.mesh_exports = 0        # meshes read from Blender
        self.light_exports = 0       # times the lights were replaced
        self.builds = 0              # core Scenes built
        self.transform_updates = 0   # set_instance_transform calls

    def sync(self, depsgraph, release=None):
        """Brings self.scene up to date with `depsgraph` (its updates tell which geometry and materials changed
        since the last call). release() is called before changing the current scene in place and must return
        True once no render uses it (None: it is not in use); False makes sync build a new scene."""
        try:
            return self._sync(depsgraph, release)
        except Exception:
            self.scene = None        # half-updated: the next sync builds a new scene from scratch
            raise
        finally:
            self._read.clear()

    def _sync(self, depsgraph, release):
        report = SyncReport()
        # The first sync builds its scene during the walk; later ones know only at its end whether they must.
        build = _Build(self.core, self._specs) if self.scene is None else None
        dirty_objects, dirty_data = self._dirty(depsgraph) if build is None else (set(), set())
        if self._materials_dirty:
            self._specs.clear()
        placements, recorder, light_notes, object_notes = [], _CallRecorder(), [], []
        known_objects = {signature[0] for signature, _ in self._layout.values()}
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
                if build is not None:
                    build.add(where, lambda needs: self._mesh_arrays(ob, where.mesh_key, report, needs))
                else:
                    generator = instance.parent.original.name_full if instance.is_instance else None
                    dirty = (where.object_name in dirty_objects or generator in dirty_objects
                             or where.object_name not in known_objects
                             or (ob.data is not None and ob.data.name_full in dirty_data))
                    needs = mesh_needs(self._specs, where)
                    kept = self._arrays.get(where.mesh_key)
                    if dirty or where.mesh_key not in self._arrays or (kept is not None
                                                                       and not kept.provides(needs)):
                        self._mesh_arrays(ob, where.mesh_key, report, needs)
                placements.append(where)
            elif ob.type in mesh.UNSUPPORTED_TYPES:
                object_notes.append(f"Object '{instance_name(instance)}': {ob.type.lower()} objects are not "
                                    "supported yet, skipped")
        self._object_notes = object_notes
        # What the core takes (a core older than world programs and portals gets the constant world, no portals).
        target = build.scene if build is not None else self.scene
        spec = world.convert_world(depsgraph.scene_eval.world, programs=hasattr(target, "set_world_program"))
        light_notes += self._portal_notes(recorder, hasattr(target, "add_portal"))
        used = {where.mesh_key for where in placements}
        for stale in set(self._arrays) - used:
            del self._arrays[stale]

        layout = {where.name: (where.signature, where.matrix) for where in placements}
        lights_changed = recorder.calls != self._light_calls
        if lights_changed:
            self._light_calls, self._light_notes = recorder.calls, light_notes
            self.light_exports += 1
            report.lights = max(1, len(recorder.calls))
        signature = spec.signature
        world_changed = signature != self._world_signature
        if world_changed:
            self._world, self._world_signature, self._world_notes = spec, signature, spec.report_lines()
            report.world = True

        reason = "first export" if build is not None else self._rebuild_reason(layout, report)
        # (An instance of a mesh without faces is not in the core scene: its moves change nothing.)
        ids = self._build.instance_ids if self._build is not None else {}
        moved = [name for name, (_, matrix) in layout.items()
                 if name in ids and not np.array_equal(matrix, self._layout[name][1])] if not reason else []
        in_place = bool(moved or lights_changed or world_changed)
        if not reason and in_place and release is not None and not release():
            reason = "the running render did not stop in time"
        if reason:
            if build is None:
                build = _Build(self.core, self._specs)
                for where in placements:
                    build.add(where, lambda needs, key=where.mesh_key: self._arrays[key])
            self._finish(build)
            report.rebuilt, report.reason = True, reason
        elif in_place:
            scene = self.scene
            for name in moved:
                scene.set_instance_transform(ids[name], layout[name][1])
            if moved:
                scene.fit_origin()   # objects moved far keep their precision (the core's render origin)
            report.moved = len(moved)
            self.transform_updates += report.moved
            if lights_changed:
                scene.clear_lights()
                self._add_lights(scene)
            if world_changed:
                self._apply_world(scene, self._build)
        self._layout = layout
        self.notes = self._current_notes()
        return report

    def _dirty(self, depsgraph):
        """(objects whose geometry changed, mesh data blocks changed), by name, from depsgraph.updates; flags
        the materials when a material, node tree or image changed."""
        import bpy

        dirty_objects, dirty_data = set(), set()
        scene_world = depsgraph.scene.world
        world_trees = set()
        if scene_world is not None and getattr(scene_world, "node_tree", None) is not None:
            world_trees.add(_original_pointer(scene_world.node_tree))
        for update in depsgraph.updates:
            item = update.id
            if isinstance(item, bpy.types.Object):
                if update.is_updated_geometry:
                    dirty_objects.add(item.name_full)
            elif isinstance(item, bpy.types.Mesh):
                dirty_data.add(item.name_full)
            elif isinstance(item, bpy.types.ShaderNodeTree) and _original_pointer(item) in world_trees:
                pass        # the world's own node tree: the world is compared whole every sync
            elif isinstance(item, (bpy.types.Material, bpy.types.ShaderNodeTree, bpy.types.Image)):
                # A node tree edit may reach us as the tree only (its material not listed): all materials are
                # converted again, which the core can only do in a new scene.
                self._materials_dirty = True
        return dirty_objects, dirty_data

    def _mesh_arrays(self, ob, key, report, needs):
        """The arrays of evaluated object `ob` with what mesh.MeshNeeds `needs` asks for, read from Blender once
        per sync (kept when keep_arrays), again when another object's materials need more of the same mesh."""
        if key in self._read:
            kept = self._arrays[key]
            if kept is None or kept.provides(needs):
                return kept
            needs = needs | mesh.MeshNeeds(tuple(sorted(kept.attributes)), kept.texspace is not None,
                                           uvs=kept.uvs_read, slots=kept.slots is not None)
        arrays = mesh.triangle_mesh(ob, needs)
        self.mesh_exports += 1
        report.meshes += 1
        if self._keep_arrays:
            self._arrays[key] = arrays
            self._read.add(key)
        return arrays

    def _rebuild_reason(self, layout, report):
        if report.meshes:
            return "geometry changed"
        if self._materials_dirty:
            return "materials changed"
        if {name: signature for name, (signature, _) in layout.items()} != \
                {name: signature for name, (signature, _) in self._layout.items()}:
            return "objects added, removed or changed"
        return ""

    def _finish(self, build):
        """Completes `build` with the lights and the world and makes it the current scene."""
        self._add_lights(build.scene)
        self._apply_world(build.scene, build)
        self.scene, self._build = build.scene, build
        self._materials_dirty = False
        self.builds += 1

    def _add_lights(self, scene):
        for method, args, kwargs in self._light_calls:
            getattr(scene, method)(*args, **kwargs)

    @staticmethod
    def _portal_notes(recorder, supported):
        """Drops the portals of `recorder` when the core has no add_portal (not `supported`); the notes."""
        if supported:
            return []
        portals = [args[0] if args else kwargs.get("name") for method, args, kwargs in recorder.calls
                   if method == "add_portal"]
        recorder.calls = [call for call in recorder.calls if call[0] != "add_portal"]
        return [f"Light '{name}': portals not supported by this core, skipped" for name in portals]

    def _apply_world(self, scene, build):
        """The world of self._world into `scene` (its images through the texture table of `build`)."""
        spec = self._world
        scene.set_background(radiance=tuple(spec.radiance))
        if not hasattr(scene, "set_world_program"):
            return
        if spec.uses_program:
            program = spec.core_program(lambda reference: self._world_texture(build, reference))
            scene.set_world_program(program, map_resolution=int(spec.map_resolution))
        else:
            scene.set_world_program(None)

    def _world_texture(self, build, reference):
        """Core index of the world's image of `reference`, in the scene's one texture table (the materials'): an
        image the materials use too is not added again. An unreadable image is a note and renders magenta."""
        return build.materials.texture_index(reference, lambda error: self._world_notes.append(
            f"World '{self._world.name}': image '{reference.image.name}' not readable ({error}); rendered magenta"))

    def _current_notes(self):
        notes = self._build.material_notes + self._light_notes + self._object_notes + self._world_notes
        if not self.lights and not self._build.materials.emissive and not self._world.emits:
            notes.append("The scene has no lights, no emissive surfaces and a black world: the image will be black")
        return unique(notes)

    # --- what the current scene holds ---------------------------------------------------------------------
    @property
    def meshes(self):
        """Distinct meshes (each stored once in the core)."""
        return 0 if self._build is None else self._build.geometry.count

    @property
    def instances(self):
        """Placements of them: objects, collection / particle / geometry-node instances."""
        return 0 if self._build is None else len(self._build.instance_ids)

    @property
    def triangles(self):
        """Triangles in the world, every instance counted."""
        return 0 if self._build is None else self._build.triangles

    @property
    def lights(self):
        """Lights exported (portals, which emit nothing, not counted)."""
        return sum(1 for method, _, _ in self._light_calls or () if method != "add_portal")

    @property
    def portals(self):
        return sum(1 for method, _, _ in self._light_calls or () if method == "add_portal")

    @property
    def materials(self):
        return 0 if self._build is None else self._build.materials.count

    @property
    def object_instances(self):
        """Original object name -> core instance ids showing it (its own mesh and every instance it generates or
        that shows it)."""
        return {} if self._build is None else self._build.geometry.instances_by_object


def _original_pointer(id_block):
    """as_pointer() of the original of an (evaluated) ID block."""
    original = getattr(id_block, "original", None) or id_block
    return original.as_pointer()


@dataclass
class ExportedFrame:
    """What the final render gives the core: the scene of one sync, the camera, the settings."""
    scene: object                  # core Scene
    camera: object                 # core Camera
    settings: object               # core RenderSettings
    width: int
    height: int
    warnings: list = field(default_factory=list)
    meshes: int = 0
    instances: int = 0
    triangles: int = 0
    object_instances: dict = field(default_factory=dict)
    lights: int = 0
    materials: int = 0


def export_frame(core, depsgraph, camera_override=None):
    """The final render's export of the evaluated scene of `depsgraph` (one sync). `camera_override` replaces
    scene.camera. With a render border, the camera covers only the border's pixels and width/height are the
    border's size."""
    scene = depsgraph.scene
    notes = []
    # The camera first: without one there is nothing to render, so fail before the costly geometry export.
    full_width, full_height = camera.resolution(scene)
    region = camera.border_region(scene, full_width, full_height)
    try:
        core_camera = camera.export_camera(core, depsgraph, camera_override or scene.camera, full_width,
                                           full_height, notes, region=region)
    except camera.CameraError as error:
        raise ExportError(str(error)) from None
    settings = render_settings(core, scene.photonsplat)
    sync = BlenderSync(core, keep_arrays=False)
    sync.sync(depsgraph)
    return ExportedFrame(scene=sync.scene, camera=core_camera, settings=settings, width=region[2] - region[0],
                         height=region[3] - region[1], warnings=unique(notes + sync.notes), meshes=sync.meshes,
                         instances=sync.instances, triangles=sync.triangles, object_instances=sync.object_instances,
                         lights=sync.lights, materials=sync.materials)
