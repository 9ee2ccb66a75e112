"""Solve a photon lattice once and keep it (non-interactive mode), or clear it.

SHGI_OT_lattice_solve exports the scene (Blender's main thread), then commits and solves on a
worker thread: from the UI (invoke) it runs modal, polled by a timer, Esc cancels and the status
bar shows progress; from a script or in background mode (execute) it waits for the thread. The
solution, with its lattice overlay (made on the same thread), goes to engine/solution_cache.py
under the scene's name; F12 renders it from the current camera until SHGI_OT_lattice_clear.
"""

import time

import bpy

from .. import native, settings
from ..engine import solution_cache
from ..engine.native_task import NativeTask

TIMER_SECONDS = 0.1


class _SolveTask(NativeTask):
    """solution_cache.solve on a worker thread, then the solution's lattice overlay (so that
    the 3D views' draw handler only uploads it)."""

    def __init__(self, shgi, scene, lattice_settings, signature, timings, warnings):
        super().__init__(shgi, "shgi-lattice-solve")
        self._arguments = (scene, lattice_settings, signature, timings, warnings)
        self.solution = None

    def _work(self):
        from ..engine import lattice_samples  # imports shgi, available per poll()

        scene, lattice_settings, signature, timings, warnings = self._arguments
        solution = solution_cache.solve(self._shgi, scene, lattice_settings, signature,
                                        self.progress, timings, warnings)
        # A committed shgi.Scene offers the instances and meshes a snapshot does.
        solution.overlay = lattice_samples.lattice_overlay(
            solution.lattice, solution.scene, solution.scene,
            solution.lattice.settings.resolution)
        self.solution = solution


class SHGI_OT_lattice_solve(bpy.types.Operator):
    """Solve the photon lattice once with the scene's settings and keep it: F12 renders it from \
any camera without solving again, until Clear"""

    bl_idname = "shgi.lattice_solve"
    bl_label = "Solve"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return context.scene is not None and native.available()

    def execute(self, context):
        task = self._start(context)
        if task is None:
            return {"CANCELLED"}
        task.wait()
        return self._finish(context, task)

    def invoke(self, context, _event):
        if context.window is None:  # no window to poll from (background mode): wait instead
            return self.execute(context)
        self._task = self._start(context)
        if self._task is None:
            return {"CANCELLED"}
        window_manager = context.window_manager
        self._timer = window_manager.event_timer_add(TIMER_SECONDS, window=context.window)
        window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC":
            self._task.cancel()
            return {"RUNNING_MODAL"}
        if event.type == "TIMER":
            if self._task.running:
                context.workspace.status_text_set(
                    f"SHGI: {self._task.progress.stage or 'solving'} "
                    f"{100 * self._task.progress.fraction:.0f}% (Esc cancels)")
                return {"PASS_THROUGH"}
            context.window_manager.event_timer_remove(self._timer)
            context.workspace.status_text_set(None)
            return self._finish(context, self._task)
        return {"PASS_THROUGH"}

    def _start(self, context):
        """Exports the scene and starts the solve (None, with a report, on failure)."""
        shgi = native.module()
        from ..export import export_scene  # imports shgi, available per poll()

        scene = context.scene
        start = time.perf_counter()
        export = export_scene(context.evaluated_depsgraph_get(), scene, report=self.report,
                              for_render=True)
        timings = {"export": time.perf_counter() - start}
        try:
            lattice_settings = settings.photon_lattice_settings(scene.shgi, shgi)
        except ValueError as error:
            self.report({"ERROR"}, f"SHGI: {error}")
            return None
        self._scene_key = scene.name_full
        return _SolveTask(shgi, export.scene, lattice_settings,
                          settings.lattice_signature(scene.shgi), timings,
                          export.warnings).start()

    def _finish(self, context, task):
        if task.cancelled:
            self.report({"INFO"}, "SHGI: solve cancelled; the previous solution is kept")
            return {"CANCELLED"}
        if task.error is not None:
            self.report({"ERROR"}, f"SHGI: {task.error}")
            return {"CANCELLED"}
        solution_cache.store(self._scene_key, task.solution)
        timings = task.solution.timings
        seconds = sum(timings.get(name, 0.0) for name in solution_cache.TIMING_LABELS)
        self.report({"INFO"}, f"SHGI: photon lattice solved in {seconds:.2f} s "
                    f"({task.solution.photons_emitted:,} photons, "
                    f"{task.solution.memory_bytes / solution_cache.BYTES_PER_MIB:.1f} MiB)")
        for area in context.screen.areas if context.screen else ():
            area.tag_redraw()
        return {"FINISHED"}


class SHGI_OT_lattice_clear(bpy.types.Operator):
    """Forget the scene's frozen photon lattice: F12 exports and solves again"""

    bl_idname = "shgi.lattice_clear"
    bl_label = "Clear"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return (context.scene is not None
                and solution_cache.get(context.scene.name_full) is not None)

    def execute(self, context):
        solution_cache.clear(context.scene.name_full)
        return {"FINISHED"}


CLASSES = (SHGI_OT_lattice_solve, SHGI_OT_lattice_clear)
