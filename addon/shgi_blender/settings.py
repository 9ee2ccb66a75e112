"""The render settings of ``scene.shgi`` and the native settings structs they fill, without bpy.

``scene.shgi`` (properties.py) is a PropertyGroup whose names are the native fields' names
(docs/architecture.md: settings mirrored 1:1). One property can feed several structs: ``samples`` is
PathTracerSettings.samples for PATH_TRACE and PreviewSettings.samples for the field methods,
as Cycles' one "Max Samples" serves every integrator; ``seed`` seeds every solver. The one
rename is ``PhotonLatticeSettings.max_bounces`` (photon scatterings after emission), fed by
``diffuse_bounces``: ``max_bounces`` in scene.shgi is Cycles' total path limit, and a photon
bounce is the light-side twin of a diffuse camera bounce (both default to 4, as in Cycles).
ProbeGridSettings' fields live in their own group, ``scene.shgi.probe_grid``, under their
native names: several of them (order, bounces, clamp) mean something else than the flat
properties of the same or similar names, exactly as the two native structs differ.

Everything here takes any object with the property names as attributes (the PropertyGroup, or a
SimpleNamespace in tests), so pytest checks the mapping outside Blender.

The property ranges (properties.py) are the native checks' ranges, so the panels offer only
values the native code accepts. What the native checks still refuse (a value saved before a
range was tightened, a spacing that puts too many probes in the scene) is reported with the
setting's place in the panels instead of the native field (``name_settings``).
"""

import re
from dataclasses import dataclass
from types import SimpleNamespace


@dataclass(frozen=True)
class Method:
    """A render method of the engine: an item of ``scene.shgi.method``."""

    identifier: str
    label: str
    description: str
    number: int        # the enum value stored in .blend files; never reuse one
    # The solver whose IndirectField the preview renderer renders (engine/field_solvers.py
    # SOLVERS): "PHOTON_LATTICE" or "PROBE_GRID"; "" for the path tracer.
    solver: str = ""

    @property
    def uses_field(self):
        """F12 and the viewport render with the preview renderer over a solved field."""
        return bool(self.solver)


# Selectable methods, in menu order. The solvers still to come keep their identifiers and file
# numbers reserved (RESERVED_METHODS) so that files saved later open here; each becomes a row of
# METHODS when its solver lands: PROPAGATION (seed 003), RADIANCE_FIELD (seed 001) and
# INSTANT_GI (seed 004).
METHODS = (
    Method("PATH_TRACE", "Path Tracing",
           "Reference path tracer: unbiased, matches Cycles, slowest to converge", 0),
    Method("PHOTON_LATTICE", "Photon Lattice",
           "Photons shot from the lights fill a 3D grid of indirect light: fast and smooth, "
           "best for diffuse scenes; exact direct light", 1,
           "PHOTON_LATTICE"),
    Method("PROBE_GRID", "Probe Grid",
           "Light probes (placed by Irradiance Volume objects) gather indirect light without "
           "leaking through walls, refined in the background; exact direct light", 2,
           "PROBE_GRID"),
)
RESERVED_METHODS = {"PROPAGATION": 3, "RADIANCE_FIELD": 4, "INSTANT_GI": 5}
METHODS_BY_ID = {method.identifier: method for method in METHODS}

# Enum-valued fields: property identifier -> name of the shgi enum type (values are the enum's
# member names, e.g. "LATTICE" -> shgi.CausticMode.LATTICE).
ENUM_FIELDS = {
    "world_sampling": "WorldSampling",
    "caustics": "CausticMode",
    "interpolation": "LatticeInterpolation",
}
# Their items (identifier = the shgi member name, label, description), for the EnumProperties.
ENUM_ITEMS = {
    "world_sampling": (
        ("COSINE", "Cosine", "Sample the world over the cosine-weighted hemisphere"),
        ("UNIFORM", "Uniform", "Sample the world uniformly over the hemisphere"),
    ),
    "caustics": (
        ("OFF", "Off", "No caustic photons"),
        ("LATTICE", "Lattice", "Caustics (light through glass or off mirrors) in a finer grid: "
         "smooth, soft caustics"),
        ("PHOTON_MAP", "Photon Map",
         "Caustics kept as individual photons: sharper caustics, slower to render"),
    ),
    "interpolation": (
        ("TRILINEAR", "Trilinear", "Blend the 8 nearest cells"),
        ("CUBIC", "Cubic", "Blend the 27 nearest cells, weighted by how their surface faces "
         "the normal (smoother, fewer leaks)"),
    ),
}

