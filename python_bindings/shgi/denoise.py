"""Denoising a baked lightmap: OpenImageDenoise (PyPI ``pyoidn``) or SHGI's own filter.

``denoise_lightmap(texel_map, texels, method)`` takes a bake as ``shgi.bake_lightmap`` returns
it, before dilation (``shgi.dilate_lightmap``), and returns a new ``shgi.LightmapTexels``:

``"SHGI"``
    ``shgi.filter_lightmap``: the edge-aware a-trous filter of native/bake/lightmap_filter.h
    (normal, plane and variance-scaled luminance weights; never mixes two UV charts).
``"OIDN"``
    Intel Open Image Denoise through ``pyoidn``, one UV chart at a time (below). Filters:
    ``"RTLightmap"`` (default) is OIDN's network trained on lightmaps; it takes the HDR colour
    only. ``"RT"`` is the network for rendered frames, run with ``hdr`` and its two guides:
    *albedo* white, because a texel holds E / pi, the light a white Lambert surface reflects
    (``LightmapSettings.content`` other than FULL): the "image" has no texture, so a white
    albedo tells the network that every pattern in it is light (pass the diffuse colour as
    ``albedo`` for FULL bakes, whose texels are multiplied by it); *normal* the texel's world
    normal (``TexelMap.normals``), so that creases inside a chart stay sharp. On the sun room's
    floor RTLightmap measured the higher PSNR (docs/baking.md, "Denoising and lightmap UVs").

UV seams. A lightmap's neighbouring texels may belong to different charts, far apart in the
world and lit differently, and empty texels between charts hold 0. A convolutional denoiser run
over the whole image pulls light across a seam and darkens texels next to empty ones (measured:
a 3-10 % dark line on the bright side of a seam, 56-74 % too much light on the dim side, 14 %
darker borders next to empty texels; tests/python/test_denoise.py). So each chart is denoised on its
own: its bounding box plus ``margin`` texels is cut out; every texel there that is not the
chart's (empty, another chart's, or past the image's edge) gets the value of the chart texel
mirrored through the nearest chart texel (what the mirror misses, the nearest chart texel's;
beyond ``margin`` texels the chart's mean); the crop is denoised and only the chart's own texels
are kept. The network thus sees around each chart a continuation of that chart, with the same
noise, and nothing else. Mirrored rather than dilated context: a smooth (dilated) border looks
noise-free to the network, which then leaves the border texels' noise in place (on the sun
room's floor the border texels' squared error was 3.2 times that with mirrored context).
Dilating the whole lightmap before and after one denoise pass was not chosen: it fills empty
texels but leaves charts that touch in UV space (a tight pack, xatlas with little padding) side
by side, and the network still blends them. Each chart's result depends only on the input
texels, so the order of the charts does not matter.

Directional lightmaps (``texels.sh``, L1 SH, ``shgi.sh`` conventions): the band-0 coefficient
c0 (RGB) is denoised like the colour. For a non-negative radiance |c1m| <= sqrt(3) c0 per
channel (Y1 / Y00 = sqrt(3)), so each band-1 coefficient is scaled per channel to
d = c1m / (sqrt(3) c0) in [-1, 1] and denoised by RTLightmap in its ``directional`` mode
(inputs in [-1, 1]), then scaled back with the denoised c0.

``variance`` is passed through unchanged: it stays the confidence of the raw estimate.
The OIDN CPU device gives identical output for identical input (checked across thread counts),
so both methods are deterministic. ``pyoidn`` is optional: ``import shgi`` works without it;
``method="OIDN"`` then raises ImportError naming the pip command.
"""

from __future__ import annotations

import importlib
import math
import os
import sys
import sysconfig
from typing import Optional

import numpy as np

from . import _shgi

__all__ = ["METHODS", "OIDN_FILTERS", "CHART_MARGIN", "denoise_lightmap", "import_optional",
           "pip_command"]

METHODS = ("OIDN", "SHGI")
OIDN_FILTERS = ("RTLightmap", "RT")
OIDN_QUALITIES = ("high", "balanced", "fast")
# Texels of mirrored context around a chart. OIDN's networks look far beyond a texel, but what
# they see within a few texels of a chart's border decides its border texels: with 8 or 16
# the seam texels of tests/python/test_denoise.py came out as accurate as interior ones (16
# slightly better); farther out the chart's mean is enough.
CHART_MARGIN = 16
# |c1m| <= SH_L1_BOUND * c0 for any non-negative function: Y1 / Y00 = 0.488603 / 0.282095.
SH_L1_BOUND = math.sqrt(3.0)
# Where c0 is below this (W m^-2 sr^-1, no light) the band-1 direction is taken as 0.
_C0_FLOOR = 1e-8


