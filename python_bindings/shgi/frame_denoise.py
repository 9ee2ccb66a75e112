"""Denoising rendered frames (F12, the viewport, ``render_preview``) with OpenImageDenoise.

``FrameDenoiser(quality, prefilter, guides).denoise(passes)`` takes the passes a renderer
returns ({name: float32 (H, W, C)}, row 0 on top: ``PathTracer.passes()``,
``PreviewRenderer.passes()``) and returns Combined denoised by OIDN's ``RT`` network in HDR mode,
with the passes Cycles writes beside it: ``Noisy Image`` (Combined before denoising),
``Denoising Albedo`` and ``Denoising Normal`` (the guides as the network saw them).

Guides, as Cycles builds them: the renderers' ``Denoising Albedo`` and ``Denoising Normal``
passes (render/film.h), written at the first surface that is not (nearly) perfectly specular,
so that through clear glass and in mirrors and polished metal they show the surface seen through
or in them, its albedo times their tint (Cycles' film_write_denoising_features_surface); the
albedo is clipped to [0, 1], the normal is world space. Passes without them (a renderer of an
older SHGI, or a hand-made dict) fall back to the first hit's: DiffCol + GlossCol + TransCol and
Normal. Both are sample means, so at low sample counts they carry noise of
their own (antialiased edges, textures, glossy lobes): ``prefilter`` says what is done about it,
with Cycles' choices: "ACCURATE" denoises each guide first with the RT network and then tells
the colour filter they are clean (``cleanAux``); "FAST" passes them as they are and lets the
colour filter allow for their noise; "NONE" passes them as they are and calls them clean (for
noise-free guides); and one of SHGI's, "AUTO": "FAST" below CLEAN_GUIDE_SAMPLES samples a pixel,
"NONE" from there on (``denoise``'s ``samples``), and from SPECULAR_CLEAN_GUIDE_SAMPLES when more
than SPECULAR_GUIDE_SHARE of the frame sees its guides through or in specular surfaces
(``specular_guide_share``). OIDN has its High-quality network only for clean
guides: with "FAST" the quality High runs the Balanced network (the same output, measured), so
once the guides are clean enough to call clean, "NONE" is worth 0.6-0.9 dB over "FAST" for about
twice its time, and "ACCURATE" gives what "NONE" gives at three times the cost
(docs/equal-time.md, "The denoiser's prefilter"). ``guides`` chooses the inputs as Cycles'
"Passes" does: "NONE" (colour only), "ALBEDO", "ALBEDO_NORMAL".

A share of the light the camera sees straight from emitters and the world (the Emit and Env
passes, when given) is taken out of Combined before the network and added back after it
(``direct_share``): a network shown a lamp 60 times brighter than the walls spreads it into a
halo (on the Cornell box at 1 spp, unsplit, it added 3-4% to the frame's light), but what goes
around the network keeps its noise, and the emitter's edge is noisy (each sample there sees the
lamp or not). How much goes around follows the pixel filter (``pixel_filter``,
``filter_width``: the film's) and the samples: with a filter that keeps each sample in its own
pixel (the box of width 1) the edge's noise falls as the samples add up, so N / (N + 1/4) of it
goes around at N samples a pixel; with a filter that spreads a sample over its neighbours
(Cycles' Blackman-Harris 1.5) the emitter's image has a soft fringe, some pixels wide, that few
samples reach and the network rebuilds better than they do, so only 4 / (N + 4) goes around,
enough to keep the frame's mean within 1% at few samples (docs/equal-time.md, "The direct
light's split"). Pixels that see only the world (Depth is the miss value everywhere in the
pixel) keep their noisy value, so the geometry's light never bleeds into the background.

The network's weights are loaded once per filter; keep one FrameDenoiser for a sequence of
frames (the viewport does). ``prepare(width, height)`` sets up every network a denoise of that
size may run before the first frame arrives (a render with a Time Limit does, before it
samples). ``denoise`` polls ``progress`` (a ``shgi.Progress``) from OIDN's progress monitor and
raises ``shgi.Cancelled`` within one slice of the network (~1/27 of its
work, 60 ms on a 1920 x 1080 frame on 2 cores); called from Python's main thread it runs the
network on a helper thread so that Ctrl-C raises KeyboardInterrupt within 0.05 s. ``pyoidn``
is optional: ``import shgi`` works without it, and ``FrameDenoiser`` then raises ImportError
naming the pip command (``available()`` asks first). OIDN's CPU device gives identical output
for identical input, so a denoised frame is as deterministic as the noisy one.
"""

