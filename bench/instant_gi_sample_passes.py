#!/usr/bin/env python3
"""Instant GI's new VPLs per sample (InstantGiSettings.passes_per_sample): for each
(passes, passes per sample) the sun room's Combined PSNR and DiffInd x DiffCol mean against the
path tracer's (the test's setting: scale 0.25, 2048 spp reference, seed 11; preview `--samples`,
16 by default) per solve seed, and the CPU times (getrusage of this process, median of
`--repeats`, seed 5's field) of the frame (render_preview), of the solve (every pass's refine,
as the Solve operator runs it) and of a first frame (that solve and a 1-sample frame: F12's
time to its first image when it solved every pass first; it now solves only the first sample's
passes first), each as a ratio to the first configuration's. A configuration
passes:per_sample[:light paths per set] (16 by default); `--filter-direct`,
`--glossy-from-vpls` and `--gather-cut-windows` solve with those settings on, and
`--near-field-reach K` with that reach. A plain script
printing a table: not a test.
The two rooms' dim room as test_instant_gi.py's dim room test reads it (128 light paths per
set):

    PYTHONPATH=build/python python3 bench/instant_gi_sample_passes.py [--scene sun_room]
        [--seeds 5 6 7 8 9 10 11 12] [--configs 4:4 64:4 16:1] [--repeats 5]
    PYTHONPATH=build/python python3 bench/instant_gi_sample_passes.py --scene two_rooms \
        --scale 0.5 --reference-samples 512 --seeds 5 6 7 8 --configs 4:4:128 64:4:128 64:4:32
"""

import argparse
import pathlib
import resource
import statistics
import sys

import numpy as np

import shgi
from shgi.metrics import psnr

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)


def cpu_seconds():
    usage = resource.getrusage(resource.RUSAGE_SELF)  # every thread of the process
    return usage.ru_utime + usage.ru_stime


def solve(scene, seed, passes, per_sample, paths=16, **fields):
    solver = shgi.InstantGi(scene, shgi.InstantGiSettings(
        seed=seed, passes_per_sample=per_sample, photons_per_set=paths, **fields))
    for _ in range(passes):
        solver.refine()
    return solver.current_field()


def frame(scene, field, samples=16):
    image, _ = shgi.render_preview(scene, field, shgi.PreviewSettings(seed=5, samples=samples))
    return image


def indirect_diffuse(passes):
    return float((passes["DiffInd"] * passes["DiffCol"]).mean())


def indirect_glossy(passes):
    return float((passes["GlossInd"] * passes["GlossCol"]).mean())


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="sun_room")
    parser.add_argument("--seeds", type=int, nargs="+", default=[5, 6, 7, 8, 9, 10, 11, 12])
    parser.add_argument("--configs", nargs="+", default=["4:4", "64:4", "16:1"],
                        help="passes:passes_per_sample")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--scale", type=float, default=0.25)
    parser.add_argument("--reference-samples", type=int, default=2048)
    parser.add_argument("--samples", type=int, default=16, help="the frame's samples")
    parser.add_argument("--filter-direct", action="store_true",
                        help="InstantGiSettings.filter_direct on")
    parser.add_argument("--glossy-from-vpls", action="store_true",
                        help="InstantGiSettings.glossy_from_vpls on")
    parser.add_argument("--gather-cut-windows", action="store_true",
                        help="InstantGiSettings.gather_cut_windows on")
    parser.add_argument("--near-field-reach", type=float, default=None,
                        help="InstantGiSettings.near_field_reach (default: the setting's)")
    args = parser.parse_args()
    builder = getattr(scenes, args.scene)(args.scale)
    builder.scene.commit()
    scene = builder.scene
    reference = shgi.render_path_traced(
        scene, shgi.PathTracerSettings(samples=args.reference_samples, seed=11))
    configs = [tuple(int(v) for v in c.split(":")) for c in args.configs]
    fields = {"filter_direct": args.filter_direct, "glossy_from_vpls": args.glossy_from_vpls,
              "gather_cut_windows": args.gather_cut_windows}
    if args.near_field_reach is not None:
        fields["near_field_reach"] = args.near_field_reach
    base = None
    for passes, per_sample, *paths in configs:
        paths = paths[0] if paths else 16
        qualities, ratios, glossy = [], [], []
        for seed in args.seeds:
            image = frame(scene, solve(scene, seed, passes, per_sample, paths, **fields),
                          args.samples)
            qualities.append(psnr(reference["Combined"], image["Combined"]))
            ratios.append(indirect_diffuse(image) / indirect_diffuse(reference))
            glossy.append(indirect_glossy(image) / indirect_glossy(reference))
        field = solve(scene, args.seeds[0], passes, per_sample, paths, **fields)
        times, solves, firsts = [], [], []
        for _ in range(args.repeats):
            start = cpu_seconds()
            frame(scene, field, args.samples)
            times.append(cpu_seconds() - start)
            start = cpu_seconds()
            first = solve(scene, args.seeds[0], passes, per_sample, paths, **fields)
            solves.append(cpu_seconds() - start)
            shgi.render_preview(scene, first, shgi.PreviewSettings(seed=5, samples=1))
            firsts.append(cpu_seconds() - start)
        seconds, solve_seconds, first_seconds = (statistics.median(t)
                                                 for t in (times, solves, firsts))
        base = base or (seconds, solve_seconds, first_seconds)
        print(f"{passes:3d} passes, {per_sample} per sample, {paths} paths per set: PSNR "
              f"{np.mean(qualities):.2f} dB ({min(qualities):.2f} to {max(qualities):.2f}), "
              f"DiffInd {np.mean(ratios):.3f} x, GlossInd {np.mean(glossy):.3f} x, "
              f"{field.vpl_count} VPLs, frame CPU "
              f"{seconds:.3f} s ({seconds / base[0]:.2f} x), solve CPU {solve_seconds:.3f} s "
              f"({solve_seconds / base[1]:.2f} x), first frame CPU {first_seconds:.3f} s "
              f"({first_seconds / base[2]:.2f} x)")


if __name__ == "__main__":
    main()
