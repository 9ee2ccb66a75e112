"""The live viewport's renders on a worker thread: build, commit, solve, frames. No bpy.

The main thread (viewport.py) sends requests — the scene snapshot, the view (camera fields),
the render properties — and reads back the newest Frame. The worker thread owns every native
object it renders with (shgi.Scene, the field solver, renderers); the main thread never touches
them, which is what lets Blender's UI keep running while native calls hold no GIL.

A new request cancels the running native call and the worker starts over with the newest
request, redoing only what changed. Each run has two shgi.Progress objects: one for the scene
(commit, the solver's construction and passes), cancelled when the scene, its irradiance
volumes or the settings change, and one for frames, cancelled by any change: orbiting the view
never throws away a photon pass or a probe update in flight, it only waits for it. What is
redone:
* moved objects, an edited world, lights, materials or textures: edited in place
  (``set_instance_transform``, ``set_world``, ``set_lights``, ``set_material``, ``set_texture``)
  and committed (no BVH build, or the top level only for moved objects); anything else in the
  snapshot (meshes, which objects use them): a new shgi.Scene and a full commit;
* the field solver (field_solvers.py: a PhotonLattice, or a ProbeGrid placed in the scene's
  Irradiance Volumes) starts afresh after any scene change, solver setting change or, for a
  probe grid, moved or resized volume; never for a view change (the preview renderer takes
  the view as a camera), so its passes carry on from where they were;
* a light propagation volume's cascade levels follow the view: before each frame the levels
  whose inner region the view's eye left are moved and rebuilt alone (field_solvers.py,
  PropagationSolver.follow_view), the other levels and the passes kept;
* frames follow frame_schedule(): direct light at 1/4 resolution while the first pass runs,
  then 1/4 and 1/2 resolution frames with indirect light, each further pass followed by a new
  1/2 resolution frame of the refined field (the probe grid's background refinement: up to
  probe_grid.viewport_passes updates while the artist works), then full resolution samples in
  rounds (render_job.sample_rounds), each round a new Frame.

The path tracer renders the scene's camera, so for PATH_TRACE the view goes into the scene
(``set_camera``, a top-level commit) for each resolution.

With viewport denoising on (settings.denoising), every frame from the start sample on is
denoised on this thread before it is published (one shgi.frame_denoise.FrameDenoiser kept while
its choices stay, so the network's weights load once); the renderers then also sum the guide
passes. Without pyoidn the frames stay noisy and the status says why. A Viewport Time Limit
stops the full-resolution rounds once that many seconds passed since the request arrived.
"""

import logging
import threading
import time
from dataclasses import dataclass

import numpy as np

from .. import settings
from ..export.light_probe import volumes_key
from ..export.scene_snapshot import DIFFERENT, EDITABLE, SAME
from . import viewport_camera
from .field_solvers import solver_recipe
from .render_job import make_renderer, sample_rounds

logger = logging.getLogger("shgi_blender.viewport")

# Reduced resolutions shown before full resolution (divisors of the region's size).
PREVIEW_DIVISORS = (4, 2)
# The passes the viewport draws: converting only these saves the other 13 passes' copies per
# published frame (~60 ms of a 640 x 360 frame on a loaded machine; Combined alone ~1 ms).
VIEWPORT_PASSES = ["Combined"]
# How long stop() waits for the thread (a cancelled native call returns within 0.2 s).
STOP_TIMEOUT_SECONDS = 2.0


@dataclass(frozen=True)
class Step:
    """One step of a viewport render: "direct" (a frame without indirect light), "solve" (one
    pass of the field solver), "frame" (one sample per pixel) or "samples" (accumulate
    `samples` at full resolution)."""

    kind: str
    divisor: int = 1
    samples: int = 1


def frame_schedule(uses_field, samples, solver_passes, passes_done):
    """The Steps of a render, given the passes the current field solver already ran."""
    steps = []
    if uses_field and passes_done == 0:
        steps += [Step("direct", PREVIEW_DIVISORS[0]), Step("solve")]
        passes_done = 1
    steps += [Step("frame", divisor) for divisor in PREVIEW_DIVISORS]
    if uses_field:
        for _ in range(passes_done, solver_passes):
            steps += [Step("solve"), Step("frame", PREVIEW_DIVISORS[-1])]
    steps.append(Step("samples", 1, samples))
    return steps


@dataclass(frozen=True)
class Request:
    """What the viewport shows: a SceneSnapshot, camera fields (viewport_camera) and
    settings.render_property_values()."""

    snapshot: object
    view: dict
    properties: tuple


