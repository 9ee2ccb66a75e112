"""Baking lightmaps to files: objects, texel density, shards for render farms, EXR and PNG output.

The native pieces (``shgi.rasterize_texels``, ``shgi.unocclude``, ``shgi.bake_lightmap``,
``shgi.filter_lightmap``, ``shgi.dilate_lightmap``) do the work; this module runs them for each
object of a scene and writes the results. The Blender operator ``shgi.bake_lightmaps`` and the
command line ``python -m shgi bake`` both use it.

One object's bake: rasterize its lightmap UV map into a texel map, move samples out of walls
(unocclude), bake the texels (all of them, or one shard's tiles), then *finish*: filter
(optional), dilate into the padding, write ``<name>.exr`` and ``<name>.png``.

Files (rows top first, as EXR and PNG store them; in memory row 0 is v = 0):

``<name>.exr``
    ``Lightmap.R/G/B`` (half): the light per texel, in Cycles' DIFFUSE bake units
    (``LightmapSettings.content``); ``Variance.V`` (float): variance of each texel's luminance,
    a confidence layer; ``Coverage.V`` (float): the fraction of each texel the UV layout covers
    (0 in the padding); with ``directional``: ``SH.c0`` .. ``SH.c3`` ``.R/G/B`` (float), the L1 SH
    of the incident radiance, coefficient index l(l+1)+m (c0 = Y00, c1 = Y1-1 (y), c2 = Y10 (z),
    c3 = Y11 (x)), real orthonormal basis without the Condon-Shortley phase (``shgi.sh``).
``<name>.png``
    an 8-bit sRGB preview of ``Lightmap`` (clamped to [0, 1]).

Shards: ``shard=(i, n)`` bakes every tile whose index, counted over all objects in order, is
i modulo n, and saves the raw texels as ``<out>/shards/<name>.shard-<i>-of-<n>.npz``;
``merge_shards`` reads every shard of every object, merges and finishes them. Texels depend only
on the seed, the object and the texel, so the merged files are byte-identical to a single bake.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
from typing import Callable, Iterable, Optional, Sequence

import numpy as np

from . import _shgi

__all__ = [
    "BakeOptions",
    "BakeJob",
    "Lightmap",
    "BakeProgress",
    "resolution_for_density",
    "bake_object",
    "finish",
    "write_lightmap",
    "bake_scene",
    "merge_shards",
    "shard_path",
]

SH_LAYERS = ("SH.c0", "SH.c1", "SH.c2", "SH.c3")


@dataclasses.dataclass
class BakeOptions:
    """How every object is baked (per-object resolution lives in BakeJob)."""

    settings: _shgi.LightmapSettings = dataclasses.field(default_factory=_shgi.LightmapSettings)
    uv_set: str = "LightmapUV"
    samples_per_axis: int = 2  # sample positions per texel side
    unocclude: bool = True
    filter: bool = False  # the edge-aware filter (shgi.LightmapFilterSettings)
    filter_settings: _shgi.LightmapFilterSettings = dataclasses.field(
        default_factory=_shgi.LightmapFilterSettings
    )
    padding: int = 4  # texels of dilation beyond the UV charts
    png: bool = True
    exposure: float = 0.0  # stops, for the PNG preview only


@dataclasses.dataclass
class BakeJob:
    """One object to bake: its scene instance, file name and lightmap size."""

    instance: int
    name: str
    width: int = 256
    height: int = 256


@dataclasses.dataclass
class Lightmap:
    """A finished lightmap; arrays (H, W, ...) with row 0 at v = 0 (Blender's Image.pixels)."""

    name: str
    color: np.ndarray  # (H, W, 3) float32
    variance: np.ndarray  # (H, W) float32
    coverage: np.ndarray  # (H, W) float32, 0 outside the charts
    filled: np.ndarray  # (H, W) bool: baked or dilated
    sh: Optional[np.ndarray] = None  # (H, W, 4, 3) float32 with directional
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
            self.stage = f"{label}: {stage}"
            if self.callback is not None:
                self.callback(self.fraction, self.stage)

        self._current = _shgi.Progress(report)
        if self._cancelled:  # cancel() ran between the check and the assignment
            self._current.cancel()
        return self._current


def resolution_for_density(scene: _shgi.Scene, instance: int, texels_per_metre: float,
                           minimum: int = 16, maximum: int = 4096) -> int:
    """Square lightmap size giving about `texels_per_metre` on the object's surface.

    The UV layout is assumed to use about half of the square (lightmap packs with margins
    reach 0.5-0.8), so the side is sqrt(2 * area) * density, rounded up to a multiple of 4.
    """
    if not (texels_per_metre > 0.0 and math.isfinite(texels_per_metre)):
        raise ValueError(f"texels_per_metre must be positive, got {texels_per_metre}")
    inst = scene.instances[instance]
    mesh = scene.meshes[inst.mesh_id]
    m = np.asarray(inst.world_from_object, dtype=np.float64)
    p = np.asarray(mesh.positions, dtype=np.float64) @ m[:3, :3].T + m[:3, 3]
    t = np.asarray(mesh.triangles, dtype=np.int64)
    area = 0.5 * np.linalg.norm(np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]),
                                axis=1).sum()
    side = math.sqrt(2.0 * area) * texels_per_metre
    return int(min(maximum, max(minimum, 4 * math.ceil(side / 4.0))))


