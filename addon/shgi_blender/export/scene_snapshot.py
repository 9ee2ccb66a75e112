"""A recorded export: what the exporter would add to an shgi.Scene, kept as values. No bpy.

The live viewport exports on Blender's main thread but builds and commits the shgi.Scene on its
worker thread (engine/viewport_worker.py), and wants to know what an edit changed. So the
viewport's exporter (export/incremental_export.py) writes into a SceneSnapshot instead of an
shgi.Scene: it offers shgi.Scene's building calls (add_mesh, add_instance, add_light, set_world,
set_camera) and records their arguments. Meshes are shgi.Mesh values shared between snapshots
(the exporter caches them), so a snapshot costs a few references per object.

Materials and textures live in a MaterialTable that outlives snapshots: an edited material is
replaced at the id it already has, so the cached meshes, whose triangles store material ids,
stay valid. A snapshot freezes the table's lists when the export ends.

``build()`` replays a snapshot into a new shgi.Scene on any thread; ``compare()`` tells the
worker whether two snapshots differ not at all, only in what an shgi.Scene edits in place, or in
their geometry (meshes, or which instances use them: a new scene is built). In place: instance
transforms (``set_instance_transform``: the next commit rebuilds the top-level BVH only), the
world, lights, materials and textures (``set_world``, ``set_lights``, ``set_material``,
``set_texture``: no BVH is built at all, so a light's power edit starts the next frame at once).
A snapshot also records the scene's irradiance volumes (``probe_volumes``): they are not scene
content (compare() leaves them out) but the volumes of a probe grid solved on it.
"""

import logging
from dataclasses import dataclass

import numpy as np
import shgi

logger = logging.getLogger("shgi_blender.export")

# What compare() returns.
SAME = "SAME"
EDITABLE = "EDITABLE"       # only what an shgi.Scene edits in place differs
DIFFERENT = "DIFFERENT"

# The shgi.Light fields that define a light (compared between snapshots).
LIGHT_FIELDS = ("type", "power", "strength", "radius", "spot_size", "spot_blend",
                "spot_cone_cosine", "angle", "shape", "size_x", "size_y", "visible_camera",
                "portal", "color")


class MaterialTable:
    """Materials and textures with stable ids: the viewport exporter's shgi.Scene stand-in for
    MaterialExporter (add_material, add_texture), plus in-place replacement."""

    def __init__(self):
        self.materials = []
        self.textures = []

    def add_material(self, material):
        self.materials.append(material)
        return len(self.materials) - 1

    def add_texture(self, texture):
        self.textures.append(texture)
        return len(self.textures) - 1

    def set_material(self, material_id, material):
        self.materials[material_id] = material

    def set_texture(self, texture_id, texture):
        self.textures[texture_id] = texture


@dataclass(frozen=True)
class InstanceRecord:
    mesh_id: int
    world_from_object: np.ndarray   # (4, 4) float32, row-major (Blender's matrix_world)
    name: str