def pip_command(module: str) -> str:
    """The command that installs a PyPI module for this Python (Debian's externally managed
    Python needs --break-system-packages)."""
    managed = os.path.exists(os.path.join(sysconfig.get_path("stdlib"), "EXTERNALLY-MANAGED"))
    flag = " --break-system-packages" if managed else ""
    return f"{sys.executable} -m pip install{flag} {module}"


def cpu_device(pyoidn):
    """A committed OIDN CPU device (RuntimeError with OIDN's message when it cannot be made)."""
    device = pyoidn.Device(pyoidn.OIDN_DEVICE_TYPE_CPU)
    # No thread pinning: it asks TBB for the CPU's core types, which loads TBB's hwloc binding,
    # and inside Debian's Blender 3.4.1 (jemalloc as malloc) hwloc then aborts the process with
    # "free(): invalid size". Pinning only speeds up large hybrid CPUs.
    device.set_bool("setAffinity", False)
    device.commit()
    error = device.get_error()
    if error is not None:
        device.release()
        raise RuntimeError(f"OpenImageDenoise failed creating the CPU device: {error}")
    return device


def import_optional(module: str, feature: str, package: Optional[str] = None):
    """Imports an optional PyPI module or raises ImportError naming the pip command for this
    Python (`make deps` installs the optional modules); `package`: what pip installs, when it is
    not the module's name (dask's 'dask[distributed]' for the module distributed)."""
    try:
        return importlib.import_module(module)
    except ImportError as error:
        raise ImportError(
            f"{feature} needs the Python module '{module}', which is not installed in "
            f"{sys.executable}: install it with `{pip_command(package or module)}` "
            "(or run `make deps`)") from error


def denoise_lightmap(texel_map, texels, method: str = "OIDN", *, oidn_filter: str = "RTLightmap",
                     albedo: Optional[np.ndarray] = None, filter_settings=None,
                     margin: int = CHART_MARGIN, quality: str = "high",
                     progress=None) -> "_shgi.LightmapTexels":
    """A denoised copy of `texels` (a LightmapTexels baked from `texel_map`, not yet dilated).

    method: "OIDN" (per chart, filter `oidn_filter`, "RTLightmap" or "RT"; `albedo` (H, W, 3)
    in [0, 1] guides RT, white when None; `margin` texels of context per chart; `quality`
    "high", "balanced" or "fast") or "SHGI" (shgi.filter_lightmap with `filter_settings`, a
    LightmapFilterSettings, defaults when None). `progress`: a shgi.Progress whose cancel()
    stops between charts (shgi.Cancelled). Texels not baked come back unchanged (0).
    Raises ValueError for sizes that do not match or a bad option, ImportError without pyoidn.
    """
    _check_inputs(texel_map, texels, method)
    copy = _shgi.LightmapTexels(texels.color, texels.variance, texels.baked, texels.sh)
    if method == "SHGI":
        settings = filter_settings if filter_settings is not None else \
            _shgi.LightmapFilterSettings()
        _shgi.filter_lightmap(texel_map, copy, settings, progress)
        return copy
    if oidn_filter not in OIDN_FILTERS:
        raise ValueError(f"oidn_filter {oidn_filter!r}: use one of {', '.join(OIDN_FILTERS)}")
    if quality not in OIDN_QUALITIES:
        raise ValueError(f"quality {quality!r}: use one of {', '.join(OIDN_QUALITIES)}")
    if not (isinstance(margin, int) and margin >= 0):
        raise ValueError(f"margin must be a whole number of texels >= 0, got {margin!r}")
    pyoidn = import_optional("pyoidn", "denoise_lightmap(method='OIDN')")
    layers = _Layers.of(texel_map, copy, albedo)
    with _Oidn(pyoidn, quality) as oidn:
        out = _denoise_charts(layers, texel_map.chart, copy.baked, oidn, oidn_filter, margin,
                              progress)
    color = np.where(copy.baked[..., None], np.maximum(out.color, 0.0), copy.color)
    sh = None
    if out.sh is not None:
        sh = np.where(copy.baked[..., None, None], out.sh, copy.sh)
    return _shgi.LightmapTexels(color.astype(np.float32), copy.variance, copy.baked, sh)