def _raster_settings(job: BakeJob, options: BakeOptions) -> _shgi.TexelRasterSettings:
    return _shgi.TexelRasterSettings(width=job.width, height=job.height, uv_set=options.uv_set,
                                     samples_per_axis=options.samples_per_axis)


def _texel_map(scene, job: BakeJob, options: BakeOptions, progress) -> _shgi.TexelMap:
    texel_map = _shgi.rasterize_texels(scene, job.instance, _raster_settings(job, options),
                                       progress)
    if texel_map.sample_count == 0:
        raise ValueError(
            f"object '{job.name}': its UV map '{options.uv_set}' covers no texel of the "
            f"{job.width} x {job.height} lightmap (all UVs outside [0, 1] or collapsed); "
            "unwrap it (Smart UV Project or Lightmap Pack) into the unit square")
    if options.unocclude:
        _shgi.unocclude(scene, texel_map, _shgi.UnoccludeSettings(), progress)
    return texel_map


def bake_object(scene, job: BakeJob, options: BakeOptions, field=None, tiles: Sequence[int] = (),
                progress=None):
    """Rasterizes and bakes one object; returns (TexelMap, raw LightmapTexels)."""
    texel_map = _texel_map(scene, job, options, progress)
    texels = _shgi.bake_lightmap(scene, texel_map, options.settings, field, list(tiles), progress)
    return texel_map, texels


def finish(texel_map, texels, options: BakeOptions, name: str, progress=None) -> Lightmap:
    """Filters (optional) and dilates a complete bake into a Lightmap."""
    if options.filter:
        _shgi.filter_lightmap(texel_map, texels, options.filter_settings, progress)
    filled = _shgi.dilate_lightmap(texels, options.padding, progress)
    return Lightmap(name=name, color=texels.color, variance=texels.variance,
                    coverage=texel_map.coverage, filled=filled, sh=texels.sh,
                    report=dict(texel_map.report, charts=texel_map.chart_count))


def write_lightmap(lightmap: Lightmap, out_dir: str, options: BakeOptions) -> list:
    """Writes <name>.exr (and <name>.png); returns the paths."""
    os.makedirs(out_dir, exist_ok=True)
    stem = os.path.join(out_dir, _file_name(lightmap.name))
    flip = lambda a: np.ascontiguousarray(a[::-1])  # noqa: E731  (row 0 = v 0 -> top row first)
    layers = {
        "Lightmap": flip(lightmap.color).astype(np.float16),
        "Variance": flip(lightmap.variance).astype(np.float32),
        "Coverage": flip(lightmap.coverage).astype(np.float32),
    }
    names = {"Variance": "V", "Coverage": "V"}
    if lightmap.sh is not None:
        for c, layer in enumerate(SH_LAYERS):
            layers[layer] = flip(lightmap.sh[:, :, c, :]).astype(np.float32)
    paths = [stem + ".exr"]
    _shgi.write_exr(paths[0], layers, channel_names=names)
    if options.png:
        paths.append(stem + ".png")
        _shgi.write_png(paths[1], flip(lightmap.color), exposure=options.exposure)
    lightmap.paths = paths
    return paths


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


def _check_jobs(scene, jobs: Sequence[BakeJob]) -> None:
    if not jobs:
        raise ValueError("nothing to bake: select at least one mesh object with a lightmap UV map")
    names = [_file_name(job.name) for job in jobs]
    duplicates = {n for n in names if names.count(n) > 1}
    if duplicates:
        raise ValueError(f"objects {sorted(duplicates)} would write the same files; rename them")
    count = len(scene.instances)
    for job in jobs:
        if not 0 <= job.instance < count:
            raise ValueError(f"object '{job.name}': instance {job.instance} is not in the scene "
                             f"({count} instances)")
    if not scene.lights and max(scene.world.color) * scene.world.strength <= 0.0 and not any(
            m.is_emissive() for m in scene.materials):
        raise ValueError("the scene has no light (no lamp, no emissive material, a black world): "
                         "a bake would be black; add a light")


