"""The solvers of the field methods as the engine drives them: build, update passes, field. No bpy.

Every method that solves a field is a shgi.GiSolver (docs/solvers.md); FieldSolver drives one
for F12 (render_job.RenderJob), frozen solutions (solution_cache.solve, the Solve operator) and
the viewport worker, which all use it the same way:

* construction (``SolverRecipe.build``, shgi.make_solver) on a committed scene: the lattice
  measures its cells, the probe grid places its probes (relocation out of geometry, DDGI);
* ``update(progress)``: one refinement pass (GiSolver.refine: a photon pass, a probe update
  pass blended in with hysteresis, ...);
* ``field()``: what to render (GiSolver.current_field), for the probe grid an immutable
  ProbeField snapshot that later updates leave untouched (seed 002 Fig. 4.1);
* ``overlay(snapshot, scene)``: the field_spheres.FieldSpheres the 3D views draw, and
  ``figures()``, the panel's rows: LatticeSolver's and ProbeGridSolver's own.

Every native call takes a shgi.Progress and releases the GIL; none of this touches bpy.
"""

import time
from dataclasses import dataclass

import numpy as np

from .. import settings
from ..export.light_probe import native_volumes


class FieldSolver:
    """A registered method's shgi.GiSolver as the engine drives it: refine passes, its field,
    its stage timings. Serves any method as it is (a plugin's: no overlay); LatticeSolver and
    ProbeGridSolver add their figures and overlays. SolverRecipe.build constructs it."""

    METHOD = ""
    BUILD_STAGE = "Building the solver"
    BUILD_TIMING = "build"

    @classmethod
    def of(cls, method):
        """This class bound to method `method`."""
        return type(f"{cls.__name__}[{method}]", (cls,), {"METHOD": method})

    def __init__(self, shgi, scene, native_settings, progress=None):
        self._shgi = shgi
        self.solver = shgi.make_solver(self.METHOD, scene, native_settings, progress)

    @staticmethod
    def pass_stage(number):
        return f"Refining, pass {number}"

    @staticmethod
    def passes_for_samples(_native_settings, _samples, passes):
        """How many of a solve's `passes` must be solved before a preview renders its first
        `samples` samples as it would over all of them: all of them (every sample reads every
        pass). F12 solves the others while it samples (render_job.RenderJob)."""
        return passes

    @property
    def passes(self):
        return self.solver.passes

    def update(self, progress=None):
        self.solver.refine(progress)

    def field(self):
        return self.solver.current_field()

    @property
    def memory_bytes(self):
        return self.solver.memory_bytes

    @property
    def timings(self):
        """Seconds of the last pass's stages."""
        return dict(self.solver.stage_seconds)

    def figures(self):
        """(label, text) rows describing the solution, for the panel and reports."""
        return [("Refinement passes", f"{self.solver.passes}")]

    def overlay(self, _snapshot, _scene):
        return None

    def follow_view(self, _camera, _progress=None):
        """Moves what follows the camera to the viewport's view (shgi.Camera); returns what
        moved (nothing here)."""
        return []


class PropagationSolver(FieldSolver):
    """A PropagationVolume (seed 003) as a FieldSolver: its cascade levels follow the viewport's
    view while the artist navigates (PropagationVolume.recenter), not only the view it was
    built with."""

    METHOD = "PROPAGATION"

    def follow_view(self, camera, progress=None):
        """Re-centres the cascade levels whose inner region the view's eye left and rebuilds
        those alone; the levels moved. Nothing without cascades or with Follow Camera off."""
        native = self.solver.settings
        if native.cascades < 2 or not native.cascade_follow_camera:
            return []
        eye = np.asarray(camera.world_from_camera, dtype=np.float64)[:3, 3]
        return self.solver.recenter(eye, progress)


class InstantGiSolver(FieldSolver):
    """An InstantGi (seed 004) as a FieldSolver: its figures add the VPL sets and the last
    frame's screen-space stages (gather, filter, shade)."""

    METHOD = "INSTANT_GI"

    @staticmethod
    def pass_stage(number):
        return f"Tracing VPLs, pass {number}"

    @staticmethod
    def passes_for_samples(native_settings, samples, passes):
        """Sample i gathers passes i k .. i k + k - 1 (k: passes_per_sample) while the field
        has them: the first `samples` samples need samples x k passes, and render over those
        bit for bit as over all `passes` (tests/python/test_instant_gi.py)."""
        return min(passes, samples * native_settings.passes_per_sample)

    def figures(self):
        field = self.solver.current_field()
        sizes = field.set_sizes
        rows = [("Refinement passes", f"{self.solver.passes}"),
                ("VPLs", f"{field.vpl_count} in {len(sizes)} sets")]
        frame = field.frame_timings
        if any(frame.values()):
            rows.append(("Last frame", ", ".join(f"{stage} {seconds:.3f} s"
                                                  for stage, seconds in frame.items())))
        return rows


