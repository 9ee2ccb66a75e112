"""Equal-time quality: at the same F12 wall time, is SHGI's preview as good as Cycles + OIDN?
Prints one table per scene. A benchmark, not a test: nothing is asserted.

    /opt/shgi/bpy-5.0.1/bin/python bench/equal_time.py [--scenes cornell_box,...]
        [--methods PATH_TRACE,...] [--limits 0.25,0.5,...] [--resolution 200x150]
        [--cache build/equal_time_cache] [--first-hit-guides] [--quick]

(the `bpy` venv: Blender 5.0.1 as a Python module; ``blender -b --python bench/equal_time.py --
<options>`` runs it too.)

Scenes (examples/blender_scenes.py, built with bpy): cornell_box, sun_room, two_rooms (the probe
grid's leak test: a thin wall between a bright and a dim room), caustics (glass and gold spheres
in the Cornell box) and dense (the Cornell box holding a UV sphere of DENSE_SEGMENTS x
DENSE_RINGS, ~523k triangles, as bench/viewport_sync_bench.py). Every scene renders at the same
resolution and with the same Light Paths limits in both renderers (BOUNCES).

Each side is scored against its own reference, since the two renderers' Principled BSDFs differ:
- Cycles (CPU) with OpenImageDenoise at CYCLES_SAMPLES spp (doubled on while a render takes
  less than the largest budget: stepped_samples), against Cycles at REFERENCE_SAMPLES
  spp without denoising;
- SHGI, each render method of shgi_blender.settings.METHODS, against SHGI's PATH_TRACE at
  REFERENCE_SAMPLES spp without denoising. With the add-on's ``scene.shgi.time_limit`` (and
  ``use_denoising``, which is then on) a render is made per time limit; without them the limit
  is emulated by stepping ``scene.shgi.samples`` as Cycles' samples and timing each render.
Scores are shgi.metrics.psnr: both images scaled by the reference's auto-exposure, sRGB-encoded
and clipped to [0, 1]. References are cached as .npy under --cache (keyed by scene, resolution,
renderer and samples): they take minutes.

A render is read back as the engine tests read theirs (tests/blender/engine_common.py): the
Render Result saved as a multilayer EXR through tests/blender/blender_test_setup.py, outside the
timing (background Blender gives Python no pixels of the Render Result otherwise).

Timing: time.perf_counter around ``bpy.ops.render.render(write_still=False)``, the whole F12
(Blender's scene sync, the renderer's export, BVH, solve and samples, denoising). Each renderer
renders the scene once untimed first, so that one-time costs (kernels, OIDN's weights, imports)
count against neither. A table row is a time budget; a cell holds the PSNR of the render of most
samples whose measured time does not exceed it (with time_limit: the render at that limit), its
samples and seconds beside it, "-" when even one sample took longer.
"""

import argparse
import math
import os
import sys
import time

import bpy

REPO_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path[:0] = [os.path.join(REPO_ROOT, "addon"), os.path.join(REPO_ROOT, "build", "python"),
                os.path.join(REPO_ROOT, "examples"),
                os.path.join(REPO_ROOT, "tests", "blender")]

import addon_utils  # noqa: E402
import blender_scenes  # noqa: E402
import blender_test_setup as setup  # noqa: E402  (tests/blender: multilayer EXR read-back)
import numpy as np  # noqa: E402

ADDON = "shgi_blender"
SCENES = ("cornell_box", "sun_room", "two_rooms", "caustics", "dense")
# The dense scene's sphere: bench/viewport_sync_bench.py's, 523,264 triangles.
DENSE_SEGMENTS, DENSE_RINGS = 512, 512
DENSE_CENTER, DENSE_RADIUS = (0.3, 0.8, 0.9), 0.3
DENSE_COLOR = (0.8, 0.4, 0.1)  # orange
LIMITS = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
CYCLES_SAMPLES = (1, 2, 4, 8, 16, 32, 64)
REFERENCE_SAMPLES = 4096
# Stepped samples stop at this share of the reference's: a render is never the reference's twin.
MAX_STEP_FRACTION = 0.25
# --quick: a smoke run of the same code.
QUICK_LIMITS = (0.5, 2.0)
QUICK_SAMPLES = (1, 4, 16)
QUICK_REFERENCE_SAMPLES = 256
# The summary compares budgets from this one up: below it F12's fixed costs dominate both sides.
SUMMARY_FROM_SECONDS = 0.5
# Cycles' Light Paths limits (tests/blender/calibration_common.BOUNCES), set in both renderers.
BOUNCES = {"max_bounces": 8, "diffuse_bounces": 4, "glossy_bounces": 4,
           "transmission_bounces": 8}
