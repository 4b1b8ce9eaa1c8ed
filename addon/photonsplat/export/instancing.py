"""How Blender's object instances become core meshes, instances and materials, for the sync (sync.py) that
serves the final render and the viewport alike.

Every entry of depsgraph.object_instances becomes a Placement (plain data, read while the instance is valid:
an instance object lives only during its own iteration step). GeometryTable adds each distinct mesh to a core
scene once and one core instance per placement; MaterialTable adds each Blender material once.
"""

from dataclasses import dataclass

import numpy as np

from . import camera, materials, mesh, textures


@dataclass
class Placement:
    """One object or instance showing a mesh, as read from depsgraph.object_instances."""
    name: str                # readable and unique per instance (core instance name, messages)
    object_name: str         # the original object (name_full): what a user moves or edits
    mesh_key: tuple          # the evaluated mesh it shows: equal keys share one core mesh
    mesh_name: str           # the mesh's name in the core (messages)
    materials: tuple         # per material slot: the Blender material or None; (None,) without slots
    holdout: bool
    visibility: tuple        # (camera, shadow, indirect) ray visibility
    matrix: np.ndarray       # float64 (4, 4) object to world
    object_info: dict = None  # Object Info: colour, pass index, random (given to the core when a program reads it)
    terminator_offset: float = 0.1  # Cycles' shadow terminator Geometry Offset (terminator_offset below)

    @property
    def signature(self):
        """Everything but the transform: equal signatures differ at most by a set_instance_transform."""
        keys = tuple(None if m is None else m.name_full for m in self.materials)
        info = None if self.object_info is None else tuple(sorted(self.object_info.items()))
        return (self.object_name, self.mesh_key, keys, self.holdout, self.visibility, info, self.terminator_offset)


def placement(instance, name=None):
    """The Placement of a depsgraph instance whose object is a mesh (or converts to one)."""
    ob = instance.object
    slots = tuple(slot.material for slot in ob.material_slots) or (None,)
    return Placement(name=name or instance_name(instance), object_name=ob.original.name_full,
                     mesh_key=mesh_key(ob), mesh_name=ob.data.name if ob.data else ob.name,
                     materials=slots, holdout=is_holdout(ob), visibility=ray_visibility(ob),
                     matrix=camera.matrix_to_numpy(instance.matrix_world), object_info=object_info(instance),
                     terminator_offset=terminator_offset(ob))


def terminator_offset(ob):
    """Cycles' Object > Shading > Shadow Terminator > Geometry Offset (0.1 unless changed): shadow rays from
    smooth triangles towards lights near their horizon start on the smooth surface (the core's
    shadow_terminator.h). Blender 3.x keeps it in the Cycles add-on's object settings, 4.x on the object."""
    for owner in (ob, getattr(ob, "cycles", None)):
        value = getattr(owner, "shadow_terminator_geometry_offset", None)
        if value is not None:
            return min(max(float(value), 0.0), 1.0)
    return 0.1


def object_info(instance):
    """What Cycles' Object Info node reads of a depsgraph instance: the object's colour and pass index, and its
    random number. Cycles 3.4 (blender/object.cpp) takes the depsgraph instance's random_id for an instance and
    hash_uint2(hash_string(object name), 0) for an object itself; the kernel's value is random_id / 0xFFFFFFFF in
    float (scene/object.cpp)."""
    ob = instance.object
    if instance.is_instance:
        random_id = int(getattr(instance, "random_id", 0)) & _MASK
    else:
        random_id = _hash_uint2(_hash_string(ob.name), 0)
    random = float(np.float32(random_id) * (np.float32(1.0) / np.float32(0xFFFFFFFF)))
    return {"color": tuple(float(c) for c in ob.color), "pass_index": int(ob.pass_index), "random": random}


_MASK = 0xFFFFFFFF


def _hash_string(text):
    """Cycles' hash_string (util/hash.h): i = i * 37 + c over the UTF-8 bytes (unsigned, as Blender 3.4's Cycles
    renders a non-ASCII name)."""
    i = 0
    for byte in text.encode("utf-8"):
        i = (i * 37 + byte) & _MASK
    return i