from __future__ import annotations

import os
import threading
import time
import numpy as np

from . import _shgi
from .denoise import cpu_device, import_optional

__all__ = ["QUALITIES", "PREFILTERS", "CLEAN_GUIDE_SAMPLES", "GUIDES", "NOISY_PASS",
           "ALBEDO_PASS", "NORMAL_PASS", "PIXEL_FILTERS", "FrameDenoiser", "available",
           "denoise_frame", "direct_share", "guide_images", "prefilter_for",
           "specular_guide_share"]

QUALITIES = ("HIGH", "BALANCED", "FAST")
PREFILTERS = ("NONE", "FAST", "ACCURATE", "AUTO")
# From this many samples a pixel "AUTO" calls the guides clean ("NONE"), below it lets the network
# allow for their noise ("FAST"). Measured at 200 x 150 (docs/equal-time.md): on a Cornell box with
# a 256 x 256 colour grid on two walls "NONE" lost 1.4 dB to "FAST" at 1 sample and 0.3 dB at 2,
# gained 0.2 dB at 4 and 0.75 dB at 8 (where it matched "ACCURATE"); in the sun room it gained
# 0.4-0.9 dB from 4 samples on. Guides seen through glass stay noisy longer: in the caustics scene
# "NONE" was 0.8-0.9 dB below "FAST" at 8 samples, 0.3-0.4 dB above at 32, 0.6-0.7 at 128.
CLEAN_GUIDE_SAMPLES = 8
# Guides seen through clear glass or in a mirror (the film follows specular bounces for them)
# change with each sample's jitter wherever the glass is curved, so they need more samples: in the
# caustics scene (17% of its covered pixels) "NONE" was 0.79 dB below "FAST" at 8 spp, 0.13 at 16
# and 0.42 above at 32. "AUTO" runs "NONE" from SPECULAR_CLEAN_GUIDE_SAMPLES where more than
# SPECULAR_GUIDE_SHARE of the covered pixels see theirs so (docs/equal-time.md); the other bench
# scenes have none.
SPECULAR_CLEAN_GUIDE_SAMPLES = 32
SPECULAR_GUIDE_SHARE = 0.05
# How far a guide may differ from the first hit's (albedo, normal component) and still count as
# the first hit's: the passes agree to 1e-5 where the first surface is not specular.
SPECULAR_GUIDE_DIFFERENCE = 0.05
GUIDES = ("NONE", "ALBEDO", "ALBEDO_NORMAL")
# The passes Cycles writes beside a denoised Combined. The renderers write the guides under the
# same names (render/film.h: they follow specular bounces as Cycles' do); a denoise replaces them
# by the guides as the network saw them.
NOISY_PASS = "Noisy Image"
ALBEDO_PASS = "Denoising Albedo"
NORMAL_PASS = "Denoising Normal"
# The passes a renderer must return for each choice of guides.
GUIDE_PASSES = {"NONE": ("Combined",),
                "ALBEDO": ("Combined", ALBEDO_PASS, "Depth"),
                "ALBEDO_NORMAL": ("Combined", ALBEDO_PASS, NORMAL_PASS, "Depth")}
# What stands in for a guide pass that is missing: the first hit's passes.
FIRST_HIT_GUIDES = {ALBEDO_PASS: ("DiffCol", "GlossCol", "TransCol"),
                    NORMAL_PASS: ("Normal",)}