# The native default of every property (checked against the native structs by
# tests/python/test_blender_engine.py). samples is the path tracer's default; the preview's is 16.
PROPERTY_DEFAULTS = {
    "samples": 64,
    "seed": 0,
    "max_bounces": 12,
    "diffuse_bounces": 4,
    "glossy_bounces": 4,
    "transmission_bounces": 12,
    "clamp_indirect": 0.0,
    "world_sampling": "COSINE",
    "max_specular_bounces": 8,
    "photons": 200000,
    "resolution": 16,
    "order": 2,
    "caustics": "LATTICE",
    "caustic_resolution": 64,
    "interpolation": "CUBIC",
    "blur_passes": 1,
    "world_in_field": False,
}

# ProbeGridSettings' fields in ``scene.shgi.probe_grid`` with their native defaults (checked
# against the native struct by tests/python/test_blender_engine.py). Not mirrored: ``seed``
# (scene.shgi.seed seeds every solver), ``volumes`` (the scene's Irradiance Volume objects,
# export/light_probe.py) and ``include_direct`` (the renderer adds direct light exactly; probes
# holding it too would count it twice).
PROBE_GRID_DEFAULTS = {
    "order": 2,
    "spacing": 0.0,
    "rays_per_probe": 256,
    "hysteresis": 0.95,
    "clamp": 0.0,
    "bounces": 3,
    "visibility": True,
    "visibility_resolution": 8,
    "visibility_blur": 0.15,
    "normal_bias": 0.25,
    "view_bias": 0.0,
    "bleed_bias": 0.0,
    "relocate": True,
    "max_offset": 0.45,
    "backface_threshold": 0.25,
    "placement_rays": 128,
}

# Properties of the engine's solves that no native struct has: the update passes a probe grid
# runs for an F12 render or a Solve (seed 002 Tables 5.1-5.3 converge in about 6).
SOLVE_PROPERTY_DEFAULTS = {
    "probe_passes": 6,
}

# Properties of the live viewport only (no native struct has them), as Cycles keeps its
# viewport samples apart: samples per pixel a viewport accumulates before it stops, photon passes
# it solves (each traces `photons`; 1 = the lattice F12 solves), probe grid update passes it runs
# in the background before it stops refining (past ~2 / (1 - hysteresis) passes the blend holds
# as much history as it ever will), and whether the overlays draw the lattice's sample spheres
# or the probes.
VIEWPORT_PROPERTY_DEFAULTS = {
    "viewport_samples": 64,
    "viewport_photon_passes": 1,
    "viewport_probe_passes": 32,
    "show_lattice_samples": False,
    "show_probes": False,
    "overlay_size": 0.12,
}
# The properties a viewport render depends on (a change restarts it); the overlay toggles are
# not among them. "probe_grid" stands for the values of the scene.shgi.probe_grid group.
VIEWPORT_RENDER_PROPERTIES = ("method", *PROPERTY_DEFAULTS, "viewport_samples",
                              "viewport_photon_passes", "viewport_probe_passes", "probe_grid")

