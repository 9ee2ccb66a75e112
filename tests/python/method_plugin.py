"""A test-only GI method prototyped in Python, registered when this module is imported: by the
tests in-process, and by ``python -m shgi`` or Blender through SHGI_METHOD_PLUGINS. It proves
that one registration reaches shgi.bake, the CLI and the add-on with no other edit.

SINGLE_PROBE_TEST: one SH probe at the centre of the scene's bounds (a ProbeGrid of one probe,
driven from Python), its settings a dataclass of its own.
"""

import dataclasses

import numpy as np

import shgi

IDENTIFIER = "SINGLE_PROBE_TEST"
NUMBER = 90


@dataclasses.dataclass
class SingleProbeSettings:
    rays_per_probe: int = 1024
    seed: int = 0


class SingleProbeSolver(shgi.GiSolver):
    """GiSolver in Python: every call goes to a native ProbeGrid of one probe."""

    def __init__(self, scene, settings, progress=None):
        super().__init__()
        settings = settings or SingleProbeSettings()
        if settings.rays_per_probe < 1:
            raise ValueError(f"SingleProbeSettings.rays_per_probe is {settings.rays_per_probe}; "
                             "use 1 or more")
        bounds = np.asarray(scene.bounds(), np.float32)
        volume = shgi.ProbeVolume()
        matrix = np.eye(4, dtype=np.float32)
        matrix[:3, 3] = 0.5 * (bounds[0] + bounds[1])
        matrix[:3, :3] *= 0.25 * float(np.max(bounds[1] - bounds[0]))
        volume.world_from_volume = matrix
        volume.resolution = (1, 1, 1)
        grid_settings = shgi.ProbeGridSettings(rays_per_probe=settings.rays_per_probe,
                                               seed=settings.seed, relocate=False)
        grid_settings.volumes = [volume]
        self._grid = shgi.ProbeGrid(scene, grid_settings, progress)

    def refine(self, progress=None):
        self._grid.refine(progress)

    def reset(self, progress=None):
        self._grid.reset(progress)

    @property
    def passes(self):
        return self._grid.passes

    def current_field(self):
        return self._grid.current_field()

    @property
    def stage_seconds(self):
        return self._grid.stage_seconds

    @property
    def memory_bytes(self):
        return self._grid.memory_bytes


if IDENTIFIER not in {row.identifier for row in shgi.methods()}:
    shgi.register_method(IDENTIFIER, "Single Probe (test)",
                         "One probe at the scene's centre: a test of the method registry",
                         NUMBER, SingleProbeSettings, SingleProbeSolver, final_passes=2)