def _check_inputs(texel_map, texels, method: str) -> None:
    if method not in METHODS:
        raise ValueError(f"method {method!r}: use one of {', '.join(METHODS)}")
    if method == "OIDN" and texels.directional and texels.sh_order != 1:
        raise ValueError("method 'OIDN' denoises L1 directional lightmaps only (this one is "
                         f"L{texels.sh_order}); use method 'SHGI', which filters L2 too")
    if (texels.width, texels.height) != (texel_map.width, texel_map.height):
        raise ValueError(f"a {texels.width} x {texels.height} lightmap does not fit its "
                         f"{texel_map.width} x {texel_map.height} texel map")
    bad = int((~np.isfinite(texels.color[texels.baked])).any(axis=-1).sum())
    if bad:
        raise ValueError(f"{bad} baked texels are not finite (NaN or inf); a denoiser would "
                         "spread them: check the scene's lights and materials")


class _Layers:
    """The per-texel images a chart's denoise reads, (H, W, ...) float32: colour, the band-0 SH
    and the scaled band-1 SH (directional only), and the RT filter's guides."""

    def __init__(self, color, albedo, normals, c0=None, directions=None):
        self.color, self.albedo, self.normals = color, albedo, normals
        self.c0, self.directions = c0, directions  # (H, W, 3), (H, W, 3, 3) or None

    @classmethod
    def of(cls, texel_map, texels, albedo):
        h, w = texels.height, texels.width
        if albedo is None:
            albedo = np.ones((h, w, 3), np.float32)
        albedo = np.asarray(albedo, np.float32)
        if albedo.shape != (h, w, 3):
            raise ValueError(f"albedo must be ({h}, {w}, 3), got {albedo.shape}")
        layers = cls(texels.color, np.clip(albedo, 0.0, 1.0), texel_map.normals)
        if texels.directional:
            sh = texels.sh  # (H, W, 4, 3)
            c0 = sh[:, :, 0, :]
            scale = np.where(c0 > _C0_FLOOR, 1.0 / (SH_L1_BOUND * np.maximum(c0, _C0_FLOOR)),
                             0.0)
            layers.c0 = c0
            layers.directions = np.clip(sh[:, :, 1:, :] * scale[:, :, None, :], -1.0, 1.0)
        return layers

    def stacked(self) -> np.ndarray:
        """Every layer as channels of one (H, W, C) array (cropped and filled together)."""
        parts = [self.color, self.albedo, self.normals]
        if self.c0 is not None:
            parts += [self.c0, self.directions.reshape(*self.c0.shape[:2], 9)]
        return np.concatenate(parts, axis=2).astype(np.float32)

    @classmethod
    def unstacked(cls, values: np.ndarray, directional: bool) -> "_Layers":
        layers = cls(values[..., 0:3], values[..., 3:6], values[..., 6:9])
        if directional:
            layers.c0 = values[..., 9:12]
            layers.directions = values[..., 12:21].reshape(*values.shape[:2], 3, 3)
        return layers


class _Denoised:
    """The denoised colour and SH of every chart's texels."""

    def __init__(self, h: int, w: int, directional: bool):
        self.color = np.zeros((h, w, 3), np.float32)
        self.sh = np.zeros((h, w, 4, 3), np.float32) if directional else None


