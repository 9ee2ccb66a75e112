"""Quality presets: the counts of scene.shgi for four levels of quality, without bpy.

A preset sets counts (samples; each field method's photons, resolutions, rays and passes) and
the F12 denoiser's effort, never the method or the bounce limits, so it means the same quality
step for every method. Photons grow with the lattice's cell count (about 25-35 photons per cell
of the global lattice per solve) so that a finer lattice is not a noisier one; probe rays and
passes double from step to step (the probes' noise halves every two steps, as the samples' does
every step). The radiance field's gather rays double too, its photons grow as the lattice's, its
resolution stays 32 up to Medium (Preview saves on gather rays: with 100k photons the two rooms'
dim room read 7% too bright through a final gather, 13% at 24 cells), then 48 and 64.
Light Propagation's light paths grow as the photons do and its resolution as the lattice's, with
the Distance in cells following it so that light travels as far at every step. Instant GI solves
four Render Passes a sample, so that every sample gathers VPLs of its own (its Light Paths per
Set stay: they set a sample's cost). Measured per method and preset: bench/preset_quality.py
(docs/addon.md, "Quality presets"). Preview's denoiser lets the network allow for noisy guides
(Fast, with the Balanced network), Medium's calls them clean once they are (Automatic: its 64
samples make them so, and the High network is worth 0.6-0.9 dB over Fast, docs/equal-time.md),
and from High on it prefilters them (Accurate, as Cycles does).

DEFAULT holds the values of a new scene (the native defaults, settings.PROPERTY_DEFAULTS, each
method group's defaults, the final and render passes and DENOISING_DEFAULTS), so that a scene
nobody has tuned shows a preset: the panel's Quality menu names the preset the values match, or
Custom. Fields are paths below scene.shgi ("photon_lattice.photons").
"""

from .settings import (DENOISING_DEFAULTS, DENOISING_ITEMS, FINAL_PASSES_FALLBACK,
                       INSTANT_GI_DEFAULTS, METHOD_SETTINGS, PHOTON_LATTICE_DEFAULTS,
                       PROBE_GRID_DEFAULTS, PROPAGATION_DEFAULTS, PROPERTY_DEFAULTS,
                       RADIANCE_FIELD_DEFAULTS, RENDER_PASSES_DEFAULTS)

# The values a preset sets: counts, then the denoiser's choices.
PRESET_FIELDS = ("samples", "photon_lattice.photons", "photon_lattice.resolution",
                 "photon_lattice.caustic_resolution", "probe_grid.rays_per_probe",
                 "probe_grid.passes", "radiance_field.photons", "radiance_field.resolution",
                 "radiance_field.gather_rays", "propagation.photons", "propagation.resolution",
                 "propagation.distance", "instant_gi.photons_per_set", "instant_gi.passes",
                 "denoising_prefilter", "denoising_quality")
_GROUP_DEFAULTS = {"photon_lattice": PHOTON_LATTICE_DEFAULTS, "probe_grid": PROBE_GRID_DEFAULTS,
                   "radiance_field": RADIANCE_FIELD_DEFAULTS, "propagation": PROPAGATION_DEFAULTS,
                   "instant_gi": INSTANT_GI_DEFAULTS}
_DEFAULTS = dict(PROPERTY_DEFAULTS, **DENOISING_DEFAULTS,
                 **{f"{group}.{name}": value for group, defaults in _GROUP_DEFAULTS.items()
                    for name, value in defaults.items()},
                 **{"probe_grid.passes": FINAL_PASSES_FALLBACK["PROBE_GRID"],
                    "instant_gi.passes": RENDER_PASSES_DEFAULTS["INSTANT_GI"]})


def _values(samples, lattice, probes, radiance_field, propagation, instant_gi, prefilter,
            quality):
    return dict(zip(PRESET_FIELDS, (samples, *lattice, *probes, *radiance_field, *propagation,
                                    *instant_gi, prefilter, quality)))


QUALITY_PRESETS = {
    "DEFAULT": {field: _DEFAULTS[field] for field in PRESET_FIELDS},
    "PREVIEW": _values(16, (100_000, 16, 32), (128, 4), (200_000, 32, 200), (50_000, 24, 24.0),
                       (16, 64), "FAST", "BALANCED"),
    "MEDIUM": _values(64, (400_000, 24, 64), (256, 8), (400_000, 32, 400), (200_000, 32, 32.0),
                      (16, 256), "AUTO", "HIGH"),
    "HIGH": _values(256, (1_000_000, 32, 96), (512, 16), (1_000_000, 48, 800),
                    (500_000, 48, 48.0), (16, 1024), "ACCURATE", "HIGH"),
    "PRODUCTION": _values(1024, (4_000_000, 48, 128), (1024, 32), (4_000_000, 64, 1600),
                          (2_000_000, 64, 64.0), (16, 4096), "ACCURATE", "HIGH"),
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
    """A preset's value as its tooltip shows it: 1,000,000; 24; "Automatic" (the menu's label)."""
    if isinstance(value, (int, float)):
        return f"{value:,}" if isinstance(value, int) or not value.is_integer() else f"{value:,.0f}"
    labels = {item[0]: item[1] for items in DENOISING_ITEMS.values() for item in items}
    return labels.get(value, value.capitalize())


def field_label(field):
    """A preset field as a tooltip names it: its panel label in the method's group
    ("propagation.photons" -> "Light Paths", "photon_lattice.caustic_resolution" -> "Caustics >
    Resolution"), else its name ("denoising_quality" -> "Denoising quality")."""
    group, _, name = field.rpartition(".")
    method = next((method for method in METHOD_SETTINGS.values() if method.prop == group), None)
    if method is not None and name in method.labels:
        return method.labels[name].split(" > ", 1)[1]
    return name.replace("_", " ").capitalize()


def preset_description(name):
    """Preset `name`'s values as its tooltip lists them, grouped by method: "Preview: samples
    16; Photon Lattice: photons 100,000, resolution 16, ...; denoising prefilter Fast, ..."."""
    parts = {}
    for field, value in QUALITY_PRESETS[name].items():
        group = field.rpartition(".")[0]
        label = next((method.label for method in METHOD_SETTINGS.values() if method.prop == group),
                     "")
        parts.setdefault(label, []).append(f"{field_label(field)} {value_text(value)}")
    return f"{PRESET_LABELS[name]}: " + "; ".join(
        f"{label}: {', '.join(items)}" if label else ", ".join(items)
        for label, items in parts.items())


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
