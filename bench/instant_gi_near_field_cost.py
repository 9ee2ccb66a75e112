#!/usr/bin/env python3
"""CPU cost of Instant GI's near field (InstantGiSettings.near_field_reach): preview frames of
examples/scenes.py's `--scene` over one field per reach (64 passes at 4 per sample, seed 5),
the reaches' frames alternated `--repeats` times in this process, each frame's CPU time
(getrusage: every thread of the process), and per reach the median and its ratio to reach 0
(the paper's filter). A plain script printing a line: not a test; the machine's load shows.

    PYTHONPATH=build/python python3 bench/instant_gi_near_field_cost.py --scene cornell_box \
        [--resolution 640 360 | --scale 0.25] [--reaches 2 3 4] [--samples 4] [--repeats 2]
"""

import argparse
import pathlib
import resource
import statistics
import sys

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)


def cpu_seconds():
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="sun_room")
    parser.add_argument("--scale", type=float, default=1.0)
    parser.add_argument("--resolution", type=int, nargs=2, default=None,
                        help="the camera's resolution_x resolution_y (default: the scene's)")
    parser.add_argument("--reaches", type=float, nargs="+", default=[2.0, 3.0, 4.0])
    parser.add_argument("--passes", type=int, default=64)
    parser.add_argument("--samples", type=int, default=4)
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    builder = getattr(scenes, args.scene)(args.scale)
    if args.resolution:
        camera = builder.scene.camera
        camera.resolution_x, camera.resolution_y = args.resolution
        builder.scene.set_camera(camera)
    builder.scene.commit()
    scene = builder.scene
    fields = {}
    for reach in [0.0] + args.reaches:
        solver = shgi.InstantGi(scene, shgi.InstantGiSettings(seed=5, near_field_reach=reach))
        for _ in range(args.passes):
            solver.refine()
        fields[reach] = solver.current_field()
    times = {reach: [] for reach in fields}
    for _ in range(args.repeats):
        for reach, field in fields.items():
            start = cpu_seconds()
            shgi.render_preview(scene, field, shgi.PreviewSettings(seed=5, samples=args.samples))
            times[reach].append(cpu_seconds() - start)
    base = statistics.median(times[0.0])
    camera = scene.camera
    print(f"{args.scene} {camera.resolution_x} x {camera.resolution_y}, {args.samples} samples: " +
          ", ".join(f"reach {reach:g}: {statistics.median(t):.2f} s "
                    f"({statistics.median(t) / base:.2f} x)" for reach, t in times.items()))


if __name__ == "__main__":
    main()