# What a renderer should return for the best result: the guides and the direct light.
WANTED_PASSES = {guides: names + ("Emit", "Env") for guides, names in GUIDE_PASSES.items()}
# The light the camera sees straight from emitters and the world: a share of it (direct_share)
# goes around the network.
DIRECT_PASSES = ("Emit", "Env")
# The films' pixel filters (render/pixel_filter.h, shgi.PixelFilter) and how far from its pixel's
# centre each puts a sample, as a multiple of its width (Box of width w spans [-w/2, w/2],
# Gaussian is cut at +-1.5 w, Blackman-Harris spans [-w, w]).
PIXEL_FILTERS = {"BOX": 0.5, "GAUSSIAN": 1.5, "BLACKMAN_HARRIS": 1.0}
# Filter Size's range (render/pixel_filter.h kMinFilterWidth, kMaxFilterWidth).
FILTER_WIDTH_RANGE = (0.01, 10.0)
# The share of the direct light that goes around the network at N samples a pixel: N / (N +
# DIRECT_SPLIT_SAMPLES) with a filter that keeps a sample in its pixel, SPREAD_SPLIT_SAMPLES /
# (N + SPREAD_SPLIT_SAMPLES) with one that spreads it. The network's halo is what bounds both
# from below at few samples: on the 128 x 128 Cornell box of tests/python/test_frame_denoise.py
# at 1 spp a share w left the denoised frame (1 - w) x 2.3-3.1% brighter than the noisy one (at
# 4 spp 1.0-1.5%, at 16 spp 0.1-0.5%), and the issue allows 1% (docs/equal-time.md, "The direct
# light's split").
DIRECT_SPLIT_SAMPLES = 0.25
SPREAD_SPLIT_SAMPLES = 4.0
# Depth of a pixel where every sample missed (the films' kMissDepth, as Cycles writes it).
MISS_DEPTH = 1e10
# Seconds per pixel of a denoise, {(prefilter, quality): s} ("AUTO" as the one it becomes),
# measured on a 256 x 256 Cornell box on this project's 2-core machine (ALBEDO_NORMAL guides),
# for a render that must fit a Time Limit before anything was denoised in this process; then
# each denoise records its own size and time (MEASURED).
ESTIMATED_RATES = {
    ("NONE", "HIGH"): 3.0e-6, ("NONE", "BALANCED"): 1.3e-6, ("NONE", "FAST"): 0.7e-6,
    ("FAST", "HIGH"): 1.3e-6, ("FAST", "BALANCED"): 1.3e-6, ("FAST", "FAST"): 0.7e-6,
    ("ACCURATE", "HIGH"): 9.1e-6, ("ACCURATE", "BALANCED"): 4.5e-6, ("ACCURATE", "FAST"): 6.3e-6,
}
# Setting the networks up, once per FrameDenoiser.
SETUP_SECONDS = 0.1
# {(quality, prefilter, guides): (pixels, seconds) of the last denoise in this process}, under the
# prefilter that ran ("AUTO" becomes "FAST" or "NONE").
MEASURED = {}
# The largest side of a frame prepare() sets a network up for (Blender's resolution limit).
MAX_SIDE = 65536
# How often a Ctrl-C in the main thread is noticed while the network runs.
_SIGNAL_POLL_SECONDS = 0.05


def available() -> bool:
    """True when the module pyoidn can be imported (a FrameDenoiser can be made)."""
    try:
        import_optional("pyoidn", "denoising frames")
    except ImportError:
        return False
    return True


def prefilter_for(prefilter: str, samples=None, specular_share: float = 0.0) -> str:
    """The prefilter that runs for a frame of `samples` samples a pixel, `specular_share` of
    whose covered pixels see their guides through or in specular surfaces: `prefilter` itself,
    but "AUTO" becomes "FAST" below CLEAN_GUIDE_SAMPLES (SPECULAR_CLEAN_GUIDE_SAMPLES when
    `specular_share` exceeds SPECULAR_GUIDE_SHARE; always when `samples` is None) and "NONE" from
    there on."""
    _check_choice("prefilter", prefilter, PREFILTERS)
    if prefilter != "AUTO":
        return prefilter
    clean = (SPECULAR_CLEAN_GUIDE_SAMPLES if specular_share > SPECULAR_GUIDE_SHARE
             else CLEAN_GUIDE_SAMPLES)
    return "NONE" if samples is not None and samples >= clean else "FAST"


def specular_guide_share(passes: dict) -> float:
    """The share of the pixels that see a surface whose guides (ALBEDO_PASS, NORMAL_PASS) are not
    the first hit's (FIRST_HIT_GUIDES), i.e. were followed through or into specular surfaces; 0
    when the passes lack either (the viewport's, which hold only what the denoiser needs)."""
    needed = (ALBEDO_PASS, NORMAL_PASS, "Depth", *FIRST_HIT_GUIDES[ALBEDO_PASS],
              *FIRST_HIT_GUIDES[NORMAL_PASS])
    if any(name not in passes for name in needed):
        return 0.0
    albedo, normal, background = guide_images(passes, "ALBEDO_NORMAL")
    first_albedo = np.clip(sum(_finite(passes[name][..., :3])
                               for name in FIRST_HIT_GUIDES[ALBEDO_PASS]), 0.0, 1.0)
    (first_normal,) = (_finite(passes[name][..., :3]) for name in FIRST_HIT_GUIDES[NORMAL_PASS])
    followed = ((np.abs(_finite(albedo) - first_albedo).max(axis=-1) > SPECULAR_GUIDE_DIFFERENCE)
                | (np.abs(_finite(normal) - first_normal).max(axis=-1)
                   > SPECULAR_GUIDE_DIFFERENCE))
    covered = ~background
    return float(followed[covered].mean()) if covered.any() else 0.0


