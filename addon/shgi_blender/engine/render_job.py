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
A field whose samples each read passes of their own (Instant GI's passes_per_sample:
FieldSolver.passes_for_samples) is solved as the rounds need its passes, the first round's
before sampling and more before each round: the same image as solving every pass first, with
the first image sooner.
``make_renderer`` builds either one as a Renderer (add samples, read passes); the viewport
worker renders through it too.

Time Limit (``time_limit`` seconds from the job's start, after the export): a field method's
solve may take SOLVE_TIME_SHARE of it (at least one pass); a sampling round is cut to the
samples that fit the time left, judged by the last round's time per sample (``samples_in_time``:
a sample's cost may change as a render goes on, so the mean over every sample so far would judge
late rounds by early ones), keeping room for the denoiser (its estimate); at least one sample is
rendered. Denoising (``denoising``, a
settings.Denoising) runs once, on the job's thread, after the last round: the last snapshot then
holds the denoised Combined and Cycles' ``Noisy Image``, ``Denoising Albedo`` and ``Denoising
Normal`` passes. Without pyoidn, or after a denoiser failure, the image stays noisy and
``denoise_error`` says why. A cancelled job is not denoised.
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
# The passes of the snapshots taken between rounds: what the image editor shows while F12 runs
# (converting all 14 passes of a 256 x 256 frame after each round took ~50 ms); the last
# snapshot, of a finished or cancelled render, holds every pass.
SHOWN_PASSES = ["Combined"]
# The share of a Time Limit a field method's solve may take before sampling starts.
SOLVE_TIME_SHARE = 0.5


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


