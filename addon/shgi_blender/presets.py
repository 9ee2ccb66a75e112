"""Quality presets: the counts of scene.shgi for four levels of quality, without bpy.

A preset sets counts (samples; the photon lattice's photons and resolutions; the probe grid's
rays per probe and update passes) and the F12 denoiser's effort, never the method or the bounce
limits, so it means the same quality step for every method. Photons grow with the lattice's cell
count (about 25-35 photons per cell of the global lattice per solve) so that a finer lattice is
not a noisier one; probe rays and passes double from step to step (the probes' noise halves
every two steps, as the samples' does every step); Preview's denoiser lets the network allow for
noisy guides (Fast, with the Balanced network), Medium's calls them clean once they are
(Automatic: its 64 samples make them so, and the High network is worth 0.6-0.9 dB over Fast,
docs/equal-time.md), and from High on it prefilters them (Accurate, as Cycles does).

DEFAULT holds the values of a new scene (the native defaults, settings.PROPERTY_DEFAULTS,
PHOTON_LATTICE_DEFAULTS, PROBE_GRID_DEFAULTS, the final passes and DENOISING_DEFAULTS), so that
a scene nobody has tuned shows a preset: the panel's Quality menu names the preset the values
match, or Custom. Fields are paths below scene.shgi ("photon_lattice.photons").
"""

from .settings import (DENOISING_DEFAULTS, FINAL_PASSES_FALLBACK, PHOTON_LATTICE_DEFAULTS,
                       PROBE_GRID_DEFAULTS, PROPERTY_DEFAULTS)

# The values a preset sets: counts, then the denoiser's choices.
PRESET_FIELDS = ("samples", "photon_lattice.photons", "photon_lattice.resolution",
                 "photon_lattice.caustic_resolution", "probe_grid.rays_per_probe",
                 "probe_grid.passes", "denoising_prefilter", "denoising_quality")
_DEFAULTS = dict(PROPERTY_DEFAULTS, **DENOISING_DEFAULTS,
                 **{f"photon_lattice.{name}": value
                    for name, value in PHOTON_LATTICE_DEFAULTS.items()},
                 **{f"probe_grid.{name}": value for name, value in PROBE_GRID_DEFAULTS.items()},
                 **{"probe_grid.passes": FINAL_PASSES_FALLBACK["PROBE_GRID"]})


def _values(samples, photons, resolution, caustic_resolution, rays, passes, prefilter,
            quality):
    return dict(zip(PRESET_FIELDS, (samples, photons, resolution, caustic_resolution, rays,
                                    passes, prefilter, quality)))


QUALITY_PRESETS = {
    "DEFAULT": {field: _DEFAULTS[field] for field in PRESET_FIELDS},
    "PREVIEW": _values(16, 100_000, 16, 32, 128, 4, "FAST", "BALANCED"),
    "MEDIUM": _values(64, 400_000, 24, 64, 256, 8, "AUTO", "HIGH"),
    "HIGH": _values(256, 1_000_000, 32, 96, 512, 16, "ACCURATE", "HIGH"),
    "PRODUCTION": _values(1024, 4_000_000, 48, 128, 1024, 32, "ACCURATE", "HIGH"),
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


def value_text(value):
    """A preset's value as its tooltip shows it: 1,000,000; "Accurate"."""
    return f"{value:,}" if isinstance(value, int) else value.capitalize()


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
