#!/usr/bin/env python3
"""Cost of one light propagation step (the PROPAGATION method, seed 003 Table 5.1's
"propagation" per frame) for the LPV (order 1: 6 directions, L1) and the HOLPV (order 2: 26
directions, L2) at 32 and 64 cells along the longest side of examples/scenes.py's Cornell box
(a cube: 33^3 and 65^3 cells with the one-cell border the volume adds around its geometry
lattice). Per row: the median seconds of the steps with occlusion (2..N), the first step's
(no occlusion), and the other stages of the pass. A plain script printing a table: benchmarks
are not tests; the machine's load shows in the figures.

    PYTHONPATH=build/python python3 bench/propagation_steps.py [--steps 8] [--photons 100000]
"""

import argparse
import pathlib
import statistics
import sys

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)
# The defaults before settings layout 6, which this bench's figures in docs/methods.md were
# measured with.
from propagation_lpv_sweep import SEED  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=8)
    parser.add_argument("--photons", type=int, default=100_000)
    parser.add_argument("--threads", type=int, default=0, help="0: all cores")
    args = parser.parse_args()
    if args.threads:
        shgi.set_max_threads(args.threads)
    scene = scenes.cornell_box(0.25).scene
    scene.commit()
    print(f"threads {shgi.max_threads()}, {args.steps} steps, {args.photons} light paths")
    print(f"{'method':<6} {'cells':>6} {'step (s)':>9} {'step 1 (s)':>10} {'trace':>7} "
          f"{'inject':>7} {'geometry':>8}")
    for resolution in (32, 64):
        for order, name in ((1, "LPV"), (2, "HOLPV")):
            volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(**dict(
                SEED, order=order, resolution=resolution, steps=args.steps,
                photons=args.photons)))
            volume.refine()
            stages = dict(volume.stage_seconds)
            steps = [stages[f"propagation_step_{k}"] for k in range(1, args.steps + 1)]
            occluded = statistics.median(steps[1:]) if len(steps) > 1 else float("nan")
            print(f"{name:<6} {resolution:>6} {occluded:>9.4f} {steps[0]:>10.4f} "
                  f"{stages['vpl_trace'] + stages.get('vpl_reflect', 0.0):>7.3f} "
                  f"{stages['injection']:>7.3f} {stages['geometry_volume']:>8.3f}")


if __name__ == "__main__":
    main()
