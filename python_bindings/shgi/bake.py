"""Baking lightmaps to files: objects, texel density, shards for render farms, EXR and PNG output.

The native pieces (``shgi.rasterize_texels``, ``shgi.unocclude``, ``shgi.bake_lightmap``,
``shgi.filter_lightmap``, ``shgi.dilate_lightmap``) do the work; this module runs them for each
object of a scene and writes the results. The Blender operator ``shgi.bake_lightmaps`` and the
command line ``python -m shgi bake`` both use it.

One object's bake: rasterize its lightmap UV map into a texel map, move samples out of walls
(unocclude), bake the texels (all of them, or one shard's tiles), then *finish*: filter
(optional), dilate into the padding, write ``<name>.exr`` and ``<name>.png``.

Lightmap UV maps: ``BakeOptions.lightmap_uvs`` "EXISTING" bakes only meshes that have the UV
map; "XATLAS" first gives each mesh without it one laid out by xatlas (``shgi.uv_atlas``,
``generate_lightmap_uvs``) and puts the mesh back into the scene (``Scene.set_mesh``). A mesh
several objects share gets one layout, packed for the smallest of their lightmaps.

Files (rows top first, as EXR and PNG store them; in memory row 0 is v = 0):

``<name>.exr``
    ``Lightmap.R/G/B`` (half): the light per texel, in Cycles' DIFFUSE bake units
    (``LightmapSettings.content``); ``Variance.V`` (float): variance of each texel's luminance,
    a confidence layer; ``Coverage.V`` (float): the fraction of each texel the UV layout covers
    (0 in the padding); with ``directional``: ``SH.c0`` .. ``SH.c3`` ``.R/G/B`` (float), the L1 SH
    of the incident radiance, coefficient index l(l+1)+m (c0 = Y00, c1 = Y1-1 (y), c2 = Y10 (z),
    c3 = Y11 (x)), real orthonormal basis without the Condon-Shortley phase (``shgi.sh``); with
    ``sh_order=2`` (L2) also ``SH.c4`` .. ``SH.c8`` (c4 = Y2-2 (xy), c5 = Y2-1 (yz),
    c6 = Y20 (3z^2 - 1), c7 = Y21 (xz), c8 = Y22 (x^2 - y^2)); c0 .. c3 are then the same
    coefficients as an L1 bake's.
``<name>.png``
    an 8-bit sRGB preview of ``Lightmap`` (clamped to [0, 1]).

Shards: ``shard=(i, n)`` bakes every tile whose index, counted over all objects in order, is
i modulo n, and saves the raw texels as ``<out>/shards/<name>.shard-<i>-of-<n>.npz`` together
with what decides their values (size, UV map and where it came from, LightmapSettings, source
of indirect light);
``merge_shards`` reads every shard of every object, checks that they were baked alike, merges and
finishes them. Texels depend only on the seed, the object and the texel, so the merged files are
byte-identical to a single bake.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
import json
import math
import os
import re
import zipfile
from typing import Callable, Iterable, Optional, Sequence

import numpy as np

from . import _shgi, uv_atlas
from . import method_registry as _methods
from .denoise import import_optional

__all__ = [
    "BakeOptions",
    "BakeJob",
    "Lightmap",
    "BakeProgress",
    "resolution_for_density",
    "resolution_for_area",
    "surface_area",
    "bake_object",
    "finish",
    "write_lightmap",
    "bake_scene",
    "merge_shards",
    "shard_path",
    "jobs_for_scene",
    "emits_light",
    "has_lamps_or_emitters",
    "solve_field",
    "sources",
    "LIGHTMAP_UV_SOURCES",
    "generate_lightmap_uvs",
    "describe_uv_layout",
]

SH_LAYERS = ("SH.c0", "SH.c1", "SH.c2", "SH.c3")
# The layers of an L2 directional lightmap (LightmapSettings.sh_order = 2): L1's and five more.
SH_LAYERS_L2 = SH_LAYERS + ("SH.c4", "SH.c5", "SH.c6", "SH.c7", "SH.c8")
# Lightmap sides chosen from a texel density are clamped to this range (texels).
MIN_RESOLUTION, MAX_RESOLUTION = 16, 4096
# The texel density (texels per metre of surface) lightmaps are sized by when no size is given:
# ``python -m shgi bake``'s and the Blender add-on's Texel Density (bake_settings.py) alike.
DEFAULT_TEXELS_PER_METRE = 32.0

# Shares of one object's progress: rasterizing its UV map and unoccluding the samples are quick
# next to baking the texels; filtering, dilation and writing the files take the rest.
_RASTER_SHARE = 0.05
_FINISH_SHARE = 0.1


def sources() -> tuple:
    """Where the indirect light of a bake can come from (the CLI's --method, the add-on's
    source): the identifier of every method of shgi.methods(), PATH_TRACE (path tracing every
    texel) first."""
    return tuple(row.identifier for row in _methods.methods())


def __getattr__(name):
    # Names of earlier versions, read from the registry so they cannot disagree with it.
    if name == "SOURCES":
        return sources()
    if name == "PROBE_GRID_PASSES":
        return _methods.method("PROBE_GRID").final_passes
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# Where an object's lightmap UV map comes from (BakeOptions.lightmap_uvs, the CLI's --uv):
# the mesh's own, or one laid out by xatlas for meshes without it.
LIGHTMAP_UV_SOURCES = ("EXISTING", "XATLAS")

# Version of the shard file layout (the arrays and the "meta" JSON below). 2: lightmap UV source.
_SHARD_FORMAT = 2
# The LightmapSettings fields that decide a texel's value: every shard of a bake must agree.
_SHARD_SETTINGS = ("content", "samples", "seed", "directional", "max_bounces", "diffuse_bounces",
                   "glossy_bounces", "transmission_bounces", "clamp_indirect", "final_gather",
                   "tile_size", "sh_order", "filter_glossy")


@dataclasses.dataclass
class BakeOptions:
    """How every object is baked (per-object resolution lives in BakeJob)."""

    settings: _shgi.LightmapSettings = dataclasses.field(default_factory=_shgi.LightmapSettings)
    uv_set: str = "LightmapUV"
    samples_per_axis: int = 2  # sample positions per texel side
    unocclude: bool = True
    filter: bool = False  # the edge-aware filter (shgi.LightmapFilterSettings); = denoise "SHGI"
    filter_settings: _shgi.LightmapFilterSettings = dataclasses.field(
        default_factory=_shgi.LightmapFilterSettings
    )
    # "NONE", "SHGI" (the edge-aware filter) or "OIDN" (OpenImageDenoise per UV chart,
    # shgi.denoise; needs the pyoidn module), applied before dilation.
    denoise: str = "NONE"
    oidn_filter: str = "RTLightmap"
    padding: int = 4  # texels of dilation beyond the UV charts
    # Where `uv_set` comes from (LIGHTMAP_UV_SOURCES): "EXISTING", each mesh's own; "XATLAS", a
    # layout from xatlas for meshes without it (generate_lightmap_uvs), with `uv_padding` empty
    # texels around each chart (2 x uv_padding between charts: room for `padding`'s dilation).
    lightmap_uvs: str = "EXISTING"
    uv_padding: int = 2
    png: bool = True
    exposure: float = 0.0  # stops, for the PNG preview only


@dataclasses.dataclass
class BakeJob:
    """One object to bake: its scene instance, file name and lightmap size; `uv_layout`, the
    report of the xatlas layout generate_lightmap_uvs made for its mesh (None: the mesh's own)."""

    instance: int
    name: str
    width: int = 256
    height: int = 256
    uv_layout: Optional[dict] = None


@dataclasses.dataclass
class Lightmap:
    """A finished lightmap; arrays (H, W, ...) with row 0 at v = 0 (Blender's Image.pixels)."""

    name: str
    color: np.ndarray  # (H, W, 3) float32
    variance: np.ndarray  # (H, W) float32
    coverage: np.ndarray  # (H, W) float32, 0 outside the charts
    filled: np.ndarray  # (H, W) bool: baked or dilated
    sh: Optional[np.ndarray] = None  # (H, W, 4, 3) float32 with directional; (H, W, 9, 3) at L2
    # The rasterizer's report and chart count ("charts"); "uv_layout": BakeJob.uv_layout when
    # xatlas laid out the UV map (chart_count, utilization, ...).
    report: dict = dataclasses.field(default_factory=dict)
    paths: list = dataclasses.field(default_factory=list)


class BakeProgress:
    """Progress over several objects: ``fraction`` in [0, 1], ``stage`` text, ``cancel()``.

    Thread-safe enough for its use: a worker thread bakes, a UI thread reads and cancels.
    ``callback(fraction, stage)`` (optional) is called from the worker.
    """

    def __init__(self, callback: Optional[Callable[[float, str], None]] = None):
        self.callback = callback
        self.fraction = 0.0
        self.stage = ""
        self._cancelled = False
        self._current: Optional[_shgi.Progress] = None

    def cancel(self) -> None:
        self._cancelled = True
        current = self._current
        if current is not None:
            current.cancel()

    @property
    def cancelled(self) -> bool:
        return self._cancelled

    def native(self, lo: float, hi: float, label: str) -> _shgi.Progress:
        """A native Progress whose [0, 1] maps onto [lo, hi] of the whole bake."""
        if self._cancelled:
            raise _shgi.Cancelled("bake cancelled")

        def report(fraction: float, stage: str) -> None:
            self.fraction = lo + (hi - lo) * fraction
            self.stage = f"{label}: {stage}" if stage else label
            if self.callback is not None:
                self.callback(self.fraction, self.stage)

        self._current = _shgi.Progress(report)
        if self._cancelled:  # cancel() ran between the check and the assignment
            self._current.cancel()
        return self._current

    def stages(self, lo: float, hi: float, label: str) -> Callable[[float, float], _shgi.Progress]:
        """For one object that owns [lo, hi] of the bake: stage(a, b) is the native Progress of
        the step that owns [a, b] of the object's own [0, 1]."""
        return lambda a, b: self.native(lo + a * (hi - lo), lo + b * (hi - lo), label)

    def note(self, stage: str) -> None:
        """Reports a step that owns no share of the bake (the fraction stays where it is), such
        as a UV layout; raises shgi.Cancelled after cancel()."""
        if self._cancelled:
            raise _shgi.Cancelled("bake cancelled")
        self.stage = stage
        if self.callback is not None:
            self.callback(self.fraction, self.stage)

    def done(self) -> None:
        """Reports the end of the whole bake (fraction 1)."""
        self.fraction, self.stage = 1.0, "done"
        if self.callback is not None:
            self.callback(self.fraction, self.stage)


def resolution_for_density(scene: _shgi.Scene, instance: int, texels_per_metre: float,
                           minimum: int = MIN_RESOLUTION, maximum: int = MAX_RESOLUTION) -> int:
    """Square lightmap size giving about `texels_per_metre` on the object's surface.

    The UV layout is assumed to use about half of the square (lightmap packs with margins
    reach 0.5-0.8), so the side is sqrt(2 * area) * density, rounded up to a multiple of 4.
    """
    inst = scene.instances[instance]
    return _side_for_density(scene.meshes[inst.mesh_id], inst, texels_per_metre, minimum,
                             maximum)


def resolution_for_area(area: float, texels_per_metre: float, minimum: int = MIN_RESOLUTION,
                        maximum: int = MAX_RESOLUTION) -> int:
    """Square lightmap size giving about `texels_per_metre` on `area` square metres of
    surface (resolution_for_density's rule, for surfaces not in a Scene yet)."""
    if not (texels_per_metre > 0.0 and math.isfinite(texels_per_metre)):
        raise ValueError(f"texels_per_metre must be positive, got {texels_per_metre}")
    side = math.sqrt(2.0 * area) * texels_per_metre
    return int(min(maximum, max(minimum, 4 * math.ceil(side / 4.0))))


def surface_area(positions, triangles) -> float:
    """Total area of the triangles (T, 3 vertex indices) over `positions` (N, 3)."""
    p = np.asarray(positions, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64)
    return float(0.5 * np.linalg.norm(np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]),
                                      axis=1).sum())


