"""The render settings of ``scene.shgi`` and the native settings structs they fill, without bpy.

``scene.shgi`` (properties.py) is one flat PropertyGroup whose names are the native fields'
names (DESIGN.md: settings mirrored 1:1). One property can feed several structs: ``samples`` is
PathTracerSettings.samples for PATH_TRACE and PreviewSettings.samples for the lattice methods,
as Cycles' one "Max Samples" serves every integrator. The one rename is
``PhotonLatticeSettings.max_bounces`` (photon scatterings after emission), fed by
``diffuse_bounces``: ``max_bounces`` in scene.shgi is Cycles' total path limit, and a photon
bounce is the light-side twin of a diffuse camera bounce (both default to 4, as in Cycles).

Everything here takes any object with the property names as attributes (the PropertyGroup, or a
SimpleNamespace in tests), so pytest checks the mapping outside Blender.
"""

from dataclasses import dataclass


@dataclass(frozen=True)
class Method:
    """A render method of the engine: an item of ``scene.shgi.method``."""

    identifier: str
    label: str
    description: str
    number: int        # the enum value stored in .blend files; never reuse one
    uses_lattice: bool  # F12 renders with the preview renderer over a PhotonLattice


# Selectable methods, in menu order. The solvers still to come keep their identifiers and file
# numbers reserved (RESERVED_METHODS) so that files saved later open here; each becomes a row of
# METHODS when its solver lands: PROBE_GRID (issue 6), PROPAGATION (seed 003), RADIANCE_FIELD
# (seed 001) and INSTANT_GI (seed 004).
METHODS = (
    Method("PATH_TRACE", "Path Tracing",
           "Reference path tracer: unbiased, matches Cycles, slowest to converge", 0, False),
    Method("PHOTON_LATTICE", "Photon Lattice",
           "Photons in SH lattices (ISLLPM) for indirect light, exact direct light", 1, True),
)
RESERVED_METHODS = {"PROBE_GRID": 2, "PROPAGATION": 3, "RADIANCE_FIELD": 4, "INSTANT_GI": 5}
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

# Properties of the live viewport only (no native struct has them), as Cycles keeps its
# viewport samples apart: samples per pixel a viewport accumulates before it stops, photon passes
# it solves (each traces `photons`; 1 = the lattice F12 solves), and whether the lattice overlay
# draws its sample spheres.
VIEWPORT_PROPERTY_DEFAULTS = {
    "viewport_samples": 64,
    "viewport_photon_passes": 1,
    "show_lattice_samples": False,
}
# The properties a viewport render depends on (a change restarts it); the overlay toggle is not
# one of them.
VIEWPORT_RENDER_PROPERTIES = ("method", *PROPERTY_DEFAULTS, "viewport_samples",
                              "viewport_photon_passes")

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


def lattice_signature(props):
    """The values a PhotonLattice solve depends on (to tell a frozen solution is out of date)."""
    return tuple((name, getattr(props, prop)) for name, prop in
                 sorted(PHOTON_LATTICE_FIELDS.items()))


def render_property_values(props):
    """((name, value), ...) of the VIEWPORT_RENDER_PROPERTIES: plain values a worker thread can
    read and compare (scene.shgi itself must stay on Blender's main thread)."""
    return tuple((name, getattr(props, name)) for name in VIEWPORT_RENDER_PROPERTIES)
