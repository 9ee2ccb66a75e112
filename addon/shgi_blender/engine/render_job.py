"""One final (F12) render on a worker thread: commit, solve a field, progressive sampling. No bpy.

The render engine exports the scene on Blender's main thread (bpy is not thread-safe), starts a
RenderJob, and then polls it from the main thread: it forwards Esc (``test_break``) to
``cancel()``, shows ``fraction`` and ``stage``, and copies each new snapshot into the render
result. The thread, the cancel and the outcome are a NativeTask's (native_task.py): every
native call the job makes releases the GIL, so the main thread stays responsive, and
``cancel()`` makes the running call raise ``shgi.Cancelled`` within one chunk of work (< 0.2 s,
docs/architecture.md). The job keeps the last complete snapshot, so an interrupted render still shows
every sample finished before Esc.

Sampling runs in rounds (``sample_rounds``): the first round is one sample per pixel so that an
image appears at once; rounds then double, up to an eighth of the total. Both renderers give the
same image however the samples are split between calls, so rounds cost only their snapshots.
``make_renderer`` builds either one as a Renderer (add samples, read passes); the viewport
worker renders through it too.
"""

import threading
import time
from dataclasses import dataclass

from . import solution_cache
from .native_task import NativeTask

# Shares of the progress bar taken by the stages before sampling, when they run.
COMMIT_SHARE = 0.05
SOLVE_SHARE = 0.35
# Rounds grow up to total / MAX_ROUND_DIVISOR samples: about that many image updates at the end.
MAX_ROUND_DIVISOR = 8


