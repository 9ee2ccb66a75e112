"""F12: RenderEngine.render for one view layer (bpy side, Blender's main thread only).

Steps: export the render depsgraph (export/), start a RenderJob on a worker thread (commit,
solve, progressive sampling, all in native calls that release the GIL), then poll it every
POLL_SECONDS: Esc (``test_break``; Ctrl-C under the bpy module) cancels the export (polled
before each object and between a mesh's reading stages) or the job; progress and the
stage go to Blender's status, each new snapshot's Combined goes to the image editor, and at
the end every pass the view layer enables is written with Cycles' names (those of the running
Blender, passes.py). Export warnings, native warnings and unsupported passes are reported as
WARNING; a failure is set with ``error_set`` and reported as ERROR (bpy.ops.render.render then
raises RuntimeError in scripts).

The field methods (PHOTON_LATTICE, PROBE_GRID) solve their field on the job's thread before
sampling (field_solvers.py); PROBE_GRID's probes fill the scene's Irradiance Volume objects, or
one volume fitted to the scene. With a frozen solution of the scene's method (solution_cache,
the Solve operator), only the camera is exported and the frozen solution is rendered from it.

With Render Region on, only the border's pixels are rendered, through a camera that sees just
the region (render_region.py); Blender places them in the full frame unless Crop to Render
Region is on, as it does for Cycles.
"""

import logging
import queue
import time

import bpy

from .. import native, settings
from . import passes, render_region, scene_checks, solution_cache
from ..operators.keyboard_interrupt import sigint_watch
from .render_job import RenderJob

POLL_SECONDS = 0.05
logger = logging.getLogger("shgi_blender.engine")

# What the last render did (method, samples, seconds, warnings, cancelled, error): shown in the
# render panel and read by the headless tests.
_last_render = {}


def last_render():
    """A copy of the record of the last final render of this session."""
    return dict(_last_render)


class _NativeLogQueue(logging.Handler):
    """Collects the shgi logger's warnings from any thread for the main thread to report."""

    def __init__(self):
        super().__init__(level=logging.WARNING)
        self.messages = queue.SimpleQueue()

    def emit(self, record):
        self.messages.put(record.getMessage())

    def drain(self):
        while not self.messages.empty():
            yield self.messages.get()


# {this Blender's pass name: the renderers' name} (passes.py; Blender 5.0 renamed the passes).
_RENDERER_PASS_NAMES = passes.names_from_blender_names(bpy.app.version)


