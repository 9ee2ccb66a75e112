"""An evaluated depsgraph → an shgi.Scene: the export entry point (bpy side).

Walks ``depsgraph.object_instances`` (objects, collection instances, particles and geometry-node
instances alike). Each distinct geometry — an original mesh data without render-changing
modifiers, else the object itself — with its material slots is converted once (``to_mesh`` on
the evaluated object, so modifiers are applied) and placed by one shgi instance per object
instance with its matrix_world. Lights keep their units; the world and the scene camera follow.
Irradiance Volume light probes are not scene content: they are returned beside the scene as
the volumes of the PROBE_GRID method (light_probe.py).

Visibility is the depsgraph's: a render depsgraph (the engine's F12 depsgraph) already leaves
out objects and collections disabled for render. For a viewport depsgraph with
``for_render=True``, objects whose own or direct collections' hide_render is set are left out too.
Problems never raise: they become warnings (logged, reported, returned), and the object is
skipped; the result keeps why each skipped object was left out (``skipped``, by object name).
"""

import time
from dataclasses import dataclass

import numpy as np
import shgi

from . import conversions, memory
from .camera import camera_from_scene
from .light import light_from_object, world_from_blender
from .light_probe import is_irradiance_volume, probe_volume_from_object
from .material import MaterialExporter
from .mesh import read_mesh, triangle_count
from .mesh_split import never_stop
from .result import ExportCancelled, ExportResult, ExportStats, WarningLog

# Object types whose geometry to_mesh() converts to triangles.
MESH_CONVERTIBLE_TYPES = ("MESH", "CURVE", "SURFACE", "FONT", "META")
# Since Blender 3.0 the depsgraph lists the evaluated mesh of curves, text and (3.4) metaballs as
# a separate MESH instance whose parent is the object; the object's own entry is then skipped
# (as Cycles' object_is_geometry does) so that the geometry is not exported twice.
NON_MESH_GEOMETRY_TYPES = ("CURVE", "SURFACE", "FONT", "META")
# Object types with render geometry SHGI cannot convert (skipped with a warning).
UNSUPPORTED_GEOMETRY_TYPES = ("CURVES", "POINTCLOUD", "VOLUME", "GPENCIL")


def export_scene(depsgraph, scene=None, *, report=None, for_render=None, with_camera=True,
                 should_stop=None, flipped=()):
    """Converts an evaluated depsgraph into a new, uncommitted shgi.Scene.

    depsgraph: an evaluated Depsgraph (the render engine's, or
        ``bpy.context.evaluated_depsgraph_get()``).
    scene: the bpy Scene whose camera, world and render size are used (default:
        ``depsgraph.scene``).
    report: a callable like ``Operator.report`` that also receives every warning.
    for_render: leave out objects hidden for render (default: True for a render depsgraph,
        False for a viewport one, which already holds only the viewport-visible objects).
    with_camera: export the scene camera (False for bakes, which need none: no warning about
        a scene without one).
    should_stop: a callable polled before each object and between the stages of reading a
        mesh (the render engine's ``test_break``: Esc during F12); when it returns True the
        export raises ExportCancelled.
    flipped: names of objects exported facing the other way (triangles wound the other way,
        normals negated): a bake then bakes their back (Bake Side: Facing the Scene).
    Returns ExportResult(scene, warnings, stats, probe_volumes).
    """
    start = time.perf_counter()
    scene = scene if scene is not None else depsgraph.scene
    if for_render is None:
        for_render = depsgraph.mode == "RENDER"
    exporter = _SceneExporter(depsgraph, WarningLog(report), for_render)
    exporter.flipped = frozenset(flipped)
    if should_stop is not None:
        exporter.check_stop = _stop_check(should_stop)
    exporter.export_instances()
    exporter.export_world(scene)
    if with_camera:
        exporter.export_camera(scene)
    exporter.stats.seconds = time.perf_counter() - start
    return ExportResult(scene=exporter.shgi_scene, warnings=list(exporter.log.messages),
                        stats=exporter.stats, probe_volumes=exporter.probe_volumes,
                        skipped=exporter.skipped)


def _stop_check(should_stop):
    """A callable raising ExportCancelled once `should_stop()` is true."""
    def check_stop():
        if should_stop():
            raise ExportCancelled("the scene export was cancelled")
    return check_stop


