"""The live viewport's renders on a worker thread: build, commit, solve, frames. No bpy.

The main thread (viewport.py) sends requests — the scene snapshot, the view (camera fields),
the render properties — and reads back the newest Frame. The worker thread owns every native
object it renders with (shgi.Scene, PhotonLattice, renderers); the main thread never touches
them, which is what lets Blender's UI keep running while native calls hold no GIL.

A new request cancels the running native call and the worker starts over with the newest
request, redoing only what changed. Each run has two shgi.Progress objects: one for the scene
(commit, lattice measure and solve), cancelled when the scene or the settings change, and one
for frames, cancelled by any change: orbiting the view never throws away a photon pass in
flight, it only waits for it. What is redone:
* moved objects, an edited world: edited in place (``set_instance_transform``, ``set_world``)
  and committed (top-level BVH only); anything else in the snapshot (meshes, materials, lights):
  a new shgi.Scene and a full commit;
* the lattice is solved again after any scene change or lattice setting change, never for a
  view change (the preview renderer takes the view as a camera);
* frames follow frame_schedule(): direct light at 1/4 resolution while the first photon pass
  is traced, then 1/4 and 1/2 resolution frames with indirect light, any further photon passes,
  then full resolution samples in rounds (render_job.sample_rounds), each round a new Frame.

The path tracer renders the scene's camera, so for PATH_TRACE the view goes into the scene
(``set_camera``, a top-level commit) for each resolution.
"""

import logging
import threading
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from .. import settings
from ..export.scene_snapshot import DIFFERENT, EDITABLE, SAME
from . import lattice_samples, viewport_camera
from .render_job import make_renderer, sample_rounds

logger = logging.getLogger("shgi_blender.viewport")

# Reduced resolutions shown before full resolution (divisors of the region's size).
PREVIEW_DIVISORS = (4, 2)
# How long stop() waits for the thread (a cancelled native call returns within 0.2 s).
STOP_TIMEOUT_SECONDS = 2.0


@dataclass(frozen=True)
class Step:
    """One step of a viewport render: "direct" (a frame without indirect light), "solve" (one
    photon pass), "frame" (one sample per pixel) or "samples" (accumulate `samples` at full
    resolution)."""

    kind: str
    divisor: int = 1
    samples: int = 1