# The samples of a time-limited SHGI render: the limit, not the samples, ends it.
TIME_LIMITED_SAMPLES = 1 << 16
SEED = 1
# The references' seed, apart from every render they score: with the renders' own seed a
# reference's first samples are the render's samples, which flatters whichever renderer scores
# more samples (the sun room's 8-s SHGI render is 230 of its reference's 4096).
REFERENCE_SEED = 1000


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", default=",".join(SCENES),
                        help=f"comma-separated, of {', '.join(SCENES)}")
    parser.add_argument("--methods", default=None,
                        help="comma-separated SHGI methods (default: every registered one)")
    parser.add_argument("--limits", default=None,
                        help=f"comma-separated time budgets in s (default {LIMITS})")
    parser.add_argument("--resolution", default="200x150", help="WxH pixels")
    parser.add_argument("--cache", default=os.path.join(REPO_ROOT, "build", "equal_time_cache"),
                        help="folder of the cached references")
    parser.add_argument("--cycles-filter-glossy", type=float, default=None,
                        help="Cycles' Light Paths > Caustics > Filter Glossy (blur_glossy) for "
                             "its renders and reference (default: Cycles' own, 1.0). Use another "
                             "--cache: Cycles' references are keyed without it")
    parser.add_argument("--shgi-filter-glossy", type=float, default=None,
                        help="SHGI's Light Paths > Filter Glossy for its renders and reference "
                             "(default: the add-on's, Cycles' 1.0; 0 before settings layout 5). "
                             "SHGI's references are keyed by it")
    parser.add_argument("--clamp-indirect", type=float, default=None,
                        help="Light Paths > Clamp Indirect for both renderers, renders and "
                             "references (default: each one's own, 10 in both; SHGI's was 0 "
                             "before settings layout 4). References are keyed by it")
    parser.add_argument("--first-hit-guides", action="store_true",
                        help="A/B of the denoiser's guides: each time-limited SHGI render is "
                             "made twice, alternating which goes first, with the renderers' "
                             "Denoising Albedo / Normal (which follow specular bounces, as "
                             "Cycles') and with the first hit's (DiffCol + GlossCol + TransCol, "
                             "Normal: SHGI's guides before them); the second gets its own column")
    parser.add_argument("--references-only", action="store_true",
                        help="render (or find cached) each scene's two references and stop: "
                             "no timed renders")
    parser.add_argument("--reference-samples", type=int, default=None,
                        help=f"samples of both renderers' references (default "
                             f"{REFERENCE_SAMPLES}; {QUICK_REFERENCE_SAMPLES} with --quick). A "
                             f"4096-spp reference is itself only ~44 dB from the converged image "
                             f"in the sun room, which caps every cell near it; more samples "
                             f"lower that floor")
    parser.add_argument("--quick", action="store_true",
                        help=f"smoke run: limits {QUICK_LIMITS}, samples {QUICK_SAMPLES}, "
                             f"{QUICK_REFERENCE_SAMPLES}-spp references")
    args = parser.parse_args(argv)
    args.scenes = args.scenes.split(",")
    unknown = [name for name in args.scenes if name not in SCENES]
    if unknown:
        parser.error(f"--scenes: {unknown} not among {list(SCENES)}")
    args.limits = (tuple(float(x) for x in args.limits.split(",")) if args.limits
                   else QUICK_LIMITS if args.quick else LIMITS)
    args.samples = QUICK_SAMPLES if args.quick else CYCLES_SAMPLES
    if args.reference_samples is None:
        args.reference_samples = QUICK_REFERENCE_SAMPLES if args.quick else REFERENCE_SAMPLES
    elif args.reference_samples < 1:
        parser.error("--reference-samples: at least 1")
    args.width, args.height = (int(x) for x in args.resolution.lower().split("x"))
    return args