def _side_for_density(mesh, inst, texels_per_metre: float, minimum: int, maximum: int) -> int:
    m = np.asarray(inst.world_from_object, dtype=np.float64)
    world = np.asarray(mesh.positions, dtype=np.float64) @ m[:3, :3].T + m[:3, 3]
    return resolution_for_area(surface_area(world, mesh.triangles), texels_per_metre, minimum,
                               maximum)


def _raster_settings(job: BakeJob, options: BakeOptions) -> _shgi.TexelRasterSettings:
    return _shgi.TexelRasterSettings(width=job.width, height=job.height, uv_set=options.uv_set,
                                     samples_per_axis=options.samples_per_axis)


def _texel_map(scene, job: BakeJob, options: BakeOptions, progress,
               tiles: Sequence[int] = (), field=None) -> _shgi.TexelMap:
    """The texel map of the job's lightmap, its samples moved out of walls (only those a bake
    of `tiles` with `field` reads, when given: what a shard bakes and, for an interleaved field,
    its filter's reach; each moves as in a whole unocclusion)."""
    texel_map = _shgi.rasterize_texels(scene, job.instance, _raster_settings(job, options),
                                       progress)
    if texel_map.sample_count == 0:
        raise ValueError(
            f"object '{job.name}': its UV map '{options.uv_set}' covers no texel of the "
            f"{job.width} x {job.height} lightmap (all UVs outside [0, 1] or collapsed); "
            "unwrap it (Smart UV Project or Lightmap Pack) into the unit square")
    if options.unocclude:
        read = _shgi.lightmap_read_tiles(job.width, job.height, options.settings.tile_size,
                                         list(tiles), field)
        _shgi.unocclude(scene, texel_map, _shgi.UnoccludeSettings(), progress, read,
                        options.settings.tile_size)
    return texel_map