def frame_schedule(uses_lattice, samples, photon_passes, passes_done):
    """The Steps of a render, given the photon passes the current lattice already holds."""
    steps = []
    if uses_lattice and passes_done == 0:
        steps += [Step("direct", PREVIEW_DIVISORS[0]), Step("solve")]
        passes_done = 1
    steps += [Step("frame", divisor) for divisor in PREVIEW_DIVISORS]
    if uses_lattice:
        for _ in range(passes_done, photon_passes):
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
        self._lattice = None
        self._lattice_key = None
        self._overlay_source = None
        self.error = None
        self.counters = {"scene_builds": 0, "in_place_updates": 0, "solves": 0, "frames": 0}
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
        """Whether the worker computes the lattice overlay (lattice_samples) after solves."""
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
        with self._condition:
            return self._status

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
            self.error = f"{type(error).__name__}: {error}"
            self._set_status(f"Error: {self.error}")
            self._scene = self._snapshot = self._lattice = None

    def _render(self, request, progress):
        self.error = None
        shgi = self._shgi
        props = SimpleNamespace(**dict(request.properties))
        method = settings.METHODS_BY_ID[props.method]
        self._prepare_scene(request.snapshot, request.view, progress.scene)
        uses_lattice = method.uses_lattice and not self._scene.empty
        if uses_lattice:
            lattice_key = settings.lattice_signature(props)
            if lattice_key != self._lattice_key:
                self._lattice = None
            self._lattice_key = lattice_key
        context = _RenderContext(request, progress, uses_lattice)
        if method.uses_lattice:
            context.preview_settings = settings.preview_settings(props, shgi)
        else:
            context.path_tracer_settings = settings.path_tracer_settings(props, shgi)
        passes_done = self._lattice.passes if (uses_lattice and self._lattice) else 0
        for step in frame_schedule(uses_lattice, props.viewport_samples,
                                   props.viewport_photon_passes, passes_done):
            self._check(progress)
            if step.kind == "solve":
                self._solve(props, progress.scene)
            elif step.kind == "samples":
                self._accumulate(context, step)
            else:
                self._set_status(f"Rendering 1/{step.divisor} resolution")
                renderer = self._renderer(context, step.divisor, use_field=step.kind == "frame")
                renderer.add(1)
                self._publish(renderer.passes(), 1, props.viewport_samples, step.divisor)
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
            self._lattice = None  # a lattice refuses an edited scene
        self._snapshot = snapshot
        if not self._scene.committed:
            self._set_status("Building BVH")
            self._scene.commit(progress=progress)

    def _solve(self, props, progress):
        shgi = self._shgi
        if self._lattice is None:
            self._set_status("Measuring lattice cells")
            self._lattice = shgi.PhotonLattice(
                self._scene, settings.photon_lattice_settings(props, shgi), progress=progress)
        self._set_status(f"Tracing photons, pass {self._lattice.passes + 1}")
        self._lattice.solve(progress=progress)
        self.counters["solves"] += 1
        self._update_overlay()

    def _accumulate(self, context, step):
        renderer = self._renderer(context, step.divisor, use_field=True)
        done = 0
        for count in sample_rounds(step.samples):
            self._check(context.progress)
            self._set_status(f"Sample {done + count}/{step.samples}")
            renderer.add(count)
            done += count
            self._publish(renderer.passes(), done, step.samples, step.divisor)

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
                self._lattice = None  # a solved lattice refuses an edited scene
        field = self._lattice if (use_field and context.uses_lattice) else None
        return make_renderer(self._shgi, self._scene, progress,
                             path_tracer_settings=context.path_tracer_settings,
                             preview_settings=context.preview_settings, field=field,
                             camera=camera)

    def _publish(self, passes, samples, target_samples, divisor):
        pixels = np.ascontiguousarray(passes["Combined"][::-1], dtype=np.float32)
        with self._condition:
            self._frame_id += 1
            self._frame = Frame(pixels, samples, target_samples, divisor, self._frame_id)
        self.counters["frames"] += 1

    def _check(self, progress):
        """Between native calls: stops a run whose request was replaced."""
        if progress.frames.cancelled:
            raise _Superseded()

    def _set_status(self, text):
        with self._condition:
            self._status = text

    def _overlay_due(self):
        """(Lock held.) The overlay is wanted and the current lattice has none yet."""
        return (self._overlay_wanted and self._lattice is not None
                and self._overlay_source != self._lattice_state())

    def _lattice_state(self):
        return (self._lattice, self._lattice.passes) if self._lattice is not None else None

    def _update_overlay(self):
        """Computes the overlay of the current lattice when it is wanted and out of date."""
        with self._condition:
            due = self._overlay_due()
        if not due:
            return
        state = self._lattice_state()
        overlay = lattice_samples.lattice_overlay(self._lattice, self._snapshot, self._scene,
                                                  self._lattice.settings.resolution)
        with self._condition:
            self._overlay_source = state
            self._overlay = overlay


def updated_scene(scene, previous, snapshot, camera):
    """(the uncommitted or committed shgi.Scene of `snapshot`, compare() of the two snapshots).

    scene: the scene built from snapshot `previous`, or None. When only transforms or the world
    changed it is edited in place (its commit then rebuilds only the top-level BVH); otherwise a
    new scene is built, with `camera` as its camera (the renderers want one even when they
    render another camera, so a later view change edits nothing).
    """
    change = snapshot.compare(previous) if scene is not None else DIFFERENT
    if change == EDITABLE:
        for index in snapshot.moved_instances(previous):
            scene.set_instance_transform(index, snapshot.instances[index].world_from_object)
        if snapshot.world_differs(previous):
            scene.set_world(snapshot.world)
    elif change == DIFFERENT:
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
    uses_lattice: bool
    preview_settings: object = None
    path_tracer_settings: object = None


def _same_scene(a, b):
    """True when requests a and b render the same scene with the same settings (a selection
    change, a redraw, a view change)."""
    return a.properties == b.properties and (a.snapshot is b.snapshot
                                             or b.snapshot.compare(a.snapshot) == SAME)


def _same_view(a, b):
    return viewport_camera.view_key(a.view) == viewport_camera.view_key(b.view)
