"""Per-sample noise of SHGI's path tracer and of Cycles on one of bench/equal_time.py's scenes
(default: caustics), undenoised, each against its own cached 4096-spp reference, and where in
the frame the error is: the squared display error (the bench's PSNR's MSE) split by what the
camera sees first, from SHGI's passes: the glass (TransCol > 0), the metal (GlossCol > 0.2 with
no DiffCol), emitters and the world seen directly (Emit + Env > 0) and the rest (diffuse walls,
floor, ceiling). The same masks are applied to both renderers' images (same geometry, camera
and resolution).

    PYTHONPATH=build/python /opt/shgi/bpy-5.0.1/bin/python bench/caustics_noise.py
        [--scene caustics] [--samples 4,16,64] [--shgi-clamp-indirect 10]
        [--shgi-filter-glossy 0,1] [--cycles-clamp-indirect 0] [--cycles-filter-glossy 0]
        [--cache build/equal_time_cache]

A benchmark, not a test: nothing is asserted. References are never rendered here (--cache holds
bench/equal_time.py's, keyed as it keys them; a row without its reference reads "-" in the
PSNR, MSE and region columns). SHGI renders
through shgi.PathTracer with the add-on's F12 settings of the scene (seed equal_time.SEED), once
per --shgi-filter-glossy value (default: the add-on's, Cycles' 1), Cycles through F12 without
denoising (seed equal_time.SEED, as the bench). "MSE x spp" is the display-space error per
sample: with 1/N variance it stays constant, and its ratio between the renderers is how many
more samples one needs for the other's noise. "pair x spp" is the same without a reference:
half the squared display difference of two renders of seeds SEED and SEED + 1, times spp (the
noise alone, no bias against the reference), every row at one exposure: the first SHGI row's
reference's, or an SHGI render's at the most samples without it.
"mean" is the mean of Combined over the frame and both seeds, relative to the first SHGI row of
the same spp (the bias a filter adds, at the spp's noise); "CPU ms/spp" is SHGI's process CPU
time for the two renders per sample (every thread's: it holds on a loaded machine, up to the
load's cache and frequency effects).
"""

import argparse
import os
import sys

import bpy

REPO_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path[:0] = [os.path.join(REPO_ROOT, "bench")]

import equal_time  # noqa: E402  (sets sys.path for the add-on, shgi and the scenes)
import numpy as np  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scene", default="caustics")
    parser.add_argument("--samples", default="4,16,64")
    parser.add_argument("--resolution", default="200x150", help="WxH pixels")
    parser.add_argument("--cache", default=os.path.join(REPO_ROOT, "build", "equal_time_cache"))
    parser.add_argument("--shgi-filter-glossy", default=None,
                        help="comma-separated Filter Glossy values, one SHGI row each (default: "
                             "the add-on's, Cycles' 1; 0 = off)")
    parser.add_argument("--shgi-clamp-indirect", type=float, default=None,
                        help="SHGI's Clamp Indirect for its renders (default: the add-on's, 0 = "
                             "off; Cycles' default is 10). Its reference stays unclamped: see "
                             "the seed-pair column")
    parser.add_argument("--cycles-clamp-indirect", type=float, default=None,
                        help="Cycles' Clamping > Indirect Light for its renders (default: its "
                             "own, 10); its reference stays as cached: see the seed-pair column")
    parser.add_argument("--cycles-filter-size", type=float, default=None,
                        help="Cycles' Film > Pixel Filter width in pixels (cycles.filter_width; Cycles' "
                             "default 1.5 px Blackman-Harris; SHGI has a 1 px box): whether the "
                             "pixel filter changes the noise per sample (pair x spp). Its PSNR "
                             "column is against the reference cached with the default")
    parser.add_argument("--cycles-filter-glossy", type=float, default=None,
                        help="Cycles' Light Paths > Caustics > Filter Glossy for its renders "
                             "(default: its own, 1.0)")
    args = parser.parse_args(argv)
    args.samples = [int(n) for n in args.samples.split(",")]
    args.shgi_filter_glossy = ([float(x) for x in args.shgi_filter_glossy.split(",")]
                               if args.shgi_filter_glossy else [None])
    args.width, args.height = (int(x) for x in args.resolution.lower().split("x"))
    return args


