#!/usr/bin/env python3
"""Cost of one Instant GI frame (the INSTANT_GI method, seed 004) by stage at 640 x 360: a
progressive 1-spp preview frame of examples/scenes.py's Cornell box and sun room over the VPL
sets of `--passes` passes (the F12 default 4: 16 sets x 16 light paths per pass), every pass
(Combined, DiffInd, ...) summed. Per row: VPLs per set (what each pixel gathers), the solve's
stages per pass, and the medians over `--frames` frames of the renderer's primary, direct and
tile-indirect stages and the screen-space stage's gather (SH of the pixel's set with its shadow
rays), filter and shade. A plain script printing a table: benchmarks are not tests; the
machine's load shows in the figures.

    PYTHONPATH=build/python python3 bench/instant_gi_frame.py [--passes 4] [--frames 5]
"""

import argparse
import pathlib
import statistics
import sys

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--passes", type=int, default=4)
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--photons-per-set", type=int, default=16)
    parser.add_argument("--scenes", nargs="+", default=["cornell_box", "sun_room"])
    args = parser.parse_args()
    print(f"{'scene':12} {'VPLs/set':>8} {'solve/pass':>10} {'primary':>8} {'direct':>8} "
          f"{'tiles ind':>9} {'gather':>8} {'filter':>8} {'shade':>8} {'frame':>8}  (seconds)")
    for name in args.scenes:
        builder = getattr(scenes, name)(1.0)
        camera = builder.scene.camera
        camera.resolution_x, camera.resolution_y = 640, 360
        builder.scene.set_camera(camera)
        builder.scene.commit()
        scene = builder.scene
        solver = shgi.InstantGi(scene, shgi.InstantGiSettings(
            seed=1, photons_per_set=args.photons_per_set))
        solve = []
        for _ in range(args.passes):
            solver.refine()
            solve.append(sum(seconds for _, seconds in solver.stage_seconds))
        field = solver.current_field()
        rows = {key: [] for key in ("primary", "direct", "indirect", "gather", "filter",
                                    "shade", "total")}
        renderer = shgi.PreviewRenderer(scene, shgi.PreviewSettings(seed=1))
        for _ in range(args.frames):
            renderer.render(field, 1)
            timings = renderer.timings
            for key in ("primary", "direct", "indirect", "total"):
                rows[key].append(timings[key])
            for key, seconds in field.frame_timings.items():
                rows[key].append(seconds)
        med = {key: statistics.median(values) for key, values in rows.items()}
        per_set = field.vpl_count / len(field.set_sizes)
        print(f"{name:12} {per_set:8.0f} {statistics.median(solve):10.3f} {med['primary']:8.3f} "
              f"{med['direct']:8.3f} {med['indirect']:9.3f} {med['gather']:8.3f} "
              f"{med['filter']:8.3f} {med['shade']:8.3f} {med['total']:8.3f}")


if __name__ == "__main__":
    main()