# --- scenes -----------------------------------------------------------------------------------

def build_scene(name, width, height, filter_glossy=None, clamp_indirect=None,
                shgi_filter_glossy=None):
    """A fresh file holding scene `name` at width x height, set up alike for Cycles and SHGI;
    Cycles' Filter Glossy `filter_glossy`, SHGI's `shgi_filter_glossy` and both renderers' Clamp
    Indirect `clamp_indirect` (None: each one's default)."""
    if name == "dense":
        scene = blender_scenes.build("cornell_box")
        builder = blender_scenes.SceneBuilder()
        sphere = blender_scenes.uv_sphere(DENSE_CENTER, DENSE_RADIUS, DENSE_SEGMENTS, DENSE_RINGS)
        builder.part("dense_sphere", sphere, "orange", DENSE_COLOR, smooth=True)
    else:
        scene = blender_scenes.build(name)
    if ADDON not in bpy.context.preferences.addons:
        addon_utils.enable(ADDON, default_set=True, handle_error=None)
    render = scene.render
    render.resolution_x, render.resolution_y = width, height
    render.resolution_percentage = 100
    render.threads_mode = "FIXED"
    render.threads = os.cpu_count()
    scene.view_settings.view_transform = "Standard"
    setup.use_multilayer_exr(render.image_settings)
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.use_adaptive_sampling = False  # the spp of a row is what Cycles rendered
    cycles.seed = SEED
    cycles.denoiser = "OPENIMAGEDENOISE"
    if filter_glossy is not None:
        cycles.blur_glossy = filter_glossy
    if clamp_indirect is not None:
        cycles.sample_clamp_indirect = clamp_indirect
        scene.shgi.clamp_indirect = clamp_indirect
    if shgi_filter_glossy is not None:
        scene.shgi.filter_glossy = shgi_filter_glossy
    for field, value in BOUNCES.items():
        setattr(cycles, field, value)
        setattr(scene.shgi, field, value)
    scene.shgi.seed = SEED
    return scene


# --- rendering --------------------------------------------------------------------------------

def render_f12(scene, engine, path):
    """(seconds of F12, float64 (H, W, 3) Combined read back from the Render Result)."""
    scene.render.engine = engine
    start = time.perf_counter()
    bpy.ops.render.render(write_still=False)
    seconds = time.perf_counter() - start
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    return seconds, setup.read_render_exr(path)["Combined"][..., :3]


def use_cycles(scene, samples, denoise):
    scene.cycles.samples = samples
    scene.cycles.use_denoising = denoise


def use_shgi(scene, method, samples, time_limit=None, denoise=False):
    """SHGI's settings for a render; time_limit only where the add-on has it (supports_limit)."""
    props = scene.shgi
    props.method = method
    props.samples = samples
    if supports_limit(scene):
        props.time_limit = time_limit or 0.0
        props.use_denoising = denoise


def supports_limit(scene):
    return hasattr(scene.shgi, "time_limit") and hasattr(scene.shgi, "use_denoising")


def shgi_reference_tag(props):
    """What SHGI's reference keys hold beyond the clamp: `_fg<Filter Glossy>` and
    pixel_filter_tag."""
    return f"_fg{props.filter_glossy:g}{pixel_filter_tag(props)}"


def pixel_filter_tag(props):
    """The pixel filter of scene.shgi `props` in a reference key when it is not the box of one
    pixel every reference had before settings layout 8 (`_blackmanharris1.5`), else "": a
    reference is scored only by renders of the same filter."""
    pixel_filter = getattr(props, "pixel_filter", "BOX")
    width = getattr(props, "filter_width", 1.0)
    if (pixel_filter, width) == ("BOX", 1.0):
        return ""
    return f"_{pixel_filter.lower().replace('_', '')}{width:g}"