def samples_in_time(count, seconds_left, round_seconds, round_samples):
    """How many of a round's `count` samples fit in `seconds_left`, judged by the last round's
    time per sample: `round_seconds` for its `round_samples` samples (with any solve it needed
    before them, as the next round may need one too). The time per sample is not assumed
    constant over the render: a field solved as its samples need it, or a scene whose samples
    cost more as the render goes on, makes the mean over every sample so far judge too low."""
    if round_samples < 1:
        return count
    per_sample = round_seconds / round_samples
    if not per_sample > 0.0:
        return count
    return max(0, min(count, int(seconds_left / per_sample)))


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
        only; a callable: the field it returns, read by each add, as a render job solves it
        while it samples) from `camera` (None: the scene's).
    """
    if path_tracer_settings is not None:
        tracer = shgi.PathTracer(scene, path_tracer_settings)
        return Renderer(lambda count: tracer.render(count, progress=progress), tracer.passes)
    preview = shgi.PreviewRenderer(scene, preview_settings, camera=camera)
    return Renderer(lambda count: preview.render(field() if callable(field) else field, count,
                                                 progress=progress),
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
    denoising: a settings.Denoising to denoise the result with, or None.
    time_limit: seconds the job may take (0: no limit).
    """

    def __init__(self, shgi, scene, samples, *, path_tracer_settings=None,
                 preview_settings=None, solver_recipe=None, field=None, camera=None,
                 denoising=None, time_limit=0.0):
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
        self._denoising = denoising
        self._deadline = None
        self.time_limit = time_limit
        self.samples_done = 0
        self.denoised = False
        self.denoise_error = None  # why a render that should be denoised is not
        self.timings = {}       # seconds per stage: commit, solve, render, denoise
        self.solution = None    # the solution_cache.Solution the job solved, if any (not cached)
        self._solve_stopped = False  # a Time Limit cut the solve short: no passes after it
        self.rounds = []  # (seconds, samples) of each sampling round, its solve included

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
        if self.time_limit > 0.0:
            self._deadline = time.perf_counter() + self.time_limit
        denoiser = self._make_denoiser()
        try:
            self._render(denoiser)
        finally:
            if denoiser is not None:
                denoiser.close()

    def _render(self, denoiser):
        render_start = COMMIT_SHARE
        if not self.scene.committed:
            self._timed("commit", "Building BVH", (0.0, COMMIT_SHARE),
                        lambda: self.scene.commit(progress=self.progress))
        if self._solver_recipe is not None and self.field is None:
            render_start = COMMIT_SHARE + SOLVE_SHARE
            self._timed("solve", self._solver_recipe.solver.BUILD_STAGE,
                        (COMMIT_SHARE, render_start), self._solve_field)
        self._sample(render_start, denoiser)
        if denoiser is not None:
            self._timed("denoise", "Denoising", (1.0, 1.0), lambda: self._denoise(denoiser))

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

        deadline = None
        if self._deadline is not None:
            deadline = self._deadline - (1.0 - SOLVE_TIME_SHARE) * self.time_limit
        recipe = self._solver_recipe
        self.solution = solution_cache.solve(self._shgi, self.scene, recipe, signature=None,
                                             progress=self.progress, on_stage=on_stage,
                                             deadline=deadline,
                                             passes=self._passes_for(sample_rounds(
                                                 self.samples)[0]))
        self.field = self.solution.field

    def _passes_for(self, samples):
        """The passes of the job's recipe its first `samples` samples need solved."""
        recipe = self._solver_recipe
        return recipe.solver.passes_for_samples(recipe.settings, samples, recipe.passes)

    def _missing_passes(self, samples):
        """The passes the first `samples` samples need when the solution lacks some (a field
        whose samples read passes of their own, solved as the rounds need them), else None."""
        if self.solution is None or self._solve_stopped:
            return None
        passes = self._passes_for(samples)
        return passes if self.solution.solver.passes < passes else None

    def _refine(self, passes):
        """Solves up to `passes` passes (fewer when the Time Limit comes first: then no more)."""
        solution_cache.refine(self.solution, passes, self._solver_recipe.passes, self.progress,
                              deadline=self._deadline)
        self.field = self.solution.field
        self._solve_stopped = self.solution.solver.passes < passes

    def _make_denoiser(self):
        """The FrameDenoiser of the job's Denoising (None when off or unavailable), its networks
        set up for the frame's size when the job has a Time Limit (so that the denoise the
        rounds leave time for does not begin with the setup of a network not run before)."""
        if self._denoising is None:
            return None
        denoiser = None
        try:
            denoiser = self._denoising.make()
            if self._deadline is not None:
                camera = self._camera if self._camera is not None else self.scene.camera
                self._timed("denoise", "Preparing the denoiser", (0.0, 0.0),
                            lambda: denoiser.prepare(camera.resolution_x, camera.resolution_y))
            return denoiser
        except (ImportError, RuntimeError, ValueError) as error:  # no pyoidn, an OIDN failure
            self.denoise_error = f"the render is not denoised: {error}"
        if denoiser is not None:
            denoiser.close()
        return None

    def _sample(self, render_start, denoiser):
        # A Time Limit that cut the first solve short keeps its passes.
        self._solve_stopped = (self.solution is not None and self.solution.solver.passes <
                               self._passes_for(sample_rounds(self.samples)[0]))
        renderer = make_renderer(self._shgi, self.scene, self.progress,
                                 path_tracer_settings=self._path_tracer_settings,
                                 preview_settings=self._preview_settings,
                                 field=lambda: self.field, camera=self._camera)
        name = "Path tracing" if self._path_tracer_settings is not None else "Rendering"
        for count in sample_rounds(self.samples):
            count = self._samples_in_time(count, denoiser)
            if count == 0:
                break
            round_start = time.perf_counter()
            lo = render_start + (1.0 - render_start) * self.samples_done / self.samples
            hi = render_start + (1.0 - render_start) * (self.samples_done + count) / self.samples
            stage = f"{name}, sample {self.samples_done + count}/{self.samples}"
            try:
                passes = self._missing_passes(self.samples_done + count)
                if passes is not None:
                    self._timed("solve", f"{self._solver_recipe.solver.pass_stage(passes)}/"
                                f"{self._solver_recipe.passes}", (lo, lo),
                                lambda: self._refine(passes))
                self._timed("render", stage, (lo, hi), lambda: renderer.add(count))
            except self._shgi.Cancelled:
                self._keep(renderer, None)  # every pass of the rounds done before Esc
                raise
            self.samples_done += count
            self.rounds.append((time.perf_counter() - round_start, count))
            self._keep(renderer, SHOWN_PASSES)
        self._keep(renderer, None)

    def _keep(self, renderer, names):
        """Makes the renderer's passes (`names`, or all) the newest snapshot (none before the
        first sample)."""
        if self.samples_done == 0:
            return
        snapshot = Snapshot(renderer.passes(names), self.samples_done)
        with self._lock:
            self._snapshot, self._snapshot_taken = snapshot, False

    def _samples_in_time(self, count, denoiser):
        """How many of a round's `count` samples fit before the deadline (all without one; at
        least one for the first round), judged by the last round (samples_in_time)."""
        if self._deadline is None or not self.rounds:
            return count
        left = self._deadline - time.perf_counter()
        if denoiser is not None:
            height, width = self._snapshot.passes["Combined"].shape[:2]
            left -= denoiser.estimate_seconds(width, height)
        return samples_in_time(count, left, *self.rounds[-1])

    def _denoise(self, denoiser):
        """Replaces the last snapshot by its denoised passes (a failure is kept as
        denoise_error and leaves the snapshot noisy)."""
        snapshot = self.last_snapshot()
        if snapshot is None:
            return
        try:
            left = None if self._deadline is None else self._deadline - time.perf_counter()
            denoised = denoiser.denoise(snapshot.passes, self.progress, snapshot.samples, left)
        except (RuntimeError, ValueError) as error:
            self.denoise_error = f"the render is not denoised: {error}"
            return
        passes = dict(snapshot.passes, **denoised)
        with self._lock:
            self._snapshot = Snapshot(passes, snapshot.samples)
            self._snapshot_taken = False
        self.denoised = True