def bake_object(scene, job: BakeJob, options: BakeOptions, field=None, tiles: Sequence[int] = (),
                progress=None):
    """Rasterizes and bakes one object (`tiles` only, all when empty); returns (TexelMap, raw
    LightmapTexels). `progress`: a native shgi.Progress, reused by every step. The mesh must
    have options.uv_set already (generate_lightmap_uvs lays out missing ones)."""
    return _bake_object(scene, job, options, field, tiles, lambda a, b: progress, 1.0)


def _bake_object(scene, job, options, field, tiles, stage, bake_end):
    """bake_object with stage(a, b) (BakeProgress.stages) giving each step its share, the bake
    ending at `bake_end` of the object's progress."""
    texel_map = _texel_map(scene, job, options, stage(0.0, _RASTER_SHARE), tiles, field)
    texels = _shgi.bake_lightmap(scene, texel_map, options.settings, field, list(tiles),
                                 stage(_RASTER_SHARE, bake_end))
    return texel_map, texels


DENOISE_METHODS = ("NONE", "SHGI", "OIDN")


def denoise_method(options: BakeOptions) -> str:
    """The denoiser `options` ask for ("filter" is the older spelling of "SHGI"); ValueError
    for an unknown one, ImportError naming the pip command when OIDN's module is missing."""
    method = options.denoise.upper()
    if method not in DENOISE_METHODS:
        raise ValueError(f"denoise {options.denoise!r}: use one of {', '.join(DENOISE_METHODS)}")
    if method == "NONE" and options.filter:
        method = "SHGI"
    if method == "OIDN":
        if options.settings.directional and options.settings.sh_order != 1:
            raise ValueError("denoise 'OIDN' denoises L1 directional lightmaps only; bake "
                             "sh_order 1, or denoise 'SHGI' (which filters L2 too), or 'NONE'")
        from .denoise import import_optional
        import_optional("pyoidn", "denoising lightmaps with OpenImageDenoise")
    return method


