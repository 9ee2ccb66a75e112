"""Exports that reuse the previous export's meshes and materials (the live viewport; bpy side).

An IncrementalExport keeps, between exports of one depsgraph:
* the triangles read from each geometry (scene_export's geometry key: a mesh data without
  modifiers, else the object), until ``invalidate_geometry`` names it;
* the shgi.Mesh of each (geometry, material slots) pair (a mesh instanced by objects whose
  slots hold other materials is read once);
* the materials and textures in a MaterialTable (stable ids; an edited material is converted
  again in place, see MaterialExporter.invalidate);
* the world, until ``invalidate_world``.

Each ``export(depsgraph, scene)`` walks the depsgraph's instances again (placements and lights
are cheap to read) and returns a frozen SceneSnapshot. Meshes no export used any more are
dropped. ``meshes_read`` counts the geometries read since the start (the tests' hook).
"""

from .material import MaterialExporter
from .result import WarningLog
from .scene_export import _SceneExporter
from .scene_snapshot import MaterialTable, SceneSnapshot


class IncrementalExport:
    """The caches of the viewport's exports (see the module docstring).

    report: like Operator.report, receives each warning once per session.
    """

    def __init__(self, report=None):
        self.log = WarningLog(report)
        self.table = MaterialTable()
        self.materials = MaterialExporter(self.table, self.log)
        # (*geometry key, tangent UV map) -> MeshGeometry, or None (empty or skipped)
        self.geometries = {}
        self.meshes = {}       # ((*geometry key, tangent UV map), material ids) -> shgi.Mesh
        self.world = None
        self.meshes_read = 0

    # --- invalidation (from the depsgraph's updates) ---------------------------------------------

    def invalidate_geometry(self, names):
        """Forgets the geometry of objects and mesh data named in `names` (name_full)."""
        names = set(names)
        for key in [key for key in self.geometries if key[1] in names]:
            del self.geometries[key]
        for key in [key for key in self.meshes if key[0][1] in names]:
            del self.meshes[key]

    def invalidate_materials(self, names=None):
        """Materials (by name_full; None: every material and image) are converted again."""
        self.materials.invalidate(names)

    def invalidate_world(self):
        self.world = None

    # --- export ----------------------------------------------------------------------------------

    def export(self, depsgraph, scene):
        """A frozen SceneSnapshot of the depsgraph, without a camera (the viewport has its own)."""
        snapshot = SceneSnapshot(self.table)
        walk = _CachedWalk(self, depsgraph, snapshot)
        walk.export_instances()
        snapshot.probe_volumes = tuple(walk.probe_volumes)
        if self.world is None:
            walk.export_world(scene)
            self.world = snapshot.world
        snapshot.set_world(self.world)
        used = walk.used_geometries
        self.geometries = {key: value for key, value in self.geometries.items() if key in used}
        self.meshes = {key: value for key, value in self.meshes.items() if key[0] in used}
        return snapshot.freeze()


class _CachedWalk(_SceneExporter):
    """One export walk that reads geometry only when the IncrementalExport has none cached."""

    def __init__(self, caches, depsgraph, snapshot):
        super().__init__(depsgraph, caches.log, for_render=False, target=snapshot,
                         materials=caches.materials)
        self.caches = caches
        self.used_geometries = set()

    # A geometry is cached with the UV map its tangents come from (None: none; a material's
    # normal map asks for them), so a material that gains a normal map reads its meshes again.
    def _read_geometry(self, obj, geometry_key, tangent_uv_map=None):
        key = (*geometry_key, tangent_uv_map)
        self.used_geometries.add(key)
        if key not in self.caches.geometries:
            self.caches.meshes_read += 1
            self.caches.geometries[key] = super()._read_geometry(obj, geometry_key,
                                                                 tangent_uv_map)
        return self.caches.geometries[key]

    def _shgi_mesh(self, geometry, geometry_key, material_ids):
        tangents = self.materials.tangent_uv_map(material_ids)
        key = ((*geometry_key, tangents), tuple(material_ids))
        if key not in self.caches.meshes:
            self.caches.meshes[key] = super()._shgi_mesh(geometry, geometry_key, material_ids)
        return self.caches.meshes[key]