class _SceneExporter:
    """The state of one export: the shgi.Scene being built and what was converted already."""

    def __init__(self, depsgraph, log, for_render, target=None, materials=None):
        """target: what receives the export (a new shgi.Scene, or a SceneSnapshot: anything
        with shgi.Scene's building calls); materials: a MaterialExporter kept between exports
        (default: a new one adding to `target`)."""
        self.depsgraph = depsgraph
        self.log = log
        self.for_render = for_render
        self.shgi_scene = target if target is not None else shgi.Scene()
        self.stats = ExportStats()
        self.materials = materials if materials is not None else MaterialExporter(
            self.shgi_scene, log)
        self._mesh_ids = {}  # (geometry key, material ids) -> mesh id, or None when skipped
        self._mesh_problems = {}  # geometry key -> why its geometry was skipped
        self.probe_volumes = []  # light_probe.ProbeVolumeRecord of the irradiance volumes
        self.skipped = {}  # object name -> why the object was left out
        self.check_stop = never_stop  # raises ExportCancelled when the caller says stop
        self.flipped = frozenset()  # names of the objects exported facing the other way

    def export_instances(self):
        """Adds every visible object instance's geometry or light; records irradiance volumes."""
        evaluated_as_mesh = self._objects_evaluated_as_mesh_instances()
        for instance in self.depsgraph.object_instances:
            self.check_stop()
            obj = instance.object
            if not instance.show_self or not self._is_visible(instance):
                continue
            if not instance.is_instance and obj.original.name_full in evaluated_as_mesh:
                continue
            if obj.type == "LIGHT":
                self._add_light(obj, instance.matrix_world)
            elif is_irradiance_volume(obj):
                self.probe_volumes.append(probe_volume_from_object(obj, instance.matrix_world))
            elif obj.type in MESH_CONVERTIBLE_TYPES:
                self._add_geometry(instance)
            elif obj.type in UNSUPPORTED_GEOMETRY_TYPES:
                self._skip(obj, f"type {obj.type} is not supported")
        self.stats.materials = len(self.shgi_scene.materials)
        self.stats.textures = self.materials.texture_count

    def _objects_evaluated_as_mesh_instances(self):
        """Names of the non-mesh objects whose geometry the depsgraph lists as MESH instances."""
        return {instance.parent.original.name_full
                for instance in self.depsgraph.object_instances
                if instance.is_instance and instance.object.type == "MESH"
                and instance.parent.type in NON_MESH_GEOMETRY_TYPES}

    def export_world(self, scene):
        try:
            self.shgi_scene.set_world(world_from_blender(scene.world, self.log))
        except ValueError as error:
            name = f"world {scene.world.name!r}" if scene.world is not None else "world"
            self.log.warn(f"{name}: {error}; SHGI's default world is used")

    def export_camera(self, scene):
        camera = camera_from_scene(scene, self.depsgraph, self.log)
        try:
            if camera is not None:
                self.shgi_scene.set_camera(camera)
        except ValueError as error:
            self.log.warn(f"camera: {error}; the export has no camera")

    def _is_visible(self, instance):
        """False for objects hidden for render when the depsgraph has not left them out."""
        if not self.for_render or self.depsgraph.mode == "RENDER":
            return True
        owner = instance.parent if instance.is_instance else instance.object
        original = owner.original
        return not (original.hide_render
                    or any(collection.hide_render for collection in original.users_collection))

    def _add_light(self, obj, matrix_world):
        try:
            self.shgi_scene.add_light(light_from_object(obj, matrix_world, self.log))
            self.stats.lights += 1
        except ValueError as error:
            self.log.warn(f"light {obj.name!r}: {error}; skipped")

    def _add_geometry(self, instance):
        """Adds an instance of the object's geometry, converting the geometry on first use."""
        obj = instance.object
        instancer = _zero_scale_instancer(instance)
        if instancer is not None:
            # Every instance it makes is flat: the instancer is what the artist must fix, not
            # the objects it instances (fine wherever else they are used).
            scale = tuple(round(axis, 6) for axis in instancer.matrix_world.to_scale())
            self._skip(instancer, f"its scale is 0 (world scale {scale}), which flattens every "
                                  "instance it makes; give every axis a non-zero scale (Object "
                                  "Properties > Transform > Scale, of it or of its parents)")
            return
        material_ids = tuple(self.materials.slot_ids(obj))
        flip = obj.name in self.flipped
        key = (self._geometry_key(obj), material_ids, flip)
        if key not in self._mesh_ids:
            self._mesh_ids[key] = self._add_mesh(obj, key[0], material_ids, flip)
        mesh_id = self._mesh_ids[key]
        if mesh_id is None:
            if key[0] in self._mesh_problems:  # the geometry another object shares was skipped
                self.skipped.setdefault(obj.name, self._mesh_problems[key[0]])
            return
        try:
            self.shgi_scene.add_instance(mesh_id, conversions.row_major(instance.matrix_world),
                                         name=instance_name(instance))
            self.stats.instances += 1
        except ValueError as error:  # e.g. a zero scale makes matrix_world singular
            self._skip(obj, str(error))

    def _skip(self, obj, problem, geometry_key=None):
        """Leaves an object out, with a warning; `geometry_key`: its geometry is what failed
        (every object sharing it is left out for the same reason)."""
        self.log.warn(f"object {obj.name!r}: {problem}; skipped")
        if obj.name not in self.skipped:  # an instancer is skipped once per instance it makes
            self.stats.skipped_objects += 1
        self.skipped.setdefault(obj.name, problem)
        if geometry_key is not None:
            self._mesh_problems[geometry_key] = problem

    def _geometry_key(self, obj):
        """("DATA", mesh name) when the geometry is the shared mesh data, else ("OBJECT", name)."""
        original = obj.original
        render = self.depsgraph.mode == "RENDER"
        modified = any(modifier.show_render if render else modifier.show_viewport
                       for modifier in original.modifiers)
        if obj.type == "MESH" and not modified and obj.data is not None:
            return ("DATA", obj.data.original.name_full)
        return ("OBJECT", original.name_full)

    def _add_mesh(self, obj, geometry_key, material_ids, flip=False):
        """Id of the new shgi mesh of an evaluated object (facing the other way with `flip`),
        or None (empty or skipped)."""
        geometry = self._read_geometry(obj, geometry_key,
                                       self.materials.tangent_uv_map(material_ids))
        if geometry is None:
            return None
        try:
            mesh = self._shgi_mesh(geometry, geometry_key, material_ids)
            mesh_id = self.shgi_scene.add_mesh(flipped_mesh(mesh) if flip else mesh)
        except ValueError as error:
            self._skip(obj, str(error), geometry_key)
            return None
        self.stats.meshes += 1
        self.stats.triangles += len(geometry.split.triangles)
        return mesh_id

    def _read_geometry(self, obj, geometry_key, tangent_uv_map=None):
        """The evaluated object's triangles as a MeshGeometry, or None (empty or skipped);
        with tangents of `tangent_uv_map` (see mesh.read_mesh) unless it is None."""
        mesh = obj.to_mesh()
        try:
            if mesh is None or not mesh.polygons:
                return None
            problem = memory.export_memory_problem(triangle_count(mesh), len(mesh.uv_layers))
            if problem is not None:
                self._skip(obj, problem, geometry_key)
                return None
            split, blender_indices = read_mesh(mesh, geometry_key[1], self.check_stop,
                                               tangent_uv_map, self.log)
            return MeshGeometry(split, blender_indices)
        except ValueError as error:
            self._skip(obj, str(error), geometry_key)
            return None
        finally:
            obj.to_mesh_clear()

    def _shgi_mesh(self, geometry, geometry_key, material_ids):
        """The shgi.Mesh of a geometry whose material slots hold scene materials material_ids."""
        # Cycles clamps material indices beyond the last slot to the last slot.
        material_indices = np.asarray(material_ids, dtype=np.int32)[
            np.clip(geometry.blender_material_indices, 0, len(material_ids) - 1)]
        split = geometry.split
        return shgi.Mesh(positions=split.positions, triangles=split.triangles,
                         normals=split.normals, uvs=split.uvs or None,
                         material_indices=material_indices, name=geometry_key[1],
                         tangents=split.tangents)