def finish(texel_map, texels, options: BakeOptions, name: str, progress=None) -> Lightmap:
    """Filters (optional) and dilates a complete bake into a Lightmap. `progress` (a native
    shgi.Progress) counts the filter when there is one (dilation is quick), else dilation."""
    method = denoise_method(options)
    if method == "SHGI":
        _shgi.filter_lightmap(texel_map, texels, options.filter_settings, progress)
        progress = None
    elif method == "OIDN":
        from .denoise import denoise_lightmap
        texels = denoise_lightmap(texel_map, texels, "OIDN", oidn_filter=options.oidn_filter,
                                  progress=progress)
        progress = None
    filled = _shgi.dilate_lightmap(texels, options.padding, progress)
    return Lightmap(name=name, color=texels.color, variance=texels.variance,
                    coverage=texel_map.coverage, filled=filled, sh=texels.sh,
                    report=dict(texel_map.report, charts=texel_map.chart_count))


def make_output_folder(folder: str) -> None:
    """Makes `folder` and its parents; an OSError naming the path when it, or a parent, is a
    file (os.makedirs says only "[Errno 17] File exists")."""
    try:
        os.makedirs(folder, exist_ok=True)
    except (FileExistsError, NotADirectoryError) as error:
        blocker = os.path.abspath(folder)
        while not os.path.exists(blocker):  # the nearest part of the path that exists
            blocker = os.path.dirname(blocker)
        raise NotADirectoryError(
            f"output folder {folder!r}: {blocker!r} is a file, not a folder; choose another "
            "folder or move the file") from error


def write_lightmap(lightmap: Lightmap, out_dir: str, options: BakeOptions) -> list:
    """Writes <name>.exr (and <name>.png); returns the paths."""
    make_output_folder(out_dir)
    stem = os.path.join(out_dir, _file_name(lightmap.name))
    layers = {
        "Lightmap": _top_row_first(lightmap.color).astype(np.float16),
        "Variance": _top_row_first(lightmap.variance).astype(np.float32),
        "Coverage": _top_row_first(lightmap.coverage).astype(np.float32),
    }
    names = {"Variance": "V", "Coverage": "V"}
    if lightmap.sh is not None:
        names_sh = SH_LAYERS_L2 if lightmap.sh.shape[2] == len(SH_LAYERS_L2) else SH_LAYERS
        for c, layer in enumerate(names_sh):
            layers[layer] = _top_row_first(lightmap.sh[:, :, c, :]).astype(np.float32)
    paths = [stem + ".exr"]
    _shgi.write_exr(paths[0], layers, channel_names=names)
    if options.png:
        paths.append(stem + ".png")
        _shgi.write_png(paths[1], _top_row_first(lightmap.color), exposure=options.exposure)
    lightmap.paths = paths
    return paths


def _top_row_first(array: np.ndarray) -> np.ndarray:
    """Rows of an in-memory lightmap (row 0 at v = 0) in the order files store them."""
    return np.ascontiguousarray(array[::-1])


def _file_name(name: str) -> str:
    """An object name made safe as a file name (keeps letters, digits, '.', '_', '-')."""
    safe = re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("._")
    return safe or "object"


def shard_path(out_dir: str, name: str, shard: int, shards: int) -> str:
    return os.path.join(out_dir, "shards", f"{_file_name(name)}.shard-{shard}-of-{shards}.npz")


def _shard_tiles(jobs: Sequence[BakeJob], options: BakeOptions, shard: int, shards: int):
    """Per job, the tiles of shard i of n: tiles counted over all jobs in order, i mod n."""
    if not (shards >= 1 and 0 <= shard < shards):
        raise ValueError(f"shard {shard}/{shards}: use i/N with N >= 1 and 0 <= i < N")
    size = options.settings.tile_size
    offset = 0
    result = []
    for job in jobs:
        count = _shgi.lightmap_tile_count(job.width, job.height, size)
        first = (shard - offset) % shards
        result.append(list(range(first, count, shards)))
        offset += count
    return result


NO_LIGHT_MESSAGE = ("the scene has no light (no lamp, no emissive material, a black world): a "
                    "bake would be black; add a light")


def has_lamps_or_emitters(scene) -> bool:
    """True when a light or a material of a shgi.Scene emits, the world aside (a portal only
    guides the sampling of the world: it emits nothing of its own)."""
    return (any(not light.portal for light in scene.lights)
            or any(material.is_emissive() for material in scene.materials))


def emits_light(scene) -> bool:
    """True when a light, a material or the world of a shgi.Scene emits."""
    if has_lamps_or_emitters(scene):
        return True
    world = scene.world
    return world.strength > 0.0 and max(world.color) > 0.0


