#!/usr/bin/env python3
"""Next-event estimation among lights of very different reach: the path tracer in the dim room of
examples/scenes.py's two_rooms (a 2000 W lamp behind a 0.1 m wall, a 20 W lamp in the room the
camera sees). Prints, per sample count, the frame's time and its RMSE against a high-sample
reference of the same build, relative to the reference's mean, and the RMSE scaled to the time
of the first row (RMSE ~ 1/sqrt(time)): the figure to compare between light selection schemes.
A plain script printing a table: benchmarks are not tests.

    PYTHONPATH=build/python python3 bench/two_rooms_nee.py [--reference-spp 1024] [--spp 4 16 64]
"""

import argparse
import pathlib
import sys
import time

import numpy as np

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)


def combined(scene, samples, seed):
    start = time.perf_counter()
    passes = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=samples, seed=seed))
    return passes["Combined"][..., :3], time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reference-spp", type=int, default=1024)
    parser.add_argument("--spp", type=int, nargs="+", default=[4, 16, 64])
    args = parser.parse_args()
    scene = scenes.two_rooms().scene
    scene.commit()
    reference, seconds = combined(scene, args.reference_spp, seed=99)
    print(f"reference: {args.reference_spp} spp in {seconds:.2f} s, mean {reference.mean():.4f}")
    print(f"{'spp':>5} {'seconds':>8} {'rel. RMSE':>10} {'at equal time':>14}")
    first_time = None
    for spp in args.spp:
        image, seconds = combined(scene, spp, seed=1)
        rmse = float(np.sqrt(np.mean((image - reference) ** 2))) / float(reference.mean())
        first_time = first_time or seconds
        print(f"{spp:5d} {seconds:8.3f} {rmse:10.3f} {rmse * np.sqrt(seconds / first_time):14.3f}")


if __name__ == "__main__":
    main()
