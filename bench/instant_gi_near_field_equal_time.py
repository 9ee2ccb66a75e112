#!/usr/bin/env python3
"""Instant GI's near field (InstantGiSettings.near_field_reach) at equal CPU time: per scene of
examples/scenes.py and camera resolution, Combined PSNR against the path tracer of denoised
first-surface frames (PreviewSettings.final_gather off: the near field lights first surfaces
only) with the near field at each `--reaches` and without (reach 0, the paper's filter), each
frame at 1, 2, 4, ... `--samples` samples, denoised as the Rendered viewport denoises
(settings.DENOISING_DEFAULTS' viewport choices: Balanced, Fast prefilter, Albedo guides).

The field is the viewport's solve (`--passes`, 1: settings.VIEWPORT_PASSES_DEFAULTS; every sample
gathers it) or F12's with Final Gather off (`--passes 64`: 4 per sample, each sample new VPLs).
A frame's cost is the CPU time (getrusage: every thread of this process) of its render_preview,
the median over `--repeats` renders of the first seed's fields, reaches alternated; the
denoise's (the same for every reach) is printed apart and not counted. At each budget (the reach-0 frames' costs) a reach's cell is
the PSNR of its render of most samples whose cost does not exceed the budget ("-": none), the
mean over `--seeds` (the solve's seed; the frame's seed is 5). References: the path tracer at
`--reference-samples`, cached as .npy under `--cache`. A plain script printing tables: not a
test; figures in docs/methods.md ("Instant GI", near field at equal time).

    PYTHONPATH=build/python python3 bench/instant_gi_near_field_equal_time.py \
        [--scenes cornell_box sun_room] [--resolutions 128x128 640x360] [--reaches 4] \
        [--samples 64] [--passes 1] [--seeds 5 6] [--repeats 3] [--reference-samples 2048 256]
"""

import argparse
import pathlib
import resource
import statistics
import sys

import numpy as np

import shgi
from shgi.frame_denoise import WANTED_PASSES, FrameDenoiser
from shgi.metrics import psnr

REPO = pathlib.Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO / "examples"), str(REPO / "addon")]
import scenes  # noqa: E402  (examples/scenes.py)
from shgi_blender import settings  # noqa: E402  (the add-on's defaults; no bpy needed)


def cpu_seconds():
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def viewport_denoiser():
    d = settings.DENOISING_DEFAULTS
    return FrameDenoiser(d["viewport_denoising_quality"], d["viewport_denoising_prefilter"],
                         d["viewport_denoising_guides"])


def scene_at(name, width, height):
    builder = getattr(scenes, name)(1.0)
    camera = builder.scene.camera
    camera.resolution_x, camera.resolution_y = width, height
    builder.scene.set_camera(camera)
    builder.scene.commit()
    return builder.scene


def reference(scene, key, samples, cache):
    path = pathlib.Path(cache) / f"{key}_{samples}spp.npy"
    if path.exists():
        return np.load(path)
    image = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=samples, seed=11))
    combined = np.asarray(image["Combined"], np.float32)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.save(path, combined)
    return combined


def solve(scene, seed, reach, passes, per_sample):
    solver = shgi.InstantGi(scene, shgi.InstantGiSettings(
        seed=seed, near_field_reach=reach, passes_per_sample=per_sample))
    for _ in range(passes):
        solver.refine()
    return solver.current_field()