class LatticeSolver(FieldSolver):
    """A PhotonLattice (seed 000) as a FieldSolver."""

    METHOD = "PHOTON_LATTICE"
    BUILD_STAGE = "Measuring lattice cells"
    BUILD_TIMING = "measure"

    @property
    def lattice(self):
        return self.solver

    @staticmethod
    def pass_stage(number):
        return f"Tracing photons, pass {number}"

    @property
    def timings(self):
        """Seconds per stage and the photon counters (PhotonLattice.timings)."""
        return dict(self.lattice.timings)

    def figures(self):
        return lattice_figures(self.lattice)

    def overlay(self, snapshot, scene):
        from .lattice_samples import lattice_overlay

        return lattice_overlay(self.lattice, snapshot, scene, self.lattice.settings.resolution)


class ProbeGridSolver(FieldSolver):
    """A ProbeGrid (seed 002) as a FieldSolver."""

    METHOD = "PROBE_GRID"
    BUILD_STAGE = "Placing probes"
    BUILD_TIMING = "placement"

    def __init__(self, shgi, scene, grid_settings, progress=None):
        super().__init__(shgi, scene, grid_settings, progress)
        self._update_seconds = 0.0
        self._snapshot = None

    @property
    def grid(self):
        return self.solver

    @staticmethod
    def pass_stage(number):
        return f"Updating probes, pass {number}"

    def update(self, progress=None):
        start = time.perf_counter()
        try:
            super().update(progress)
        finally:  # a cancelled pass still took its time
            self._update_seconds += time.perf_counter() - start

    def field(self):
        """The ProbeField of the current pass (one snapshot per pass)."""
        if self._snapshot is None or self._snapshot.passes != self.grid.passes:
            self._snapshot = self.grid.field()
        return self._snapshot

    @property
    def timings(self):
        """Seconds of all update passes ("update") and the paths of the last one."""
        return {"update": self._update_seconds, "paths": self.grid.timings["paths"]}

    def figures(self):
        grid = self.grid
        error = grid.relative_error()[grid.active]
        finite = error[np.isfinite(error)]
        rows = probe_figures(grid.active_count, grid.probe_count, grid.passes)
        if len(finite):
            rows.append(("Median relative error", f"{100.0 * float(np.median(finite)):.1f}%"))
        return rows

    def overlay(self, _snapshot, _scene):
        return probe_overlay(self._shgi, self.field())


class LoadedProbeField:
    """A ProbeField read from files (a saved solution, or Export Volume's) in a FieldSolver's
    place: nothing to update, its probes' figures and overlay."""

    METHOD = ProbeGridSolver.METHOD

    def __init__(self, shgi, probe_field, path):
        self._shgi = shgi
        self._field = probe_field
        self.path = path

    @property
    def passes(self):
        return self._field.passes

    def field(self):
        return self._field

    @property
    def memory_bytes(self):
        return sum(getattr(self._field, name).nbytes
                   for name in ("sh", "positions", "active", "variance"))

    @property
    def timings(self):
        return {}

    def figures(self):
        probe_field = self._field
        return probe_figures(int(probe_field.active.sum()), probe_field.probe_count,
                             probe_field.passes) + [("Read from", self.path)]

    def overlay(self, _snapshot, _scene):
        return probe_overlay(self._shgi, self._field)


class LoadedLattice:
    """A PhotonLattice read from a saved solution's file (PhotonLattice.load) in a FieldSolver's
    place: nothing to update (it has no scene), the saved figures, and spheres at the cells
    that hold light."""

    METHOD = LatticeSolver.METHOD

    def __init__(self, lattice, path):
        self.lattice = lattice
        self.path = path

    @property
    def passes(self):
        return self.lattice.passes

    def field(self):
        return self.lattice

    @property
    def memory_bytes(self):
        return self.lattice.memory_bytes

    @property
    def timings(self):
        return dict(self.lattice.timings)

    def figures(self):
        return lattice_figures(self.lattice) + [("Read from", self.path)]

    def overlay(self, _snapshot, _scene):
        """Spheres at the centres of the global lattice's cells holding light (the saved file
        has no scene to find the cells holding surface in), or None when none does."""
        from .field_spheres import field_spheres

        grid = self.lattice.lattices["global"]
        lit = np.argwhere(np.any(grid["sh"] != 0.0, axis=(3, 4)))  # (K, 3) as (k, j, i)
        if len(lit) == 0:
            return None
        cell = grid["cell_size"]
        centres = np.asarray(grid["origin"]) + (lit[:, ::-1] + 0.5) * cell
        return field_spheres(self.lattice, centres, cell)