# Where each property is drawn in Properties > Render ("panel > label"), for messages that name a
# setting: scene.shgi's, then scene.shgi.probe_grid's (placement_rays is in no panel).
SETTING_LABELS = {
    "samples": "SHGI > Samples > Render",
    "seed": "SHGI > Seed",
    "max_bounces": "Light Paths > Total",
    "diffuse_bounces": "Light Paths > Diffuse",
    "glossy_bounces": "Light Paths > Glossy",
    "transmission_bounces": "Light Paths > Transmission",
    "clamp_indirect": "Light Paths > Clamp",
    "world_sampling": "Light Paths > World",
    "max_specular_bounces": "Light Paths > Max Bounces > Specular",
    "photons": "Photon Lattice > Photons",
    "resolution": "Photon Lattice > Resolution",
    "order": "Photon Lattice > SH Order",
    "caustics": "Photon Lattice > Caustics",
    "caustic_resolution": "Photon Lattice > Caustics > Resolution",
    "interpolation": "Photon Lattice > Interpolation",
    "blur_passes": "Photon Lattice > Blur Passes",
    "world_in_field": "Photon Lattice > World in Lattice",
}
PROBE_GRID_LABELS = {
    "order": "Probe Grid > SH Order",
    "spacing": "Probe Grid > Spacing",
    "rays_per_probe": "Probe Grid > Rays",
    "hysteresis": "Probe Grid > History",
    "clamp": "Probe Grid > Clamp",
    "bounces": "Probe Grid > Bounces",
    "visibility": "Probe Grid > Visibility",
    "visibility_resolution": "Probe Grid > Visibility > Resolution",
    "visibility_blur": "Probe Grid > Visibility > Blur",
    "normal_bias": "Probe Grid > Visibility > Bias",
    "view_bias": "Probe Grid > Visibility > View Bias",
    "bleed_bias": "Probe Grid > Visibility > Bleed Bias",
    "relocate": "Probe Grid > Relocation > Move Out of Geometry",
    "max_offset": "Probe Grid > Relocation > Max Offset",
    "backface_threshold": "Probe Grid > Relocation > Back Faces",
    "placement_rays": "scene.shgi.probe_grid.placement_rays",
}
# The native checks' limits the property ranges follow (properties.py), so that the panels offer
# only values the native code accepts.
MAX_SAMPLES = 1 << 24                # Path/PreviewSettings.samples (kMaxPathTracerSamples)
MAX_LATTICE_RESOLUTION = 1024        # PhotonLatticeSettings.resolution, caustic_resolution
MAX_PROBE_SPACING = 1e12             # ProbeGridSettings.spacing, m (kMaxCoordinate)
MAX_RAYS_PER_PROBE = 65536           # ProbeGridSettings.rays_per_probe, placement_rays
MIN_PLACEMENT_RAYS = 4               # ProbeGridSettings.placement_rays
MIN_VISIBILITY_BLUR = 0.01           # ProbeGridSettings.visibility_blur, radians
# ProbeGridSettings.bleed_bias must stay below 1 and backface_threshold above 0: the nearest
# values the panels' two decimals show.
MAX_BLEED_BIAS = 0.99
MIN_BACKFACE_THRESHOLD = 0.01
# A photon is stored after at least one scattering (PhotonLatticeSettings.max_bounces >= 1):
# Diffuse 0, direct light only, has no photon lattice.
MIN_PHOTON_BOUNCES = 1

# Native struct -> {native field: scene.shgi property}.
PATH_TRACER_FIELDS = {name: name for name in (
    "samples", "seed", "max_bounces", "diffuse_bounces", "glossy_bounces",
    "transmission_bounces", "clamp_indirect", "world_sampling")}
PREVIEW_FIELDS = {name: name for name in (
    "samples", "seed", "clamp_indirect", "max_specular_bounces", "world_sampling")}
PHOTON_LATTICE_FIELDS = dict(
    {name: name for name in ("photons", "seed", "resolution", "order", "caustics",
                             "caustic_resolution", "interpolation", "blur_passes",
                             "world_in_field")},
    max_bounces="diffuse_bounces")
# ProbeGridSettings: {native field: scene.shgi.probe_grid property}; the seed is scene.shgi's.
PROBE_GRID_FIELDS = {name: name for name in PROBE_GRID_DEFAULTS}


# Native struct -> {native field: its label}, for name_settings.
NATIVE_LABELS = {
    "PathTracerSettings": {name: SETTING_LABELS[prop]
                           for name, prop in PATH_TRACER_FIELDS.items()},
    "PreviewSettings": {name: SETTING_LABELS[prop] for name, prop in PREVIEW_FIELDS.items()},
    "PhotonLatticeSettings": {name: SETTING_LABELS[prop]
                              for name, prop in PHOTON_LATTICE_FIELDS.items()},
    "ProbeGridSettings": dict(PROBE_GRID_LABELS),
}
# A native field in a message: "ProbeGridSettings.visibility_blur".
_NATIVE_FIELD = re.compile(r"\b([A-Z]\w*Settings)\.(\w+)\b")


def name_settings(message, labels=None):
    """`message` with each native field it names ("ProbeGridSettings.visibility_blur is 0")
    replaced by the setting's place in the panels ("Probe Grid > Visibility > Blur is 0").

    labels: {native struct: {field: label}} (default NATIVE_LABELS); other fields stay.
    """
    labels = NATIVE_LABELS if labels is None else labels

    def label(match):
        return labels.get(match.group(1), {}).get(match.group(2), match.group(0))

    return _NATIVE_FIELD.sub(label, str(message))


def validated(native_settings, labels=None):
    """native_settings after its native checks (``validate()``); their ValueError names the
    panel setting (name_settings with `labels`)."""
    try:
        native_settings.validate()
    except ValueError as error:
        raise ValueError(name_settings(error, labels)) from None
    return native_settings