def reference_path(cache, key):
    """The cache file of reference `key` (`<scene>_<W>x<H>_<renderer>..._<spp>spp`), tagged with
    REFERENCE_SEED so that no reference of another seed is read."""
    stem, spp = key.rsplit("_", 1)
    return os.path.join(cache, f"{stem}_seed{REFERENCE_SEED}_{spp}.npy")


def reference(scene, key, engine, configure, args):
    """The reference `key` (`<scene>_<W>x<H>_<renderer>_<spp>spp`) and its samples: the cached
    one of the most samples, at least key's, for that scene, size and renderer (a --quick run
    after a full one scores against the 4096-spp reference: the sun room's 256-spp references
    are only 30.6 dB (SHGI) and 32.1 dB (Cycles) from their 4096-spp ones, which capped every
    --quick figure there); rendered with `engine` after configure(scene), with REFERENCE_SEED,
    when none is cached."""
    os.makedirs(args.cache, exist_ok=True)
    stem, spp = key.rsplit("_", 1)
    wanted = int(spp[:-len("spp")])
    head_wanted = os.path.basename(reference_path(args.cache, key)).rsplit("_", 1)[0]
    cached = []
    for file in os.listdir(args.cache):
        head, _, tail = file.rpartition("_")
        if head == head_wanted and tail.endswith("spp.npy") and tail[:-len("spp.npy")].isdigit():
            cached.append(int(tail[:-len("spp.npy")]))
    best = max((n for n in cached if n >= wanted), default=None)
    if best is not None:
        if best != wanted:
            print(f"  reference {key}: using the cached {best}-spp one", flush=True)
        return np.load(reference_path(args.cache, f"{stem}_{best}spp")), best
    configure(scene)
    scene.cycles.seed = scene.shgi.seed = REFERENCE_SEED
    try:
        seconds, image = render_f12(scene, engine, os.path.join(args.cache, "render.exr"))
    finally:
        scene.cycles.seed = scene.shgi.seed = SEED
    print(f"  reference {key} (seed {REFERENCE_SEED}): {seconds:.1f} s", flush=True)
    np.save(reference_path(args.cache, key), image)
    return image, wanted


def stepped_samples(args, runs):
    """args.samples, then doubling on while the last of `runs` (appended by the caller as it
    goes) was faster than the largest budget, up to MAX_STEP_FRACTION of the reference's
    samples: a renderer fast at low samples gets rows up to the largest budget too."""
    yield from args.samples
    samples = args.samples[-1]
    while (runs and runs[-1].seconds < max(args.limits)
           and 2 * samples <= args.reference_samples * MAX_STEP_FRACTION):
        samples *= 2
        yield samples


class Run:
    """One measured render: seconds of F12, samples (rendered, or asked for), PSNR (dB), and
    the time limit it was made for (None when samples were stepped)."""

    def __init__(self, seconds, samples, psnr, limit=None):
        self.seconds, self.samples, self.psnr, self.limit = seconds, samples, psnr, limit


def cycles_runs(scene, ref, args, exr):
    from shgi import metrics

    use_cycles(scene, 1, True)
    render_f12(scene, "CYCLES", exr)  # untimed: first-render costs
    runs = []
    for samples in stepped_samples(args, runs):
        use_cycles(scene, samples, True)
        seconds, image = render_f12(scene, "CYCLES", exr)
        runs.append(Run(seconds, samples, metrics.psnr(ref, image)))
        print(f"  Cycles+OIDN {samples:4d} spp: {seconds:6.2f} s {runs[-1].psnr:6.2f} dB",
              flush=True)
    return runs


class FirstHitGuides:
    """While active, shgi.frame_denoise builds its guides from the first hit's passes
    (DiffCol + GlossCol + TransCol, Normal) instead of the renderers' Denoising Albedo /
    Normal: the guides SHGI denoised with before the renderers wrote those (--first-hit-guides)."""

    def __init__(self):
        from shgi import frame_denoise

        self.module = frame_denoise
        self.renderer_guides = frame_denoise.guide_images
        dropped = (frame_denoise.ALBEDO_PASS, frame_denoise.NORMAL_PASS)

        def first_hit_guides(passes, guides="ALBEDO_NORMAL"):
            return self.renderer_guides(
                {name: value for name, value in passes.items() if name not in dropped}, guides)

        self.first_hit_guides = first_hit_guides

    def use(self, active):
        self.module.guide_images = self.first_hit_guides if active else self.renderer_guides