def bake_scene(scene, jobs: Sequence[BakeJob], options: BakeOptions, out_dir: str, field=None,
               shard: Optional[tuple] = None, progress: Optional[BakeProgress] = None,
               on_lightmap: Optional[Callable[[Lightmap], None]] = None) -> list:
    """Bakes every job into out_dir. Without a shard: finishes and writes each lightmap and
    returns the Lightmaps (on_lightmap(lightmap) is called as each one completes, so a
    cancelled bake keeps what finished). With shard=(i, n): writes raw shard files and returns
    their paths."""
    _check_jobs(scene, jobs)
    options.settings.validate()
    progress = progress or BakeProgress()
    count = len(jobs)
    tiles = _shard_tiles(jobs, options, *shard) if shard else [[] for _ in jobs]
    results = []
    for k, job in enumerate(jobs):
        native = progress.native(k / count, (k + 1) / count, job.name)
        if shard and not tiles[k]:
            # Nothing of this object in this shard: an empty shard file keeps merging simple.
            texels = _empty_texels(job, options)
        else:
            texel_map, texels = bake_object(scene, job, options, field, tiles[k], native)
        if shard:
            path = shard_path(out_dir, job.name, *shard)
            _save_shard(path, texels)
            results.append(path)
            continue
        lightmap = finish(texel_map, texels, options, job.name, native)
        write_lightmap(lightmap, out_dir, options)
        results.append(lightmap)
        if on_lightmap is not None:
            on_lightmap(lightmap)
    progress.fraction = 1.0
    return results


def _empty_texels(job: BakeJob, options: BakeOptions) -> _shgi.LightmapTexels:
    h, w = job.height, job.width
    sh = np.zeros((h, w, 4, 3), np.float32) if options.settings.directional else None
    return _shgi.LightmapTexels(np.zeros((h, w, 3), np.float32), np.zeros((h, w), np.float32),
                                np.zeros((h, w), bool), sh)


def _save_shard(path: str, texels) -> None:
    os.makedirs(os.path.dirname(path), exist_ok=True)
    arrays = {"color": texels.color, "variance": texels.variance, "baked": texels.baked}
    if texels.directional:
        arrays["sh"] = texels.sh
    temp = path + ".partial.npz"
    np.savez(temp, **arrays)
    os.replace(temp, path)


def _load_shard(path: str) -> _shgi.LightmapTexels:
    try:
        with np.load(path) as data:
            return _shgi.LightmapTexels(data["color"], data["variance"], data["baked"],
                                        data["sh"] if "sh" in data else None)
    except (OSError, KeyError, ValueError) as error:
        raise OSError(f"shard file {path} is missing or damaged ({error}); bake that shard "
                      "again") from error


def merge_shards(scene, jobs: Sequence[BakeJob], options: BakeOptions, out_dir: str,
                 shards: int, progress: Optional[BakeProgress] = None) -> list:
    """Merges the shard files of `shards` shards in out_dir/shards and writes the lightmaps
    exactly as a single bake would."""
    _check_jobs(scene, jobs)
    progress = progress or BakeProgress()
    results = []
    for k, job in enumerate(jobs):
        native = progress.native(k / len(jobs), (k + 1) / len(jobs), job.name)
        merged = _empty_texels(job, options)
        for i in range(shards):
            _shgi.merge_lightmap(merged, _load_shard(shard_path(out_dir, job.name, i, shards)))
        texel_map = _texel_map(scene, job, options, native)
        missing = int(((texel_map.coverage > 0) & ~merged.baked).sum())
        if missing:
            raise ValueError(f"object '{job.name}': {missing} texels are in no shard file; were "
                             f"all {shards} shards baked with the same settings?")
        lightmap = finish(texel_map, merged, options, job.name, native)
        write_lightmap(lightmap, out_dir, options)
        results.append(lightmap)
    return results


def jobs_for_scene(scene, uv_set: str, resolution: int = 0, texels_per_metre: float = 0.0,
                   names: Optional[Iterable[str]] = None) -> list:
    """A BakeJob for every instance whose mesh has the UV map `uv_set` (or only `names`).

    Size: `resolution` when positive, else from `texels_per_metre`; raises ValueError naming
    objects that lack the UV map when they were asked for by name.
    """
    wanted = set(names) if names is not None else None
    jobs, missing = [], []
    meshes = scene.meshes
    for index, inst in enumerate(scene.instances):
        name = inst.name or f"instance_{index}"
        if wanted is not None and name not in wanted:
            continue
        if uv_set not in meshes[inst.mesh_id].uv_sets:
            if wanted is not None:
                missing.append(f"'{name}' (has {sorted(meshes[inst.mesh_id].uv_sets)})")
            continue
        if resolution > 0:
            size = resolution
        elif texels_per_metre > 0:
            size = resolution_for_density(scene, index, texels_per_metre)
        else:
            size = 256
        jobs.append(BakeJob(instance=index, name=name, width=size, height=size))
    if missing:
        raise ValueError(f"no UV map '{uv_set}' on {', '.join(missing)}: add one or choose "
                         "another UV map")
    if wanted is not None:
        unknown = wanted - {job.name for job in jobs}
        if unknown:
            raise ValueError(f"no object named {sorted(unknown)} in the scene")
    return jobs