def squared_error(reference, image):
    """Per-pixel squared display error (mean over RGB), as shgi.metrics.psnr computes it."""
    from shgi import metrics

    exposure = metrics.auto_exposure(reference)
    difference = metrics.display(reference, exposure) - metrics.display(image, exposure)
    return (difference ** 2).mean(axis=-1)


def squared_error_pair(reference, first, second):
    """Per-pixel squared display difference of two renders, at the reference's exposure."""
    from shgi import metrics

    exposure = metrics.auto_exposure(reference)
    difference = metrics.display(first, exposure) - metrics.display(second, exposure)
    return (difference ** 2).mean(axis=-1)


def regions(passes):
    """{name: bool (H, W) mask} of what the camera sees first, from SHGI's passes."""
    trans = passes["TransCol"][..., :3].max(axis=-1)
    gloss = passes["GlossCol"][..., :3].max(axis=-1)
    diff = passes["DiffCol"][..., :3].max(axis=-1)
    direct = (passes["Emit"][..., :3] + passes["Env"][..., :3]).max(axis=-1)
    glass = trans > 0.0
    metal = ~glass & (gloss > 0.2) & (diff == 0.0)
    emitter = ~glass & ~metal & (direct > 0.0)
    rest = ~glass & ~metal & ~emitter
    return {"glass": glass, "metal": metal, "emitters/world": emitter, "diffuse": rest}


def load_reference(args, renderer, clamp, filter_glossy=None, pixel_tag=""):
    """bench/equal_time.py's cached reference of `renderer` with Clamp Indirect `clamp` (and
    SHGI's Filter Glossy `filter_glossy` and pixel filter, `pixel_tag`), or None."""
    fg = "" if filter_glossy is None else f"_fg{filter_glossy:g}{pixel_tag}"
    key = (f"{args.scene}_{args.width}x{args.height}_{renderer}_clamp{clamp:g}{fg}_"
           f"{equal_time.REFERENCE_SAMPLES}spp")
    path = equal_time.reference_path(args.cache, key)
    if not os.path.exists(path):
        print(f"{path}: no cached reference (bench/equal_time.py renders it): its PSNR, MSE "
              "and regions left out")
        return None
    return np.load(path)


