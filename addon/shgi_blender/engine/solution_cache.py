"""Frozen field solutions, one per Blender scene, kept between renders. No bpy.

Non-interactive mode (docs/architecture.md; seed 000 §6.5): the Solve operator exports the scene,
solves the method's field once (a PhotonLattice with the scene's photon count, or a ProbeGrid
with its render passes; field_solvers.py) and stores it here with the committed shgi.Scene it
was solved on. F12 renders of that Blender scene with the same method then render the frozen
solution from the current camera without exporting the geometry or solving again, until Clear.
Edits made after the solve are not seen: ``note_edit`` counts the edits of each scene that
change its light (solution_files.py feeds it from Blender's depsgraph updates), and
``changed_since`` tells a solution made before the last of them (F12 warns, the panel offers
Re-solve).

Probe Grid, Photon Lattice and Light Propagation solutions are saved beside the .blend file and
read back when the file opens (solution_files.py): ``save_solution`` writes the field natively
(FIELD_FILES: a ProbeField's float EXR + JSON export, a PhotonLattice's or PropagationField's
binary save) and a small JSON of the
solution's own figures; ``load_solution`` reads them into a Solution whose field came from the
file (LoadedProbeField, LoadedLattice), which renders the same pixels as before. F12 then
exports the scene's geometry once per render, as there is no solved scene to reuse.

``solve`` is also how F12 solves a field when nothing is frozen (render_job.RenderJob).

The cache is module state of the add-on; its key is the scene's ``name_full``, and loading a
file clears it (render_engine.py registers the handler) before the file's saved solutions are
read.
"""

import json
import os
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
    edits_seen: int = 0     # the scene's edit count (edit_count) when it was exported

    @property
    def seconds(self):
        """Wall time of the stages shown in the panel."""
        return sum(self.timings.get(name, 0.0) for name in TIMING_LABELS)


def solve(shgi, scene, recipe, signature, progress=None, timings=None, warnings=(),
          on_stage=None, deadline=None, passes=None):
    """Commits `scene` (if needed), builds the recipe's solver and runs its passes (or the first
    `passes` of them: refine runs the others); a Solution.

    Runs on any thread (no bpy); raises shgi.Cancelled when `progress` is cancelled.
    recipe: a field_solvers.SolverRecipe.
    timings: stage seconds measured before (the export), kept in the solution's timings.
    on_stage: called as on_stage(stage name, lo, hi) when a stage starts, [lo, hi] being its
        share of the whole solve (for a progress bar).
    deadline: a time.perf_counter() value (a render's Time Limit): after the first pass, a pass
        that would end past it (judged by the last pass's time) is not started.
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
    solution = Solution(method=recipe.solver.METHOD, scene=scene, solver=solver, field=None,
                        signature=signature, timings=timings, memory_bytes=0,
                        warnings=list(warnings))
    refine(solution, recipe.passes if passes is None else passes, recipe.passes, progress,
           on_stage, deadline)
    return solution


def refine(solution, passes, total, progress=None, on_stage=None, deadline=None):
    """Runs the passes of `solution`'s solver up to `passes` of `total` (none when it has them)
    and makes its field, memory and timings the solver's.

    on_stage, deadline: as solve's (stages named pass/total, shares of the passes run here).
    """
    on_stage = on_stage or (lambda _stage, _lo, _hi: None)
    solver = solution.solver
    first = solver.passes
    for index in range(first, passes):
        share = (1.0 - BUILD_SHARE) / (passes - first)
        lo = BUILD_SHARE + (index - first) * share
        on_stage(f"{solver.pass_stage(index + 1)}/{total}", lo, lo + share)
        pass_start = time.perf_counter()
        solver.update(progress)
        now = time.perf_counter()
        if deadline is not None and now + (now - pass_start) > deadline:  # the next would pass it
            break
    solution.timings.update(solver.timings)
    solution.field, solution.memory_bytes = solver.field(), solver.memory_bytes


_solutions = {}
# {scene key: (edits counted since the file opened, what the last one was)}
_edits = {}
# The format of the JSON save_solution writes beside the field's own files.
SOLUTION_FORMAT = "shgi-frozen-solution"
SOLUTION_VERSION = 1


@dataclass(frozen=True)
class FieldFile:
    """How a method's solved field is written beside a saved solution and read back."""

    suffix: str    # appended to the solution JSON's stem
    write: object  # write(field, path)
    read: object   # read(shgi, path, lookup) -> (field solver adapter, field)


def _read_probe_field(shgi, path, lookup):
    from .field_solvers import LoadedProbeField

    solver = LoadedProbeField(shgi, shgi.ProbeField.import_exr(path, lookup), path)
    return solver, solver.field()


def _read_propagation(shgi, path, _lookup):
    from .field_solvers import LoadedPropagationField

    solver = LoadedPropagationField(shgi.PropagationField.load(path), path)
    return solver, solver.field()


def _read_lattice(shgi, path, _lookup):
    from .field_solvers import LoadedLattice

    solver = LoadedLattice(shgi.PhotonLattice.load(path), path)
    return solver, solver.field()


# The methods whose solutions are saved with the .blend, by identifier.
FIELD_FILES = {
    "PROBE_GRID": FieldFile("_field.json", lambda field, path: field.export(path),
                            _read_probe_field),
    "PHOTON_LATTICE": FieldFile("_lattice.shlattice", lambda field, path: field.save(path),
                                _read_lattice),
    "PROPAGATION": FieldFile("_field.shlpv", lambda field, path: field.save(path),
                             _read_propagation),
}