def _denoise_charts(layers: _Layers, chart: np.ndarray, baked: np.ndarray, oidn, oidn_filter,
                    margin: int, progress) -> _Denoised:
    """Denoises each chart in its own crop and keeps only that chart's texels."""
    h, w = chart.shape
    directional = layers.c0 is not None
    out = _Denoised(h, w, directional)
    stacked = layers.stacked()
    valid = baked & (chart >= 0)
    for chart_id, (y0, y1, x0, x1) in _chart_boxes(chart, valid):
        if progress is not None and progress.cancelled:
            raise _shgi.Cancelled("denoising cancelled")
        # Crop rows y0..y1 and columns x0..x1 (exclusive), reaching past the image when the
        # chart touches its border: the margin is then all mirrored context.
        y0, y1, x0, x1 = y0 - margin, y1 + margin, x0 - margin, x1 + margin
        own = _crop(valid, y0, y1, x0, x1) & (_crop(chart, y0, y1, x0, x1) == chart_id)
        values = _fill_outside(_crop(stacked, y0, y1, x0, x1), own, margin)
        crop = _Layers.unstacked(values, directional)
        color = oidn.rgb(crop.color, oidn_filter, crop.albedo, crop.normals)
        region = (slice(max(y0, 0), min(y1, h)), slice(max(x0, 0), min(x1, w)))
        inner = (slice(region[0].start - y0, region[0].stop - y0),
                 slice(region[1].start - x0, region[1].stop - x0))
        keep = own[inner]
        out.color[region][keep] = color[inner][keep]
        if directional:
            sh = _denoise_sh(crop, oidn, oidn_filter)
            out.sh[region][keep] = sh[inner][keep]
    return out


def _chart_boxes(chart: np.ndarray, valid: np.ndarray):
    """[(chart id, (y0, y1, x0, x1))]: each chart's bounding box over the `valid` texels
    (exclusive ends), in order of chart id; one pass over the lightmap for all charts."""
    ys, xs = np.nonzero(valid)
    if len(ys) == 0:
        return []
    ids = chart[ys, xs]
    order = np.argsort(ids, kind="stable")
    ids, ys, xs = ids[order], ys[order], xs[order]
    starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
    boxes = zip(np.minimum.reduceat(ys, starts), np.maximum.reduceat(ys, starts),
                np.minimum.reduceat(xs, starts), np.maximum.reduceat(xs, starts))
    return [(int(ids[s]), (int(y0), int(y1) + 1, int(x0), int(x1) + 1))
            for s, (y0, y1, x0, x1) in zip(starts, boxes)]


def _denoise_sh(crop: _Layers, oidn, oidn_filter) -> np.ndarray:
    """(h, w, 4, 3) denoised L1 SH of a crop: c0 like the colour, band 1 scaled to [-1, 1]
    through RTLightmap's directional mode, scaled back by the denoised c0."""
    c0 = np.maximum(oidn.rgb(crop.c0, oidn_filter, crop.albedo, crop.normals), 0.0)
    sh = np.empty(crop.c0.shape[:2] + (4, 3), np.float32)
    sh[:, :, 0, :] = c0
    for m in range(3):
        direction = np.clip(oidn.directional(crop.directions[:, :, m, :]), -1.0, 1.0)
        sh[:, :, 1 + m, :] = direction * SH_L1_BOUND * c0
    return sh


def _crop(array: np.ndarray, y0: int, y1: int, x0: int, x1: int) -> np.ndarray:
    """array[y0:y1, x0:x1] with zeros (False) where the window reaches past the array."""
    h, w = array.shape[:2]
    out = np.zeros((y1 - y0, x1 - x0) + array.shape[2:], array.dtype)
    ty0, tx0 = max(y0, 0), max(x0, 0)
    ty1, tx1 = min(y1, h), min(x1, w)
    out[ty0 - y0:ty1 - y0, tx0 - x0:tx1 - x0] = array[ty0:ty1, tx0:tx1]
    return out