def native_fields(props, fields, shgi):
    """{native field: value} read from `props` through a field table, enums converted."""
    values = {}
    for native_name, prop_name in fields.items():
        value = getattr(props, prop_name)
        if prop_name in ENUM_FIELDS:
            value = getattr(getattr(shgi, ENUM_FIELDS[prop_name]), value)
        values[native_name] = value
    return values


def path_tracer_settings(props, shgi):
    """shgi.PathTracerSettings of scene.shgi (ValueError naming a refused setting)."""
    return validated(shgi.PathTracerSettings(**native_fields(props, PATH_TRACER_FIELDS, shgi)))


def preview_settings(props, shgi):
    """shgi.PreviewSettings of scene.shgi (the F12 renderer of the lattice methods; ValueError
    naming a refused setting)."""
    return validated(shgi.PreviewSettings(**native_fields(props, PREVIEW_FIELDS, shgi)))


def photon_lattice_settings(props, shgi):
    """shgi.PhotonLatticeSettings of scene.shgi (ValueError naming a refused setting)."""
    if props.diffuse_bounces < MIN_PHOTON_BOUNCES:
        raise ValueError(f"{SETTING_LABELS['diffuse_bounces']} is {props.diffuse_bounces}: the "
                         f"Photon Lattice stores light after {MIN_PHOTON_BOUNCES} or more diffuse "
                         f"bounces; set it to {MIN_PHOTON_BOUNCES} or more, or use Path Tracing "
                         "(which renders 0 as direct light only)")
    return validated(shgi.PhotonLatticeSettings(
        **native_fields(props, PHOTON_LATTICE_FIELDS, shgi)))


def probe_grid_settings(props, shgi, volumes=()):
    """shgi.ProbeGridSettings of scene.shgi (its probe_grid group and seed).

    volumes: shgi.ProbeVolume list (the scene's Irradiance Volumes); empty: one volume fitted to
    the scene with the spacing setting. ValueError naming a refused setting.
    """
    return validated(shgi.ProbeGridSettings(
        **native_fields(props.probe_grid, PROBE_GRID_FIELDS, shgi), seed=props.seed,
        volumes=list(volumes)))


# ProbeGridSettings' fields that say how a probe field is read (shgi.ProbeLookupSettings).
PROBE_LOOKUP_FIELDS = ("normal_bias", "view_bias", "bleed_bias", "visibility")


def probe_lookup_settings(props, shgi):
    """shgi.ProbeLookupSettings of scene.shgi.probe_grid: how a probe field read from a file is
    looked up, as the grid's own field is."""
    return shgi.ProbeLookupSettings(**{name: getattr(props.probe_grid, name)
                                       for name in PROBE_LOOKUP_FIELDS})


def solver_signature(props):
    """The values the solve of scene.shgi's method depends on (to tell that a frozen solution
    is out of date): the method, its solver's settings and the seed."""
    solver = METHODS_BY_ID[props.method].solver
    if solver == "PROBE_GRID":
        values = [(name, getattr(props.probe_grid, name)) for name in sorted(PROBE_GRID_FIELDS)]
        values.append(("seed", props.seed))
    else:
        values = [(name, getattr(props, prop)) for name, prop in
                  sorted(PHOTON_LATTICE_FIELDS.items())]
    return (("method", props.method), *values)


def overlay_wanted(props):
    """True when the 3D views should draw the method's field overlay (lattice samples or
    probes)."""
    solver = METHODS_BY_ID[props.method].solver
    return ((solver == "PHOTON_LATTICE" and props.show_lattice_samples)
            or (solver == "PROBE_GRID" and props.show_probes))


def render_property_values(props):
    """((name, value), ...) of the VIEWPORT_RENDER_PROPERTIES: plain values a worker thread can
    read and compare (scene.shgi itself must stay on Blender's main thread). The probe_grid
    group becomes a nested ((name, value), ...)."""
    values = []
    for name in VIEWPORT_RENDER_PROPERTIES:
        value = getattr(props, name)
        if name == "probe_grid":
            value = tuple((field, getattr(value, field)) for field in PROBE_GRID_DEFAULTS)
        values.append((name, value))
    return tuple(values)


def properties_from_values(values):
    """A namespace with the property names as attributes (and ``probe_grid`` as a nested one)
    from render_property_values(): what the settings functions above take on a worker thread."""
    props = dict(values)
    props["probe_grid"] = SimpleNamespace(**dict(props["probe_grid"]))
    return SimpleNamespace(**props)
