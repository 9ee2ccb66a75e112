"""Export the scene's solved field as a volume other tools read: EXR files + a JSON (bpy).

SHGI_OT_export_volume writes the frozen solution of the scene's method (Solve, in
engine/solution_cache.py), solving and freezing one first when there is none (the Solve
operator, waiting for it; its refusal becomes this operator's ERROR report):
* PROBE_GRID: ProbeField.export(path): ``<stem>.json`` and per volume ``<stem>_volume<v>.exr``
  (+ ``_visibility.exr``), the probes' SH of incident radiance, positions and states;
* PHOTON_LATTICE: shgi.volume_export.export_lattice(lattice, path): ``<stem>.json`` and one EXR
  per lattice (global, caustic), the cells' SH of incident indirect radiance.
The path is the operator's ``filepath``, else scene.shgi.bake.volume_path (the Bake panel);
".json" is added when it has another ending.
"""

import os

import bpy
from bpy.props import StringProperty

from .. import native, settings
from ..engine import solution_cache
from .bake_lightmaps import report_text

REPORT_PREFIX = "SHGI export volume: "


def export_solution(solution, json_path):
    """Writes a frozen solution's field to json_path; the paths written (ValueError for a
    solution with nothing to export)."""
    if solution.method == "PROBE_GRID":
        solution.field.export(json_path)
        stem = json_path[: -len(".json")]
        return [json_path] + [f"{stem}_volume{index}{suffix}.exr"
                              for index in range(len(solution.field.volumes))
                              for suffix in ("", "_visibility")]
    if solution.method == "PHOTON_LATTICE":
        try:
            from shgi.volume_export import export_lattice
        except ImportError as error:
            raise ValueError(f"this build of shgi cannot export photon lattices ({error}); "
                             "update SHGI, or export a Probe Grid solution") from None
        return export_lattice(solution.solver.lattice, json_path)
    raise ValueError(f"a {solution.method} solution has no volume to export")


class SHGI_OT_export_volume(bpy.types.Operator):
    """Write the scene's solved photon lattice or probe grid as EXR files and a JSON that \
describes them (solving it first when there is no frozen solution)"""

    bl_idname = "shgi.export_volume"
    bl_label = "Export Volume"
    bl_options = {"REGISTER"}

    filepath: StringProperty(
        name="File Path", subtype="FILE_PATH",
        description="The JSON file to write (EXR files go beside it); empty: the Bake "
                    "panel's Volume File")

    @classmethod
    def poll(cls, context):
        return context.scene is not None

    def execute(self, context):
        scene = context.scene
        if not native.available():
            return self._error(native.error())
        method = settings.METHODS_BY_ID[scene.shgi.method]
        if not method.uses_field:
            return self._error(f"the method {method.label} solves no volume: choose Photon "
                               "Lattice or Probe Grid")
        path = self.filepath or scene.shgi.bake.volume_path
        if path.startswith("//") and not bpy.data.filepath:
            return self._error(f"the path {path!r} is relative to the .blend file, which has "
                               "not been saved: save the file first, or choose an absolute path")
        json_path = bpy.path.ensure_ext(os.path.normpath(bpy.path.abspath(path)), ".json")
        solution = solution_cache.get(scene.name_full, scene.shgi.method)
        if solution is None:
            try:
                status = bpy.ops.shgi.solve()
            except RuntimeError as error:  # the solve's ERROR report, raised by bpy.ops
                problem = report_text(error).removeprefix("SHGI: ")
                return self._error(f"nothing to export, the solve failed: {problem}")
            if status != {"FINISHED"}:
                return self._error("nothing to export: the solve was cancelled")
            solution = solution_cache.get(scene.name_full, scene.shgi.method)
        try:
            os.makedirs(os.path.dirname(json_path), exist_ok=True)
            paths = export_solution(solution, json_path)
        except (ValueError, OSError) as error:
            return self._error(str(error))
        self.report({"INFO"}, f"{REPORT_PREFIX}{len(paths)} files: {', '.join(paths)}")
        group = settings.METHOD_SETTINGS.get(method.solver)
        if group is not None and getattr(scene.shgi, group.prop).final_gather:
            # Solved for F12's final gather (settings.light_path_fields): one bounce shallower
            # than a field read directly, as other tools read it.
            self.report({"WARNING"}, f"{REPORT_PREFIX}the field was solved for Final Gather "
                        "and holds one diffuse bounce less than Light Paths > Diffuse: for a "
                        f"volume read directly, turn off {group.label} > Final Gather, Solve "
                        "again and export")
        return {"FINISHED"}

    def _error(self, message):
        self.report({"ERROR"}, f"{REPORT_PREFIX}{message}")
        return {"CANCELLED"}


CLASSES = (SHGI_OT_export_volume,)
