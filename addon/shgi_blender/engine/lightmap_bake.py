"""Lightmap bakes on a worker thread, polled from Blender's main thread. No bpy.

The bake operators (operators/bake_lightmaps.py) export the scene and decide what to bake on
the main thread (a BakeRequest), then a BakeTask does the native work on a NativeTask thread:

1. commit the exported scene (the BVH);
2. for a field source, solve the field with solution_cache.solve (the recipe of
   engine/field_solvers.py: scene.shgi's photon lattice or probe grid settings);
3. shgi.bake.bake_scene (whole lightmaps, or one shard's raw files) or shgi.bake.merge_shards;
   with a farm target (Bake > Farm "Dask"), shgi.farm.bake_scene_on_cluster instead: the scene
   travels to the Dask workers, which solve the field (step 2 is skipped here) and bake the
   shards, merged here into the lightmaps a bake here writes.

Each lightmap that completes is queued (``take_finished``): a worker thread must not touch bpy,
so the main thread turns them into Blender images, as they come in a modal bake's timer or at
the end of a synchronous one. ``cancel()`` stops the running native call (shgi.Cancelled within
one tile); lightmaps completed before it stay queued and their files stay written.
"""

import queue
import time
from dataclasses import dataclass

import numpy as np

from . import solution_cache
from .native_task import NativeTask

# Share of the progress bar taken by the field's solve, when the bake solves one first.
SOLVE_SHARE = 0.3
# Image.pixels holds RGBA.
BLENDER_CHANNELS = 4


@dataclass
class BakeRequest:
    """Everything a bake needs, made on the main thread; plain shgi values, no bpy."""

    scene: object            # the exported shgi.Scene (committed by the task if needed)
    jobs: list               # shgi.bake.BakeJob per object, in bake order
    options: object          # shgi.bake.BakeOptions
    out_dir: str             # absolute output folder
    recipe: object = None    # field_solvers.SolverRecipe of the field source; None: path tracer
    shard: tuple = None      # (index, count): write that shard's raw files; None: whole bake
    merge_shards: int = 0    # > 0: merge that many shard files instead of baking
    farm: object = None      # bake_settings.FarmTarget: bake the shards on a Dask cluster


class BakeTask(NativeTask):
    """A BakeRequest run on a worker thread; finished lightmaps queue up for the main thread."""

    def __init__(self, shgi, request):
        super().__init__(shgi, "shgi-bake")
        from shgi import bake as shgi_bake

        self._bake_module = shgi_bake
        self.request = request
        self.bake_progress = shgi_bake.BakeProgress()
        self.results = []     # bake_scene's / merge_shards' return value once it ended
        self.timings = {}     # seconds: "commit", "solve" (field sources), "bake"
        self._finished = queue.Queue()
        self._solve_range = None  # [lo, hi] of the solve's current stage, None outside the solve
        self._solve_stage = ""

    # --- main thread ---------------------------------------------------------------------------

    def cancel(self):
        """Stops the bake within one tile; what finished before stays (take_finished)."""
        self.bake_progress.cancel()

    @property
    def fraction(self):
        """Progress of the whole request in [0, 1]."""
        progress = self.bake_progress
        if self._solve_range is not None:
            lo, hi = self._solve_range
            return SOLVE_SHARE * (lo + (hi - lo) * progress.fraction)
        if self.request.recipe is None:
            return progress.fraction
        return SOLVE_SHARE + (1.0 - SOLVE_SHARE) * progress.fraction

    @property
    def stage(self):
        if self._solve_range is not None:
            return self._solve_stage
        return self.bake_progress.stage

    def take_finished(self):
        """The shgi.bake.Lightmaps completed since the last call, in bake order."""
        lightmaps = []
        while True:
            try:
                lightmaps.append(self._finished.get_nowait())
            except queue.Empty:
                return lightmaps

    # --- worker thread -------------------------------------------------------------------------

    def _work(self):
        request = self.request
        start = time.perf_counter()
        if not request.scene.committed:
            request.scene.commit(progress=self.bake_progress.native(0.0, 0.0, "Building BVH"))
        self.timings["commit"] = time.perf_counter() - start
        if request.farm is not None:
            self._bake_on_farm()
            return
        field = self._solve_field() if request.recipe is not None else None
        start = time.perf_counter()
        bake = self._bake_module
        if request.merge_shards:
            self.results = bake.merge_shards(request.scene, request.jobs, request.options,
                                             request.out_dir, request.merge_shards,
                                             self.bake_progress)
            for lightmap in self.results:
                self._finished.put(lightmap)
        else:
            self.results = bake.bake_scene(request.scene, request.jobs, request.options,
                                           request.out_dir, field, request.shard,
                                           self.bake_progress, on_lightmap=self._finished.put)
        self.timings["bake"] = time.perf_counter() - start

    def _bake_on_farm(self):
        """The bake's shards on the Dask cluster of request.farm, merged here."""
        from shgi import farm

        request, target = self.request, self.request.farm
        recipe = None
        if request.recipe is not None:
            recipe = (request.recipe.solver.METHOD, request.recipe.settings,
                      request.recipe.passes)
        start = time.perf_counter()
        self.bake_progress.note(f"starting {target.workers} Dask workers" if not target.scheduler
                                else f"connecting to {target.scheduler}")
        with farm.connect(target.scheduler, target.workers,
                          cancelled=lambda: self.bake_progress.cancelled) as client:
            self.timings["connect"] = time.perf_counter() - start
            start = time.perf_counter()
            self.results = farm.bake_scene_on_cluster(
                client, request.scene, request.jobs, request.options, request.out_dir, recipe,
                target.shards, progress=self.bake_progress, on_lightmap=self._finished.put)
        self.timings["bake"] = time.perf_counter() - start

    def _solve_field(self):
        """Solves the request's field on its committed scene; the IndirectField to bake with."""
        def on_stage(stage, lo, hi):
            self._solve_stage = f"Solving: {stage}"
            self._solve_range = (lo, hi)

        start = time.perf_counter()
        on_stage("", 0.0, 0.0)
        native = self.bake_progress.native(0.0, 1.0, "Solving")
        try:
            solution = solution_cache.solve(self._shgi, self.request.scene, self.request.recipe,
                                            None, native, on_stage=on_stage)
        finally:
            self._solve_range = None
        self.timings["solve"] = time.perf_counter() - start
        return solution.field


def rgba_pixels(color):
    """Flat float32 RGBA for Image.pixels of an (H, W, 3) lightmap (alpha 1).

    shgi.bake's arrays have row 0 at v = 0, the bottom row, which is Image.pixels' first row:
    no flip.
    """
    color = np.asarray(color, np.float32)
    height, width, _ = color.shape
    rgba = np.ones((height, width, BLENDER_CHANNELS), np.float32)
    rgba[..., :3] = color
    return rgba.ravel()