class LoadedPropagationField:
    """A PropagationField read from a saved solution's file (PropagationField.load) in a
    FieldSolver's place: nothing to update (it has no scene), its passes as the solution's file
    recorded them (saved_passes, set when read)."""

    METHOD = "PROPAGATION"

    def __init__(self, field, path):
        self._field = field
        self.path = path
        self.saved_passes = None

    @property
    def passes(self):
        return self.saved_passes or 0

    def field(self):
        return self._field

    @property
    def memory_bytes(self):
        return self._field.memory_bytes

    @property
    def timings(self):
        return {}

    def figures(self):
        return [("Refinement passes", f"{self.passes}"), ("Read from", self.path)]

    def overlay(self, _snapshot, _scene):
        return None


def lattice_figures(lattice):
    """The (label, text) rows of a PhotonLattice: the photons of its last pass."""
    timings = lattice.timings
    return [("Photons emitted / stored", f"{int(timings.get('photons_emitted', 0)):,} / "
                                         f"{int(timings.get('photons_stored', 0)):,}")]


def probe_figures(active, total, passes):
    """The (label, text) rows every probe field shows: its probes and update passes."""
    return [("Probes active / total", f"{active:,} / {total:,}"), ("Update passes", f"{passes}")]


def probe_overlay(shgi, probe_field):
    """The FieldSpheres of the active probes of a ProbeField, or None when none is active.

    Each sphere shows its probe's own irradiance: the field is read at the probe's position
    without normal bias and visibility weights, where trilinear interpolation gives that probe
    the whole weight (a relocated probe, off its cell centre, shows a blend of its neighbours,
    as a surface there would).
    """
    from .field_spheres import field_spheres

    active = probe_field.active
    if not active.any():
        return None
    lookup = probe_field.with_lookup(shgi.ProbeLookupSettings(normal_bias=0.0, visibility=False))
    return field_spheres(lookup, probe_field.positions[active], probe_spacing(probe_field.volumes))


def probe_spacing(volumes):
    """The smallest distance (m) between neighbouring probes of the volumes: 2 × (length of
    the volume's axis) / probes along it, over every axis and volume."""
    spacings = []
    for volume in volumes:
        matrix = np.asarray(volume.world_from_volume, np.float64)
        lengths = np.linalg.norm(matrix[:3, :3], axis=0)  # the images of the local axes
        spacings.extend(2.0 * lengths / np.asarray(volume.resolution, np.float64))
    return float(min(spacings))


@dataclass(frozen=True)
class SolverRecipe:
    """What to solve: a FieldSolver class, its native settings and the update passes to run."""

    solver: type
    settings: object
    passes: int

    def build(self, shgi, scene, progress=None):
        """The solver on a committed scene (runs on any thread; raises shgi.Cancelled)."""
        return self.solver(shgi, scene, self.settings, progress)


def solver_recipe(props, shgi, volumes=(), viewport=False, gather=None, bake=False):
    """The SolverRecipe of scene.shgi's method (props: scene.shgi or its values as a namespace).

    volumes: the scene's irradiance volumes (export/light_probe.ProbeVolumeRecord).
    viewport: the method group's viewport_passes; else its passes (F12, Solve, a bake).
    bake: a bake's solve: the group's bake_passes where it has them (settings.
        RENDER_PASSES_DEFAULTS: a bake gathers every pass, F12's samples some each).
    gather: whether the field will be read through a final gather (one bounce less in the field;
        settings.light_path_fields); None: as F12, the viewport and Solve read it (the group's
        Final Gather: settings.reads_through_gather), False for a bake,
        which reads its field at the texels.
    ValueError for a method that solves no field, or a bad volume.
    """
    solver = settings.METHODS_BY_ID[props.method].solver
    if solver == LatticeSolver.METHOD:
        native_settings = settings.photon_lattice_settings(props, shgi, gather)
        recipe_solver = LatticeSolver
    elif solver == "RADIANCE_FIELD":
        native_settings = settings.radiance_field_settings(props, shgi, gather)
        recipe_solver = FieldSolver.of(solver)
    elif solver == ProbeGridSolver.METHOD:
        native_settings = settings.probe_grid_settings(props, shgi, native_volumes(volumes, shgi),
                                                       gather)
        recipe_solver = ProbeGridSolver
    elif solver == "PROPAGATION":
        native_settings = settings.propagation_settings(props, shgi, gather)
        recipe_solver = PropagationSolver
    elif solver == InstantGiSolver.METHOD:
        native_settings = settings.instant_gi_settings(props, shgi, gather)
        recipe_solver = InstantGiSolver
    elif solver:
        # A registered method without a settings group here (a plugin's): its settings'
        # defaults with the scene's seed, its registry's passes for F12 and the viewport alike.
        return SolverRecipe(FieldSolver.of(solver),
                            shgi.default_settings(solver, seed=props.seed),
                            shgi.method(solver).final_passes)
    else:
        raise ValueError(f"method {props.method!r} solves no field")
    group = getattr(props, settings.METHOD_SETTINGS[solver].prop)
    if viewport:
        passes = group.viewport_passes
    elif bake and solver in settings.RENDER_PASSES_DEFAULTS:
        passes = group.bake_passes
    else:
        passes = group.passes
    return SolverRecipe(recipe_solver, native_settings, passes)
