"""The render settings of ``scene.shgi`` and the native settings structs they fill, without bpy.

``scene.shgi`` (properties.py) holds what every method shares: the samples, the seed and Light
Paths (docs/architecture.md: settings mirrored 1:1, under the native names). One property can
feed several structs: ``samples`` is PathTracerSettings.samples for PATH_TRACE and
PreviewSettings.samples for the field methods, as Cycles' one "Max Samples" serves every
integrator; ``seed`` seeds every solver. Each field method has its own group named after its
method (METHOD_SETTINGS: ``scene.shgi.photon_lattice`` mirrors shgi.PhotonLatticeSettings,
``scene.shgi.probe_grid`` shgi.ProbeGridSettings, field by field), so that ``order``,
``resolution`` and the like mean one thing per group, with the method's pass counts beside them
(``passes`` of a final solve, ``viewport_passes`` of the Rendered viewport), as Cycles keeps
``samples`` and ``preview_samples`` side by side.

Light Paths is shared and every method follows it: a native field that Light Paths governs is
not mirrored in the method's group but derived from it (LIGHT_PATH_VALUES):
PhotonLatticeSettings.max_bounces (photon scatterings after emission, the light-side twin of a
diffuse camera bounce) is Diffuse; ProbeGridSettings.bounces is Diffuse - 1 (a probe's path
starts one bounce after the renderer's surface) and its per-sample ``clamp`` is Clamp. What a
method cannot follow (the probe grid's one bounce limit for diffuse and glossy, its fixed total
and transmission limits) the Light Paths panel says under the method's name (ui/render_panels.py).

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

from . import native


@dataclass(frozen=True)
class Method:
    """A render method of the engine: an item of ``scene.shgi.method``, a row of the method
    registry (shgi.methods(); docs/solvers.md)."""

    identifier: str
    label: str
    description: str
    number: int        # the enum value stored in .blend files; never reuse one
    # The method whose IndirectField the preview renderer renders: its identifier for a method
    # that solves a field, "" for the path tracer.
    solver: str = ""

    @property
    def uses_field(self):
        """F12 and the viewport render with the preview renderer over a solved field."""
        return bool(self.solver)


# The native registry's built-in rows (native/methods/method_registry.cpp), for when the module
# shgi cannot be imported: the add-on then still registers and opens files with their method
# (tests/python/test_blender_engine.py checks these against the registry).
BUILT_IN_METHODS = (
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
    Method("RADIANCE_FIELD", "Radiance Field",
           "Photons shot from the lights are gathered on a grid of surface radiance, and rays "
           "from points near surfaces turn it into smooth indirect light: photon mapping with a "
           "cheap final gather; exact direct light", 4,
           "RADIANCE_FIELD"),
    Method("PROPAGATION", "Light Propagation Volumes",
           "Light from where the lights land spreads cell to cell through a coarse grid: a "
           "fixed cost, soft and approximate light that may leak through thin walls; exact "
           "direct light", 3,
           "PROPAGATION"),
    Method("INSTANT_GI", "Instant GI",
           "Light from a few hundred virtual point lights with exact shadows, each pixel seeing "
           "its own set, then blended across neighbouring pixels in SH so normal maps keep their "
           "detail; exact direct light", 5,
           "INSTANT_GI"),
)


def registry_methods(shgi):
    """Every method of the registry of the module `shgi` (plugins included), in menu order;
    BUILT_IN_METHODS without the module."""
    if shgi is None or not hasattr(shgi, "methods"):
        return BUILT_IN_METHODS
    return tuple(Method(row.identifier, row.label, row.description, row.number,
                        row.identifier if row.solves_field else "")
                 for row in shgi.methods())


# Selectable methods, in menu order: the registry's rows when the add-on loads. Solvers still to
# come would keep their identifiers and file numbers reserved here (RESERVED_METHODS) so that
# files saved later open; none is reserved now.
METHODS = registry_methods(native.module())
RESERVED_METHODS = {}
METHODS_BY_ID = {method.identifier: method for method in METHODS}

# Enum-valued fields: property identifier -> name of the shgi enum type (values are the enum's
# member names, e.g. "LATTICE" -> shgi.CausticMode.LATTICE).
ENUM_FIELDS = {
    "world_sampling": "WorldSampling",
    "caustics": "CausticMode",
    "interpolation": "LatticeInterpolation",
    "face_estimator": "FaceEstimator",
    "filter_mode": "InstantGiFilter",
    "pixel_filter": "PixelFilter",
}
# Their items (identifier = the shgi member name, label, description), for the EnumProperties.
ENUM_ITEMS = {
    "pixel_filter": (
        ("BOX", "Box", "Each sample counts in its own pixel, evenly over it (of width 1): the "
         "sharpest image"),
        ("GAUSSIAN", "Gaussian", "Samples spread over neighbouring pixels with a Gaussian "
         "weight (sigma a quarter of the width)"),
        ("BLACKMAN_HARRIS", "Blackman-Harris", "Samples spread over neighbouring pixels with a "
         "Blackman-Harris weight spanning twice the width: Cycles' default"),
    ),
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
    "face_estimator": (
        ("PROJECTED_AREA", "Projected Area",
         "Divide each cell face's photon flux by the area of surface facing it: exact for flat "
         "surfaces at any angle"),
        ("PAPER", "Paper",
         "The original paper's estimate (flux split over faces, divided by the face's area): "
         "darker on surfaces not aligned with the grid, for comparison"),
    ),
    "filter_mode": (
        ("SH", "SH", "Blend the light arriving from every direction between neighbouring "
         "pixels, then shade each pixel with its own (normal-mapped) normal: smooth and "
         "detailed"),
        ("IRRADIANCE", "Irradiance", "Blend each pixel's shaded light: smooth, but normal-map "
         "detail is blurred away (for comparison)"),
        ("STRICT", "Strict", "Blend shaded light only between pixels whose normals agree: "
         "keeps detail, but the pattern of the light sets shows on bumpy surfaces"),
        ("NONE", "None", "No blending: each pixel shows its own set's light (the raw pattern)"),
    ),
}

# Light Paths whose add-on default is Cycles' own rather than the native one: an artist's scene
# then clamps alike in both engines, and the preview shows what Cycles will render. Cycles'
# Clamping > Indirect Light is 10 by default (clamped as SHGI clamps, render/shading.h); with
# it off SHGI's 4096-spp reference of the caustics scene read 5.3% brighter than Cycles'
# default one, with it on 0.55% (docs/equal-time.md). Scripts and `python -m shgi` keep the
# native 0: the unbiased answer the tests compare with closed forms. Cycles' Light Paths > Caustics
# > Filter Glossy is 1 by default (PrincipledBsdf::blur): it takes the caustic fireflies of
# mirrors and sharp glass seen through a diffuse bounce (docs/equal-time.md). Not Cycles' Film >
# Pixel Filter (a Blackman-Harris of width 1.5): the add-on keeps the native box of one pixel,
# which the denoiser reads 0.7-2.4 dB better on the Cornell box and the caustics scene (and 0.5-0.9
# dB worse in the sun room; docs/equal-time.md, "The pixel filter").
CYCLES_DEFAULTS = {"clamp_indirect": 10.0, "filter_glossy": 1.0}

# scene.shgi's own properties with their native defaults (checked against the native structs by
# tests/python/test_blender_engine.py): the samples, the seed and Light Paths, which every method
# shares. samples is the path tracer's default; the preview's is 16. Two depart, as
# CYCLES_DEFAULTS says: Clamp Indirect is Cycles' 10 and Filter Glossy Cycles' 1, where the
# native structs keep 0 (off).
PROPERTY_DEFAULTS = {
    "samples": 64,
    "seed": 0,
    "max_bounces": 12,
    "diffuse_bounces": 4,
    "glossy_bounces": 4,
    "transmission_bounces": 12,
    "clamp_indirect": CYCLES_DEFAULTS["clamp_indirect"],
    "filter_glossy": CYCLES_DEFAULTS["filter_glossy"],
    "pixel_filter": "BOX",
    "filter_width": 1.0,
    "world_sampling": "COSINE",
    "light_splits": 4,
    "max_specular_bounces": 8,
}


# PhotonLatticeSettings' fields in ``scene.shgi.photon_lattice`` with their native defaults. Not
# mirrored: ``seed`` (scene.shgi.seed seeds every solver), ``max_bounces`` and
# ``glossy_bounces`` (Light Paths > Diffuse and Glossy, LIGHT_PATH_VALUES).
PHOTON_LATTICE_DEFAULTS = {
    "photons": 200000,
    "resolution": 16,
    "order": 2,
    "caustics": "LATTICE",
    "caustic_resolution": 64,
    "interpolation": "CUBIC",
    "blur_passes": 1,
    "world_in_field": False,
}

# ProbeGridSettings' fields in ``scene.shgi.probe_grid`` with their native defaults. Not
# mirrored: ``seed`` (scene.shgi.seed), ``bounces`` and ``clamp`` (Light Paths,
# LIGHT_PATH_VALUES), ``volumes`` (the scene's Irradiance Volume objects, export/light_probe.py)
# and ``include_direct`` (the renderer adds direct light exactly; probes holding it too would
# count it twice).
PROBE_GRID_DEFAULTS = {
    "order": 2,
    "spacing": 0.0,
    "rays_per_probe": 256,
    "hysteresis": 0.95,
    "visibility": True,
    "visibility_resolution": 8,
    "visibility_blur": 0.10,
    "normal_bias": 0.25,
    "view_bias": 0.0,
    "bleed_bias": 0.0,
    "relocate": True,
    "max_offset": 0.45,
    "backface_threshold": 0.25,
    "placement_rays": 128,
}

# RadianceFieldSettings' fields in ``scene.shgi.radiance_field`` with their native defaults. Not
# mirrored: ``seed`` (scene.shgi.seed), ``max_bounces`` and ``glossy_bounces`` (Light Paths >
# Diffuse and Glossy, LIGHT_PATH_VALUES) and the constants an artist has no reason to change
# (glossy_in_grid, face_sigma, min_footprint_cosine, backface_threshold, specular_roughness,
# the obscurance's weight, distance and rays, the bounds), which keep the native defaults.
RADIANCE_FIELD_DEFAULTS = {
    "photons": 200000,
    "resolution": 32,
    "gather_rays": 400,
    "face_estimator": "PROJECTED_AREA",
    "use_mips": True,
    "mip_levels": 4,
    "side_test": True,
    "visibility_test": False,
    "occlusion_test": True,
    "monte_carlo_gathers": False,
    "diffuse_gather_rays": 32,
    "glossy_gather_rays": 64,
    "obscurance": False,
    "world_in_field": False,
}

# PropagationSettings' fields in ``scene.shgi.propagation`` with their native defaults. Not
# mirrored: ``seed`` (scene.shgi.seed), ``vpl_bounces`` (Light Paths > Diffuse,
# LIGHT_PATH_VALUES), ``cascade_follow_camera`` and ``cascade_center`` (the cascades follow the
# camera the exported scene renders from, the native default).
PROPAGATION_DEFAULTS = {
    "photons": 100000,
    "resolution": 32,
    "steps": 0,
    "distance": 32.0,
    "order": 2,
    "occlusion": True,
    "normal_offset": 1.0,
    "damping": True,
    "occlude_first_step": True,
    "drop_outward_vpls": True,
    "travel_reinjection": True,
    "unclamped_transfer": True,
    "clamp_at_surfaces": True,
    "cascades": 1,
}

# InstantGiSettings' fields in ``scene.shgi.instant_gi`` with their native defaults. Not
# mirrored: ``seed`` (scene.shgi.seed), ``vpl_bounces`` and ``glossy_bounces`` (Light Paths >
# Diffuse and Glossy, LIGHT_PATH_VALUES).
INSTANT_GI_DEFAULTS = {
    "sets_x": 4,
    "sets_y": 4,
    "photons_per_set": 16,
    "clamp_distance": 0.05,
    "filter_mode": "SH",
    "depth_threshold": 0.1,
    "normal_threshold": 0.9,
    "filter_direct": False,
    "passes_per_sample": 4,
}

# Refinement passes of a final solve (F12, Solve, a bake) when ``shgi`` cannot be imported as the
# add-on registers: the method registry's final_passes, which ``python -m shgi bake`` runs
# (shgi.bake.PROBE_GRID_PASSES); tests/python/test_blender_versioning.py checks that they agree.
FINAL_PASSES_FALLBACK = {"PHOTON_LATTICE": 1, "PROBE_GRID": 8, "RADIANCE_FIELD": 1,
                         "PROPAGATION": 1, "INSTANT_GI": 4}
# Passes the Rendered viewport runs (no native struct has them), as Cycles keeps its viewport
# samples apart: photon passes it solves (each traces `photons`; as many as `passes` give the
# lattice F12 solves), and probe grid update passes it runs in the background before it stops
# refining (past ~2 / (1 - hysteresis) passes the blend holds as much history as it ever will).
VIEWPORT_PASSES_DEFAULTS = {"PHOTON_LATTICE": 1, "PROBE_GRID": 32, "RADIANCE_FIELD": 1,
                            "PROPAGATION": 1, "INSTANT_GI": 1}
# Whether F12 and the viewport read each field method's field through a final gather
# (PreviewSettings.final_gather: one traced bounce, the field read where it lands, the field one
# bounce shallower: light_path_fields) rather than at the first surface. Chosen by measurement
# (docs/methods.md, "Final gather"): denoised, the photon lattice gains 1-4 dB on the Cornell box
# and the sun room, the probe grid 1.5-4 dB on every scene, and the probe grid's dim room of the
# two-rooms scene comes within 5% of the path tracer's.
# The light propagation volume is read directly: its cost is the propagation, and a gather would
# multiply the render's cost for it.
# Instant GI through a gather reads one set of little lights per gather ray instead of its
# screen-space filter (render/preview_renderer.h): at equal CPU, denoised, +2.8 to +4.5 dB on the
# Cornell box and +0.1 to +0.5 dB on the sun room (docs/methods.md, "Instant GI through a final
# gather").
FINAL_GATHER_DEFAULTS = {"PHOTON_LATTICE": True, "PROBE_GRID": True, "RADIANCE_FIELD": True,
                         "PROPAGATION": False, "INSTANT_GI": True}
# The diffuse bounces a final gather traces before the field is read (light_path_fields).
GATHER_BOUNCES = 1


def final_passes(solver, shgi=None):
    """The refinement passes of `solver`'s final solve: the native registry's (what ``python -m
    shgi bake`` runs) when the module `shgi` is given and has it, else FINAL_PASSES_FALLBACK."""
    try:
        return int(shgi.method(solver).final_passes)
    except (AttributeError, ValueError):
        return FINAL_PASSES_FALLBACK[solver]


# Render Passes of the methods whose F12 solves more passes than a bake: {solver: default}.
# Their groups hold Bake Passes too, with the final passes as default. Instant GI: a sample
# gathers Per Sample (passes_per_sample) of the passes, the next ones after the previous
# sample's, so 64 passes cost a sample no more than 4 and a frame's samples average 16 times the
# VPLs (the sun room at 16 samples, seeds 5..8: 32.95 dB against 31.15 dB;
# bench/instant_gi_sample_passes.py, docs/methods.md "Instant GI"), while a bake gathers every
# pass at each texel: 64 passes would cost it 16 times as much.
RENDER_PASSES_DEFAULTS = {"INSTANT_GI": 64}


def render_passes(solver, shgi=None):
    """Render Passes' default of `solver` (F12, Solve): RENDER_PASSES_DEFAULTS, else the final
    passes (final_passes)."""
    return RENDER_PASSES_DEFAULTS.get(solver) or final_passes(solver, shgi)


# Properties of the live viewport only (no native struct has them): samples per pixel a viewport
# accumulates before it stops, and whether the overlays draw the lattice's sample spheres or the
# probes.
VIEWPORT_PROPERTY_DEFAULTS = {
    "viewport_samples": 64,
    "show_lattice_samples": False,
    "show_probes": False,
    "overlay_size": 0.12,
}

# Denoising of F12 and of the Rendered viewport with OpenImageDenoise (shgi.frame_denoise), with
# Cycles' controls and Cycles' defaults but one: F12 denoises once at the end with both guides at
# full quality; the viewport denoises every frame from `viewport_denoising_start_sample` on, with
# the albedo guide, at Cycles' viewport quality. F12's prefilter is "AUTO" where Cycles' is
# "ACCURATE": Fast while the guides are noisy, None once they are clean enough (8 samples), which
# gives Accurate's image at a third of its time and led the equal-time table by 0.4-1.0 dB more
# than Fast (docs/equal-time.md, "The denoiser's prefilter"). A render with a Time Limit sets
# both networks up before it samples (FrameDenoiser.prepare), and runs None only where it fits.
DENOISING_DEFAULTS = {
    "use_denoising": True,
    "denoising_guides": "ALBEDO_NORMAL",
    "denoising_prefilter": "AUTO",
    "denoising_quality": "HIGH",
    "use_viewport_denoising": True,
    "viewport_denoising_guides": "ALBEDO",
    "viewport_denoising_prefilter": "FAST",
    "viewport_denoising_quality": "BALANCED",
    "viewport_denoising_start_sample": 1,
}
# The choices (shgi.frame_denoise's), with Cycles' labels.
DENOISING_ITEMS = {
    "guides": (
        ("NONE", "None", "Denoise the image alone"),
        ("ALBEDO", "Albedo", "Guide the denoiser with the surfaces' colours"),
        ("ALBEDO_NORMAL", "Albedo and Normal",
         "Guide the denoiser with the surfaces' colours and normals (keeps the most detail)"),
    ),
    "prefilter": (
        ("NONE", "None", "The guides are taken as noise-free (for renders of many samples)"),
        ("FAST", "Fast", "The denoiser allows for noise in the guides"),
        ("ACCURATE", "Accurate", "Denoise the guides first (keeps the most detail, slowest)"),
        ("AUTO", "Automatic",
         "Fast while the guides are noisy (under 8 samples; under 32 where much of the image "
         "is seen through glass or in mirrors), then None: the guides are then clean enough "
         "for the denoiser's best network"),
    ),
    "quality": (
        ("HIGH", "High", "Best quality"),
        ("BALANCED", "Balanced", "Half the time of High, a little less detail"),
        ("FAST", "Fast", "Fastest, for the viewport"),
    ),
}
# Seconds a render may take, 0 for no limit (Cycles' Time Limit): F12 and the viewport stop
# sampling where the next round would pass it, and show that image, denoised.
TIME_LIMIT_DEFAULTS = {"time_limit": 0.0, "viewport_time_limit": 0.0}


@dataclass(frozen=True)
class Denoising:
    """How a render is denoised (shgi.frame_denoise.FrameDenoiser's arguments), from which
    sample on."""

    quality: str
    prefilter: str
    guides: str
    start_sample: int = 1
    # The film's pixel filter: how much of the directly seen light goes around the network
    # follows it (shgi.frame_denoise.direct_share).
    pixel_filter: str = "BOX"
    filter_width: float = 1.0

    def passes(self):
        """The passes a renderer must return for these guides."""
        from shgi.frame_denoise import WANTED_PASSES

        return WANTED_PASSES[self.guides]

    def make(self):
        """A shgi.frame_denoise.FrameDenoiser with these choices (ImportError without pyoidn)."""
        from shgi.frame_denoise import FrameDenoiser

        return FrameDenoiser(self.quality, self.prefilter, self.guides, self.pixel_filter,
                             self.filter_width)


def denoising(props, viewport=False):
    """The Denoising of F12 (or of the viewport) of scene.shgi `props`; None when off."""
    prefix = "viewport_" if viewport else ""
    if not getattr(props, f"use_{prefix}denoising"):
        return None
    return Denoising(getattr(props, f"{prefix}denoising_quality"),
                     getattr(props, f"{prefix}denoising_prefilter"),
                     getattr(props, f"{prefix}denoising_guides"),
                     props.viewport_denoising_start_sample if viewport else 1,
                     props.pixel_filter, props.filter_width)


# Where each property is drawn in Properties > Render ("panel > label"), for messages that name a
# setting: scene.shgi's, then each method group's (placement_rays is in no panel).
SETTING_LABELS = {
    "samples": "SHGI > Samples > Render",
    "seed": "SHGI > Seed",
    "max_bounces": "Light Paths > Total",
    "diffuse_bounces": "Light Paths > Diffuse",
    "glossy_bounces": "Light Paths > Glossy",
    "transmission_bounces": "Light Paths > Transmission",
    "clamp_indirect": "Light Paths > Clamp",
    "filter_glossy": "Light Paths > Filter Glossy",
    "pixel_filter": "Film > Pixel Filter",
    "filter_width": "Film > Pixel Filter > Width",
    "world_sampling": "Light Paths > World",
    "light_splits": "Light Paths > Light Splits",
    "max_specular_bounces": "Light Paths > Max Bounces > Specular",
}
PHOTON_LATTICE_LABELS = {
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
RADIANCE_FIELD_LABELS = {
    "photons": "Radiance Field > Photons",
    "resolution": "Radiance Field > Resolution",
    "gather_rays": "Radiance Field > Gather Rays",
    "face_estimator": "Radiance Field > Face Estimator",
    "use_mips": "Radiance Field > Mip Filtering",
    "mip_levels": "Radiance Field > Mip Filtering > Levels",
    "side_test": "Radiance Field > Side Test",
    "visibility_test": "Radiance Field > Visibility Test",
    "occlusion_test": "Radiance Field > Occlusion Test",
    "monte_carlo_gathers": "Radiance Field > Monte Carlo Gathers",
    "diffuse_gather_rays": "Radiance Field > Monte Carlo Gathers > Diffuse Rays",
    "glossy_gather_rays": "Radiance Field > Monte Carlo Gathers > Glossy Rays",
    "obscurance": "Radiance Field > Obscurance",
    "world_in_field": "Radiance Field > World in Field",
}
PROPAGATION_LABELS = {
    "photons": "Light Propagation > Light Paths",
    "resolution": "Light Propagation > Resolution",
    "steps": "Light Propagation > Steps",
    "distance": "Light Propagation > Distance",
    "order": "Light Propagation > Order",
    "occlusion": "Light Propagation > Occlusion",
    "normal_offset": "Light Propagation > Normal Offset",
    "damping": "Light Propagation > Damping",
    "occlude_first_step": "Light Propagation > Occlude First Step",
    "drop_outward_vpls": "Light Propagation > Drop Outward Lights",
    "travel_reinjection": "Light Propagation > Travel Re-injection",
    "unclamped_transfer": "Light Propagation > Unclamped Transfer",
    "clamp_at_surfaces": "Light Propagation > Clamp At Walls",
    "cascades": "Light Propagation > Cascades",
}
INSTANT_GI_LABELS = {
    "sets_x": "Instant GI > Sets X",
    "sets_y": "Instant GI > Sets Y",
    "photons_per_set": "Instant GI > Light Paths per Set",
    "clamp_distance": "Instant GI > Clamp Distance",
    "filter_mode": "Instant GI > Filter",
    "depth_threshold": "Instant GI > Depth Threshold",
    "normal_threshold": "Instant GI > Normal Threshold",
    "filter_direct": "Instant GI > Filter Direct Light",
    "passes_per_sample": "Instant GI > Passes per Sample",
}
# The native checks' limits the property ranges follow (properties.py), so that the panels offer
# only values the native code accepts.
MAX_SAMPLES = 1 << 24                # Path/PreviewSettings.samples (kMaxPathTracerSamples)
MAX_LATTICE_RESOLUTION = 1024        # PhotonLatticeSettings.resolution, caustic_resolution
MAX_PROBE_SPACING = 1e12             # ProbeGridSettings.spacing, m (kMaxCoordinate)
MAX_RAYS_PER_PROBE = 65536           # ProbeGridSettings.rays_per_probe, placement_rays
MIN_PLACEMENT_RAYS = 4               # ProbeGridSettings.placement_rays
MIN_VISIBILITY_BLUR = 0.01           # ProbeGridSettings.visibility_blur, radians
MAX_PROBE_BOUNCES = 64               # ProbeGridSettings.bounces
MAX_RADIANCE_RESOLUTION = 128        # RadianceFieldSettings.resolution
MAX_GATHER_RAYS = 1 << 20            # RadianceFieldSettings.gather_rays
MAX_MIP_LEVELS = 16                  # RadianceFieldSettings.mip_levels
MAX_RADIANCE_GLOSSY_BOUNCES = 64     # RadianceFieldSettings.glossy_bounces
MAX_LATTICE_GLOSSY_BOUNCES = 1024    # PhotonLatticeSettings.glossy_bounces
MAX_SHADING_GATHER_RAYS = 1 << 16    # RadianceFieldSettings.diffuse/glossy_gather_rays
# ProbeGridSettings.bleed_bias must stay below 1 and backface_threshold above 0: the nearest
# values the panels' two decimals show.
MAX_BLEED_BIAS = 0.99
MIN_BACKFACE_THRESHOLD = 0.01
MAX_PROPAGATION_RESOLUTION = 256    # PropagationSettings.resolution (min 2)
MAX_PROPAGATION_STEPS = 1024        # PropagationSettings.steps
MAX_PROPAGATION_DISTANCE = 512.0    # PropagationSettings.distance, cells
MAX_PROPAGATION_NORMAL_OFFSET = 2.0  # PropagationSettings.normal_offset, cells
MAX_LIGHT_SPLITS = 8                # kMaxLightSplits (render/light_tree.h)
MAX_VPL_BOUNCES = 64                # PropagationSettings.vpl_bounces
MAX_PROPAGATION_CASCADES = 8        # PropagationSettings.cascades
MIN_CASCADE_RESOLUTION = 16         # PropagationSettings.resolution with cascades > 1
MAX_INSTANT_SETS = 16               # InstantGiSettings.sets_x, sets_y
MAX_INSTANT_PHOTONS_PER_SET = 1 << 24  # InstantGiSettings.photons_per_set
MAX_INSTANT_VPL_BOUNCES = 16        # InstantGiSettings.vpl_bounces
MAX_INSTANT_GLOSSY_BOUNCES = 64     # InstantGiSettings.glossy_bounces
MAX_INSTANT_PASSES_PER_SAMPLE = 1 << 16  # InstantGiSettings.passes_per_sample
# A photon is stored after at least one scattering (PhotonLatticeSettings.max_bounces >= 1):
# Diffuse 0, direct light only, has no photon lattice.
MIN_PHOTON_BOUNCES = 1


@dataclass(frozen=True)
class LightPathValue:
    """A native field of a method's settings that Light Paths sets: scene.shgi.`prop` + `offset`.
    Below `minimum` (in the Light Paths setting's values) the method has nothing to solve and
    refuses; above `maximum` it follows `maximum` (the native limit; None: no limit)."""

    prop: str
    offset: int = 0
    minimum: int = None
    maximum: int = None


# A probe's path starts at the probe: the renderer's own surface, where it reads the probes, is
# the first bounce of the path tracer's path, so a probe path with Diffuse - 1 bounces gives the
# rendered light the path depth of the path tracer's (Light Paths > Diffuse 4: 3 probe bounces).
# Diffuse 0, direct light only, has no probe grid (its paths would need -1 bounces).
PROBE_PATH_FIRST_BOUNCE = 1

# Light Paths in the method's native settings: {native struct: {native field: LightPathValue}}.
# Every method follows Light Paths > Diffuse (the depth of its indirect light); the probe grid's
# per-sample clamp is Light Paths > Clamp (a probe's radiance sample is the incident indirect
# light a renderer's diffuse sample carries, in the same units; the photon lattice has no
# per-sample clamp: its light is clamped where F12 reads it, PreviewSettings.clamp_indirect).
LIGHT_PATH_VALUES = {
    # The photons' glossy scatterings have a budget of their own, as a path's Glossy bounces.
    "PhotonLatticeSettings": {
        "max_bounces": LightPathValue("diffuse_bounces", 0, MIN_PHOTON_BOUNCES),
        "glossy_bounces": LightPathValue("glossy_bounces", 0, None, MAX_LATTICE_GLOSSY_BOUNCES),
    },
    "RadianceFieldSettings": {
        "max_bounces": LightPathValue("diffuse_bounces", 0, MIN_PHOTON_BOUNCES),
        "glossy_bounces": LightPathValue("glossy_bounces", 0, None, MAX_RADIANCE_GLOSSY_BOUNCES),
    },
    "ProbeGridSettings": {
        # Past 64 probe bounces what is left of the light (albedo^64: 6e-7 at 0.8) is invisible.
        "bounces": LightPathValue("diffuse_bounces", -PROBE_PATH_FIRST_BOUNCE,
                                  PROBE_PATH_FIRST_BOUNCE,
                                  MAX_PROBE_BOUNCES + PROBE_PATH_FIRST_BOUNCE),
        "clamp": LightPathValue("clamp_indirect"),
    },
    # A VPL is a surface hit of a light path, so the volume's bounces are Diffuse's (at least 1).
    "PropagationSettings": {
        "vpl_bounces": LightPathValue("diffuse_bounces", 0, 1, MAX_VPL_BOUNCES),
    },
    # A VPL is a surface hit of a light path, as the propagation volume's; the light paths'
    # glossy scatterings have a budget of their own, as the photon lattice's.
    "InstantGiSettings": {
        "vpl_bounces": LightPathValue("diffuse_bounces", 0, 1, MAX_INSTANT_VPL_BOUNCES),
        "glossy_bounces": LightPathValue("glossy_bounces", 0, None, MAX_INSTANT_GLOSSY_BOUNCES),
    },
}


@dataclass(frozen=True)
class MethodSettings:
    """A field method's settings group: ``scene.shgi.<prop>``, mirroring shgi.<native_type> by
    name, with the method's pass counts: ``passes`` (a final solve: F12, Solve, a bake),
    ``viewport_passes`` (the Rendered viewport) and, for the methods of RENDER_PASSES_DEFAULTS,
    ``bake_passes`` (a bake's, where ``passes`` is F12's and Solve's)."""

    solver: str          # Method.solver: "PHOTON_LATTICE", "PROBE_GRID"
    label: str           # as the panels name the method
    prop: str            # scene.shgi.<prop>
    native_type: str     # the shgi settings class it fills
    defaults: dict       # {mirrored native field: native default}
    labels: dict         # {mirrored native field: "panel > label"}

    @property
    def light_paths(self):
        """{native field: LightPathValue} of the fields Light Paths sets."""
        return LIGHT_PATH_VALUES[self.native_type]


# What a field method's solve cannot take from Light Paths > Max Bounces, as the panel says under
# the limits (F12 renders its first surface exactly and follows mirrors and glass up to
# Specular, whatever the method).
LIGHT_PATH_LIMITS = {
    "PHOTON_LATTICE": "Photon Lattice: photons follow Diffuse and Glossy; Total and "
                      "Transmission apply to path tracing only",
    "PROBE_GRID": f"Probe Grid: Glossy follows Diffuse (at most "
                  f"{MAX_PROBE_BOUNCES + PROBE_PATH_FIRST_BOUNCE}); Total and Transmission are "
                  f"{PROPERTY_DEFAULTS['max_bounces']} and "
                  f"{PROPERTY_DEFAULTS['transmission_bounces']}; probe paths split at "
                  f"{PROPERTY_DEFAULTS['light_splits']} lights",
    "RADIANCE_FIELD": "Radiance Field: photons follow Diffuse and Glossy; Total and "
                      "Transmission apply to path tracing only",
    "PROPAGATION": "Light Propagation: light paths follow Diffuse; Total, Glossy and "
                   "Transmission apply to path tracing only",
    "INSTANT_GI": "Instant GI: light paths follow Diffuse; Total, Glossy and Transmission "
                  "apply to path tracing only",
}


def light_path_limits(solver):
    """What method `solver`'s solve takes from Light Paths, as the panel says it."""
    label = METHODS_BY_ID[solver].label if solver in METHODS_BY_ID else solver
    return LIGHT_PATH_LIMITS.get(
        solver, f"{label}: solved with its own settings' defaults; Light Paths apply to the "
                "traced parts of the render")


# The field methods' groups, by Method.solver.
METHOD_SETTINGS = {
    "PHOTON_LATTICE": MethodSettings("PHOTON_LATTICE", "Photon Lattice", "photon_lattice",
                                     "PhotonLatticeSettings", PHOTON_LATTICE_DEFAULTS,
                                     PHOTON_LATTICE_LABELS),
    "PROBE_GRID": MethodSettings("PROBE_GRID", "Probe Grid", "probe_grid", "ProbeGridSettings",
                                 PROBE_GRID_DEFAULTS, PROBE_GRID_LABELS),
    "RADIANCE_FIELD": MethodSettings("RADIANCE_FIELD", "Radiance Field", "radiance_field",
                                     "RadianceFieldSettings", RADIANCE_FIELD_DEFAULTS,
                                     RADIANCE_FIELD_LABELS),
    "PROPAGATION": MethodSettings("PROPAGATION", "Light Propagation", "propagation",
                                  "PropagationSettings", PROPAGATION_DEFAULTS,
                                  PROPAGATION_LABELS),
    "INSTANT_GI": MethodSettings("INSTANT_GI", "Instant GI", "instant_gi", "InstantGiSettings",
                                 INSTANT_GI_DEFAULTS, INSTANT_GI_LABELS),
}
# The properties a viewport render depends on (a change restarts it); the overlay toggles and
# the final solve's passes are not among them. A group name stands for the values of its
# mirrored fields and viewport_passes.
VIEWPORT_RENDER_PROPERTIES = ("method", *PROPERTY_DEFAULTS, "viewport_samples",
                              "viewport_time_limit",
                              *(name for name in DENOISING_DEFAULTS if "viewport" in name),
                              *(group.prop for group in METHOD_SETTINGS.values()))

# Native struct -> {native field: scene.shgi property}.
PATH_TRACER_FIELDS = {name: name for name in (
    "samples", "seed", "max_bounces", "diffuse_bounces", "glossy_bounces",
    "transmission_bounces", "clamp_indirect", "filter_glossy", "world_sampling",
    "light_splits", "pixel_filter", "filter_width")}
PREVIEW_FIELDS = {name: name for name in (
    "samples", "seed", "clamp_indirect", "filter_glossy", "max_specular_bounces",
    "world_sampling", "light_splits", "pixel_filter", "filter_width")}


def _native_labels(group):
    labels = dict(group.labels)
    # A derived value is named by its Light Paths setting only when it is that value unchanged.
    labels.update({field: SETTING_LABELS[value.prop] for field, value in group.light_paths.items()
                   if value.offset == 0})
    labels["seed"] = SETTING_LABELS["seed"]
    return labels


# Native struct -> {native field: its label}, for name_settings.
NATIVE_LABELS = {
    "PathTracerSettings": {name: SETTING_LABELS[prop]
                           for name, prop in PATH_TRACER_FIELDS.items()},
    "PreviewSettings": {name: SETTING_LABELS[prop] for name, prop in PREVIEW_FIELDS.items()},
    **{group.native_type: _native_labels(group) for group in METHOD_SETTINGS.values()},
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


def reads_through_gather(props, group):
    """Whether F12 and the viewport read method `group`'s field through a final gather: its
    group's Final Gather."""
    return getattr(getattr(props, group.prop, None), "final_gather", False)


def light_path_fields(props, group, check=True, gather=None):
    """{native field: value} that Light Paths (scene.shgi `props`) gives method `group`. With
    `check`, ValueError naming the Light Paths setting when it leaves the method nothing to
    solve.

    With the group's Final Gather on, the renderer traces one diffuse bounce before it reads the
    field, so the field's depth is one bounce less (GATHER_BOUNCES): the path then has Light
    Paths > Diffuse bounces in all, as the path tracer's. Without that, a gathered probe grid
    read 7-13% too bright in closed white rooms (docs/methods.md, "Final gather"). Where the
    setting leaves the field less than its minimum (Diffuse 1 through a gather) the minimum is
    kept: one bounce too many at that extreme. `gather`: whether the field is read through a
    gather (None: as F12 and the viewport read it, reads_through_gather; a bake reads its field
    directly: False)."""
    if gather is None:
        gather = reads_through_gather(props, group)
    values = {}
    for field, value in group.light_paths.items():
        setting = getattr(props, value.prop)
        if check and value.minimum is not None and setting < value.minimum:
            raise ValueError(
                f"{SETTING_LABELS[value.prop]} is {setting}: the {group.label} stores light "
                f"after {value.minimum} or more diffuse bounces; set it to {value.minimum} or "
                "more, or use Path Tracing (which renders 0 as direct light only)")
        if gather and value.prop == "diffuse_bounces":
            setting = max(setting - GATHER_BOUNCES,
                          value.minimum if value.minimum is not None else 0)
        if value.maximum is not None:
            setting = min(setting, value.maximum)
        values[field] = setting + value.offset
    return values


def method_native_fields(props, group, shgi, gather=None):
    """{native field: value} of method `group`'s settings struct from scene.shgi `props`: its
    group's mirrored fields, Light Paths' values and the seed."""
    values = native_fields(getattr(props, group.prop), {name: name for name in group.defaults},
                           shgi)
    values.update(light_path_fields(props, group, gather=gather))
    values["seed"] = props.seed
    return values


def path_tracer_settings(props, shgi):
    """shgi.PathTracerSettings of scene.shgi (ValueError naming a refused setting)."""
    return validated(shgi.PathTracerSettings(**native_fields(props, PATH_TRACER_FIELDS, shgi)))


def preview_settings(props, shgi):
    """shgi.PreviewSettings of scene.shgi (the F12 renderer of the field methods; ValueError
    naming a refused setting), with the final gather of the method's group
    (reads_through_gather)."""
    values = native_fields(props, PREVIEW_FIELDS, shgi)
    group = METHOD_SETTINGS.get(METHODS_BY_ID[props.method].solver)
    if group is not None:  # a plugin method without a group reads its field directly
        values["final_gather"] = reads_through_gather(props, group)
    return validated(shgi.PreviewSettings(**values))


def photon_lattice_settings(props, shgi, gather=None):
    """shgi.PhotonLatticeSettings of scene.shgi: its photon_lattice group, Light Paths and the
    seed (ValueError naming a refused setting)."""
    return validated(shgi.PhotonLatticeSettings(
        **method_native_fields(props, METHOD_SETTINGS["PHOTON_LATTICE"], shgi, gather)))


def probe_grid_settings(props, shgi, volumes=(), gather=None):
    """shgi.ProbeGridSettings of scene.shgi: its probe_grid group, Light Paths and the seed.

    volumes: shgi.ProbeVolume list (the scene's Irradiance Volumes); empty: one volume fitted to
    the scene with the spacing setting. ValueError naming a refused setting.
    """
    return validated(shgi.ProbeGridSettings(
        **method_native_fields(props, METHOD_SETTINGS["PROBE_GRID"], shgi, gather),
        volumes=list(volumes)))


def radiance_field_settings(props, shgi, gather=None):
    """shgi.RadianceFieldSettings of scene.shgi: its radiance_field group, Light Paths and the
    seed (ValueError naming a refused setting)."""
    return validated(shgi.RadianceFieldSettings(
        **method_native_fields(props, METHOD_SETTINGS["RADIANCE_FIELD"], shgi, gather)))


def propagation_settings(props, shgi, gather=None):
    """shgi.PropagationSettings of scene.shgi: its propagation group, Light Paths and the seed
    (ValueError naming a refused setting)."""
    return validated(shgi.PropagationSettings(
        **method_native_fields(props, METHOD_SETTINGS["PROPAGATION"], shgi, gather)))


def instant_gi_settings(props, shgi, gather=None):
    """shgi.InstantGiSettings of scene.shgi: its instant_gi group, Light Paths and the seed
    (ValueError naming a refused setting)."""
    return validated(shgi.InstantGiSettings(
        **method_native_fields(props, METHOD_SETTINGS["INSTANT_GI"], shgi, gather)))


# ProbeGridSettings' fields that say how a probe field is read (shgi.ProbeLookupSettings).
PROBE_LOOKUP_FIELDS = ("normal_bias", "view_bias", "bleed_bias", "visibility")


def probe_lookup_settings(props, shgi):
    """shgi.ProbeLookupSettings of scene.shgi.probe_grid: how a probe field read from a file is
    looked up, as the grid's own field is."""
    return shgi.ProbeLookupSettings(**{name: getattr(props.probe_grid, name)
                                       for name in PROBE_LOOKUP_FIELDS})


def solver_signature(props):
    """The values the solve of scene.shgi's method depends on (to tell that a frozen solution
    is out of date): the method and its native settings' fields, by their native names, so that
    a signature saved with a solution compares whatever the properties' layout (a Light Paths
    value the method follows counts under the native field it fills)."""
    group = METHOD_SETTINGS.get(METHODS_BY_ID[props.method].solver)
    values = {}
    if group is not None:  # a method without a group (a plugin's) solves with its defaults
        group_props = getattr(props, group.prop)
        values = {name: getattr(group_props, name) for name in group.defaults}
        values.update(light_path_fields(props, group, check=False))
    # The seed last, as signatures saved with probe grid solutions have it.
    return (("method", props.method), *sorted(values.items()), ("seed", props.seed))


def overlay_wanted(props):
    """True when the 3D views should draw the method's field overlay (lattice samples or
    probes)."""
    solver = METHODS_BY_ID[props.method].solver
    return ((solver == "PHOTON_LATTICE" and props.show_lattice_samples)
            or (solver == "PROBE_GRID" and props.show_probes))


def group_properties(group):
    """The properties of method `group`'s PropertyGroup a viewport render depends on."""
    return (*group.defaults, "viewport_passes", "final_gather")


def render_property_values(props):
    """((name, value), ...) of the VIEWPORT_RENDER_PROPERTIES: plain values a worker thread can
    read and compare (scene.shgi itself must stay on Blender's main thread). Each method's group
    becomes a nested ((name, value), ...)."""
    groups = {group.prop: group for group in METHOD_SETTINGS.values()}
    values = []
    for name in VIEWPORT_RENDER_PROPERTIES:
        value = getattr(props, name)
        if name in groups:
            value = tuple((field, getattr(value, field))
                          for field in group_properties(groups[name]))
        values.append((name, value))
    return tuple(values)


def properties_from_values(values):
    """A namespace with the property names as attributes (and each method group as a nested
    one) from render_property_values(): what the settings functions above take on a worker
    thread."""
    props = dict(values)
    for group in METHOD_SETTINGS.values():
        props[group.prop] = SimpleNamespace(**dict(props[group.prop]))
    return SimpleNamespace(**props)


def default_properties(shgi=None, **overrides):
    """scene.shgi of a new scene as a namespace (method groups nested), `overrides` set: the
    stand-in the settings functions take outside Blender. shgi: the module whose registry gives
    the final passes (FINAL_PASSES_FALLBACK without it)."""
    values = dict(PROPERTY_DEFAULTS, **VIEWPORT_PROPERTY_DEFAULTS, **DENOISING_DEFAULTS,
                  **TIME_LIMIT_DEFAULTS, method=METHODS[0].identifier)
    for solver, group in METHOD_SETTINGS.items():
        bake = ({"bake_passes": final_passes(solver, shgi)}
                if solver in RENDER_PASSES_DEFAULTS else {})
        values[group.prop] = SimpleNamespace(
            **group.defaults, passes=render_passes(solver, shgi),
            viewport_passes=VIEWPORT_PASSES_DEFAULTS[solver],
            final_gather=FINAL_GATHER_DEFAULTS[solver], **bake)
    values.update(overrides)
    return SimpleNamespace(**values)