def sample_rounds(total):
    """Samples per round: 1, 2, 4, ... capped at max(1, total // 8); they sum to `total`."""
    if total < 1:
        raise ValueError(f"samples: {total} is not >= 1")
    cap = max(1, total // MAX_ROUND_DIVISOR)
    rounds, done, size = [], 0, 1
    while done < total:
        step = min(size, cap, total - done)
        rounds.append(step)
        done += step
        size *= 2
    return rounds


@dataclass
class Snapshot:
    """The passes after `samples` samples per pixel ({name: float32 (H, W, C)}, row 0 on top)."""

    passes: dict
    samples: int


@dataclass
class Renderer:
    """A renderer as the render job and the viewport worker drive it."""

    add: object      # add(count): adds `count` samples per pixel
    passes: object   # passes(names=None): {name: float32 (H, W, C)}, row 0 on top


def make_renderer(shgi, scene, progress, *, path_tracer_settings=None, preview_settings=None,
                  field=None, camera=None):
    """The Renderer of a committed shgi.Scene; its native calls poll `progress`.

    path_tracer_settings: renders with the reference path tracer (from the scene's camera).
    preview_settings: else renders with the preview renderer over `field` (None: direct light
        only) from `camera` (None: the scene's).
    """
    if path_tracer_settings is not None:
        tracer = shgi.PathTracer(scene, path_tracer_settings)
        return Renderer(lambda count: tracer.render(count, progress=progress), tracer.passes)
    preview = shgi.PreviewRenderer(scene, preview_settings, camera=camera)
    return Renderer(lambda count: preview.render(field, count, progress=progress),
                    preview.passes)


class RenderJob(NativeTask):
    """Renders a shgi.Scene with one method on a worker thread (start, cancel, wait, running,
    error and cancelled as NativeTask has them).

    scene: a shgi.Scene (committed by the job if it is not yet).
    samples: samples per pixel in total.
    path_tracer_settings: renders with the reference path tracer when given.
    preview_settings: renders with the preview renderer over `field`, or over the field
        solved first by `solver_recipe` (a field_solvers.SolverRecipe: a PhotonLattice, a
        ProbeGrid and its update passes) when `field` is None, or with direct light only when
        both are None (a scene without geometry has nothing to solve).
    camera: a shgi.Camera replacing the scene's (a frozen solution seen from a new camera).
    """

    def __init__(self, shgi, scene, samples, *, path_tracer_settings=None,
                 preview_settings=None, solver_recipe=None, field=None, camera=None):
        if (path_tracer_settings is None) == (preview_settings is None):
            raise ValueError("give exactly one of path_tracer_settings and preview_settings")
        super().__init__(shgi, "shgi-render")
        self.scene = scene
        self.samples = samples
        self._path_tracer_settings = path_tracer_settings
        self._preview_settings = preview_settings
        self._solver_recipe = solver_recipe
        self.field = field
        self._camera = camera
        self._lock = threading.Lock()
        self._snapshot = None
        self._snapshot_taken = True
        self._span = (0.0, COMMIT_SHARE)
        self._stage = "Starting"
        self.samples_done = 0
        self.timings = {}       # seconds per stage: commit, solve, render
        self.solution = None    # the solution_cache.Solution the job solved, if any (not cached)

    # --- main thread ---------------------------------------------------------------------------

    @property
    def fraction(self):
        """Overall progress in [0, 1]."""
        with self._lock:
            lo, hi = self._span
        return lo + (hi - lo) * min(max(self.progress.fraction, 0.0), 1.0)

    @property
    def stage(self):
        with self._lock:
            return self._stage

    def take_snapshot(self):
        """The newest Snapshot not taken yet, or None."""
        with self._lock:
            if self._snapshot_taken:
                return None
            self._snapshot_taken = True
            return self._snapshot

    def last_snapshot(self):
        """The newest Snapshot, taken or not (None before the first round ends)."""
        with self._lock:
            return self._snapshot

    # --- worker thread -------------------------------------------------------------------------

    def _work(self):
        render_start = COMMIT_SHARE
        if not self.scene.committed:
            self._timed("commit", "Building BVH", (0.0, COMMIT_SHARE),
                        lambda: self.scene.commit(progress=self.progress))
        if self._solver_recipe is not None and self.field is None:
            render_start = COMMIT_SHARE + SOLVE_SHARE
            self._timed("solve", self._solver_recipe.solver.BUILD_STAGE,
                        (COMMIT_SHARE, render_start), self._solve_field)
        self._sample(render_start)

    def _timed(self, name, stage, span, work):
        with self._lock:
            self._stage, self._span = stage, span
        start = time.perf_counter()
        try:
            work()
        finally:  # a cancelled stage still shows the time it ran
            self.timings[name] = self.timings.get(name, 0.0) + time.perf_counter() - start

    def _solve_field(self):
        def on_stage(stage, lo, hi):  # the solve's share of the progress bar, split by stage
            span = COMMIT_SHARE + SOLVE_SHARE * lo, COMMIT_SHARE + SOLVE_SHARE * hi
            with self._lock:
                self._stage, self._span = stage, span

        self.solution = solution_cache.solve(self._shgi, self.scene, self._solver_recipe,
                                             signature=None, progress=self.progress,
                                             on_stage=on_stage)
        self.field = self.solution.field

    def _sample(self, render_start):
        renderer = make_renderer(self._shgi, self.scene, self.progress,
                                 path_tracer_settings=self._path_tracer_settings,
                                 preview_settings=self._preview_settings, field=self.field,
                                 camera=self._camera)
        name = "Path tracing" if self._path_tracer_settings is not None else "Rendering"
        for count in sample_rounds(self.samples):
            lo = render_start + (1.0 - render_start) * self.samples_done / self.samples
            hi = render_start + (1.0 - render_start) * (self.samples_done + count) / self.samples
            stage = f"{name}, sample {self.samples_done + count}/{self.samples}"
            self._timed("render", stage, (lo, hi), lambda: renderer.add(count))
            self.samples_done += count
            snapshot = Snapshot(renderer.passes(), self.samples_done)
            with self._lock:
                self._snapshot, self._snapshot_taken = snapshot, False
