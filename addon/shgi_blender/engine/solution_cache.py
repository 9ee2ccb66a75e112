"""Frozen field solutions, one per Blender scene, kept between renders. No bpy.

Non-interactive mode (DESIGN.md, use 2c; seed 000 §6.5): the Solve operator exports the scene,
solves the method's field once (a PhotonLattice with the scene's photon count, or a ProbeGrid
with its render passes; field_solvers.py) and stores it here with the committed shgi.Scene it
was solved on. F12 renders of that Blender scene with the same method then render the frozen
solution from the current camera without exporting the geometry or solving again, until Clear.
Edits made after the solve are not seen (the panel says so).

``solve`` is also how F12 solves a field when nothing is frozen (render_job.RenderJob).

The cache is module state of the add-on (it cannot live in the .blend file); its key is the
scene's ``name_full``, and loading a file clears it (render_engine.py registers the handler).
"""

import time
from dataclasses import dataclass, field

# Bytes in a mebibyte: memory figures are shown in MiB.
BYTES_PER_MIB = 2**20
# Share of a solve's progress taken by the solver's construction (measure, placement).
BUILD_SHARE = 0.1

# Timings shown in the panel, in order: {key in Solution.timings: label}.
TIMING_LABELS = {
    "export": "Export",
    "commit": "BVH",
    "measure": "Cell areas",
    "emit_trace": "Emit + trace",
    "injection": "Injection",
    "blur": "Blur",
    "placement": "Probe placement",
    "update": "Probe updates",
}


@dataclass
class Solution:
    """A solved field with the scene it was solved on."""

    method: str            # the method identifier it was solved for (settings.METHODS)
    scene: object          # the committed shgi.Scene
    solver: object         # the field_solvers FieldSolver (LatticeSolver, ProbeGridSolver)
    field: object          # the IndirectField to render (solver.field() after the last pass)
    signature: tuple       # settings.solver_signature() at solve time (None: not compared)
    timings: dict          # seconds per stage (TIMING_LABELS) and the solver's counters
    memory_bytes: int      # held by the solver
    warnings: list = field(default_factory=list)  # export warnings
    solved_at: float = field(default_factory=time.time)
    overlay: object = None  # its field_spheres.FieldSpheres (the Solve operator's), or None

    @property
    def seconds(self):
        """Wall time of the stages shown in the panel."""
        return sum(self.timings.get(name, 0.0) for name in TIMING_LABELS)


def solve(shgi, scene, recipe, signature, progress=None, timings=None, warnings=(),
          on_stage=None):
    """Commits `scene` (if needed), builds the recipe's solver and runs its passes; a Solution.

    Runs on any thread (no bpy); raises shgi.Cancelled when `progress` is cancelled.
    recipe: a field_solvers.SolverRecipe.
    timings: stage seconds measured before (the export), kept in the solution's timings.
    on_stage: called as on_stage(stage name, lo, hi) when a stage starts, [lo, hi] being its
        share of the whole solve (for a progress bar).
    """
    on_stage = on_stage or (lambda _stage, _lo, _hi: None)
    timings = dict(timings or {})
    start = time.perf_counter()
    if not scene.committed:
        on_stage("Building BVH", 0.0, 0.0)
        scene.commit(progress=progress)
    timings["commit"] = time.perf_counter() - start
    on_stage(recipe.solver.BUILD_STAGE, 0.0, BUILD_SHARE)
    start = time.perf_counter()
    solver = recipe.build(shgi, scene, progress)
    timings[recipe.solver.BUILD_TIMING] = time.perf_counter() - start
    for index in range(recipe.passes):
        share = (1.0 - BUILD_SHARE) / recipe.passes
        on_stage(f"{solver.pass_stage(index + 1)}/{recipe.passes}",
                 BUILD_SHARE + index * share, BUILD_SHARE + (index + 1) * share)
        solver.update(progress)
    timings.update(solver.timings)
    return Solution(method=recipe.solver.METHOD, scene=scene, solver=solver,
                    field=solver.field(), signature=signature, timings=timings,
                    memory_bytes=solver.memory_bytes, warnings=list(warnings))


_solutions = {}


def store(key, solution):
    _solutions[key] = solution


def get(key, method=None):
    """The frozen solution of scene `key` (solved for `method` when given), or None."""
    solution = _solutions.get(key)
    if solution is not None and method is not None and solution.method != method:
        return None
    return solution


def clear(key):
    """Forgets the solution of scene `key`; True when there was one."""
    return _solutions.pop(key, None) is not None


def clear_all():
    _solutions.clear()