def direct_share(samples=None, pixel_filter: str = "BOX", filter_width: float = 1.0) -> float:
    """The share of the direct light (Emit + Env) that goes around the network for a frame of
    `samples` samples a pixel (None: taken as 1, the fewest) filtered by `pixel_filter` of width
    `filter_width`: N / (N + DIRECT_SPLIT_SAMPLES) when the filter keeps each sample in its own
    pixel, SPREAD_SPLIT_SAMPLES / (N + SPREAD_SPLIT_SAMPLES) when it spreads samples over their
    neighbours."""
    _check_filter(pixel_filter, filter_width)
    if samples is not None and (not isinstance(samples, (int, np.integer)) or samples < 1):
        raise ValueError(f"samples {samples!r}: give the frame's samples a pixel (1 or more), "
                         "or None when unknown")
    count = 1.0 if samples is None else float(samples)
    if PIXEL_FILTERS[pixel_filter] * filter_width <= 0.5:
        return count / (count + DIRECT_SPLIT_SAMPLES)
    return SPREAD_SPLIT_SAMPLES / (count + SPREAD_SPLIT_SAMPLES)


def guide_images(passes: dict, guides: str = "ALBEDO_NORMAL"):
    """(albedo, normal, background) from a renderer's passes: float32 (H, W, 3) guides (None when
    not used) and the bool (H, W) mask of pixels that saw only the world."""
    _check_choice("guides", guides, GUIDES)
    # {guide pass: the passes it is read from}: itself, else the first hit's passes.
    sources = {name: (name,) if name in passes or name not in FIRST_HIT_GUIDES
               else FIRST_HIT_GUIDES[name] for name in GUIDE_PASSES[guides]}
    missing = [name for name, source in sources.items()
               if any(part not in passes for part in source)]
    if missing:
        wanted = ", ".join(f"{name} (or {' + '.join(FIRST_HIT_GUIDES[name])})"
                           if name in FIRST_HIT_GUIDES else name for name in missing)
        raise ValueError(f"passes: {wanted} missing; denoising with guides {guides!r} needs "
                         f"{', '.join(GUIDE_PASSES[guides])} (render every pass, not "
                         "PreviewSettings.combined_only)")
    combined = np.asarray(passes["Combined"], np.float32)
    height, width = combined.shape[:2]
    albedo = normal = None
    if guides != "NONE":
        albedo = np.clip(sum(np.asarray(passes[name], np.float32)[..., :3]
                             for name in sources[ALBEDO_PASS]), 0.0, 1.0)
    if guides == "ALBEDO_NORMAL":
        (name,) = sources[NORMAL_PASS]
        normal = np.ascontiguousarray(np.asarray(passes[name], np.float32)[..., :3])
    if "Depth" in passes:
        depth = np.asarray(passes["Depth"], np.float32).reshape(height, width, -1)[..., 0]
        background = depth >= MISS_DEPTH
    else:
        background = np.zeros((height, width), bool)
    return albedo, normal, background