@dataclass(frozen=True)
class Frame:
    """A rendered frame: (H, W, 4) float32 Combined, row 0 at the bottom (texture order)."""

    pixels: np.ndarray
    samples: int
    target_samples: int
    divisor: int
    frame_id: int


class _Superseded(Exception):
    """A newer request arrived between two native calls."""


class ViewportWorker:
    """The worker thread and the request/frame slots the main thread uses (lock-protected)."""

    def __init__(self, shgi):
        self._shgi = shgi
        self._condition = threading.Condition()
        self._request = None
        self._version = 0
        self._progress = None
        self._stopped = False
        self._frame = None
        self._frame_id = 0
        self._status = ""
        self._overlay_wanted = False
        self._overlay = None
        # Worker-thread state: what the current native objects were made from.
        self._snapshot = None
        self._scene = None
        self._scene_camera = None
        self._solver = None
        self._solver_key = None
        self._overlay_source = None
        self._denoiser = None
        self.denoise_error = None
        self.error = None
        self.counters = {"scene_builds": 0, "in_place_updates": 0, "solves": 0, "frames": 0,
                         "recentres": 0}
        self._thread = threading.Thread(target=self._loop, name="shgi-viewport", daemon=True)
        self._thread.start()

    # --- main thread -----------------------------------------------------------------------------

    def request(self, snapshot, view, properties):
        """Renders this from now on; a request equal to the current one changes nothing.

        Returns True when the request replaced the current one."""
        request = Request(snapshot, view, properties)
        with self._condition:
            current = self._request
            same_scene = current is not None and _same_scene(current, request)
            if same_scene and _same_view(current, request):
                return False
            self._request = request
            self._version += 1
            if self._progress is not None:
                self._progress.frames.cancel()
                if not same_scene:
                    self._progress.scene.cancel()
            self._condition.notify_all()
        return True

    def set_overlay_wanted(self, wanted):
        """Whether the worker computes the field's overlay (lattice samples, probes) after
        each pass."""
        with self._condition:
            self._overlay_wanted = bool(wanted)
            self._condition.notify_all()

    def latest_frame(self):
        with self._condition:
            return self._frame

    def latest_overlay(self):
        with self._condition:
            return self._overlay

    @property
    def status(self):
        """What the worker does, and why frames are not denoised when they should be."""
        with self._condition:
            status, denoise_error = self._status, self.denoise_error
        return status if denoise_error is None else f"{status} ({denoise_error})"

    def stop(self):
        """Cancels the running call and ends the thread (waits up to STOP_TIMEOUT_SECONDS)."""
        with self._condition:
            self._stopped = True
            if self._progress is not None:
                self._progress.scene.cancel()
                self._progress.frames.cancel()
            self._condition.notify_all()
        self._thread.join(STOP_TIMEOUT_SECONDS)

    @property
    def running(self):
        return self._thread.is_alive()

    # --- worker thread ---------------------------------------------------------------------------

    def _loop(self):
        done_version = 0
        while True:
            with self._condition:
                while not self._stopped and self._version == done_version \
                        and not self._overlay_due():
                    self._condition.wait()
                if self._stopped:
                    self._close_denoiser()
                    return
                request, version = self._request, self._version
                if version != done_version:
                    self._progress = _RunProgress(self._shgi.Progress(), self._shgi.Progress())
                progress = self._progress
            if version != done_version:
                done_version = version
                self._run_guarded(request, progress)
            self._update_overlay()

    def _run_guarded(self, request, progress):
        try:
            self._render(request, progress)
        except (self._shgi.Cancelled, _Superseded):
            pass
        except Exception as error:  # shown by the viewport; the next request starts afresh
            logger.exception("SHGI viewport render failed")
            self.error = f"{type(error).__name__}: {settings.name_settings(error)}"
            self._set_status(f"Error: {self.error}")
            self._scene = self._snapshot = None
            self._drop_solver()

    def _render(self, request, progress):
        self.error = None
        shgi = self._shgi
        props = settings.properties_from_values(request.properties)
        method = settings.METHODS_BY_ID[props.method]
        self._prepare_scene(request.snapshot, request.view, progress.scene)
        uses_field = method.uses_field and not self._scene.empty
        context = _RenderContext(request, progress, uses_field)
        if uses_field:
            context.recipe = solver_recipe(props, shgi, request.snapshot.probe_volumes,
                                           viewport=True)
            solver_key = (settings.solver_signature(props),
                          volumes_key(request.snapshot.probe_volumes))
            if solver_key != self._solver_key:
                self._drop_solver()
            self._solver_key = solver_key
        context.denoising = settings.denoising(props, viewport=True)
        context.passes = list(VIEWPORT_PASSES)
        if context.denoising is not None:
            context.passes = list(context.denoising.passes())
        if method.uses_field:
            context.preview_settings = settings.preview_settings(props, shgi)
            # The viewport shows only Combined; the denoiser's guides need the other passes.
            context.preview_settings.combined_only = context.passes == VIEWPORT_PASSES
        else:
            context.path_tracer_settings = settings.path_tracer_settings(props, shgi)
        if props.viewport_time_limit > 0.0:
            context.deadline = time.perf_counter() + props.viewport_time_limit
        passes_done = self._solver.passes if (uses_field and self._solver) else 0
        solver_passes = context.recipe.passes if uses_field else 0
        for step in frame_schedule(uses_field, props.viewport_samples, solver_passes,
                                   passes_done):
            self._check(progress)
            if step.kind == "solve":
                self._solve(context.recipe, progress.scene)
                continue
            if uses_field and self._solver is not None and step.kind != "direct":
                self._follow_view(request.view, progress.frames)
            if step.kind == "samples":
                self._accumulate(context, step)
            else:
                self._set_status(f"Rendering 1/{step.divisor} resolution")
                renderer = self._renderer(context, step.divisor, use_field=step.kind == "frame")
                renderer.add(1)
                self._publish(context, renderer.passes(context.passes), 1,
                              props.viewport_samples, step.divisor)
        if context.stopped_at is not None:
            self._set_status(f"Done, time limit at {context.stopped_at} samples")
        else:
            self._set_status(f"Done, {props.viewport_samples} samples")

    def _prepare_scene(self, snapshot, view, progress):
        """Makes self._scene the committed scene of `snapshot`, as cheaply as possible."""
        self._set_status("Updating scene")
        camera = viewport_camera.shgi_camera(self._shgi, view)
        self._scene, change = updated_scene(self._scene, self._snapshot, snapshot, camera)
        if change == EDITABLE:
            self.counters["in_place_updates"] += 1
        elif change == DIFFERENT:
            self._scene_camera = viewport_camera.view_key(view)
            self.counters["scene_builds"] += 1
        if change != SAME:
            self._drop_solver()  # a solver refuses an edited scene
        self._snapshot = snapshot
        if not self._scene.committed:
            self._set_status("Building BVH")
            self._scene.commit(progress=progress)

    def _solve(self, recipe, progress):
        if self._solver is None:
            self._set_status(recipe.solver.BUILD_STAGE)
            self._solver = recipe.build(self._shgi, self._scene, progress)
        self._set_status(f"{self._solver.pass_stage(self._solver.passes + 1)}/{recipe.passes}")
        self._solver.update(progress)
        self.counters["solves"] += 1
        self._update_overlay()

    def _follow_view(self, view, progress):
        """Moves the solver's camera-following parts (propagation cascades) to the view: a view
        change cancels it with the frames, and the next request moves them from where they were."""
        moved = self._solver.follow_view(viewport_camera.shgi_camera(self._shgi, view), progress)
        if moved:
            self.counters["recentres"] += 1
            self._set_status(f"Moved cascade levels {', '.join(map(str, moved))} to the view")

    def _accumulate(self, context, step):
        renderer = self._renderer(context, step.divisor, use_field=True)
        done = 0
        for count in sample_rounds(step.samples):
            self._check(context.progress)
            if context.deadline is not None and time.perf_counter() >= context.deadline:
                context.stopped_at = done
                return
            self._set_status(f"Sample {done + count}/{step.samples}")
            renderer.add(count)
            done += count
            self._publish(context, renderer.passes(context.passes), done, step.samples,
                          step.divisor)

    def _renderer(self, context, divisor, use_field):
        """A render_job.Renderer of the request's view at 1/divisor resolution."""
        fields = viewport_camera.scaled_fields(context.request.view, divisor)
        camera = viewport_camera.shgi_camera(self._shgi, fields)
        progress = context.progress.frames
        if context.path_tracer_settings is not None:
            # The path tracer renders the scene's camera: the view goes into the scene.
            key = viewport_camera.view_key(fields)
            if key != self._scene_camera:
                self._scene.set_camera(camera)
                self._scene.commit(progress=progress)  # the top level only
                self._scene_camera = key
                self._drop_solver()  # a solver refuses an edited scene
        field = self._solver.field() if (use_field and context.uses_field) else None
        return make_renderer(self._shgi, self._scene, progress,
                             path_tracer_settings=context.path_tracer_settings,
                             preview_settings=context.preview_settings, field=field,
                             camera=camera)

    def _publish(self, context, passes, samples, target_samples, divisor):
        if context.denoising is not None and samples >= context.denoising.start_sample:
            passes = self._denoised(context, passes, samples)
        pixels = np.ascontiguousarray(passes["Combined"][::-1], dtype=np.float32)
        with self._condition:
            self._frame_id += 1
            self._frame = Frame(pixels, samples, target_samples, divisor, self._frame_id)
        self.counters["frames"] += 1

    def _denoised(self, context, passes, samples):
        """`passes` with Combined denoised by the kept FrameDenoiser of context.denoising (the
        noisy passes when pyoidn is missing or OIDN fails: denoise_error says why)."""
        if self._denoiser is None or self._denoiser[0] != context.denoising:
            self._close_denoiser()
            try:
                self._denoiser = (context.denoising, context.denoising.make())
            except (ImportError, RuntimeError) as error:
                self.denoise_error = f"not denoised: {error}"
                return passes
        try:
            passes = self._denoiser[1].denoise(passes, context.progress.frames, samples)
        except RuntimeError as error:
            self.denoise_error = f"not denoised: {error}"
            return passes
        self.denoise_error = None
        return passes

    def _close_denoiser(self):
        if self._denoiser is not None:
            self._denoiser[1].close()
            self._denoiser = None

    def _check(self, progress):
        """Between native calls: stops a run whose request was replaced."""
        if progress.frames.cancelled:
            raise _Superseded()

    def _set_status(self, text):
        with self._condition:
            self._status = text

    def _drop_solver(self):
        """Forgets the field solver and its overlay (the next solve starts afresh)."""
        self._solver = None
        with self._condition:
            self._overlay = self._overlay_source = None

    def _overlay_due(self):
        """(Lock held.) The overlay is wanted and the current solver's pass has none yet."""
        return (self._overlay_wanted and self._solver is not None
                and self._overlay_source != self._solver_state())

    def _solver_state(self):
        return (self._solver, self._solver.passes) if self._solver is not None else None

    def _update_overlay(self):
        """Computes the overlay of the current solver when it is wanted and out of date."""
        with self._condition:
            due = self._overlay_due()
        if not due:
            return
        state = self._solver_state()
        overlay = self._solver.overlay(self._snapshot, self._scene)
        with self._condition:
            self._overlay_source = state
            self._overlay = overlay


