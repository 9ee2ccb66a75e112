#!/usr/bin/env python3
"""Next-event estimation among lights of very different reach: the path tracer in the dim room of
examples/scenes.py's two_rooms (a 2000 W lamp behind a 0.1 m wall, a 20 W lamp in the room the
camera sees). Prints, per light-split setting (PathTracerSettings.light_splits: 1 is one
emitter per shadow ray, more lets the light tree sample one emitter per node of its cut) and
sample count, the frame's time and its RMSE against a high-sample reference of the same build
(rendered with the default splitting), relative to the reference's mean, and the RMSE scaled to
the time of the table's first row (RMSE ~ 1/sqrt(time)): the figure to compare between light
selection schemes at equal time. A plain script printing a table: benchmarks are not tests.

    PYTHONPATH=build/python python3 bench/two_rooms_nee.py [--reference-spp 1024] [--spp 4 16 64]
        [--splits 1 4] [--scale 1]
"""

import argparse
import pathlib
import sys
import time

import numpy as np

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)


def combined(scene, samples, seed, splits=None):
    settings = shgi.PathTracerSettings(samples=samples, seed=seed)
    if splits is not None:
        settings.light_splits = splits
    start = time.perf_counter()
    passes = shgi.render_path_traced(scene, settings)
    return passes["Combined"][..., :3], time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reference-spp", type=int, default=1024)
    parser.add_argument("--spp", type=int, nargs="+", default=[4, 16, 64])
    parser.add_argument("--splits", type=int, nargs="+", default=[1, 4])
    parser.add_argument("--scale", type=float, default=1.0, help="of the 128 x 96 frame")
    args = parser.parse_args()
    scene = scenes.two_rooms(scale=args.scale).scene
    scene.commit()
    reference, seconds = combined(scene, args.reference_spp, seed=99)
    print(f"reference: {args.reference_spp} spp in {seconds:.2f} s, mean {reference.mean():.4f}")
    print(f"{'splits':>6} {'spp':>5} {'seconds':>8} {'rel. RMSE':>10} {'at equal time':>14}")
    first_time = None
    for splits in args.splits:
        for spp in args.spp:
            image, seconds = combined(scene, spp, seed=1, splits=splits)
            rmse = float(np.sqrt(np.mean((image - reference) ** 2))) / float(reference.mean())
            first_time = first_time or seconds
            print(f"{splits:6d} {spp:5d} {seconds:8.3f} {rmse:10.3f} "
                  f"{rmse * np.sqrt(seconds / first_time):14.3f}")


if __name__ == "__main__":
    main()
