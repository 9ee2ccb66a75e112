"""The lightmap bake settings of ``scene.shgi.bake`` and the shgi.bake options they fill, no bpy.

``scene.shgi.bake`` (properties.py, ShgiBakeSettings) holds what the Bake panel shows; the
operators ``shgi.bake_lightmaps`` and ``shgi.merge_lightmap_shards`` carry the same properties
and take every one a caller did not set from that group (operators/bake_lightmaps.py), so a
script or a farm job overrides only what it names.

Names are the native ones where a native field exists (docs/architecture.md: settings mirrored 1:1):
``content``, ``samples``, ``directional``, ``sh_order``, ``tile_size`` are LightmapSettings fields; ``filter``
and ``padding`` are BakeOptions fields. The one rename is BakeOptions ``uv_set``, shown as
``uv_map`` (Blender's word for it). The light-path limits and the seed are not repeated here:
a bake uses the render settings' (``scene.shgi``: the Light Paths panel and the seed), as a
Cycles bake uses Cycles' render settings. Not mirrored: BakeOptions ``samples_per_axis``,
``unocclude``, ``filter_settings``, ``png`` and ``exposure`` keep shgi.bake's defaults (an
artist-facing panel needs none of them; ``python -m shgi bake`` does not expose them either).

Everything here takes any object with the property names as attributes (the PropertyGroup, an
operator, or a SimpleNamespace in tests).
"""

import math
from dataclasses import dataclass

from . import settings

# Where the indirect light of a bake comes from: every method of the registry
# (settings.METHODS), under the same identifier and file number as the render method. The path
# tracer bakes every texel by path tracing; the others solve their field first (the Photon
# Lattice, Probe Grid and Radiance Field with their panels' settings, engine/field_solvers.py). Files saved when
# the path tracer's source was called PATH_TRACER hold its number, 0, and open as PATH_TRACE.
SOURCE_DESCRIPTIONS = {
    "PATH_TRACE": "Reference path tracer per texel: matches a Cycles bake, slowest",
    "PHOTON_LATTICE": "Indirect light from a photon lattice solved with the Photon Lattice "
                      "settings; exact direct light",
    "PROBE_GRID": "Indirect light from a probe grid solved with the Probe Grid settings "
                  "(Irradiance Volume objects place it); exact direct light",
    "RADIANCE_FIELD": "Indirect light from a radiance field solved with the Radiance Field "
                      "settings; exact direct light",
    "PROPAGATION": "Indirect light from a light propagation volume solved with the Light "
                   "Propagation settings; exact direct light",
    "INSTANT_GI": "Indirect light from the Instant GI's virtual point lights (every set, exact "
                  "shadows, no screen-space filter); exact direct light",
}
SOURCE_ITEMS = tuple(
    (method.identifier, method.label,
     SOURCE_DESCRIPTIONS.get(method.identifier, f"Indirect light from {method.label}: "
                                                f"{method.description}"), method.number)
    for method in settings.METHODS)
FIELD_SOURCES = tuple(method.identifier for method in settings.METHODS if method.uses_field)

# LightmapSettings.content: what a texel holds, in Cycles' Diffuse bake units.
CONTENT_ITEMS = (
    ("DIRECT_INDIRECT", "Direct + Indirect",
     "Cycles' Diffuse bake with Direct and Indirect: the light a white Lambert surface "
     "reflects (irradiance / pi), without the surface's colour"),
    ("DIRECT", "Direct", "Cycles' Diffuse bake with Direct only: light straight from emitters"),
    ("INDIRECT", "Indirect",
     "Cycles' Diffuse bake with Indirect only: light that scattered at least once"),
    ("FULL", "Full",
     "Cycles' Diffuse bake with Direct, Indirect and Color: the surface's diffuse radiance"),
)

# Every property of scene.shgi.bake (and of the bake operators) with its default. The native
# ones are checked against LightmapSettings and BakeOptions by tests/python/test_blender_bake.py.
BAKE_PROPERTY_DEFAULTS = {
    "uv_map": "LightmapUV",
    "create_uv": False,
    "uv_layout": "LIGHTMAP_PACK",
    "resolution": 0,
    "texel_density": 32.0,
    "samples": 256,
    "content": "DIRECT_INDIRECT",
    "source": "PATH_TRACE",
    "directional": False,
    "sh_order": 1,
    "final_gather": False,
    "filter": False,
    "denoiser": "SHGI",
    "padding": 4,
    "tile_size": 16,
    "output_folder": "//lightmaps",
    "shard_index": 0,
    "shard_count": 1,
    "farm": "LOCAL",
    "scheduler": "",
    "workers": 2,
    "hook_up_material": False,
    "single_user_materials": True,
    "bake_side": "FRONT",
}
# Where Export Volume writes when its operator's filepath is not set (scene.shgi.bake only).
VOLUME_PATH_DEFAULT = "//shgi_volume.json"

