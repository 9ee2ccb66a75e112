"""Quality presets: the counts of scene.shgi for four levels of quality, without bpy.

A preset sets only counts (samples, photons and lattice resolutions), never the method or the
bounce limits, so it means the same for every method. Photons grow with the lattice's cell count
(about 25-35 photons per cell of the global lattice per solve) so that a finer lattice is not a
noisier one.

DEFAULT holds the counts of a new scene (the native defaults, settings.PROPERTY_DEFAULTS), so
that a scene nobody has tuned shows a preset: the panel's Quality menu names the preset the
counts match, or Custom.
"""

from .settings import PROPERTY_DEFAULTS

# The counts a preset sets.
PRESET_FIELDS = ("samples", "photons", "resolution", "caustic_resolution")
QUALITY_PRESETS = {
    "DEFAULT": {field: PROPERTY_DEFAULTS[field] for field in PRESET_FIELDS},
    "PREVIEW": {"samples": 16, "photons": 100_000, "resolution": 16, "caustic_resolution": 32},
    "MEDIUM": {"samples": 64, "photons": 400_000, "resolution": 24, "caustic_resolution": 64},
    "HIGH": {"samples": 256, "photons": 1_000_000, "resolution": 32, "caustic_resolution": 96},
    "PRODUCTION": {"samples": 1024, "photons": 4_000_000, "resolution": 48,
                   "caustic_resolution": 128},
}
PRESET_LABELS = {"DEFAULT": "Default", "PREVIEW": "Preview", "MEDIUM": "Medium", "HIGH": "High",
                 "PRODUCTION": "Production"}


def apply_preset(props, name):
    """Sets the counts of preset `name` on `props` (scene.shgi); KeyError names the presets."""
    if name not in QUALITY_PRESETS:
        raise KeyError(f"quality preset {name!r} is not one of {list(QUALITY_PRESETS)}")
    for field, value in QUALITY_PRESETS[name].items():
        setattr(props, field, value)


def matching_preset(props):
    """The name of the preset whose counts `props` has, or None (custom counts)."""
    for name, values in QUALITY_PRESETS.items():
        if all(getattr(props, field) == value for field, value in values.items()):
            return name
    return None


def preset_label(props):
    """The label of the preset `props` matches, or "Custom"."""
    name = matching_preset(props)
    return "Custom" if name is None else PRESET_LABELS[name]
