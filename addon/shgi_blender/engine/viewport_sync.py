"""The live viewport's scene sync: depsgraph updates -> a SceneSnapshot (bpy, main thread only).

``RenderEngine.view_update`` calls ``ViewportSync.sync(depsgraph)``. The first sync exports
everything; later ones turn ``depsgraph.updates`` into a SyncPlan (sync_plan.py), drop only the
caches it names and export again from the IncrementalExport's caches: a moved object or light,
an edited light, material or world costs a walk over the depsgraph's instances and no
``to_mesh``; only geometry flagged as changed is read again. The new snapshot is compared with
the previous one (SAME, EDITABLE, DIFFERENT) so that the worker thread restarts only when
something it renders changed, and cheaply when only transforms or the world did.

``sync(depsgraph, updates)`` takes the updates explicitly as well: the tests and the sync
benchmark drive it from a ``depsgraph_update_post`` handler without a viewport.
"""

import time
from dataclasses import dataclass

import bpy

from ..export.incremental_export import IncrementalExport
from ..export.scene_snapshot import DIFFERENT
from . import sync_plan

# bpy ID types -> UpdateRecord kinds (the first match wins).
_ID_KINDS = (
    (bpy.types.Object, "OBJECT"), (bpy.types.Mesh, "MESH"), (bpy.types.Material, "MATERIAL"),
    (bpy.types.World, "WORLD"), (bpy.types.Image, "IMAGE"), (bpy.types.NodeTree, "NODETREE"),
    (bpy.types.Light, "LIGHT"), (bpy.types.Scene, "SCENE"), (bpy.types.Collection, "COLLECTION"),
)


def update_record(update):
    """A DepsgraphUpdate as a sync_plan.UpdateRecord."""
    id_data = update.id
    kind = next((name for id_type, name in _ID_KINDS if isinstance(id_data, id_type)), "OTHER")
    original = getattr(id_data, "original", None) or id_data
    object_type = data_name = ""
    if kind == "OBJECT":
        object_type = id_data.type
        if id_data.data is not None:
            data_name = id_data.data.original.name_full
    return sync_plan.UpdateRecord(
        kind=kind, name=original.name_full, geometry=update.is_updated_geometry,
        transform=update.is_updated_transform, shading=update.is_updated_shading,
        object_type=object_type, data_name=data_name,
        embedded=bool(getattr(id_data, "is_embedded_data", False)))


@dataclass
class SyncReport:
    """What one sync did: read counts, the time it took and how the snapshot changed."""

    plan: sync_plan.SyncPlan
    change: str               # scene_snapshot.SAME, EDITABLE or DIFFERENT
    meshes_read: int          # geometries read (to_mesh) by this sync
    materials_converted: int  # materials converted by this sync
    seconds: float


class ViewportSync:
    """The viewport's export state between view_update calls.

    report: like Operator.report, receives each export warning once per session.
    """

    def __init__(self, report=None):
        self.export = IncrementalExport(report)
        self.snapshot = None
        self.last_report = None
        self._world_name = None

    def sync(self, depsgraph, updates=None):
        """Exports what changed; returns the SyncReport (the snapshot is ``self.snapshot``).

        updates: the DepsgraphUpdates to apply (default: ``depsgraph.updates``).
        """
        start = time.perf_counter()
        meshes_read = self.export.meshes_read
        conversions = self.export.materials.conversions
        if self.snapshot is None:
            plan = sync_plan.full_plan()
        else:
            updates = depsgraph.updates if updates is None else updates
            plan = sync_plan.plan_updates(update_record(update) for update in updates)
        scene = depsgraph.scene
        world_name = scene.world.name_full if scene.world is not None else None
        self._apply(plan, world_changed=world_name != self._world_name)
        self._world_name = world_name
        snapshot = self.export.export(depsgraph, scene)
        change = snapshot.compare(self.snapshot) if self.snapshot is not None else DIFFERENT
        self.snapshot = snapshot
        self.last_report = SyncReport(
            plan=plan, change=change, meshes_read=self.export.meshes_read - meshes_read,
            materials_converted=self.export.materials.conversions - conversions,
            seconds=time.perf_counter() - start)
        return self.last_report

    def _apply(self, plan, world_changed):
        if plan.full:  # the first sync: the caches are empty
            return
        if plan.geometry_names:
            self.export.invalidate_geometry(plan.geometry_names)
        if plan.all_materials:
            self.export.invalidate_materials(None)
        elif plan.material_names:
            self.export.invalidate_materials(plan.material_names)
        if plan.world or world_changed:
            self.export.invalidate_world()