# Datablocks whose edits leave the light alone: the scene's own settings (render settings, the
# frame, the selection) and the camera (a frozen solution is rendered from any camera).
_UNLIT_KINDS = ("Scene", "Camera")


def edit_description(kind, name, is_camera, moved, reshaped, reshaded):
    """What a depsgraph update of datablock `name` of type `kind` ("Object", "PointLight",
    "Material", ...) changed in the scene's light, or None for an update that changes none:
    the scene's settings, a camera, an object re-tagged without moving or changing shape."""
    if kind in _UNLIT_KINDS or is_camera:
        return None
    if kind == "Object":
        if moved:
            return f"object {name!r} moved"
        return f"object {name!r} changed" if reshaped else None
    return f"{kind} {name!r} changed" if moved or reshaped or reshaded else None


def note_edit(key, what):
    """Counts an edit of scene `key` that changes its light; `what` says what changed."""
    count, _ = _edits.get(key, (0, ""))
    _edits[key] = (count + 1, what)


def edit_count(key):
    """Edits of scene `key` counted so far (a solution keeps the count at its export)."""
    return _edits.get(key, (0, ""))[0]


def changed_since(key, solution):
    """What changed in scene `key` after `solution` was exported (the last edit), or None."""
    count, what = _edits.get(key, (0, ""))
    return what if count > solution.edits_seen else None


def solved_at_text(solution):
    """The local time of day the solution was solved, e.g. "10:42:07"."""
    return time.strftime("%H:%M:%S", time.localtime(solution.solved_at))


def save_solution(solution, json_path):
    """Writes a solution of a method of FIELD_FILES: its field at json_path's stem + the
    method's suffix (a Probe Grid's EXR files beside it), and json_path with the solution's
    method, time, settings signature and figures. ValueError for a solution whose field cannot
    be written back."""
    field_file = FIELD_FILES.get(solution.method)
    if field_file is None:
        raise ValueError(f"a {solution.method} solution cannot be saved: only "
                         f"{' and '.join(FIELD_FILES)} fields are read back")
    field_path = json_path[: -len(".json")] + field_file.suffix
    field_file.write(solution.field, field_path)
    doc = {"format": SOLUTION_FORMAT, "version": SOLUTION_VERSION, "method": solution.method,
           "solved_at": solution.solved_at, "field": os.path.basename(field_path),
           "signature": None if solution.signature is None else list(solution.signature),
           "timings": solution.timings, "warnings": solution.warnings,
           "passes": solution.solver.passes}
    with open(json_path, "w", encoding="utf-8") as out:
        json.dump(doc, out, indent=1)


def load_solution(shgi, json_path, lookup):
    """The Solution save_solution wrote at json_path, a probe field's probes read with `lookup`
    (shgi.ProbeLookupSettings); OSError or ValueError naming the file when it is not one."""
    with open(json_path, encoding="utf-8") as file:
        doc = json.load(file)
    if doc.get("format") != SOLUTION_FORMAT or doc.get("version") != SOLUTION_VERSION:
        raise ValueError(f"{json_path} is not a saved SHGI solution (format "
                         f"{SOLUTION_FORMAT} {SOLUTION_VERSION})")
    field_file = FIELD_FILES.get(doc.get("method"))
    if field_file is None:
        raise ValueError(f"{json_path} holds a {doc.get('method')} solution, which this "
                         "version cannot read")
    field_path = os.path.join(os.path.dirname(json_path), doc["field"])
    solution = _read_solution(shgi, field_file, field_path, lookup)
    solution.solved_at = doc["solved_at"]
    solution.signature = (None if doc["signature"] is None
                          else tuple(tuple(pair) for pair in doc["signature"]))
    solution.timings = doc["timings"]
    solution.warnings = doc["warnings"]
    if hasattr(solution.solver, "saved_passes"):  # a field whose file does not count them
        solution.solver.saved_passes = doc.get("passes")
    return solution


def loaded_solution(shgi, field_json_path, lookup):
    """A Solution of the probe field a ProbeField.export wrote (Export Volume's files), read with
    `lookup`; its scene is None (F12 exports the current one) and its signature None (its
    settings are unknown). ValueError naming the file for a photon lattice's export."""
    with open(field_json_path, encoding="utf-8") as file:
        doc = json.load(file)
    if "lattices" in doc:
        raise ValueError(f"{field_json_path} holds photon lattices, which SHGI cannot read back "
                         "(there is no lattice import): Solve the Photon Lattice instead, or "
                         "load a Probe Grid volume")
    return _read_solution(shgi, FIELD_FILES["PROBE_GRID"], field_json_path, lookup)


def _read_solution(shgi, field_file, field_path, lookup):
    """A Solution of the field at field_path, read as `field_file` says; its scene is None (F12
    exports the current one), its signature None (its settings are unknown) and its time the
    file's."""
    solver, field_ = field_file.read(shgi, field_path, lookup)
    return Solution(method=solver.METHOD, scene=None, solver=solver, field=field_,
                    signature=None, timings={}, memory_bytes=solver.memory_bytes,
                    solved_at=os.path.getmtime(field_path), overlay=solver.overlay(None, None))


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
    _edits.clear()


def keys():
    """The scene keys that have a frozen solution."""
    return list(_solutions)