def flipped_mesh(mesh):
    """A new shgi.Mesh facing the other way: each triangle wound the other way (the front is
    counter-clockwise), the normals negated, and the tangents' bitangent signs too, so that
    sign × cross(normal, tangent) still points along +V."""
    tangents = None
    if len(mesh.tangents):
        tangents = mesh.tangents.copy()
        tangents[:, 3] = -tangents[:, 3]
    return shgi.Mesh(positions=mesh.positions, triangles=mesh.triangles[:, ::-1].copy(),
                     normals=-mesh.normals, uvs=mesh.uv_sets or None,
                     material_indices=mesh.material_indices, name=mesh.name, tangents=tangents)


def instance_name(instance):
    """The exported instance's name: its object's, or for a copy an instancer makes (a
    collection instance's Empty, particles, geometry nodes) "<object> (instanced by
    <instancer>)", so that a message about the copy (a transform the scene refuses at commit)
    names the instancer the artist must fix, and the object's own instance keeps its name."""
    obj = instance.object
    parent = instance.parent if instance.is_instance else None
    # A text or metaball object is an instance of its own converted geometry: its own name.
    if parent is not None and parent.original.name != obj.original.name:
        return f"{obj.name} (instanced by {parent.name})"
    return obj.name


def _zero_scale_instancer(instance):
    """The object that instances `instance` (a collection instance's Empty, a particle system's
    or geometry nodes' owner) when its world scale is 0 on some axis, else None."""
    instancer = instance.parent if instance.is_instance else None
    if instancer is None or min(map(abs, instancer.matrix_world.to_scale())) > 0.0:
        return None
    return instancer


@dataclass
class MeshGeometry:
    """An evaluated object's triangles before material slots are resolved."""

    split: object                     # mesh_split.SplitMesh
    blender_material_indices: object  # (T,) int32 material slot per triangle