class FrameDenoiser:
    """One OIDN CPU device and its RT filters, kept for a sequence of frames (close() or `with`
    releases them). Not thread-safe: one thread denoises at a time."""

    def __init__(self, quality: str = "HIGH", prefilter: str = "ACCURATE",
                 guides: str = "ALBEDO_NORMAL", pixel_filter: str = "BOX",
                 filter_width: float = 1.0):
        _check_choice("quality", quality, QUALITIES)
        _check_choice("prefilter", prefilter, PREFILTERS)
        _check_choice("guides", guides, GUIDES)
        _check_filter(pixel_filter, filter_width)
        self.quality, self.prefilter, self.guides = quality, prefilter, guides
        # The film's pixel filter, which direct_share follows.
        self.pixel_filter, self.filter_width = pixel_filter, float(filter_width)
        self._pyoidn = import_optional("pyoidn", "denoising frames")
        self._device = cpu_device(self._pyoidn)
        self._filters = {}
        self._buffers = {}  # {id(filter): ((shape, slots), {slot: its shared buffer})}
        self._prepared = set()  # {(prefilter, pixels)} whose networks prepare() set up
        self._monitor = _ProgressMonitor(self._pyoidn)

    def __enter__(self) -> "FrameDenoiser":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        for flt in self._filters.values():
            flt.release()
        self._filters.clear()
        self._buffers.clear()
        if self._device is not None:
            self._device.release()
            self._device = None

    def prepare(self, width: int, height: int) -> None:
        """Sets up every network this denoiser may run on a width x height frame (with "AUTO"
        both the Fast and the None one), so that a denoise of that size starts at once: a render
        with a Time Limit calls this before it samples, as the setup of a network not run yet in
        this process is the part of a denoise hardest to foresee."""
        shape = (_check_size("height", height), _check_size("width", width), 3)
        for prefilter in self._candidates():
            if prefilter == "ACCURATE":
                for name in self._color_slots()[1:]:
                    self._setup(self._filter(name, False), shape, (name,))
            self._setup(self._filter("color", prefilter != "FAST"), shape, self._color_slots())
            self._prepared.add((prefilter, width * height))

    def estimate_seconds(self, width: int, height: int) -> float:
        """Seconds a denoise of a width x height frame is expected to take: the last denoise of
        these choices in this process scaled up to this size (never down: its time holds fixed
        costs), else _first_estimate. With "AUTO", whose prefilter follows the samples a render
        has not reached yet, the longer of the two it can become."""
        return max(self._estimate(prefilter, width * height) for prefilter in self._candidates())

    def _candidates(self):
        """The prefilters a denoise with this denoiser's choice can run."""
        return ("FAST", "NONE") if self.prefilter == "AUTO" else (self.prefilter,)

    def _estimate(self, prefilter: str, pixels: int) -> float:
        last = MEASURED.get((self.quality, prefilter, self.guides))
        if last is None:
            setup = 0.0 if (prefilter, pixels) in self._prepared else SETUP_SECONDS
            return _first_estimate(prefilter, self.quality, pixels, setup)
        last_pixels, seconds = last
        return seconds * max(1.0, pixels / max(1, last_pixels))

    def denoise(self, passes: dict, progress=None, samples=None, seconds=None) -> dict:
        """{"Combined": denoised (H, W, 4), NOISY_PASS: the input Combined, ALBEDO_PASS,
        NORMAL_PASS: the guides used (when used)}; `progress`: a shgi.Progress whose cancel()
        makes this raise shgi.Cancelled; `samples`: the frame's samples a pixel, which the
        prefilter "AUTO" goes by (None: taken as too few to call the guides clean); `seconds`:
        the time left for the denoise (None: no limit), in which "AUTO" runs None only where its
        estimate fits, else Fast (half its time)."""
        if self._device is None:
            raise ValueError("FrameDenoiser: closed")
        noisy = np.asarray(passes["Combined"], np.float32)
        if noisy.ndim != 3 or noisy.shape[2] not in (3, 4):
            raise ValueError(f"passes['Combined']: shape {noisy.shape} is not (H, W, 3 or 4)")
        start = time.perf_counter()
        prefilter = prefilter_for(self.prefilter, samples, specular_guide_share(passes)
                                  if self.prefilter == "AUTO" else 0.0)
        if (self.prefilter == "AUTO" and prefilter == "NONE" and seconds is not None
                and self._estimate("NONE", noisy.shape[0] * noisy.shape[1]) > seconds):
            prefilter = "FAST"
        share = direct_share(samples, self.pixel_filter, self.filter_width)
        albedo, normal, background = guide_images(passes, self.guides)
        color = _finite(noisy[..., :3])
        # A share of the emitters and the world seen directly (Emit, Env) goes around the
        # network: a network given a 60x brighter lamp spreads it over its neighbours, but what
        # goes around keeps the noise of the emitter's edge (direct_share).
        direct = np.float32(share) * sum(_finite(passes[name][..., :3])
                                         for name in DIRECT_PASSES if name in passes)
        images = {"color": np.ascontiguousarray(np.maximum(color - direct, 0.0))}
        if albedo is not None:
            images["albedo"] = self._guide("albedo", albedo, prefilter, progress)
        if normal is not None:
            images["normal"] = self._guide("normal", normal, prefilter, progress)
        clean = prefilter != "FAST"
        rgb = self._execute(self._filter("color", clean), images, progress, "the frame")
        rgb += direct
        rgb[background] = color[background]
        out = noisy.copy()
        out[..., :3] = rgb
        MEASURED[(self.quality, prefilter, self.guides)] = (
            noisy.shape[0] * noisy.shape[1], time.perf_counter() - start)
        result = {"Combined": out, NOISY_PASS: noisy}
        if albedo is not None:
            result[ALBEDO_PASS] = images["albedo"]
        if normal is not None:
            result[NORMAL_PASS] = images["normal"]
        return result

    # --- OIDN ------------------------------------------------------------------------------------

    def _guide(self, name: str, image: np.ndarray, prefilter: str, progress) -> np.ndarray:
        image = np.ascontiguousarray(image, np.float32)
        if prefilter != "ACCURATE":
            return image
        return self._execute(self._filter(name, False), {name: image}, progress,
                             f"the {name} guide")

    def _filter(self, role: str, clean_aux: bool):
        """The RT filter for the colour (role "color") or for prefiltering one guide."""
        key = (role, clean_aux)
        if key not in self._filters:
            flt = self._pyoidn.Filter(self._device, "RT")
            self._check("creating the RT filter")
            if role == "color":
                flt.set_bool("hdr", True)
                flt.set_bool("cleanAux", clean_aux)
            flt.set_quality({"HIGH": self._pyoidn.OIDN_QUALITY_HIGH,
                             "BALANCED": self._pyoidn.OIDN_QUALITY_BALANCED,
                             "FAST": self._pyoidn.OIDN_QUALITY_FAST}[self.quality])
            self._monitor.attach(flt)
            self._filters[key] = flt
        return self._filters[key]

    def _color_slots(self):
        """The colour filter's inputs for this denoiser's guides."""
        return ("color", *{"NONE": (), "ALBEDO": ("albedo",),
                           "ALBEDO_NORMAL": ("albedo", "normal")}[self.guides])

    def _setup(self, flt, shape, slots):
        """The shared input and output buffers of filter `flt` for (H, W, 3) images in `slots`,
        committing the filter when its size or slots change (a commit sets the network up again:
        0.1 s per filter, more than the denoise of a small frame)."""
        buffers = self._buffers.get(id(flt))
        if buffers is not None and buffers[0] == (shape, tuple(slots)):
            return buffers[1]
        for name in ("color", "albedo", "normal"):
            flt.unset_image(name)
        owned = {name: np.zeros(shape, np.float32) for name in (*slots, "output")}
        for name, image in owned.items():
            flt.set_image(name, image, self._pyoidn.OIDN_FORMAT_FLOAT3)
        self._buffers[id(flt)] = ((shape, tuple(slots)), owned)
        flt.commit()
        self._check(f"setting up the {'/'.join(slots)} filter")
        return owned

    def _execute(self, flt, images: dict, progress, label: str) -> np.ndarray:
        """Runs filter `flt` over `images` ({slot: (H, W, 3) float32}); returns a new output.
        While the frame size and slots stay, the inputs are copied into the filter's buffers
        and it runs without a new commit."""
        shape = next(iter(images.values())).shape
        owned = self._setup(flt, shape, tuple(images))
        for name, image in images.items():
            np.copyto(owned[name], image)
        self._monitor.run(flt.execute, progress)
        error = self._device.get_error()
        if self._monitor.cancelled:
            raise _shgi.Cancelled(f"denoising {label} was cancelled")
        if error is not None:
            raise RuntimeError(f"OpenImageDenoise failed denoising {label}: {error}")
        return owned["output"].copy()

    def _check(self, operation: str) -> None:
        error = self._device.get_error()
        if error is not None:
            raise RuntimeError(f"OpenImageDenoise failed {operation}: {error}")


