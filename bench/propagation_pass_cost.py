#!/usr/bin/env python3
"""CPU seconds of one light propagation pass (tracing, injection, propagation; all threads, best
of 3 after a first pass) on the Cornell box at scale 0.25, for the defaults and the defaults
before settings layout 6 (SEED: 8 steps, rescaled, face-normal lobes), per order; with --steps N
both at N steps (the cost of the transfer alone). CPU time, not wall time: the machine is shared.

    PYTHONPATH=build/python python3 bench/propagation_pass_cost.py [--steps N]
"""

import argparse
import pathlib
import sys
import time

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)
from propagation_lpv_sweep import SEED  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=None)
    args = parser.parse_args()
    scene = scenes.cornell_box(0.25).scene
    scene.commit()
    for order in (1, 2):
        for name, settings in (("seed", SEED), ("defaults", {})):
            if args.steps is not None:
                settings = dict(settings, steps=args.steps)
            volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
                seed=5, order=order, **settings))
            volume.refine()
            best = float("inf")
            for _ in range(3):
                start = time.process_time()
                volume.refine()
                best = min(best, time.process_time() - start)
            steps = shgi.propagation_steps(volume.settings)
            print(f"order {order}, {name:<8} ({steps} steps): {best:.3f} CPU s a pass", flush=True)


if __name__ == "__main__":
    main()
