#!/usr/bin/env python3
"""CPU seconds of one light propagation step at the defaults (unclamped, clamped at walls, travel
re-injection, occlusion from the first step) for the LPV and the HOLPV (its plain beams) at 32
and 64 cells along the Cornell box (33^3 and 65^3 cells with the volume's border), and with
--windowed the HOLPV's windowed re-injection (the default) too. CPU time, not wall time (the
machine is shared): a pass of `--long` steps less a pass of `--short` steps, over the difference,
so that tracing, injection and the geometry volume cancel; each pass best of `--repeats`; one
thread unless --threads says more.

    PYTHONPATH=build/python python3 bench/propagation_step_cost.py [--windowed]
"""

import argparse
import pathlib
import sys
import time

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)


def pass_cpu_seconds(scene, repeats, **settings):
    best = float("inf")
    for _ in range(repeats):
        start = time.process_time()
        volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(seed=5, **settings))
        volume.refine()
        best = min(best, time.process_time() - start)
    return best


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--short", type=int, default=2)
    parser.add_argument("--long", type=int, default=10)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--windowed", action="store_true")
    args = parser.parse_args()
    shgi.set_max_threads(args.threads)
    scene = scenes.cornell_box(0.25).scene
    scene.commit()
    variants = [("LPV", dict(order=1)), ("HOLPV", dict(order=2, windowed_reinjection=False))]
    if args.windowed:
        variants.append(("HOLPV windowed", dict(order=2, windowed_reinjection=True)))
    print(f"threads {shgi.max_threads()}, steps {args.long} - {args.short}, CPU s per step")
    for resolution in (32, 64):
        for label, settings in variants:
            seconds = [pass_cpu_seconds(scene, args.repeats, resolution=resolution, steps=steps,
                                        **settings) for steps in (args.short, args.long)]
            per_step = (seconds[1] - seconds[0]) / (args.long - args.short)
            print(f"{label:<15} {resolution + 1}^3 cells: {per_step:.4f} s a step "
                  f"(passes {seconds[0]:.2f} and {seconds[1]:.2f} s)", flush=True)


if __name__ == "__main__":
    main()
