"""Blender's Irradiance Volume light probes → the volumes of a probe grid (no bpy import).

An Irradiance Volume is a Light Probe object whose data type is 'GRID' (Blender 2.8 to 3.6) or
'VOLUME' (4.x, EEVEE Next). It spans the cube [-1, 1]^3 of its matrix_world and holds
grid_resolution_x × _y × _z probes (resolution_x × _y × _z in Blender 5.0,
``resolution_properties``) at the cell centres, exactly what shgi.ProbeVolume is, so the
artist places, turns and sizes the PROBE_GRID method's probes by moving and scaling the object
and sets their counts in its Object Data panel. Volumes are recorded as plain values
(ProbeVolumeRecord) on Blender's main thread and turned into shgi.ProbeVolume on any thread.
"""

import re
from dataclasses import dataclass

import numpy as np

from . import conversions

# LightProbe.type of an irradiance volume, by Blender version.
IRRADIANCE_VOLUME_TYPES = ("GRID", "VOLUME")
# The irradiance volume's probe counts along x, y, z: Blender 3.x's names, then Blender 5.0's.
RESOLUTION_PROPERTIES = (("grid_resolution_x", "grid_resolution_y", "grid_resolution_z"),
                         ("resolution_x", "resolution_y", "resolution_z"))


@dataclass(frozen=True)
class ProbeVolumeRecord:
    """An irradiance volume: world_from_volume (4, 4) float32 row-major, resolution (nx, ny, nz)."""

    world_from_volume: np.ndarray
    resolution: tuple
    name: str

    def key(self):
        """Hashable values that tell two volumes apart (for comparisons)."""
        return (self.world_from_volume.tobytes(), self.resolution)


def is_irradiance_volume(obj):
    """True for a Light Probe object that is an irradiance volume."""
    return obj.type == "LIGHT_PROBE" and obj.data is not None \
        and obj.data.type in IRRADIANCE_VOLUME_TYPES


def resolution_properties(data):
    """The names of the probe count properties of an irradiance volume's LightProbe data."""
    for names in RESOLUTION_PROPERTIES:
        if hasattr(data, names[0]):
            return names
    raise ValueError(f"light probe {data.name!r} has none of the probe count properties "
                     f"{[names[0] for names in RESOLUTION_PROPERTIES]}")


def probe_volume_from_object(obj, matrix_world):
    """The ProbeVolumeRecord of an irradiance volume object placed at `matrix_world`."""
    data = obj.data
    resolution = tuple(getattr(data, name) for name in resolution_properties(data))
    matrix = np.asarray(conversions.row_major(matrix_world), np.float32).reshape(4, 4)
    return ProbeVolumeRecord(matrix, tuple(int(n) for n in resolution), obj.name)


# How the native checks of ProbeGridSettings name the volume they check: "...volumes[0]: " or
# "...volumes[0].resolution[0] is 0".
_NATIVE_VOLUME_PREFIX = re.compile(r"^\w+\.volumes\[\d+\](: |\.)")


def native_volumes(records, shgi):
    """[shgi.ProbeVolume] of ProbeVolumeRecords; ValueError names the Irradiance Volume object
    the native checks refuse (a zero scale, a resolution out of range)."""
    volumes = []
    for record in records:
        try:
            volume = shgi.ProbeVolume(world_from_volume=record.world_from_volume,
                                      resolution=record.resolution)
            shgi.ProbeGridSettings(volumes=[volume]).validate()  # the native volume checks
        except ValueError as error:
            problem = _NATIVE_VOLUME_PREFIX.sub("", str(error))
            raise ValueError(f"Irradiance Volume {record.name!r}: {problem}") from error
        volumes.append(volume)
    return volumes


def volumes_key(records):
    return tuple(record.key() for record in records)
