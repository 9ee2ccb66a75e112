"""Solve the method's field once and keep it (non-interactive mode), or clear it.

SHGI_OT_solve exports the scene (Blender's main thread), then commits and solves on a worker
thread the field of the scene's method (a photon lattice, or a probe grid in the scene's
Irradiance Volumes with its render passes; engine/field_solvers.py): from the UI (invoke) it
runs modal, polled by a timer, Esc cancels and the status bar shows progress; from a script or
in background mode (execute) it waits for the thread. The solution, with its overlay (made on
the same thread), goes to engine/solution_cache.py under the scene's name; F12 renders it from
the current camera until SHGI_OT_clear_solution. It keeps the scene's edit count at the export,
so that later edits mark it out of date (engine/solution_files.py counts them).

SHGI_OT_load_solution reads a probe field Export Volume wrote back as the scene's frozen
solution (a photon lattice's EXR export cannot be read back: the lattice is read back only from
the binary file saved with the .blend, solution_files.py).
"""

import os
import time

import bpy
from bpy.props import StringProperty

from .. import native, settings
from ..engine import solution_cache
from ..engine.native_task import NativeTask
from .modal_task import ModalTaskOperator


class _SolveTask(NativeTask):
    """solution_cache.solve on a worker thread, then the solution's overlay (so that the 3D
    views' draw handler only uploads it)."""

    def __init__(self, shgi, scene, recipe, signature, timings, warnings):
        super().__init__(shgi, "shgi-solve")
        self._arguments = (scene, recipe, signature, timings, warnings)
        self.solution = None

    def _work(self):
        scene, recipe, signature, timings, warnings = self._arguments
        solution = solution_cache.solve(self._shgi, scene, recipe, signature, self.progress,
                                        timings, warnings)
        # A committed shgi.Scene offers the instances and meshes a snapshot does.
        solution.overlay = solution.solver.overlay(solution.scene, solution.scene)
        self.solution = solution


class SHGI_OT_solve(ModalTaskOperator, bpy.types.Operator):
    """Solve the method's indirect light once with the scene's settings and keep it: F12 \
renders it from any camera without solving again, until Clear"""

    STATUS_IDLE = "solving"
    bl_idname = "shgi.solve"
    bl_label = "Solve"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return (context.scene is not None and native.available()
                and settings.METHODS_BY_ID[context.scene.shgi.method].uses_field)

    def _progress(self, task):
        return task.progress.fraction, task.progress.stage

    def _start(self, context):
        """Exports the scene and starts the solve (None, with a report, on failure)."""
        shgi = native.module()
        from ..engine.field_solvers import solver_recipe  # imports shgi, available per poll()
        from ..export import export_scene

        scene = context.scene
        start = time.perf_counter()
        export = export_scene(context.evaluated_depsgraph_get(), scene, report=self.report,
                              for_render=True)
        timings = {"export": time.perf_counter() - start}
        if export.scene.empty:
            self.report({"ERROR"}, "SHGI: the scene has no geometry SHGI can render; nothing "
                        "to solve")
            return None
        try:
            recipe = solver_recipe(scene.shgi, shgi, export.probe_volumes)
        except ValueError as error:
            self.report({"ERROR"}, f"SHGI: {error}")
            return None
        self._scene_key = scene.name_full
        self._edits_seen = solution_cache.edit_count(scene.name_full)
        return _SolveTask(shgi, export.scene, recipe, settings.solver_signature(scene.shgi),
                          timings, export.warnings).start()

    def _finish(self, context, task):
        if task.cancelled:
            self.report({"INFO"}, "SHGI: solve cancelled; the previous solution is kept")
            return {"CANCELLED"}
        if task.error is not None:
            self.report({"ERROR"}, f"SHGI: {task.error}")
            return {"CANCELLED"}
        solution = task.solution
        solution.edits_seen = self._edits_seen
        solution_cache.store(self._scene_key, solution)
        figures = ", ".join(f"{label} {text}" for label, text in solution.solver.figures())
        self.report({"INFO"}, f"SHGI: solved in {solution.seconds:.2f} s ({figures}, "
                    f"{solution.memory_bytes / solution_cache.BYTES_PER_MIB:.1f} MiB)")
        for area in context.screen.areas if context.screen else ():
            area.tag_redraw()
        return {"FINISHED"}


class SHGI_OT_clear_solution(bpy.types.Operator):
    """Forget the scene's frozen solution: F12 exports and solves again"""

    bl_idname = "shgi.clear_solution"
    bl_label = "Clear"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return (context.scene is not None
                and solution_cache.get(context.scene.name_full) is not None)

    def execute(self, context):
        solution_cache.clear(context.scene.name_full)
        return {"FINISHED"}


class SHGI_OT_load_solution(bpy.types.Operator):
    """Read a Probe Grid volume written by Export Volume (its JSON file) as the scene's frozen \
solution: F12 renders its probes until Clear"""

    bl_idname = "shgi.load_solution"
    bl_label = "Load"
    bl_options = {"REGISTER"}

    filepath: StringProperty(
        name="File Path", subtype="FILE_PATH",
        description="The JSON file Export Volume wrote (its EXR files beside it)")
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    @classmethod
    def poll(cls, context):
        return (context.scene is not None and native.available()
                and context.scene.shgi.method == "PROBE_GRID")

    def invoke(self, context, _event):
        if not self.filepath:
            self.filepath = bpy.path.abspath(context.scene.shgi.bake.volume_path)
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        scene = context.scene
        path = bpy.path.abspath(self.filepath)
        if not os.path.isfile(path):
            self.report({"ERROR"}, f"SHGI: no file {path!r}: choose the JSON file Export Volume "
                        "wrote")
            return {"CANCELLED"}
        shgi = native.module()
        try:
            solution = solution_cache.loaded_solution(
                shgi, path, settings.probe_lookup_settings(scene.shgi, shgi))
        except (OSError, ValueError, KeyError) as error:
            self.report({"ERROR"}, f"SHGI: {path} was not read: {error}")
            return {"CANCELLED"}
        solution.edits_seen = solution_cache.edit_count(scene.name_full)
        solution_cache.store(scene.name_full, solution)
        self.report({"INFO"}, f"SHGI: {solution.field.probe_count} probes read from {path}; "
                    "F12 renders them until Clear")
        return {"FINISHED"}


CLASSES = (SHGI_OT_solve, SHGI_OT_clear_solution, SHGI_OT_load_solution)