class FinalRender:
    """One view layer's final render driven from the main thread.

    engine: the RenderEngine (begin_result, test_break, report, ... are called on it).
    """

    def __init__(self, engine, depsgraph):
        self.engine = engine
        self.depsgraph = depsgraph
        self.scene = depsgraph.scene
        self.view_layer = depsgraph.view_layer
        self.width, self.height = engine.resolution_x, engine.resolution_y
        self.region = None  # the render_region.Region rendered when Render Region is on
        self.record = {"method": self.scene.shgi.method, "warnings": [], "errors": [],
                       "cancelled": False, "samples": 0, "timings": {},
                       "size": (self.width, self.height), "frozen_solution": False,
                       "figures": {}}

    # --- reports ---------------------------------------------------------------------------------

    def warn(self, message):
        if message not in self.record["warnings"]:
            self.record["warnings"].append(message)
            self.engine.report({"WARNING"}, message)

    def fail(self, message):
        self.record["errors"].append(message)
        self.engine.error_set(message)
        self.engine.report({"ERROR"}, message)

    # --- the render ------------------------------------------------------------------------------

    def run(self):
        start = time.perf_counter()
        log = _NativeLogQueue()
        logging.getLogger("shgi").addHandler(log)
        try:
            self._render(log)
        except ValueError as error:  # bad settings or scene, named by the native checks
            self.fail(f"SHGI: {error}")
        except Exception as error:  # a bug: report it rather than leave Blender mid-render
            logger.exception("SHGI render failed")
            self.fail(f"SHGI: internal error, {type(error).__name__}: {error} (traceback in the "
                      "console)")
        finally:
            logging.getLogger("shgi").removeHandler(log)
            self.record["timings"]["total"] = time.perf_counter() - start
            _last_render.clear()
            _last_render.update(self.record)

    def _render(self, log):
        shgi = native.module()
        if shgi is None:
            self.fail(native.error())
            return
        for name in passes.unsupported_enabled_passes(self.view_layer):
            self.warn(f"view layer {self.view_layer.name!r}: the {name} pass is not computed "
                      "by SHGI; it is left out")
        if self.scene.render.use_border:
            self._use_render_region()
        with sigint_watch() as interrupted:
            self._interrupted = interrupted
            job = self._start_job(shgi)
            if job is not None:
                self._follow(job, log)

    def _use_render_region(self):
        """Renders only the border's pixels: Blender's result then has the border's size (and
        Blender places it in the full frame unless Crop to Render Region is on)."""
        border = self.scene.render
        self.region = render_region.border_region(
            self.width, self.height, border.border_min_x, border.border_min_y,
            border.border_max_x, border.border_max_y)
        self.width, self.height = self.region.width, self.region.height
        self.record["size"] = (self.width, self.height)
        self.record["region"] = (self.region.x, self.region.top)

    def _region_camera(self, shgi, camera):
        """`camera` (the full frame's shgi.Camera) seeing only the Render Region, if any."""
        if self.region is None:
            return camera
        return render_region.crop_camera(shgi, camera, self.region)

    def _should_stop(self):
        """Esc (Blender's break flag), or a Ctrl-C under the bpy module even if the
        KeyboardInterrupt it raised was swallowed on the way (keyboard_interrupt.py)."""
        return self.engine.test_break() or self._interrupted()

    def _start_job(self, shgi):
        """Exports and starts the RenderJob of the scene's method (None after a failure)."""
        props = self.scene.shgi
        method = settings.METHODS_BY_ID.get(props.method)
        if method is None:
            self.fail(f"SHGI: render method {props.method!r} is not available in this version")
            return None
        solution = (solution_cache.get(self.scene.name_full, method.identifier)
                    if method.uses_field else None)
        if solution is not None and solution.scene is not None:
            return self._start_frozen_job(shgi, props, solution)
        from ..export import ExportCancelled, export_scene  # imports shgi: once it imports

        export_start = time.perf_counter()
        try:
            export = export_scene(self.depsgraph, self.scene, report=self._export_warning,
                                  should_stop=self._should_stop)
            self.record["timings"]["export"] = time.perf_counter() - export_start
            # Ctrl-C under the bpy module raises in whatever Python runs next: until the job
            # has started, that is here.
            return self._job_for(shgi, props, method, export, solution)
        except (ExportCancelled, KeyboardInterrupt):  # Esc; Ctrl-C under the bpy module
            self.record["timings"].setdefault("export", time.perf_counter() - export_start)
            self.record["cancelled"] = True
            self.engine.report({"INFO"}, "SHGI: render cancelled before its native work began")
            return None

    def _job_for(self, shgi, props, method, export, solution=None):
        """The started RenderJob of the exported scene (None after a failure); `solution`: a
        frozen solution read from a file, whose field it renders."""
        if not export.scene.has_camera:
            self.fail("SHGI: the scene has no usable camera (see the warnings)")
            return None
        for message in scene_checks.scene_warnings(export.scene):
            self.warn(f"SHGI: {message}")
        if self.region is not None:
            export.scene.set_camera(self._region_camera(shgi, export.scene.camera))
        if solution is not None:
            self._use_frozen_solution(solution)
            job = RenderJob(shgi, export.scene, props.samples,
                            preview_settings=settings.preview_settings(props, shgi),
                            field=solution.field, **self._finishing(props))
        elif method.uses_field:
            from .field_solvers import solver_recipe

            # Without geometry there is nothing to solve: direct light (the world) only.
            recipe = (None if export.scene.empty
                      else solver_recipe(props, shgi, export.probe_volumes))
            job = RenderJob(shgi, export.scene, props.samples,
                            preview_settings=settings.preview_settings(props, shgi),
                            solver_recipe=recipe, **self._finishing(props))
        else:
            job = RenderJob(shgi, export.scene, props.samples,
                            path_tracer_settings=settings.path_tracer_settings(props, shgi),
                            **self._finishing(props))
        return job.start()

    @staticmethod
    def _finishing(props):
        """The RenderJob arguments of F12's Denoise and Time Limit."""
        return {"denoising": settings.denoising(props), "time_limit": props.time_limit}

    def _export_warning(self, _level, message):
        self.warn(message)

    def _start_frozen_job(self, shgi, props, solution):
        """A job rendering the scene's frozen solution from the current camera."""
        from ..export.camera import camera_from_scene
        from ..export.result import WarningLog

        camera = camera_from_scene(self.scene, self.depsgraph, WarningLog(self._export_warning))
        if camera is None:
            self.fail("SHGI: the scene has no usable camera (see the warnings)")
            return None
        self._use_frozen_solution(solution)
        return RenderJob(shgi, solution.scene, props.samples,
                         preview_settings=settings.preview_settings(props, shgi),
                         field=solution.field, camera=self._region_camera(shgi, camera),
                         **self._finishing(props)).start()

    def _use_frozen_solution(self, solution):
        """Records and reports that the render shows `solution`: a WARNING naming the last
        edit when the scene changed after it was solved."""
        self.record["frozen_solution"] = True
        self._record_solution(solution)
        solved_at = solution_cache.solved_at_text(solution)
        changed = solution_cache.changed_since(self.scene.name_full, solution)
        if (changed is None and solution.signature is not None
                and solution.signature != settings.solver_signature(self.scene.shgi)):
            changed = "its settings"
        self.record["stale_solution"] = changed
        if changed is None:
            self.engine.report({"INFO"}, f"SHGI: rendering the frozen solution of {solved_at}")
            return
        panel = settings.METHODS_BY_ID[solution.method].label
        self.warn(f"SHGI: using the solution of {solved_at}; the scene changed since ({changed})"
                  f": Re-solve in Render Properties > {panel}, or Clear it to render the scene "
                  "as it is now")

    def _follow(self, job, log):
        """Polls the job until it ends, then writes the result and reports the outcome."""
        result = self.engine.begin_result(0, 0, self.width, self.height,
                                          layer=self.view_layer.name)
        try:
            if (result.resolution_x, result.resolution_y) != (self.width, self.height):
                raise RuntimeError(f"Blender's render result is {result.resolution_x}x"
                                   f"{result.resolution_y} px, SHGI renders {self.width}x"
                                   f"{self.height} px")
            try:
                self._poll_until_done(job, result, log)
            except KeyboardInterrupt:
                # Blender as a Python module (bpy) has no Esc: Ctrl-C (SIGINT) raises here, where
                # background Blender turns the first SIGINT into Esc. Stop as Esc does.
                job.cancel()
                job.wait()
            self._report_native_warnings(log)
            snapshot = job.last_snapshot()
            if snapshot is not None:
                self._write(result, snapshot, None)
        finally:
            if job.running:  # an exception on this side: stop the worker before leaving
                job.cancel()
                job.wait()
            self.engine.end_result(result)
        self._record_job(job)

    def _poll_until_done(self, job, result, log):
        """Every POLL_SECONDS until the job ends: Esc cancels it; progress, stage, native
        warnings and each new snapshot's Combined go to Blender."""
        while not job.wait(POLL_SECONDS):
            if self._should_stop():
                job.cancel()
            self.engine.update_progress(job.fraction)
            self.engine.update_stats("", f"SHGI | {job.stage}")
            self._report_native_warnings(log)
            snapshot = job.take_snapshot()
            if snapshot is not None:
                self._write(result, snapshot, ("Combined",))
                self.engine.update_result(result)

    def _record_solution(self, solution):
        """Blender's memory statistics show the solver's bytes (render buffers are Blender's);
        the record keeps the solver's figures and, for a probe grid, the probes it rendered."""
        mebibytes = solution.memory_bytes / solution_cache.BYTES_PER_MIB
        self.engine.update_memory_stats(memory_used=mebibytes, memory_peak=mebibytes)
        self.record["figures"] = dict(solution.solver.figures())
        positions = getattr(solution.field, "positions", None)
        if positions is not None:  # the tests check where the probes went
            self.record["probe_positions"] = positions.tolist()

    def _report_native_warnings(self, log):
        for message in log.drain():
            self.warn(f"SHGI: {message}")

    def _write(self, result, snapshot, names):
        """Copies the snapshot's passes (all, or those in `names`: the renderers' names) into
        the render result, whose passes carry this Blender's names."""
        layer = result.layers[0]
        for render_pass in layer.passes:
            name = _RENDERER_PASS_NAMES.get(render_pass.name)
            if name is None or (names is not None and name not in names):
                continue
            pixels = snapshot.passes.get(name)
            if pixels is None and name == passes.DENOISING_PASSES[0].name:
                # Denoising was asked for but did not run (no pyoidn, cancelled, failed): the
                # Noisy Image is Combined as it is.
                pixels = snapshot.passes.get("Combined")
            if pixels is None:
                continue
            if pixels.shape[:2] != (self.height, self.width):
                raise ValueError(f"pass {render_pass.name}: {pixels.shape[1]}x{pixels.shape[0]} "
                                 f"pixels for a {self.width}x{self.height} render")
            render_pass.rect = passes.blender_rect(pixels, render_pass.channels)

    def _record_job(self, job):
        self.record["samples"] = job.samples_done
        self.record["denoised"] = job.denoised
        if job.denoise_error is not None:
            self.warn(f"SHGI: {job.denoise_error}")
        self.record["timings"].update(job.timings)
        self.record["cancelled"] = job.cancelled
        if job.solution is not None:
            self._record_solution(job.solution)
        if job.error is not None:
            self.fail(f"SHGI: {job.error}")
        elif job.cancelled:
            self.engine.report({"INFO"}, f"SHGI: render cancelled after {job.samples_done} of "
                               f"{job.samples} samples")


def render(engine, depsgraph):
    """RenderEngine.render: renders the depsgraph's view layer into a new render result."""
    FinalRender(engine, depsgraph).run()
