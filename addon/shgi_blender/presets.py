"""Quality presets: the counts of scene.shgi for four levels of quality, without bpy.

A preset sets only counts (samples, photons and lattice resolutions), never the method or the
bounce limits, so it means the same for every method. Photons grow with the lattice's cell count
(about 25-35 photons per cell of the global lattice per solve) so that a finer lattice is not a
noisier one.

DEFAULT holds the counts of a new scene (the native defaults, settings.PROPERTY_DEFAULTS and
PHOTON_LATTICE_DEFAULTS), so that a scene nobody has tuned shows a preset: the panel's Quality
menu names the preset the counts match, or Custom. Fields are paths below scene.shgi
("photon_lattice.photons").
"""

from .settings import PHOTON_LATTICE_DEFAULTS, PROPERTY_DEFAULTS

# The counts a preset sets.
PRESET_FIELDS = ("samples", "photon_lattice.photons", "photon_lattice.resolution",
                 "photon_lattice.caustic_resolution")
_DEFAULTS = dict(PROPERTY_DEFAULTS, **{f"photon_lattice.{name}": value
                                       for name, value in PHOTON_LATTICE_DEFAULTS.items()})


def _counts(samples, photons, resolution, caustic_resolution):
    return dict(zip(PRESET_FIELDS, (samples, photons, resolution, caustic_resolution)))


QUALITY_PRESETS = {
    "DEFAULT": {field: _DEFAULTS[field] for field in PRESET_FIELDS},
    "PREVIEW": _counts(16, 100_000, 16, 32),
    "MEDIUM": _counts(64, 400_000, 24, 64),
    "HIGH": _counts(256, 1_000_000, 32, 96),
    "PRODUCTION": _counts(1024, 4_000_000, 48, 128),
}
PRESET_LABELS = {"DEFAULT": "Default", "PREVIEW": "Preview", "MEDIUM": "Medium", "HIGH": "High",
                 "PRODUCTION": "Production"}


def apply_preset(props, name):
    """Sets the counts of preset `name` on `props` (scene.shgi); KeyError names the presets."""
    if name not in QUALITY_PRESETS:
        raise KeyError(f"quality preset {name!r} is not one of {list(QUALITY_PRESETS)}")
    for field, value in QUALITY_PRESETS[name].items():
        owner, _, prop = field.rpartition(".")
        setattr(_owner(props, owner), prop, value)


def _owner(props, path):
    """The group at `path` ("photon_lattice", "" for props itself) below props."""
    for part in filter(None, path.split(".")):
        props = getattr(props, part)
    return props


def preset_value(props, field):
    """The value of a preset's field (a path below scene.shgi) in `props`."""
    owner, _, prop = field.rpartition(".")
    return getattr(_owner(props, owner), prop)


def field_label(field):
    """A preset field as a tooltip names it: "photon_lattice.caustic_resolution" -> "caustic
    resolution"."""
    return field.rpartition(".")[2].replace("_", " ")


def matching_preset(props):
    """The name of the preset whose counts `props` has, or None (custom counts)."""
    for name, values in QUALITY_PRESETS.items():
        if all(preset_value(props, field) == value for field, value in values.items()):
            return name
    return None


def preset_label(props):
    """The label of the preset `props` matches, or "Custom"."""
    name = matching_preset(props)
    return "Custom" if name is None else PRESET_LABELS[name]
