#!/usr/bin/env python3
"""Instant GI's F12 with Final Gather off and on at equal CPU time, as the add-on renders it
(engine/render_job.RenderJob: the add-on's solve, with the field one diffuse bounce shallower
through a gather, its samples and its F12 denoiser; default settings otherwise).

Per scene, mode and sample count: the CPU seconds of the whole F12 (process time of this
process: solve, samples and denoise, every thread), the PSNR of the denoised Combined against a
path-traced reference (shgi.metrics.psnr: auto-exposure, sRGB), and the undenoised Combined and
DiffInd x DiffCol means over the reference's. Then, per gathered render, the PSNR of Final
Gather off at the same CPU seconds (interpolated in log CPU between the two renders around it):
the figures behind settings.FINAL_GATHER_DEFAULTS["INSTANT_GI"] (docs/methods.md). CPU seconds,
not wall time, so that the comparison holds on a loaded machine. A plain script printing
tables: benchmarks are not tests.

    PYTHONPATH=build/python python3 bench/instant_gi_final_gather.py
        [--scenes cornell_box sun_room two_rooms] [--scale 0.78125] [--spp 1 2 4 8 16 32 64]
        [--reference-spp 1024] [--cache build/instant_gi_gather_cache]

The default scale renders the sun room at 200 x 150 (the equal-time table's resolution), the
Cornell box at 200 x 200. References are cached as .npy under --cache (scene, scale, samples).
"""

import argparse
import math
import pathlib
import sys
import time

import numpy as np

import shgi
from shgi import metrics

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT / "addon"))
import scenes  # noqa: E402  (examples/scenes.py)
from shgi_blender import settings  # noqa: E402
from shgi_blender.engine import field_solvers  # noqa: E402
from shgi_blender.engine.render_job import RenderJob  # noqa: E402

REFERENCE_SEED = 7
SEED = 3


def reference(scene, name, args):
    """The path tracer's passes Combined, DiffInd and DiffCol at --reference-spp, cached."""
    cache = pathlib.Path(args.cache)
    cache.mkdir(parents=True, exist_ok=True)
    stem = f"{name}_{args.scale}_{args.reference_spp}"
    paths = {pass_name: cache / f"{stem}_{pass_name}.npy"
             for pass_name in ("Combined", "DiffInd", "DiffCol")}
    if not all(path.exists() for path in paths.values()):
        passes = shgi.render_path_traced(
            scene, shgi.PathTracerSettings(samples=args.reference_spp, seed=REFERENCE_SEED))
        for pass_name, path in paths.items():
            np.save(path, passes[pass_name])
    return {pass_name: np.load(path) for pass_name, path in paths.items()}


def render(scene, gather, spp):
    """(denoised Combined, undenoised passes, CPU seconds) of F12 with Final Gather `gather`."""
    props = settings.default_properties(shgi, method="INSTANT_GI")
    props.seed, props.samples = SEED, spp
    props.instant_gi.final_gather = gather
    start = time.process_time()
    job = RenderJob(shgi, scene, spp, preview_settings=settings.preview_settings(props, shgi),
                    solver_recipe=field_solvers.solver_recipe(props, shgi),
                    denoising=settings.denoising(props)).start()
    if not job.wait(3600) or job.error is not None:
        raise RuntimeError(f"final gather {gather}, {spp} spp: {job.error}")
    seconds = time.process_time() - start
    if getattr(job, "denoise_error", None) is not None:
        raise RuntimeError(f"not denoised: {job.denoise_error}")
    snapshot = job.last_snapshot()
    noisy = snapshot.passes.get("Noisy Image", snapshot.passes["Combined"])
    return snapshot.passes["Combined"], {**snapshot.passes, "Combined": noisy}, seconds


def at_seconds(runs, seconds):
    """PSNR of `runs` [(CPU seconds, PSNR)] at `seconds`, interpolated in log CPU; None outside
    their range."""
    runs = sorted(runs)
    for (s0, p0), (s1, p1) in zip(runs, runs[1:]):
        if s0 <= seconds <= s1:
            t = 0.0 if s1 == s0 else math.log(seconds / s0) / math.log(s1 / s0)
            return p0 + t * (p1 - p0)
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=["cornell_box", "sun_room", "two_rooms"])
    parser.add_argument("--scale", type=float, default=0.78125)
    parser.add_argument("--spp", type=int, nargs="+", default=[1, 2, 4, 8, 16, 32, 64])
    parser.add_argument("--reference-spp", type=int, default=1024)
    parser.add_argument("--cache", default=str(ROOT / "build" / "instant_gi_gather_cache"))
    args = parser.parse_args()
    summary = []
    print("| scene | final gather | spp | CPU s | PSNR denoised | Combined / reference | "
          "DiffInd x DiffCol / reference |")
    print("|---|---|---|---|---|---|---|")
    for name in args.scenes:
        scene = getattr(scenes, name)(args.scale).scene
        scene.commit()
        ref = reference(scene, name, args)
        ref_diffuse = float((ref["DiffInd"] * ref["DiffCol"]).mean())
        runs = {False: [], True: []}
        for gather in (False, True):
            for spp in args.spp:
                denoised, passes, seconds = render(scene, gather, spp)
                quality = metrics.psnr(ref["Combined"], denoised)
                runs[gather].append((seconds, quality))
                combined = passes["Combined"][..., :3].mean() / ref["Combined"][..., :3].mean()
                diffuse = float((passes["DiffInd"] * passes["DiffCol"]).mean()) / ref_diffuse
                print(f"| {name} | {'on' if gather else 'off'} | {spp} | {seconds:.2f} | "
                      f"{quality:.2f} | {combined:.3f} | {diffuse:.3f} |", flush=True)
        for (seconds, quality), spp in zip(runs[True], args.spp):
            off = at_seconds(runs[False], seconds)
            summary.append((name, spp, seconds, quality, off))
    print("\nEqual CPU: each gathered render against Final Gather off at its CPU seconds\n")
    print("| scene | spp (on) | CPU s | PSNR on | PSNR off at that CPU | on - off |")
    print("|---|---|---|---|---|---|")
    for name, spp, seconds, quality, off in summary:
        off_text, gain = ("-", "-") if off is None else (f"{off:.2f}", f"{quality - off:+.2f}")
        print(f"| {name} | {spp} | {seconds:.2f} | {quality:.2f} | {off_text} | {gain} |")


if __name__ == "__main__":
    main()