FIRST_HIT = " first-hit guides"


def shgi_runs(scene, method, ref, args, exr):
    """{column label: runs}: `method`, and with --first-hit-guides `method` + FIRST_HIT."""
    from shgi import metrics
    from shgi_blender.engine import final_render

    use_shgi(scene, method, 1)
    render_f12(scene, "SHGI", exr)  # untimed: first-render costs
    runs = []
    columns = {method: runs}
    if supports_limit(scene):
        settings = [(TIME_LIMITED_SAMPLES, limit) for limit in args.limits]
    else:
        settings = ((samples, None) for samples in stepped_samples(args, runs))
    switch = FirstHitGuides() if args.first_hit_guides and supports_limit(scene) else None
    if switch is not None:
        columns[method + FIRST_HIT] = []
    for index, (samples, limit) in enumerate(settings):
        # A/B: the two variants alternate which renders first, budget by budget.
        variants = [False] if switch is None else [False, True][::1 if index % 2 == 0 else -1]
        for first_hit in variants:
            if switch is not None:
                switch.use(first_hit)
            use_shgi(scene, method, samples, time_limit=limit, denoise=limit is not None)
            try:
                seconds, image = render_f12(scene, "SHGI", exr)
            finally:
                if switch is not None:
                    switch.use(False)
            record = final_render.last_render()
            if record.get("errors"):
                raise RuntimeError(f"SHGI {method} on {scene.name}: {record['errors']}")
            rendered = record.get("samples") or samples
            label = method + (FIRST_HIT if first_hit else "")
            column = columns[label]
            column.append(Run(seconds, rendered, metrics.psnr(ref, image), limit))
            print(f"  SHGI {label:14s} {rendered:4d} spp: {seconds:6.2f} s "
                  f"{column[-1].psnr:6.2f} dB", flush=True)
    return columns


# --- the table --------------------------------------------------------------------------------

def run_within(runs, budget):
    """The run made for `budget` (time-limited runs), else the one of most samples whose time
    does not exceed it; None when none fits."""
    limited = [run for run in runs if run.limit == budget]
    if limited:
        return limited[0]
    fitting = [run for run in runs if run.limit is None and run.seconds <= budget]
    return max(fitting, key=lambda run: run.samples) if fitting else None


def cell(run):
    if run is None:
        return "-"
    return f"{run.psnr:5.1f} ({run.samples} spp, {run.seconds:.2f} s)"


def print_table(name, args, cycles, methods, default_method, limited, reference_spp):
    columns = ["Cycles+OIDN"] + [f"SHGI {method}" for method in methods]
    width = max([26] + [len(c) for c in columns])
    print(f"\n{name} ({args.width}x{args.height}, references {reference_spp[0]} spp (Cycles) and "
          f"{reference_spp[1]} spp (SHGI); "
          f"PSNR dB, samples and F12 seconds of the render within the budget; SHGI "
          f"{'time_limit + OIDN' if limited else 'samples stepped, no denoising'})")
    print(f"{'budget':>7s} " + " ".join(f"{c:>{width}s}" for c in columns))
    for budget in args.limits:
        cells = [cell(run_within(cycles, budget))]
        cells += [cell(run_within(methods[m], budget)) for m in methods]
        print(f"{budget:6.2f}s " + " ".join(f"{c:>{width}s}" for c in cells))
    if default_method in methods:
        print(summary(name, args, cycles, methods[default_method], default_method))


