"""Frozen photon-lattice solutions, one per Blender scene, kept between renders. No bpy.

Non-interactive mode (DESIGN.md, use 2c; seed 000 §6.5): the Solve operator exports the scene,
solves a PhotonLattice once with the scene's photon count and stores it here with the committed
shgi.Scene it was solved on. F12 renders of that Blender scene then render the frozen solution
from the current camera without exporting the geometry or solving again, until Clear. Edits
made after the solve are not seen (the panel says so).

The cache is module state of the add-on (it cannot live in the .blend file); its key is the
scene's ``name_full``, and loading a file clears it (properties.py registers the handler).
"""

import time
from dataclasses import dataclass, field

# Bytes in a mebibyte: memory figures are shown in MiB.
BYTES_PER_MIB = 2**20

# Timings shown in the panel, in order: {key in LatticeSolution.timings: label}.
TIMING_LABELS = {
    "export": "Export",
    "commit": "BVH",
    "measure": "Cell areas",
    "emit_trace": "Emit + trace",
    "injection": "Injection",
    "blur": "Blur",
}


@dataclass
class LatticeSolution:
    """A solved PhotonLattice with the scene it was solved on."""

    scene: object          # the committed shgi.Scene
    lattice: object        # the solved shgi.PhotonLattice (an IndirectField)
    signature: tuple       # settings.lattice_signature() at solve time
    timings: dict          # seconds per stage (TIMING_LABELS) and the lattice's counters
    memory_bytes: int      # held by the lattices (PhotonLattice.memory_bytes)
    warnings: list = field(default_factory=list)  # export warnings
    solved_at: float = field(default_factory=time.time)
    overlay: object = None  # its lattice_samples.LatticeOverlay (the Solve operator's), or None

    @property
    def photons_emitted(self):
        return int(self.timings.get("photons_emitted", 0))


def solve(shgi, scene, lattice_settings, signature, progress=None, timings=None, warnings=()):
    """Commits `scene` (if needed), solves a PhotonLattice on it once; a LatticeSolution.

    Runs on any thread (no bpy); raises shgi.Cancelled when `progress` is cancelled.
    timings: stage seconds measured before (the export), kept in the solution's timings.
    """
    timings = dict(timings or {})
    start = time.perf_counter()
    if not scene.committed:
        scene.commit(progress=progress)
    timings["commit"] = time.perf_counter() - start
    start = time.perf_counter()
    lattice = shgi.PhotonLattice(scene, lattice_settings, progress=progress)
    timings["measure"] = time.perf_counter() - start
    lattice.solve(progress=progress)
    timings.update(lattice.timings)
    return LatticeSolution(scene=scene, lattice=lattice, signature=signature, timings=timings,
                           memory_bytes=lattice.memory_bytes, warnings=list(warnings))


_solutions = {}


def store(key, solution):
    _solutions[key] = solution


def get(key):
    """The frozen solution of scene `key`, or None."""
    return _solutions.get(key)


def clear(key):
    """Forgets the solution of scene `key`; True when there was one."""
    return _solutions.pop(key, None) is not None


def clear_all():
    _solutions.clear()
