"""Blender scene export: an evaluated depsgraph → an shgi.Scene.

``export_scene(depsgraph, scene=None, *, report=None, for_render=None, with_camera=True,
should_stop=None) -> ExportResult`` is the entry point the render engine and operators call
(scene_export.py). The modules split bpy code from bpy-free code so that pytest checks the
conversions outside Blender:

* bpy-free: conversions.py (socket names, units, fields), mesh_split.py (per-corner → per-vertex),
  memory.py (whether a mesh's export fits in the available memory),
  result.py (ExportResult, ExportStats, ExportCancelled, warnings), light_probe.py
  (Irradiance Volume objects → probe grid volumes), scene_snapshot.py (an export recorded as
  values, built into an shgi.Scene later on the viewport's worker thread);
* bpy: scene_export.py (instances), mesh.py, material.py, light.py (and the world), camera.py,
  node_tree.py, incremental_export.py (the viewport's exports, reusing unchanged meshes and
  materials).

``export_scene`` is imported lazily so that ``import shgi_blender.export.conversions`` works
without bpy.
"""

from .result import ExportCancelled, ExportResult, ExportStats

__all__ = ["ExportCancelled", "ExportResult", "ExportStats", "export_scene"]


def __getattr__(name):
    if name == "export_scene":
        from .scene_export import export_scene
        return export_scene
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