def updated_scene(scene, previous, snapshot, camera):
    """(the uncommitted or committed shgi.Scene of `snapshot`, compare() of the two snapshots).

    scene: the scene built from snapshot `previous`, or None. When only transforms, the world,
    lights, materials or textures changed it is edited in place (its commit then rebuilds at
    most the top-level BVH); otherwise, or when an edited item is refused, a new scene is built,
    with `camera` as its camera (the renderers want one even when they render another camera, so
    a later view change edits nothing).
    """
    change = snapshot.compare(previous) if scene is not None else DIFFERENT
    if change == EDITABLE:
        try:
            snapshot.edit_in_place(scene, previous)
        except ValueError:
            change = DIFFERENT  # build() below skips the refused item with a warning
    if change == DIFFERENT:
        scene, _ = snapshot.build()  # build() logs its warnings
        scene.set_camera(camera)
    return scene, change


@dataclass
class _RunProgress:
    scene: object    # shgi.Progress of commit, measure and solve
    frames: object   # shgi.Progress of the renders (cancelled by any new request)


@dataclass
class _RenderContext:
    request: Request
    progress: _RunProgress
    uses_field: bool
    recipe: object = None   # field_solvers.SolverRecipe when uses_field
    denoising: object = None   # settings.Denoising of the viewport, None when off
    passes: list = None        # the passes each frame reads (Combined, and the guides)
    deadline: float = None     # time.perf_counter() at the Viewport Time Limit, if any
    stopped_at: int = None     # samples done when the time limit stopped the render
    preview_settings: object = None
    path_tracer_settings: object = None


def _same_scene(a, b):
    """True when requests a and b render the same scene with the same settings and irradiance
    volumes (a selection change, a redraw, a view change)."""
    return a.properties == b.properties and (
        a.snapshot is b.snapshot
        or (b.snapshot.compare(a.snapshot) == SAME
            and volumes_key(b.snapshot.probe_volumes) == volumes_key(a.snapshot.probe_volumes)))


def _same_view(a, b):
    return viewport_camera.view_key(a.view) == viewport_camera.view_key(b.view)