def frame(scene, field, samples):
    image, _ = shgi.render_preview(scene, field, shgi.PreviewSettings(
        seed=5, samples=samples, final_gather=False))
    return image


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=["cornell_box", "sun_room"])
    parser.add_argument("--resolutions", nargs="+", default=["128x128", "640x360"])
    parser.add_argument("--reaches", type=float, nargs="+", default=[4.0])
    parser.add_argument("--samples", type=int, default=64, help="the most samples (powers of 2)")
    parser.add_argument("--passes", type=int, default=settings.VIEWPORT_PASSES_DEFAULTS[
        "INSTANT_GI"])
    parser.add_argument("--passes-per-sample", type=int,
                        default=settings.INSTANT_GI_DEFAULTS["passes_per_sample"])
    parser.add_argument("--seeds", type=int, nargs="+", default=[5, 6])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--reference-samples", type=int, nargs="+", default=[2048, 256],
                        help="the path tracer's samples per resolution (one: for all)")
    parser.add_argument("--cache", default=str(REPO / "build" / "near_field_equal_time_cache"))
    args = parser.parse_args()
    reaches = [0.0] + [r for r in args.reaches if r > 0.0]
    counts = [1 << k for k in range(args.samples.bit_length()) if 1 << k <= args.samples]
    guides = settings.DENOISING_DEFAULTS["viewport_denoising_guides"]
    wanted = ("Combined", *WANTED_PASSES[guides])
    with viewport_denoiser() as denoiser:
        for name in args.scenes:
            for i, resolution in enumerate(args.resolutions):
                width, height = map(int, resolution.split("x"))
                scene = scene_at(name, width, height)
                spp = args.reference_samples[min(i, len(args.reference_samples) - 1)]
                ref = reference(scene, f"{name}_{width}x{height}", spp, args.cache)
                # {(reach, samples): [PSNR per seed]}, {(reach, samples): [CPU s]}
                quality, cost, denoise_cost = {}, {}, []
                last = {reach: [] for reach in reaches}  # the most samples' frames per seed
                for seed in args.seeds:
                    fields = {r: solve(scene, seed, r, args.passes, args.passes_per_sample)
                              for r in reaches}
                    for samples in counts:
                        for repeat in range(args.repeats if seed == args.seeds[0] else 1):
                            for reach in reaches:
                                field = fields[reach]
                                start = cpu_seconds()
                                image = frame(scene, field, samples)
                                if seed == args.seeds[0]:
                                    cost.setdefault((reach, samples), []).append(
                                        cpu_seconds() - start)
                                if repeat:
                                    continue
                                start = cpu_seconds()
                                denoised = denoiser.denoise(
                                    {k: v for k, v in image.items() if k in wanted},
                                    samples=samples)
                                denoise_cost.append(cpu_seconds() - start)
                                quality.setdefault((reach, samples), []).append(
                                    psnr(ref, denoised["Combined"]))
                                if samples == counts[-1]:
                                    last[reach].append(denoised["Combined"][..., :3])
                report(name, width, height, args, spp, reaches, counts, quality, cost,
                       statistics.median(denoise_cost))
                spread(ref, last, counts[-1])


def report(name, width, height, args, spp, reaches, counts, quality, cost, denoise):
    median = {key: statistics.median(times) for key, times in cost.items()}
    mean = {key: float(np.mean(values)) for key, values in quality.items()}
    print(f"\n{name} {width} x {height}: {args.passes} passes ({args.passes_per_sample} per "
          f"sample), seeds {args.seeds}, reference {spp} spp; "
          f"denoise {denoise:.3f} CPU s a frame (not counted)")
    print("samples | " + " | ".join(f"reach {r:g}: CPU s, PSNR" for r in reaches))
    for samples in counts:
        print(f"{samples:7d} | " + " | ".join(
            f"{median[(r, samples)]:.3f} s, {mean[(r, samples)]:.2f} dB" for r in reaches))
    print("budget (reach 0's frames) | " + " | ".join(f"reach {r:g}" for r in reaches) +
          " | " + " | ".join(f"reach {r:g} interpolated" for r in reaches[1:]))
    for samples in counts:
        budget = median[(0.0, samples)]
        cells = []
        for r in reaches:
            fits = [s for s in counts if median[(r, s)] <= budget * 1.0001]
            cells.append(f"{mean[(r, max(fits))]:.2f} dB ({max(fits)})" if fits else "-")
        for r in reaches[1:]:
            quality_at = interpolated(budget, [(median[(r, s)], mean[(r, s)]) for s in counts])
            cells.append("-" if quality_at is None else f"{quality_at:.2f} dB")
        print(f"{budget:.3f} s | " + " | ".join(cells))


def interpolated(budget, frames):
    """The PSNR a reach would reach at CPU `budget`, linear in log(CPU) between its two frames
    around it (frames: (CPU, PSNR) by samples); None outside them. The frames' samples double,
    so a reach slower by 10% would otherwise get half the samples at every budget."""
    for (cost_lo, psnr_lo), (cost_hi, psnr_hi) in zip(frames, frames[1:]):
        if cost_lo <= budget <= cost_hi:
            t = np.log(budget / cost_lo) / np.log(cost_hi / cost_lo)
            return psnr_lo + t * (psnr_hi - psnr_lo)
    return None


def spread(ref, last, samples):
    """Where each reach's error lies at `samples`: the RMS of its seed-mean image's difference
    from the reference (what more seeds would not remove) and the RMS of its frames around that
    mean (the VPLs' noise; the unbiased spread over seeds)."""
    if len(next(iter(last.values()))) < 2:
        return
    target = np.asarray(ref, np.float64)[..., :3]
    cells = []
    for reach, frames in last.items():
        frames = np.asarray(frames, np.float64)
        mean = frames.mean(axis=0)
        noise = np.sqrt(((frames - mean) ** 2).sum(axis=0).mean() / (len(frames) - 1))
        cells.append(f"reach {reach:g}: mean error {np.sqrt(((mean - target) ** 2).mean()):.4f},"
                     f" seed spread {noise:.4f}")
    print(f"RMS over pixels at {samples} samples: " + "; ".join(cells))


if __name__ == "__main__":
    main()
