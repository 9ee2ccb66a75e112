"""The render settings of ``scene.shgi`` and the native settings structs they fill, without bpy.

``scene.shgi`` (properties.py) is a PropertyGroup whose names are the native fields' names
(DESIGN.md: settings mirrored 1:1). One property can feed several structs: ``samples`` is
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
"""

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
           "Photons in SH lattices (ISLLPM) for indirect light, exact direct light", 1,
           "PHOTON_LATTICE"),
    Method("PROBE_GRID", "Probe Grid",
           "SH probes updated by path tracing, with leak prevention (Irradiance Volume "
           "objects place them); refined in the background, exact direct light", 2,
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
        ("LATTICE", "Lattice", "Caustic photons in a fine SH lattice"),
        ("PHOTON_MAP", "Photon Map",
         "Caustic photons in a k-d tree, density estimation per lookup"),
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
}
# The properties a viewport render depends on (a change restarts it); the overlay toggles are
# not among them. "probe_grid" stands for the values of the scene.shgi.probe_grid group.
VIEWPORT_RENDER_PROPERTIES = ("method", *PROPERTY_DEFAULTS, "viewport_samples",
                              "viewport_photon_passes", "viewport_probe_passes", "probe_grid")

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
    """shgi.PathTracerSettings of scene.shgi."""
    return shgi.PathTracerSettings(**native_fields(props, PATH_TRACER_FIELDS, shgi))


def preview_settings(props, shgi):
    """shgi.PreviewSettings of scene.shgi (the F12 renderer of the lattice methods)."""
    return shgi.PreviewSettings(**native_fields(props, PREVIEW_FIELDS, shgi))


def photon_lattice_settings(props, shgi):
    """shgi.PhotonLatticeSettings of scene.shgi."""
    return shgi.PhotonLatticeSettings(**native_fields(props, PHOTON_LATTICE_FIELDS, shgi))


def probe_grid_settings(props, shgi, volumes=()):
    """shgi.ProbeGridSettings of scene.shgi (its probe_grid group and seed).

    volumes: shgi.ProbeVolume list (the scene's Irradiance Volumes); empty: one volume fitted to
    the scene with the spacing setting.
    """
    return shgi.ProbeGridSettings(**native_fields(props.probe_grid, PROBE_GRID_FIELDS, shgi),
                                  seed=props.seed, volumes=list(volumes))


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
