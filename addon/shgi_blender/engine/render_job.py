"""One final (F12) render on a worker thread: commit, solve, progressive sampling. No bpy.

The render engine exports the scene on Blender's main thread (bpy is not thread-safe), starts a
RenderJob, and then polls it from the main thread: it forwards Esc (``test_break``) to
``cancel()``, shows ``fraction`` and ``stage``, and copies each new snapshot into the render
result. Every native call the job makes releases the GIL, so the main thread stays responsive;
``cancel()`` makes the running call raise ``shgi.Cancelled`` within one chunk of work (< 0.2 s,
DESIGN.md), and the job keeps the last complete snapshot, so an interrupted render still shows
every sample finished before Esc.

Sampling runs in rounds (``sample_rounds``): the first round is one sample per pixel so that an
image appears at once; rounds then double, up to an eighth of the total. Both renderers give the
same image however the samples are split between calls, so rounds cost only their snapshots.
"""

import threading
import time
from dataclasses import dataclass

from . import solution_cache

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


class RenderJob:
    """Renders a shgi.Scene with one method on a worker thread.

    scene: a shgi.Scene (committed by the job if it is not yet).
    samples: samples per pixel in total.
    path_tracer_settings: renders with the reference path tracer when given.
    preview_settings: renders with the preview renderer over `field`, or over a PhotonLattice
        solved first with `lattice_settings` when `field` is None, or with direct light only
        when both are None (a scene without geometry has nothing to solve).
    camera: a shgi.Camera replacing the scene's (a frozen solution seen from a new camera).
    """

    def __init__(self, shgi, scene, samples, *, path_tracer_settings=None,
                 preview_settings=None, lattice_settings=None, field=None, camera=None):
        if (path_tracer_settings is None) == (preview_settings is None):
            raise ValueError("give exactly one of path_tracer_settings and preview_settings")
        self._shgi = shgi
        self.scene = scene
        self.samples = samples
        self._path_tracer_settings = path_tracer_settings
        self._preview_settings = preview_settings
        self._lattice_settings = lattice_settings
        self.field = field
        self._camera = camera
        self._progress = shgi.Progress()
        self._lock = threading.Lock()
        self._snapshot = None
        self._snapshot_taken = True
        self._span = (0.0, COMMIT_SHARE)
        self._stage = "Starting"
        self._thread = threading.Thread(target=self._run, name="shgi-render", daemon=True)
        self.error = None       # the exception that ended the job, other than Cancelled
        self.cancelled = False
        self.samples_done = 0
        self.timings = {}       # seconds per stage: commit, solve, render
        self.solution = None    # the LatticeSolution the job solved, if any (not cached)

    # --- main thread ---------------------------------------------------------------------------

    def start(self):
        self._thread.start()
        return self

    def cancel(self):
        """Asks the running native call to stop (it raises Cancelled within one chunk)."""
        self._progress.cancel()

    def wait(self, timeout=None):
        """Waits up to `timeout` seconds; True when the job has ended."""
        self._thread.join(timeout)
        return not self._thread.is_alive()

    @property
    def running(self):
        return self._thread.is_alive()

    @property
    def fraction(self):
        """Overall progress in [0, 1]."""
        with self._lock:
            lo, hi = self._span
        return lo + (hi - lo) * min(max(self._progress.fraction, 0.0), 1.0)

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

    def _run(self):
        try:
            render_start = COMMIT_SHARE
            if not self.scene.committed:
                self._timed("commit", "Building BVH", (0.0, COMMIT_SHARE),
                            lambda: self.scene.commit(progress=self._progress))
            if self._lattice_settings is not None and self.field is None:
                render_start = COMMIT_SHARE + SOLVE_SHARE
                self._timed("solve", "Tracing photons", (COMMIT_SHARE, render_start),
                            self._solve_lattice)
            self._sample(render_start)
        except self._shgi.Cancelled:
            self.cancelled = True
        except Exception as error:  # reported by the engine on the main thread
            self.error = error

    def _timed(self, name, stage, span, work):
        with self._lock:
            self._stage, self._span = stage, span
        start = time.perf_counter()
        try:
            work()
        finally:  # a cancelled stage still shows the time it ran
            self.timings[name] = self.timings.get(name, 0.0) + time.perf_counter() - start

    def _solve_lattice(self):
        self.solution = solution_cache.solve(self._shgi, self.scene, self._lattice_settings,
                                             signature=None, progress=self._progress)
        self.field = self.solution.lattice

    def _sample(self, render_start):
        shgi = self._shgi
        if self._path_tracer_settings is not None:
            renderer = shgi.PathTracer(self.scene, self._path_tracer_settings)
            add_samples = lambda count: renderer.render(count, progress=self._progress)  # noqa
            name = "Path tracing"
        else:
            renderer = shgi.PreviewRenderer(self.scene, self._preview_settings,
                                            camera=self._camera)
            add_samples = lambda count: renderer.render(  # noqa: E731
                self.field, count, progress=self._progress)
            name = "Rendering"
        for count in sample_rounds(self.samples):
            lo = render_start + (1.0 - render_start) * self.samples_done / self.samples
            hi = render_start + (1.0 - render_start) * (self.samples_done + count) / self.samples
            stage = f"{name}, sample {self.samples_done + count}/{self.samples}"
            self._timed("render", stage, (lo, hi), lambda: add_samples(count))
            self.samples_done += count
            snapshot = Snapshot(renderer.passes(), self.samples_done)
            with self._lock:
                self._snapshot, self._snapshot_taken = snapshot, False