# How Create UV Map lays out a missing UV map (scene.shgi.bake.uv_layout).
UV_LAYOUT_ITEMS = (
    ("LIGHTMAP_PACK", "Lightmap Pack", "Blender's Lightmap Pack: each face its own box"),
    ("XATLAS", "xatlas", "xatlas charts packed into the lightmap's size with padding between "
                         "them (needs the xatlas module: make deps installs it)"),
)

# Which side of a surface a bake holds (scene.shgi.bake.bake_side; operators/facing_check.py).
BAKE_SIDE_ITEMS = (
    ("FRONT", "Front", "Bake each surface's front (its normal's side), as Cycles does; objects "
                       "facing away from the scene are warned about"),
    ("FACING_SCENE", "Facing the Scene",
     "Bake objects whose fronts face away from the scene (a room modelled with its normals "
     "out) from their backs, the side facing the scene; every such object of the scene is "
     "turned around for the bake"),
)

# Denoiser of "Denoise" (scene.shgi.bake.denoiser): shgi.bake.BakeOptions.denoise methods.
DENOISER_ITEMS = (
    ("SHGI", "SHGI Filter", "SHGI's edge-aware filter (never crosses UV charts)"),
    ("OIDN", "OpenImageDenoise", "Intel OpenImageDenoise, lightmap filter, per UV chart (needs "
                                 "the pyoidn module: make deps installs it)"),
)

# Where a bake runs (scene.shgi.bake.farm): the Bake panel's Farm section.
FARM_ITEMS = (
    ("LOCAL", "This Computer",
     "Bake here; with Shards > 1, only shard Shard (a farm job runs the others, Merge Shards "
     "joins them)"),
    ("DASK", "Dask",
     "Bake the shards as tasks on a Dask cluster (the Scheduler's address; empty: Workers "
     "processes on this computer) and merge them here into the lightmaps a bake here writes"),
    ("FLAMENCO", "Flamenco",
     "Write a job of the SHGI Lightmap Bake job type (examples/flamenco) for a Flamenco farm: "
     "its workers open this saved .blend file"),
)
# Worker processes of a Dask bake on this computer (Scheduler empty): shgi.farm's limit.
MAX_FARM_WORKERS = 256
# Shards per Dask worker when Shards is 1: shgi.farm.SHARDS_PER_WORKER (this module imports no
# shgi; tests/python/test_blender_bake.py checks the two agree).
SHARDS_PER_WORKER = 4

# LightmapSettings.samples' native limit (native/bake/lightmap_baker.cpp kMaxSamples): the
# Samples property's range.
MAX_SAMPLES = 1 << 20

# LightmapSettings field -> scene.shgi.bake property.
LIGHTMAP_FIELDS = {name: name for name in (
    "content", "samples", "directional", "sh_order", "final_gather", "tile_size")}
# LightmapSettings field -> scene.shgi property (the render settings' light paths and seed).
LIGHT_PATH_FIELDS = {name: name for name in (
    "seed", "max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
    "clamp_indirect", "filter_glossy", "light_splits")}
# LightmapSettings field -> where the Bake and Light Paths panels show it, for refusals.
LIGHTMAP_LABELS = {
    "content": "Bake > Content", "samples": "Bake > Samples", "directional": "Bake > Directional",
    "sh_order": "Bake > SH Order",
    "final_gather": "Bake > Final Gather",
    "tile_size": "Bake > Farm > Tile Size",
    **{field: settings.SETTING_LABELS[prop] for field, prop in LIGHT_PATH_FIELDS.items()}}
# BakeOptions field -> scene.shgi.bake property.
OPTION_FIELDS = {"uv_set": "uv_map", "filter": "filter", "padding": "padding"}

# The Mix Shader that "Show in Materials" (hook_up_material) puts between a material's surface and
# its output (operators/lightmap_images.py); SHGI's export reads the surface through it
# (export/material.py), so a preview of baked light never changes what SHGI renders or bakes.
LIGHTMAP_MIX_NODE = "SHGI Lightmap Mix"


def resolution_range(shgi):
    """IntProperty keywords bounding the Resolution property by the sizes the bake accepts:
    max, the native lightmap side limit (shgi.MAX_LIGHTMAP_RESOLUTION; above it rasterize_texels
    refuses); soft_max, the largest side a texel density picks (shgi.bake.MAX_RESOLUTION).
    None of them without the module `shgi` (nothing can be baked then).

    The Texel Density needs no maximum: any density gives a side within shgi.bake's
    [MIN_RESOLUTION, MAX_RESOLUTION] (resolution_for_density clamps it).
    """
    if shgi is None:
        return {}
    from shgi import bake as shgi_bake

    return {"max": shgi.MAX_LIGHTMAP_RESOLUTION, "soft_max": shgi_bake.MAX_RESOLUTION}