def main():
    args = parse_args()
    import shgi
    import time

    from shgi_blender import settings
    from shgi_blender.export.scene_export import export_scene

    scene = equal_time.build_scene(args.scene, args.width, args.height,
                                   args.cycles_filter_glossy)
    if args.cycles_clamp_indirect is not None:
        scene.cycles.sample_clamp_indirect = args.cycles_clamp_indirect
    if args.cycles_filter_size is not None:
        scene.cycles.filter_width = args.cycles_filter_size
    # Each row's own reference: Cycles' by its clamp (as cached: --cycles-filter-glossy is not
    # in its key), SHGI's by its clamp and Filter Glossy.
    shgi_clamp = (scene.shgi.clamp_indirect if args.shgi_clamp_indirect is None
                  else args.shgi_clamp_indirect)
    filters = [scene.shgi.filter_glossy if value is None else value
               for value in args.shgi_filter_glossy]
    references = {f"shgi fg{value:g}": load_reference(args, "shgi", shgi_clamp, value,
                                                      equal_time.pixel_filter_tag(scene.shgi))
                  for value in filters}
    references["cycles"] = load_reference(args, "cycles", scene.cycles.sample_clamp_indirect)
    native = export_scene(bpy.context.evaluated_depsgraph_get(), scene).scene
    native.commit()
    exr = os.path.join(args.cache, "noise_render.exr")
    masks = None
    rows = []
    # The pair column's one exposure for every row: the first SHGI row's reference, or without
    # it an SHGI render at the most samples (seed SEED + 2, the first --shgi-filter-glossy).
    fixed_exposure = references[f"shgi fg{filters[0]:g}"]
    if fixed_exposure is None:
        exposure_settings = settings.path_tracer_settings(scene.shgi, shgi)
        exposure_settings.samples = max(args.samples)
        exposure_settings.seed = equal_time.SEED + 2
        if args.shgi_filter_glossy[0] is not None:
            exposure_settings.filter_glossy = args.shgi_filter_glossy[0]
        if args.shgi_clamp_indirect is not None:
            exposure_settings.clamp_indirect = args.shgi_clamp_indirect
        fixed_exposure = shgi.render_path_traced(native, exposure_settings)["Combined"][..., :3]
    for samples in args.samples:
        renders = []  # (name, image, second image, CPU seconds of both)
        for filter_glossy in args.shgi_filter_glossy:
            tracer_settings = settings.path_tracer_settings(scene.shgi, shgi)
            tracer_settings.samples = samples
            if args.shgi_clamp_indirect is not None:
                tracer_settings.clamp_indirect = args.shgi_clamp_indirect
            if filter_glossy is not None:
                tracer_settings.filter_glossy = filter_glossy
            tracer_settings.seed = equal_time.SEED
            start = time.process_time()
            passes = shgi.render_path_traced(native, tracer_settings)
            tracer_settings.seed = equal_time.SEED + 1
            second = shgi.render_path_traced(native, tracer_settings)["Combined"]
            cpu = time.process_time() - start
            renders.append((f"shgi fg{tracer_settings.filter_glossy:g}", passes["Combined"],
                            second, cpu))
            if masks is None:
                masks = regions(passes)
                print(f"{args.scene}: pixels per region "
                      + ", ".join(f"{k} {int(v.sum())}" for k, v in masks.items()))
        equal_time.use_cycles(scene, samples, False)
        cycles = []
        for seed in (equal_time.SEED, equal_time.SEED + 1):
            scene.cycles.seed = seed
            cycles.append(equal_time.render_f12(scene, "CYCLES", exr)[1])
        scene.cycles.seed = equal_time.SEED
        renders.append(("cycles", cycles[0], cycles[1], None))
        base_mean = float((renders[0][1][..., :3] + renders[0][2][..., :3]).mean())
        for name, image, other, cpu in renders:
            reference = references[name]
            psnr = per_sample = parts = None
            if reference is not None:
                error = squared_error(reference, image)
                total = float(error.mean())
                parts = {k: float(error[m].sum()) / error.size for k, m in masks.items()}
                psnr, per_sample = 10.0 * np.log10(1.0 / total), total * samples
            # Reference-free: two independent renders differ by twice the per-render variance
            # (display space, scaled by the reference's exposure).
            pair = float(squared_error_pair(fixed_exposure, image, other).mean()) / 2.0
            mean = float((image[..., :3] + other[..., :3]).mean()) / base_mean
            rows.append((samples, name, psnr, per_sample, pair * samples, parts, mean,
                         None if cpu is None else 1e3 * cpu / (2 * samples)))
    print(f"{'spp':>5s} {'renderer':10s} {'PSNR dB':>8s} {'MSE x spp':>10s} {'pair x spp':>10s} "
          f"{'mean':>7s} {'CPU ms/spp':>10s}  " + "  ".join(f"{k + ' share':>20s}" for k in masks))
    for samples, name, psnr, per_sample, pair, parts, mean, cpu in rows:
        cells = (f"{samples:5d} {name:10s} "
                 + (f"{psnr:8.2f} {per_sample:10.4f}" if psnr is not None else f"{'-':>8s} "
                    f"{'-':>10s}")
                 + f" {pair:10.4f} {mean:7.4f} "
                 + (f"{cpu:10.1f}" if cpu is not None else f"{'-':>10s}"))
        if parts is not None:
            total = sum(parts.values())
            cells += "  " + "  ".join(f"{parts[k] * samples:9.4f} ({100 * parts[k] / total:4.1f}%)"
                                      for k in masks)
        print(cells)


if __name__ == "__main__":
    main()