def _first_estimate(prefilter: str, quality: str, pixels: int,
                    setup: float = SETUP_SECONDS) -> float:
    """Seconds of a denoise of choices not yet run in this process: ESTIMATED_RATES and `setup`
    (the networks' setup: none once prepared), or, when longer, the last denoise of other
    choices scaled by the two choices' rates and the sizes (a machine busy with other work is
    slower for every choice: after a Fast denoise on a loaded machine the table alone planned
    Automatic's first None 0.08 s short on a 128 x 128 frame)."""
    rate = ESTIMATED_RATES[(prefilter, quality)]
    estimates = [pixels * rate + setup]
    for (other_quality, other_prefilter, _), (other_pixels, seconds) in MEASURED.items():
        estimates.append(seconds * rate / ESTIMATED_RATES[(other_prefilter, other_quality)]
                         * max(1.0, pixels / max(1, other_pixels)))
    return max(estimates)


def denoise_frame(passes: dict, quality: str = "HIGH", prefilter: str = "ACCURATE",
                  guides: str = "ALBEDO_NORMAL", progress=None, samples=None,
                  pixel_filter: str = "BOX", filter_width: float = 1.0) -> dict:
    """One frame's FrameDenoiser.denoise with a denoiser made for it."""
    with FrameDenoiser(quality, prefilter, guides, pixel_filter, filter_width) as denoiser:
        return denoiser.denoise(passes, progress, samples)