# The 8 neighbours in the fixed order in which they offer their nearest chart texel (the first
# of equally near offers wins, so the fill does not depend on anything but the input).
_NEIGHBOURS = ((-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (-1, 1), (1, -1), (1, 1))


def _nearest_own(own: np.ndarray, passes: int):
    """For each texel within `passes` rings of `own`: the (y, x) of a nearest `own` texel,
    propagated ring by ring from the 8 neighbours (each texel takes the nearest of the sources
    its neighbours hold). Returns (source_y, source_x, reached)."""
    h, w = own.shape
    yy, xx = np.mgrid[0:h, 0:w]
    source_y, source_x = np.where(own, yy, 0), np.where(own, xx, 0)
    reached = own.copy()
    for _ in range(passes):
        best = np.full((h, w), np.inf)
        next_y, next_x = source_y.copy(), source_x.copy()
        # One texel of border, never reached, so every texel has 8 neighbours to read.
        pr, py, px = (np.pad(a, 1) for a in (reached, source_y, source_x))
        for dy, dx in _NEIGHBOURS:
            window = (slice(1 + dy, 1 + dy + h), slice(1 + dx, 1 + dx + w))
            cy, cx = py[window], px[window]
            distance = (cy - yy) ** 2 + (cx - xx) ** 2
            better = pr[window] & ~reached & (distance < best)
            best = np.where(better, distance, best)
            next_y, next_x = np.where(better, cy, next_y), np.where(better, cx, next_x)
        grown = np.isfinite(best)
        if not grown.any():
            break
        source_y, source_x, reached = next_y, next_x, reached | grown
    return source_y, source_x, reached


def _fill_outside(values: np.ndarray, own: np.ndarray, passes: int) -> np.ndarray:
    """`values` (h, w, C) with every texel outside `own` replaced: within `passes` texels of
    `own` by the chart texel mirrored through the nearest chart texel (the nearest one itself
    when the mirror image is not the chart's), beyond by the mean over `own`.

    Mirroring keeps the chart's noise in the context: a denoiser that sees a smooth (dilated)
    border trusts the border texels' noise and leaves it (on the sun room's floor, dilated
    context made the border texels' squared error 3.2 times that of mirrored context)."""
    h, w = own.shape
    source_y, source_x, reached = _nearest_own(own, passes)
    yy, xx = np.mgrid[0:h, 0:w]
    mirror_y, mirror_x = 2 * source_y - yy, 2 * source_x - xx
    inside = (mirror_y >= 0) & (mirror_y < h) & (mirror_x >= 0) & (mirror_x < w)
    inside &= own[np.clip(mirror_y, 0, h - 1), np.clip(mirror_x, 0, w - 1)]
    from_y = np.where(inside, mirror_y, source_y)
    from_x = np.where(inside, mirror_x, source_x)
    out = values.copy()
    context = reached & ~own
    out[context] = values[from_y[context], from_x[context]]
    out[~reached] = values[own].mean(axis=0)
    return out


class _Oidn:
    """One OIDN CPU device and its filters for one denoise_lightmap call (released on exit)."""

    def __init__(self, pyoidn, quality: str):
        self.pyoidn = pyoidn
        self.quality = {"high": pyoidn.OIDN_QUALITY_HIGH,
                        "balanced": pyoidn.OIDN_QUALITY_BALANCED,
                        "fast": pyoidn.OIDN_QUALITY_FAST}[quality]
        self.device = None
        self.filters = {}

    def __enter__(self) -> "_Oidn":
        self.device = cpu_device(self.pyoidn)
        return self

    def __exit__(self, *exc) -> None:
        for flt in self.filters.values():
            flt.release()
        self.filters.clear()
        self.device.release()

    def _check(self, operation: str) -> None:
        error = self.device.get_error()
        if error is not None:
            raise RuntimeError(f"OpenImageDenoise failed {operation}: {error}")

    def _filter(self, kind: str, directional: bool):
        key = (kind, directional)
        if key not in self.filters:
            flt = self.pyoidn.Filter(self.device, kind)
            self._check(f"creating the {kind} filter")
            if kind == "RT":
                flt.set_bool("hdr", True)
            else:
                flt.set_bool("directional", directional)
            flt.set_quality(self.quality)
            self.filters[key] = flt
        return self.filters[key]

    def _run(self, flt, images: dict, label: str) -> np.ndarray:
        color = images["color"]
        output = np.zeros_like(color)
        for name, image in list(images.items()) + [("output", output)]:
            flt.set_image(name, image, self.pyoidn.OIDN_FORMAT_FLOAT3)
        flt.commit()
        self._check(f"setting up {label}")
        flt.execute()
        self._check(f"denoising {label}")
        return output

    def rgb(self, color, kind: str, albedo, normals) -> np.ndarray:
        """Denoised HDR RGB (h, w, 3): RTLightmap on the colour alone, RT with the guides."""
        images = {"color": np.ascontiguousarray(color, np.float32)}
        if kind == "RT":
            images["albedo"] = np.ascontiguousarray(albedo, np.float32)
            images["normal"] = np.ascontiguousarray(normals, np.float32)
        return self._run(self._filter(kind, False), images, f"a chart ({kind})")

    def directional(self, values) -> np.ndarray:
        """Denoised (h, w, 3) values in [-1, 1] (RTLightmap, directional mode)."""
        images = {"color": np.ascontiguousarray(values, np.float32)}
        return self._run(self._filter("RTLightmap", True), images, "a chart's SH directions")