def _check_jobs(scene, jobs: Sequence[BakeJob]) -> None:
    if not jobs:
        raise ValueError("nothing to bake: select at least one mesh object with a lightmap UV map")
    names = [_file_name(job.name) for job in jobs]
    duplicates = {n for n in names if names.count(n) > 1}
    if duplicates:
        raise ValueError(f"objects {sorted(duplicates)} would write the same files; rename them")
    _check_instances(scene, jobs)
    if not emits_light(scene):
        raise ValueError(NO_LIGHT_MESSAGE)


def _check_instances(scene, jobs: Sequence[BakeJob]) -> None:
    count = len(scene.instances)
    for job in jobs:
        if not 0 <= job.instance < count:
            raise ValueError(f"object '{job.name}': instance {job.instance} is not in the scene "
                             f"({count} instances)")


def _lightmap_uv_source(value: str) -> str:
    """BakeOptions.lightmap_uvs / jobs_for_scene's lightmap_uvs, checked (any case)."""
    source = str(value).upper()
    if source not in LIGHTMAP_UV_SOURCES:
        raise ValueError(f"lightmap_uvs {value!r}: use one of {', '.join(LIGHTMAP_UV_SOURCES)}")
    return source


def _meshes_without_uv_set(scene, jobs: Sequence[BakeJob], uv_set: str) -> dict:
    """{mesh id: [indices into jobs]} of the jobs whose mesh lacks `uv_set`, in jobs order."""
    meshes, instances = scene.meshes, scene.instances
    missing = {}
    for k, job in enumerate(jobs):
        mesh_id = instances[job.instance].mesh_id
        if uv_set not in meshes[mesh_id].uv_sets:
            missing.setdefault(mesh_id, []).append(k)
    return missing


def _job_names(jobs: Sequence[BakeJob], missing: dict) -> str:
    """'a', 'b': the names of the jobs _meshes_without_uv_set found."""
    return ", ".join(f"'{jobs[k].name}'" for members in missing.values() for k in members)


def generate_lightmap_uvs(scene, jobs: Sequence[BakeJob], options: BakeOptions,
                          progress: Optional[BakeProgress] = None) -> list:
    """Gives every job's mesh that lacks the UV map `options.uv_set` one laid out by xatlas
    (options.lightmap_uvs "XATLAS"), puts the new mesh into the scene with Scene.set_mesh and
    commits it again. Returns the jobs, each whose mesh was laid out here with the layout's
    report in `uv_layout` (uv_atlas.LightmapUVs.report: chart_count, utilization, uv_coverage,
    texels_per_metre, width, height, padding; plus `objects`, the jobs sharing the layout), and
    reports each through `progress`. Jobs whose mesh has the UV map are returned as they were,
    so a second call changes nothing.

    The layout is packed into a square of min(width, height) texels, the job's size, at the
    highest density that fits, with `options.uv_padding` empty texels around each chart.
    A mesh that several jobs' instances share gets one layout (the UV map belongs to the mesh):
    packed for the smallest of their lightmaps, so that every one keeps at least uv_padding
    texels around each chart (a larger lightmap only widens the gaps), with the first job's
    world_from_object deciding the charts' relative sizes (the same for every instance that
    differs only by a rotation, a translation or a uniform scale).

    Call it before solving an indirect-light field (solve_field): a field belongs to the scene
    as it was when solved. "EXISTING": ValueError naming the objects without the UV map.
    ImportError naming the pip command when xatlas is not installed.
    """
    source = _lightmap_uv_source(options.lightmap_uvs)
    _check_instances(scene, jobs)
    missing = _meshes_without_uv_set(scene, jobs, options.uv_set)
    if not missing:
        return list(jobs)
    if source == "EXISTING":
        raise ValueError(f"no UV map '{options.uv_set}' on {_job_names(jobs, missing)}: add "
                         "one, choose another UV map, or let xatlas lay one out "
                         "(BakeOptions.lightmap_uvs='XATLAS', the command line's --uv xatlas)")
    if not (isinstance(options.uv_padding, int) and options.uv_padding >= 0):
        raise ValueError(f"uv_padding must be a whole number of texels >= 0, got "
                         f"{options.uv_padding!r}")
    # Before any mesh changes: without xatlas the scene stays as it was.
    import_optional("xatlas", "laying out lightmap UVs (lightmap_uvs 'XATLAS', --uv xatlas)")
    progress = progress or BakeProgress()
    jobs = list(jobs)
    meshes, instances = scene.meshes, scene.instances
    for mesh_id, members in missing.items():
        first = jobs[members[0]]
        progress.note(f"{first.name}: lightmap UVs (xatlas)")
        resolution = min(min(jobs[k].width, jobs[k].height) for k in members)
        try:
            mesh, layout = uv_atlas.add_lightmap_uvs(
                meshes[mesh_id], uv_set=options.uv_set,
                world_from_object=instances[first.instance].world_from_object,
                resolution=resolution, padding=options.uv_padding)
        except ValueError as error:
            raise ValueError(f"object '{first.name}': {error}") from error
        scene.set_mesh(mesh_id, mesh)
        report = dict(layout.report, objects=[jobs[k].name for k in members])
        for k in members:
            jobs[k] = dataclasses.replace(jobs[k], uv_layout=report)
            progress.note(f"{jobs[k].name}: {describe_uv_layout(report)}")
    scene.commit()
    return jobs


