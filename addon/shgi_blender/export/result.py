"""What an export returns, and how its warnings reach the user, without bpy."""

import logging
from dataclasses import dataclass, field

import shgi

logger = logging.getLogger("shgi_blender.export")


class ExportCancelled(Exception):
    """export_scene's ``should_stop`` said stop (Esc during F12); the partial scene is dropped."""


@dataclass
class ExportStats:
    """Counts of what went into the shgi.Scene and what was left out."""

    meshes: int = 0             # distinct shgi meshes (one per Blender mesh data and materials)
    instances: int = 0          # placements of those meshes
    triangles: int = 0          # triangles over the distinct meshes
    materials: int = 0
    textures: int = 0
    lights: int = 0
    skipped_objects: int = 0    # objects with geometry that could not be exported
    seconds: float = 0.0        # wall time of the export


@dataclass
class ExportResult:
    """An uncommitted shgi.Scene with the warnings raised while building it, the scene's
    irradiance volumes (light_probe.ProbeVolumeRecord, for the PROBE_GRID method) and why each
    object left out was left out ({object name: problem}; the bake names it)."""

    scene: shgi.Scene
    warnings: list = field(default_factory=list)
    stats: ExportStats = field(default_factory=ExportStats)
    probe_volumes: list = field(default_factory=list)
    skipped: dict = field(default_factory=dict)


class WarningLog:
    """Collects warnings, logs each to ``shgi_blender.export`` and forwards it to ``report``.

    report: an operator's or render engine's ``self.report`` (called as
    ``report({'WARNING'}, message)``), or None.
    """

    def __init__(self, report=None):
        self.messages = []
        self._report = report

    def warn(self, message):
        """Records one warning; a message already recorded (N instances of one object) is not
        repeated."""
        if message in self.messages:
            return
        self.messages.append(message)
        logger.warning(message)
        if self._report is not None:
            self._report({"WARNING"}, message)