def _rot(x, k):
    return ((x << k) | (x >> (32 - k))) & _MASK


def _hash_uint2(kx, ky):
    """Cycles' hash_uint2: Bob Jenkins' lookup3 final mix of two words."""
    a = b = c = (0xDEADBEEF + (2 << 2) + 13) & _MASK
    b = (b + ky) & _MASK
    a = (a + kx) & _MASK
    c ^= b
    c = (c - _rot(b, 14)) & _MASK
    a ^= c
    a = (a - _rot(c, 11)) & _MASK
    b ^= a
    b = (b - _rot(a, 25)) & _MASK
    c ^= b
    c = (c - _rot(b, 16)) & _MASK
    a ^= c
    a = (a - _rot(c, 4)) & _MASK
    b ^= a
    b = (b - _rot(a, 14)) & _MASK
    c ^= b
    c = (c - _rot(b, 24)) & _MASK
    return c


def mesh_key(ob):
    """Which evaluated mesh an instance object shows. Instances of one mesh (particles, geometry nodes,
    collection instances, linked duplicates) share the same evaluated data block, hence the same key; a
    converted curve, text or metaball is keyed by its object."""
    if ob.type == 'MESH':
        return ('MESH', ob.data.as_pointer(), ob.data.name_full)
    return ('OBJECT', ob.original.name_full)


def instance_name(instance):
    """A readable name, unique per instance (the viewport cache keys its instances by it): an instance
    generated by particles, nodes or a collection gets its persistent id, the path of indices that Blender
    keeps for it across updates (unused trailing entries are INT_MAX)."""
    ob = instance.object
    if instance.is_instance:
        path = [i for i in instance.persistent_id if i != _UNUSED_ID] or [0]
        return f"{ob.name} (instance {'/'.join(map(str, path))} of {instance.parent.name})"
    return ob.name


_UNUSED_ID = 2**31 - 1


def ray_visibility(ob):
    """Cycles' object ray visibility, as the core's three ray kinds (diffuse, glossy and transmission rays are
    one kind there: 'indirect', seen if any of the three sees the object)."""
    camera_ray = bool(getattr(ob, "visible_camera", True))
    shadow = bool(getattr(ob, "visible_shadow", True))
    indirect = any(bool(getattr(ob, attr, True))
                   for attr in ("visible_diffuse", "visible_glossy", "visible_transmission"))
    return (camera_ray, shadow, indirect)


def is_holdout(ob):
    """Object holdout (Object > Visibility > Holdout)."""
    return bool(getattr(ob, "is_holdout", False))


def material_spec(specs, material):
    """The MaterialSpec of `material` (None: the default), converted once per cache `specs` (name -> spec)."""
    key = None if material is None else material.name_full
    if key not in specs:
        specs[key] = materials.convert_material(material)
    return specs[key]


def mesh_needs(specs, where):
    """What the materials of Placement `where` read from its mesh (mesh.MeshNeeds): only the attributes and the
    texture space that some program uses are exported, the render UV map only for materials that may read it, and
    the triangles' slots only when the slots hold different materials."""
    needs = mesh.MeshNeeds()
    if where.holdout:
        return needs
    # Per-triangle slots only matter where the slots hold different materials.
    names = {None if material is None else material.name_full for material in where.materials}
    needs = mesh.MeshNeeds(slots=len(names) > 1)
    for material in where.materials:
        spec = material_spec(specs, material)
        needs = needs | mesh.MeshNeeds(tuple(sorted(spec.attributes)), spec.uses_texspace, uvs=spec.uses_uvs)
    return needs