def describe_uv_layout(report: dict) -> str:
    """One line for people: "lightmap UVs by xatlas: 6 charts, utilization 0.71 (48 x 48)"."""
    return (f"lightmap UVs by xatlas: {report['chart_count']} charts, utilization "
            f"{report['utilization']:.2f} ({report['width']} x {report['height']})")


def _spans(weights: Sequence[float]) -> list:
    """Each job's [lo, hi] of the whole bake's progress, in proportion to its weight."""
    total = float(sum(weights)) or 1.0
    spans, lo = [], 0.0
    for weight in weights:
        hi = lo + weight / total
        spans.append((lo, min(hi, 1.0)))
        lo = hi
    return spans


def bake_scene(scene, jobs: Sequence[BakeJob], options: BakeOptions, out_dir: str, field=None,
               shard: Optional[tuple] = None, progress: Optional[BakeProgress] = None,
               on_lightmap: Optional[Callable[[Lightmap], None]] = None) -> list:
    """Bakes every job into out_dir. Without a shard: finishes and writes each lightmap and
    returns the Lightmaps (on_lightmap(lightmap) is called as each one completes, so a
    cancelled bake keeps what finished). With shard=(i, n): writes raw shard files and returns
    their paths. `field`: None for the path tracer, else the IndirectField giving the indirect
    light (every shard of a bake must use the same).

    With options.lightmap_uvs "XATLAS", meshes without the UV map get one first
    (generate_lightmap_uvs, which must run before the field is solved when there is one); each
    such Lightmap's report holds the layout's in "uv_layout"."""
    _check_jobs(scene, jobs)
    options.settings.validate()
    if not shard:
        denoise_method(options)  # fail before baking, not after
    _check_padding(options)
    if field is not None and _lightmap_uv_source(options.lightmap_uvs) == "XATLAS":
        missing = _meshes_without_uv_set(scene, jobs, options.uv_set)
        if missing:
            raise ValueError(f"no UV map '{options.uv_set}' on {_job_names(jobs, missing)} yet, "
                             "and the indirect light field was solved for the scene without "
                             "it: call generate_lightmap_uvs(scene, jobs, options) before "
                             "solve_field and bake the jobs it returns")
    progress = progress or BakeProgress()
    jobs = generate_lightmap_uvs(scene, jobs, options, progress)
    if shard:
        tiles = _shard_tiles(jobs, options, *shard)
        weights = [len(t) for t in tiles]
    else:
        tiles = [[] for _ in jobs]  # every tile
        weights = [job.width * job.height for job in jobs]
    results = []
    for job, job_tiles, (lo, hi) in zip(jobs, tiles, _spans(weights)):
        stage = progress.stages(lo, hi, job.name)
        if shard:
            if job_tiles:
                _, texels = _bake_object(scene, job, options, field, job_tiles, stage, 1.0)
            else:
                # Nothing of this object in this shard: an empty shard file keeps merging simple.
                texels = _empty_texels(job, options)
            path = shard_path(out_dir, job.name, *shard)
            meta = _shard_meta(jobs, job, options, *shard, _source_name(field))
            _save_shard(path, texels, meta)
            results.append(path)
            continue
        texel_map, texels = _bake_object(scene, job, options, field, (), stage,
                                         1.0 - _FINISH_SHARE)
        lightmap = _finish_job(texel_map, texels, options, job, out_dir,
                               stage(1.0 - _FINISH_SHARE, 1.0))
        results.append(lightmap)
        if on_lightmap is not None:
            on_lightmap(lightmap)
    progress.done()
    return results


def _finish_job(texel_map, texels, options: BakeOptions, job: BakeJob, out_dir: str,
                progress) -> Lightmap:
    """finish() and write_lightmap() for a job, its UV layout's report added."""
    lightmap = finish(texel_map, texels, options, job.name, progress)
    if job.uv_layout is not None:
        lightmap.report["uv_layout"] = job.uv_layout
    write_lightmap(lightmap, out_dir, options)
    return lightmap


def _check_padding(options: BakeOptions) -> None:
    if not (isinstance(options.padding, int) and options.padding >= 0):
        raise ValueError(f"padding must be a whole number of texels >= 0, got {options.padding!r}")


def _empty_texels(job: BakeJob, options: BakeOptions) -> _shgi.LightmapTexels:
    h, w = job.height, job.width
    settings = options.settings
    coefficients = (settings.sh_order + 1) ** 2
    sh = np.zeros((h, w, coefficients, 3), np.float32) if settings.directional else None
    return _shgi.LightmapTexels(np.zeros((h, w, 3), np.float32), np.zeros((h, w), np.float32),
                                np.zeros((h, w), bool), sh)


def _source_name(field) -> str:
    """What gave the indirect light: PATH_TRACE, or the field's type (PhotonLattice, ...)."""
    return "PATH_TRACE" if field is None else type(field).__name__