class SceneSnapshot:
    """The recorded content of an shgi.Scene (see the module docstring).

    table: the MaterialTable the exporter's materials go to; freeze() copies its lists.
    """

    def __init__(self, table):
        self._table = table
        self._frozen = None
        self.meshes = []        # shgi.Mesh
        self.instances = []     # InstanceRecord
        self.lights = []        # shgi.Light
        self.world = shgi.World()
        self.camera = None
        self.probe_volumes = ()  # light_probe.ProbeVolumeRecord

    # --- shgi.Scene's building calls -------------------------------------------------------------

    def add_mesh(self, mesh):
        self.meshes.append(mesh)
        return len(self.meshes) - 1

    def add_instance(self, mesh_id, world_from_object, name=""):
        matrix = np.asarray(world_from_object, np.float32).reshape(4, 4)
        self.instances.append(InstanceRecord(mesh_id, matrix, name))
        return len(self.instances) - 1

    def add_light(self, light):
        self.lights.append(light)
        return len(self.lights) - 1

    def set_world(self, world):
        self.world = world

    def set_camera(self, camera):
        self.camera = camera

    @property
    def materials(self):
        return self._frozen[0] if self._frozen is not None else self._table.materials

    @property
    def textures(self):
        return self._frozen[1] if self._frozen is not None else self._table.textures

    def freeze(self):
        """Keeps the material table's current lists: later edits of the table are not seen."""
        self._frozen = (list(self._table.materials), list(self._table.textures))
        return self

    @property
    def triangles(self):
        """Triangles over the distinct meshes."""
        return sum(len(mesh.triangles) for mesh in self.meshes)

    # --- replay and comparison -------------------------------------------------------------------

    def build(self):
        """(new uncommitted shgi.Scene, [warnings]): the snapshot replayed; runs on any thread.

        Items the native checks refuse (the exporter checks most of them first) are left out
        with a warning, instances of a refused mesh too; a refused material becomes the
        default material so that material ids keep their meaning.
        """
        scene, warnings = shgi.Scene(), []
        for texture in self.textures:
            scene.add_texture(texture)
        for material in self.materials:
            try:
                scene.add_material(material)
            except ValueError as error:
                warnings.append(f"material {material.name!r}: {error}; default material used")
                scene.add_material(shgi.Material(name=material.name))
        mesh_ids = [_try_add(scene.add_mesh, mesh, f"mesh {mesh.name!r}", warnings)
                    for mesh in self.meshes]
        for record in self.instances:
            if mesh_ids[record.mesh_id] is not None:
                _try_add(lambda r: scene.add_instance(mesh_ids[r.mesh_id], r.world_from_object,
                                                      name=r.name),
                         record, f"object {record.name!r}", warnings)
        for light in self.lights:
            _try_add(scene.add_light, light, f"light {light.name!r}", warnings)
        _try_add(scene.set_world, self.world, "world", warnings)
        if self.camera is not None:
            _try_add(scene.set_camera, self.camera, "camera", warnings)
        for message in warnings:
            logger.warning(message)
        return scene, warnings

    def compare(self, other):
        """SAME, EDITABLE (only transforms, the world, lights, materials or textures differ; the
        material and texture tables only grew) or DIFFERENT."""
        if other is None:
            return DIFFERENT
        same_geometry = (
            _same_items(self.meshes, other.meshes)
            and [(i.mesh_id, i.name) for i in self.instances]
            == [(i.mesh_id, i.name) for i in other.instances]
            and len(self.materials) >= len(other.materials)
            and len(self.textures) >= len(other.textures))
        if not same_geometry:
            return DIFFERENT
        if (self.moved_instances(other) or self.world_differs(other) or self.lights_differ(other)
                or _edited(self.materials, other.materials)
                or _edited(self.textures, other.textures)):
            return EDITABLE
        return SAME

    def lights_differ(self, other):
        return ([light_signature(light) for light in self.lights]
                != [light_signature(light) for light in other.lights])

    def edit_in_place(self, scene, previous):
        """Brings `scene`, built from snapshot `previous` (compare() said EDITABLE), to this
        snapshot's content by shgi.Scene's in-place edits. ValueError when the native checks
        refuse an edited item (the caller then builds a new scene, which skips it with a
        warning)."""
        for index in _edited(self.textures, previous.textures):
            if index < len(previous.textures):
                scene.set_texture(index, self.textures[index])
            else:
                scene.add_texture(self.textures[index])
        for index in _edited(self.materials, previous.materials):
            if index < len(previous.materials):
                scene.set_material(index, self.materials[index])
            else:
                scene.add_material(self.materials[index])
        if self.lights_differ(previous):
            scene.set_lights(list(self.lights))
        for index in self.moved_instances(previous):
            scene.set_instance_transform(index, self.instances[index].world_from_object)
        if self.world_differs(previous):
            scene.set_world(self.world)

    def world_differs(self, other):
        return world_signature(self.world) != world_signature(other.world)

    def moved_instances(self, other):
        """Ids of the instances whose matrix differs from `other`'s (same instance lists)."""
        return [index for index, (a, b) in enumerate(zip(self.instances, other.instances))
                if not np.array_equal(a.world_from_object, b.world_from_object)]


def light_signature(light):
    """The values that define an shgi.Light (for comparisons)."""
    values = [getattr(light, name) for name in LIGHT_FIELDS]
    return tuple(values) + (np.asarray(light.world_from_light, np.float32).tobytes(),)


def world_signature(world):
    return (tuple(world.color), world.strength)


def _same_items(a, b):
    return len(a) == len(b) and all(x is y for x, y in zip(a, b))


def _edited(items, previous):
    """Indices of `items` that are not the same objects as `previous`'s (new ones included)."""
    return [i for i, item in enumerate(items) if i >= len(previous) or item is not previous[i]]


def _try_add(add, item, what, warnings):
    """add(item), or None with a warning when the native checks refuse it."""
    try:
        return add(item)
    except ValueError as error:
        warnings.append(f"{what}: {error}; skipped")
        return None