def summary(name, args, cycles, shgi, method):
    """Where SHGI's default method is at or above Cycles+OIDN, from SUMMARY_FROM_SECONDS up."""
    at_or_above, below, neither = [], [], []
    for budget in (b for b in args.limits if b >= SUMMARY_FROM_SECONDS):
        ours, theirs = run_within(shgi, budget), run_within(cycles, budget)
        label = f"{budget:g} s"
        if ours is None:
            (neither if theirs is None else below).append(label)
        elif theirs is None:  # only SHGI has an image this fast
            at_or_above.append(label + " (no Cycles render)")
        elif ours.psnr >= theirs.psnr:
            at_or_above.append(label)
        else:
            below.append(label)
    leads = []
    for budget in (b for b in args.limits if b >= SUMMARY_FROM_SECONDS):
        ours = run_within(shgi, budget)
        theirs = None if ours is None else cycles_at(cycles, ours.seconds)
        if theirs is not None:
            leads.append(f"{ours.seconds:.2f} s {ours.psnr - theirs:+.2f} dB")
    return (f"summary {name}: SHGI {method} (the default method) at/above Cycles+OIDN at "
            f"{', '.join(at_or_above) or 'no budget'}; below at {', '.join(below) or 'none'}"
            + (f"; neither renders within {', '.join(neither)}" if neither else "")
            + f"\n  at equal seconds (Cycles' PSNR interpolated in log time to SHGI's): "
            + (", ".join(leads) or "no budget within Cycles' renders"))


def cycles_at(cycles, seconds):
    """Cycles' PSNR at F12 time `seconds`, interpolated in log time between its two renders
    either side (sorted by time); None outside them."""
    runs = sorted(cycles, key=lambda run: run.seconds)
    for low, high in zip(runs, runs[1:]):
        if low.seconds <= seconds <= high.seconds and high.seconds > low.seconds:
            t = math.log(seconds / low.seconds) / math.log(high.seconds / low.seconds)
            return low.psnr + t * (high.psnr - low.psnr)
    return None


# --- main -------------------------------------------------------------------------------------

def main():
    args = parse_args()
    if ADDON not in bpy.context.preferences.addons:
        addon_utils.enable(ADDON, default_set=True, handle_error=None)
    from shgi_blender import settings

    all_methods = [method.identifier for method in settings.METHODS]
    methods = args.methods.split(",") if args.methods else all_methods
    unknown = [m for m in methods if m not in all_methods]
    if unknown:
        raise SystemExit(f"--methods: {unknown} not among {all_methods}")
    default_method = bpy.types.Scene.bl_rna.properties["shgi"].fixed_type.bl_rna.properties[
        "method"].default
    print(f"equal time: Blender {bpy.app.version_string}, {os.cpu_count()} cores, "
          f"scenes {args.scenes}, SHGI methods {methods} (default {default_method})")
    exr = os.path.join(args.cache, "render.exr")
    for name in args.scenes:
        scene = build_scene(name, args.width, args.height, args.cycles_filter_glossy,
                            args.clamp_indirect, args.shgi_filter_glossy)
        limited = supports_limit(scene)
        # References are keyed by each renderer's Clamp Indirect and SHGI's by its Filter Glossy
        # and pixel filter too: a biased estimate is scored against a reference with the same
        # bias. (Cycles' pixel filter is its default, Blackman-Harris 1.5, in every key.)
        key = (f"{name}_{args.width}x{args.height}_{{}}_clamp{{:g}}{{}}_"
               f"{args.reference_samples}spp")
        print(f"{name}:", flush=True)
        cycles_ref, cycles_spp = reference(
            scene, key.format("cycles", scene.cycles.sample_clamp_indirect, ""), "CYCLES",
            lambda s: use_cycles(s, args.reference_samples, False), args)
        shgi_ref, shgi_spp = reference(
            scene, key.format("shgi", scene.shgi.clamp_indirect,
                              shgi_reference_tag(scene.shgi)), "SHGI",
            lambda s: use_shgi(s, "PATH_TRACE", args.reference_samples), args)
        if args.references_only:
            continue
        cycles = cycles_runs(scene, cycles_ref, args, exr)
        results = {}
        for method in methods:
            results.update(shgi_runs(scene, method, shgi_ref, args, exr))
        print_table(name, args, cycles, results, default_method, limited,
                    (cycles_spp, shgi_spp))


if __name__ == "__main__":
    main()