def _shard_meta(jobs: Sequence[BakeJob], job: BakeJob, options: BakeOptions, shard: int,
                shards: int, source: Optional[str]) -> dict:
    """Everything that decides a shard's texels, saved with them and checked when merging:
    also every object of the bake and its size, since they decide which tiles a shard bakes.
    `source` None: not known (a merge does not bake; it checks the shards agree). With xatlas
    layouts: their padding and xatlas's version, since every shard and the merge lay the meshes
    out again and must get the same charts (the layout is deterministic for a given version)."""
    settings = options.settings
    uv_source = _lightmap_uv_source(options.lightmap_uvs)
    xatlas = uv_source == "XATLAS"
    return {
        "format": _SHARD_FORMAT, "object": job.name, "width": job.width, "height": job.height,
        "objects": [[other.name, other.width, other.height] for other in jobs],
        "shard": shard, "shards": shards, "uv_set": options.uv_set,
        "samples_per_axis": options.samples_per_axis, "unocclude": options.unocclude,
        "source": source,
        "lightmap_uvs": uv_source,
        "uv_padding": options.uv_padding if xatlas else None,
        "xatlas": _xatlas_version() if xatlas else None,
        "settings": {name: getattr(settings, name) for name in _SHARD_SETTINGS},
    }


def _xatlas_version() -> Optional[str]:
    """The installed xatlas's version, None without it (a bake that needed it has failed)."""
    try:
        return importlib.metadata.version("xatlas")
    except importlib.metadata.PackageNotFoundError:
        return None


def _save_shard(path: str, texels, meta: dict) -> None:
    make_output_folder(os.path.dirname(path))
    arrays = {"color": texels.color, "variance": texels.variance, "baked": texels.baked,
              "meta": np.array(json.dumps(meta, sort_keys=True))}
    if texels.directional:
        arrays["sh"] = texels.sh
    # Written under another name and renamed, so a shard killed mid-write leaves no file that
    # looks complete. Compressed: a shard's arrays are the whole lightmap's, zero outside its
    # 1/N of the tiles, so a farm moves about 1/N of the dense bytes per shard (docs/farm.md).
    temp = path + ".partial.npz"
    np.savez_compressed(temp, **arrays)
    os.replace(temp, path)


def _load_shard(path: str):
    """(LightmapTexels, meta dict) of a shard file; OSError naming it when missing or damaged."""
    try:
        with np.load(path) as data:
            meta = json.loads(str(data["meta"]))
            texels = _shgi.LightmapTexels(data["color"], data["variance"], data["baked"],
                                          data["sh"] if "sh" in data else None)
    except (OSError, KeyError, ValueError, zipfile.BadZipFile) as error:
        raise OSError(f"shard file {path} is missing or damaged ({error}); bake that shard "
                      "again") from error
    return texels, meta


def _check_shard_meta(path: str, meta: dict, expected: dict) -> None:
    """Raises ValueError naming the shard file and what differs from this merge's settings."""
    if meta.get("format") != _SHARD_FORMAT:
        raise ValueError(f"shard file {path} has layout {meta.get('format')}, this version of "
                         f"shgi reads {_SHARD_FORMAT}; bake the shards again")
    # "source" is not compared: a merge bakes nothing; the shards must agree among themselves.
    differences = [f"{key} {meta.get(key)!r} (merge: {value!r})"
                   for key, value in expected.items()
                   if key not in ("settings", "source") and meta.get(key) != value]
    settings = dict(meta.get("settings") or {})
    settings.setdefault("sh_order", 1)  # shards from before L2 lightmaps are L1
    settings.setdefault("filter_glossy", 0.0)  # and from before Filter Glossy unfiltered
    differences += [f"{key} {settings.get(key)!r} (merge: {value!r})"
                    for key, value in sorted(expected["settings"].items())
                    if settings.get(key) != value]
    if differences:
        raise ValueError(f"shard file {path} was baked with {', '.join(differences)}; bake every "
                         "shard and merge with the same objects, resolution and settings")


def merge_shards(scene, jobs: Sequence[BakeJob], options: BakeOptions, out_dir: str,
                 shards: int, progress: Optional[BakeProgress] = None) -> list:
    """Merges the shard files of `shards` shards in out_dir/shards and writes the lightmaps
    exactly as a single bake would. Raises OSError naming a missing or damaged shard file and
    ValueError when a file was baked with other settings or shards overlap."""
    _check_jobs(scene, jobs)
    if not (isinstance(shards, int) and shards >= 1):
        raise ValueError(f"shards must be a whole number >= 1, got {shards!r}")
    options.settings.validate()
    denoise_method(options)
    _check_padding(options)
    progress = progress or BakeProgress()
    jobs = generate_lightmap_uvs(scene, jobs, options, progress)  # as the shards laid them out
    results = []
    spans = _spans([job.width * job.height for job in jobs])
    for job, (lo, hi) in zip(jobs, spans):
        stage = progress.stages(lo, hi, job.name)
        merged = _empty_texels(job, options)
        sources = {}
        for i in range(shards):
            path = shard_path(out_dir, job.name, i, shards)
            part, meta = _load_shard(path)
            _check_shard_meta(path, meta, _shard_meta(jobs, job, options, i, shards, None))
            sources.setdefault(meta["source"], path)
            if len(sources) > 1:
                raise ValueError(f"shard files {' and '.join(sources.values())} took their "
                                 f"indirect light from different sources ({', '.join(sources)})")
            try:
                _shgi.merge_lightmap(merged, part)
            except ValueError as error:
                raise ValueError(f"shard file {path}: {error}") from error
        texel_map = _texel_map(scene, job, options, stage(0.0, _RASTER_SHARE))
        missing = int(((texel_map.coverage > 0) & ~merged.baked).sum())
        if missing:
            raise ValueError(f"object '{job.name}': {missing} texels are in no shard file; were "
                             f"all {shards} shards baked with the same settings?")
        results.append(_finish_job(texel_map, merged, options, job, out_dir,
                                   stage(_RASTER_SHARE, 1.0)))
    progress.done()
    return results