class _ProgressMonitor:
    """OIDN's progress monitor (oidnSetFilterProgressMonitorFunction, which pyoidn does not
    wrap): returns False, OIDN's cancel, once the current Progress is cancelled or a Ctrl-C
    arrived."""

    def __init__(self, pyoidn):
        import cffi

        from pyoidn.capi import oidn_ffi

        self._ffi = cffi.FFI()
        self._ffi.cdef("typedef _Bool (*ShgiMonitor)(void*, double);"
                       "void oidnSetFilterProgressMonitorFunction(void*, ShgiMonitor, void*);")
        library = os.path.join(os.path.dirname(pyoidn.__file__), "oidn", "lib",
                               "libOpenImageDenoise.so")
        self._lib = self._ffi.dlopen(library)
        self._pyoidn_ffi = oidn_ffi
        self._callback = self._ffi.callback("_Bool(void*, double)", self._keep_going)
        self._progress = None
        self._stop = threading.Event()

    @property
    def cancelled(self) -> bool:
        return self._stop.is_set()

    def attach(self, flt) -> None:
        pointer = int(self._pyoidn_ffi.cast("uintptr_t", flt._filter))
        self._lib.oidnSetFilterProgressMonitorFunction(self._ffi.cast("void*", pointer),
                                                       self._callback, self._ffi.NULL)

    def _keep_going(self, _user, _fraction) -> bool:
        if self._progress is not None and self._progress.cancelled:
            self._stop.set()
        return not self._stop.is_set()

    def run(self, execute, progress) -> None:
        """execute() with `progress` watched; in the main thread on a helper thread, so that a
        Ctrl-C (KeyboardInterrupt) stops the network and propagates."""
        self._progress = progress
        self._stop.clear()
        try:
            if threading.current_thread() is not threading.main_thread():
                execute()
                return
            worker = threading.Thread(target=execute, name="shgi-oidn", daemon=True)
            worker.start()
            try:
                while worker.is_alive():
                    worker.join(_SIGNAL_POLL_SECONDS)
            except KeyboardInterrupt:
                self._stop.set()
                worker.join()
                raise
        finally:
            self._progress = None


def _finite(image) -> np.ndarray:
    """float32 `image` with NaN and infinities as 0 (the network turns one into a blotch)."""
    return np.nan_to_num(np.asarray(image, np.float32), nan=0.0, posinf=0.0, neginf=0.0)


def _check_size(name: str, value) -> int:
    if not isinstance(value, (int, np.integer)) or not 0 < value <= MAX_SIDE:
        raise ValueError(f"{name} {value!r}: give a whole number of pixels in 1..{MAX_SIDE}")
    return int(value)


def _check_filter(pixel_filter: str, filter_width) -> None:
    _check_choice("pixel_filter", pixel_filter, PIXEL_FILTERS)
    low, high = FILTER_WIDTH_RANGE
    if (isinstance(filter_width, bool) or not isinstance(filter_width, (int, float, np.number))
            or not low <= filter_width <= high):
        raise ValueError(f"filter_width {filter_width!r}: give the pixel filter's width in "
                         f"pixels, {low:g} to {high:g}")


def _check_choice(name: str, value: str, choices) -> None:
    if value not in choices:
        raise ValueError(f"{name} {value!r}: use one of {', '.join(choices)}")