def lightmap_settings(bake, props, shgi):
    """shgi.LightmapSettings of scene.shgi.bake (`bake`) and scene.shgi (`props`)."""
    values = {field: getattr(bake, prop) for field, prop in LIGHTMAP_FIELDS.items()}
    values.update({field: getattr(props, prop) for field, prop in LIGHT_PATH_FIELDS.items()})
    return shgi.LightmapSettings(**values)


def bake_options(bake, props, shgi):
    """shgi.bake.BakeOptions of scene.shgi.bake and scene.shgi (ValueError for a bad setting,
    naming it)."""
    from shgi import bake as shgi_bake

    lightmap = settings.validated(lightmap_settings(bake, props, shgi),
                                  {"LightmapSettings": LIGHTMAP_LABELS})
    options = shgi_bake.BakeOptions(
        settings=lightmap, **{field: getattr(bake, prop) for field, prop in OPTION_FIELDS.items()})
    if bake.filter and bake.denoiser == "OIDN":  # Denoise with OpenImageDenoise, not SHGI's filter
        options.filter, options.denoise = False, "OIDN"
    return options


def shard(bake):
    """(index, count) of the shard to bake, or None for a whole bake (shard_count 1).
    ValueError when the index is not below the count."""
    if bake.shard_count <= 1:
        return None
    if not 0 <= bake.shard_index < bake.shard_count:
        raise ValueError(f"shard {bake.shard_index} of {bake.shard_count}: the shard index must "
                         f"lie in 0..{bake.shard_count - 1}")
    return (bake.shard_index, bake.shard_count)


@dataclass
class FarmTarget:
    """Where a Dask bake runs (shgi.farm.connect): a scheduler's address, or `workers` processes
    on this computer; `shards` 0: SHARDS_PER_WORKER per worker."""

    scheduler: str
    workers: int
    shards: int


def farm_target(bake):
    """The FarmTarget of a bake with Farm "Dask", else None. ValueError for an address that is
    not tcp://HOST:PORT (naming Bake > Farm > Scheduler)."""
    if bake.farm != "DASK":
        return None
    address = bake.scheduler.strip()
    if address:
        host, _, port = address.removeprefix("tcp://").rpartition(":")
        if not address.startswith("tcp://") or not host or not port.isdigit():
            raise ValueError(f"Bake > Farm > Scheduler {address!r} is not an address like "
                             "tcp://192.168.1.20:8786 (what `dask scheduler` prints); empty "
                             "bakes on Workers processes on this computer")
    if not 1 <= bake.workers <= MAX_FARM_WORKERS:
        raise ValueError(f"Bake > Farm > Workers must lie in 1..{MAX_FARM_WORKERS}, got "
                         f"{bake.workers}")
    return FarmTarget(address, bake.workers, bake.shard_count if bake.shard_count > 1 else 0)


# The Flamenco job type of examples/flamenco/shgi_bake.js, as a Manager names a job compiler
# script: its file name, "_" as "-".
FLAMENCO_JOB_TYPE = "shgi-bake"
# The job's settings taken from scene.shgi.bake under the same names (shgi_bake.js's keys).
FLAMENCO_SETTINGS = ("uv_map", "create_uv", "resolution", "texel_density", "samples", "content",
                     "source", "directional", "sh_order", "filter", "padding", "shard_count")


def flamenco_job(bake, objects, blendfile, output_folder, name):
    """A job of the SHGI Lightmap Bake job type (examples/flamenco/shgi_bake.js) as the body a
    Flamenco Manager's job submission takes ({"name", "type", "priority", "settings",
    "metadata"}): the Bake panel's settings (`bake`), the names of the objects to bake, the
    saved .blend file every task opens (runner "blender") and the absolute output folder.
    examples/flamenco/preview_job.js compiles it and runs its tasks on one machine."""
    settings = {key: getattr(bake, key) for key in FLAMENCO_SETTINGS}
    settings.update(objects=", ".join(sorted(objects)), output_folder=output_folder,
                    runner="blender", blendfile=blendfile)
    return {"name": name, "type": FLAMENCO_JOB_TYPE, "priority": 50, "settings": settings,
            "metadata": {"created_by": "SHGI Write Flamenco Job"}}


def lightmap_size(bake, scene, instance):
    """Texels per side of an instance's lightmap: `resolution` when positive, else from
    `texel_density` (texels per metre, shgi.bake.resolution_for_density). ValueError when both
    are 0."""
    if bake.resolution > 0:
        return bake.resolution
    if not (bake.texel_density > 0.0 and math.isfinite(bake.texel_density)):
        raise ValueError("resolution and texel density are both 0: set one of them")
    from shgi import bake as shgi_bake

    return shgi_bake.resolution_for_density(scene, instance, bake.texel_density)


def uses_field(bake):
    """True when the bake's indirect light comes from a solved field, not the path tracer."""
    return bake.source in FIELD_SOURCES