# The settings field that holds a field method's depth in diffuse bounces, and its least value.
# A field read through a final gather (LightmapSettings.final_gather) is solved one bounce
# shallower, since the gather ray is a bounce itself: the light then has as many bounces as the
# path tracer's (the add-on does the same from Light Paths > Diffuse). Methods not listed keep
# their settings (the gather adds a bounce to them).
GATHER_DEPTH_FIELDS = {"PhotonLatticeSettings": ("max_bounces", 1),
                       "ProbeGridSettings": ("bounces", 1),
                       "RadianceFieldSettings": ("max_bounces", 1),
                       "PropagationSettings": ("vpl_bounces", 1),
                       "InstantGiSettings": ("vpl_bounces", 1)}


def _gather_settings(settings):
    """A copy of a field method's settings one diffuse bounce shallower (GATHER_DEPTH_FIELDS),
    for a field read through a final gather; the settings themselves for a method not listed."""
    if type(settings).__name__ not in GATHER_DEPTH_FIELDS:
        return settings
    name, least = GATHER_DEPTH_FIELDS[type(settings).__name__]
    shallow = _methods.settings_from_dict(type(settings), _methods.settings_to_dict(settings))
    setattr(shallow, name, max(least, getattr(settings, name) - 1))
    return shallow


def solve_field(scene, source: str, seed: int = 0, progress: Optional[BakeProgress] = None,
                settings=None, passes: Optional[int] = None, gather: bool = False):
    """The IndirectField a bake takes its indirect light from: None for PATH_TRACE (the path
    tracer bakes every texel), else the field of method `source` (shgi.methods(); older names
    such as PATH_TRACER are accepted) solved on the (committed) scene with `settings` (None: the
    method's defaults with `seed`) over `passes` refinement passes (None: the method's
    final_passes, as the add-on's F12 and bake run); with `gather` (a bake with
    LightmapSettings.final_gather), one diffuse bounce shallower (GATHER_DEPTH_FIELDS). The
    solve owns no share of `progress` (its bar waits); cancel works."""
    row = _methods.method(source)
    if not row.solves_field:
        return None
    progress = progress or BakeProgress()
    if settings is None:
        settings = _methods.default_settings(row.identifier, seed)
    if gather:
        settings = _gather_settings(settings)
    native = progress.native(0.0, 0.0, row.label.lower())
    return _methods.solve(row.identifier, scene, settings, passes, native).current_field()


def jobs_for_scene(scene, uv_set: str, resolution: int = 0, texels_per_metre: float = 0.0,
                   names: Optional[Iterable[str]] = None, lightmap_uvs: str = "EXISTING") -> list:
    """A BakeJob for every instance whose mesh has the UV map `uv_set` (or only `names`); with
    lightmap_uvs "XATLAS" for every instance (generate_lightmap_uvs lays out the missing maps).

    Size: `resolution` when positive, else from `texels_per_metre` (resolution_for_density;
    an xatlas layout is then packed into that square); raises ValueError naming objects that
    lack the UV map when they were asked for by name.
    """
    generate = _lightmap_uv_source(lightmap_uvs) == "XATLAS"
    wanted = set(names) if names is not None else None
    jobs, missing = [], []
    meshes = scene.meshes
    for index, inst in enumerate(scene.instances):
        name = inst.name or f"instance_{index}"
        if wanted is not None and name not in wanted:
            continue
        if uv_set not in meshes[inst.mesh_id].uv_sets and not generate:
            if wanted is not None:
                missing.append(f"'{name}' (has {sorted(meshes[inst.mesh_id].uv_sets)})")
            continue
        if resolution > 0:
            size = resolution
        elif texels_per_metre > 0:
            size = _side_for_density(meshes[inst.mesh_id], inst, texels_per_metre,
                                     MIN_RESOLUTION, MAX_RESOLUTION)
        else:
            size = BakeJob.width
        jobs.append(BakeJob(instance=index, name=name, width=size, height=size))
    if missing:
        raise ValueError(f"no UV map '{uv_set}' on {', '.join(missing)}: add one, choose "
                         "another UV map or let xatlas lay one out (lightmap_uvs='XATLAS')")
    if wanted is not None:
        unknown = wanted - {job.name for job in jobs}
        if unknown:
            raise ValueError(f"no object named {sorted(unknown)} in the scene")
    return jobs