class GeometryTable:
    """Adds each distinct mesh (with its materials) to the core scene once, then one core instance per
    placement showing it: Embree builds each mesh's BVH once however often it is instanced."""

    def __init__(self, core_scene, material_table):
        self._core_scene = core_scene
        self._materials = material_table
        self._ids = {}                 # (mesh key, core material id per slot) -> (core mesh id, triangles)
        self.instances_by_object = {}  # original object name -> [core instance id]

    @property
    def count(self):
        return sum(1 for mesh_id, _ in self._ids.values() if mesh_id is not None)

    def add(self, where, read_mesh):
        """Adds Placement `where`; read_mesh(needs) gives its mesh.TriangleMesh (or None) with what mesh.MeshNeeds
        `needs` asks for, called only for a mesh not added yet. Returns (core instance id, triangles), (None, 0)
        when there is nothing to render."""
        slots = [self._materials.id_for(m) for m in where.materials]
        if where.holdout:
            slots = [self._materials.holdout_id()] * len(slots)
        key = (where.mesh_key, tuple(slots))
        if key not in self._ids:
            needs = mesh_needs(self._materials.specs, where)
            self._ids[key] = self._add_mesh(read_mesh(needs), where.mesh_name, slots, needs)
        mesh_id, triangles = self._ids[key]
        if mesh_id is None:
            return None, 0             # no faces (only loose edges or points): nothing to hit
        camera_ray, shadow, indirect = where.visibility
        extra = {}
        if not where.holdout and where.object_info is not None and any(
                material_spec(self._materials.specs, m).uses_object_info for m in where.materials):
            extra["object_info"] = dict(where.object_info)
        instance_id = self._core_scene.add_instance(mesh_id=mesh_id, transform=where.matrix, name=where.name,
                                                    visible_camera=camera_ray, visible_shadow=shadow,
                                                    visible_indirect=indirect,
                                                    terminator_offset=where.terminator_offset, **extra)
        self.instances_by_object.setdefault(where.object_name, []).append(instance_id)
        return instance_id, triangles

    def _add_mesh(self, triangles, name, slots, needs):
        if triangles is None:
            return None, 0
        extra = {}
        # Keyed by the core's attribute ids (Scene.attribute_id), which the programs' params name too.
        attributes = {self._core_scene.attribute_id(n): triangles.attributes[n] for n in needs.attributes
                      if n in triangles.attributes}
        if attributes:
            extra["attributes"] = attributes
        if needs.texspace and triangles.texspace is not None:
            extra["texspace"] = triangles.texspace
        mesh_id = self._core_scene.add_mesh_data(name=name, vertices=triangles.vertices,
                                                 triangles=triangles.triangles, normals=triangles.normals,
                                                 uvs=triangles.uvs,
                                                 material_ids=mesh.scene_material_ids(triangles.slots, slots,
                                                                                      len(triangles.triangles)),
                                                 **extra)
        return mesh_id, len(triangles.triangles)


class MaterialTable:
    """Adds every Blender material to the core scene once, and remembers its index there."""

    def __init__(self, core_scene, notes, specs=None):
        self._core_scene = core_scene
        self._notes = notes
        self.specs = {} if specs is None else specs    # material name -> MaterialSpec (shared with the sync)
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
            spec = material_spec(self.specs, material)
            attribute_id = self._core_scene.attribute_id if spec.attributes else None
            arguments = spec.core_arguments(texture_index=lambda reference: self._texture_index(spec, reference),
                                            attribute_id=attribute_id)
            self._ids[key] = self._core_scene.add_material(**arguments)
            self.emissive = self.emissive or spec.emits
            if spec.notes:
                self._notes.append(f"Material '{spec.name}': " + "; ".join(unique(spec.notes)))
        return self._ids[key]

    def _texture_index(self, spec, reference):
        """Core index of the image of `reference` (added once per image), a texture of the material `spec`; a
        failure to read it becomes a note and the closure keeps a plain colour (index -1)."""
        return self.texture_index(reference, lambda error: self._notes.append(
            f"Material '{spec.name}': image '{reference.image.name}' not readable ({error}); its colour is used"))

    def texture_index(self, reference, on_error):
        """Core index of the image of `reference` in the scene's one texture table, added on first use (the
        materials' and the world's images alike); an unreadable image calls on_error(error) once and is -1."""
        if reference.key not in self._textures:
            try:
                self._textures[reference.key] = textures.add_texture(self._core_scene, reference)
            except (ValueError, RuntimeError) as error:
                on_error(error)
                self._textures[reference.key] = -1
        return self._textures[reference.key]


def unique(lines):
    return list(dict.fromkeys(lines))
