#!/usr/bin/env python3
"""Light propagation cascades on examples/scenes.py's hall (32 x 8 x 4 m), against single
volumes (docs/methods.md, "Cascades"). Per order and configuration: the pass's seconds per level
(injection, geometry volume of the reset, all propagation steps), the solver's memory and its
estimate, the field's irradiance along the floor (y = 0.3, every 0.05 m) near the camera
(|x + 4| < 2.5) against one volume of the finest level's cells over the whole hall, far from it
(|x + 4| > 9) against the single coarsest volume, and the seam: the steepest relative change per
0.05 m where the field is neither level alone (the blend bands). A plain script printing a table.

    PYTHONPATH=build/python python3 bench/propagation_cascades.py [--steps 8] [--photons 100000]
"""

import argparse
import pathlib
import sys
import time

import numpy as np

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)
# The defaults before settings layout 6, which this bench's figures in docs/methods.md were
# measured with.
from propagation_lpv_sweep import SEED  # noqa: E402

CENTER = (-4.0, 0.0, 1.5)


def solve(scene, **settings):
    start = time.perf_counter()
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(seed=3, **dict(SEED,
                                                                                  **settings)))
    volume.refine()
    return volume, time.perf_counter() - start


def per_level(stage_seconds):
    """{level: (injection, geometry volume, propagation)} seconds ('' for a single volume)."""
    levels = {}
    for name, seconds in stage_seconds:
        if name.startswith("vpl_"):
            continue
        level = name.split("_")[1] if name.startswith("level_") else "-"
        stage = name.split("_", 2)[2] if name.startswith("level_") else name
        entry = levels.setdefault(level, [0.0, 0.0, 0.0])
        index = 0 if stage == "injection" else 1 if stage == "geometry_volume" else 2
        entry[index] += seconds
    return levels


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=8)
    parser.add_argument("--photons", type=int, default=100000)
    args = parser.parse_args()
    scene = scenes.hall()
    scene.scene.commit()
    scene = scene.scene
    xs = np.arange(-15.5, 15.5, 0.05)
    points = np.stack([xs, np.full_like(xs, 0.3), np.zeros_like(xs)], 1).astype(np.float32)
    normals = np.tile(np.float32([0, 0, 1]), (len(xs), 1))
    near, far = np.abs(xs - CENTER[0]) < 2.5, np.abs(xs - CENTER[0]) > 9.0
    common = dict(steps=args.steps, photons=args.photons)
    for order in (1, 2):
        print(f"order {order} ({'LPV' if order == 1 else 'HOLPV'}), {args.steps} steps")
        print(f"  {'configuration':<26} {'seconds':>7} {'MB':>6} {'est. MB':>7} "
              f"{'near err':>9} {'far err':>8} {'seam':>6}  per level: inject/geometry/steps s")
        for resolution, cascades in ((32, 1), (64, 1), (128, 1), (32, 2), (32, 3)):
            settings = dict(common, order=order, resolution=resolution, cascades=cascades,
                            cascade_center=CENTER, cascade_follow_camera=False)
            volume, seconds = solve(scene, **settings)
            field = volume.current_field()
            finest = resolution * 2 ** (cascades - 1)
            fine, _ = solve(scene, **dict(common, order=order, resolution=finest))
            coarse, _ = solve(scene, **dict(common, order=order, resolution=resolution))
            e, e_fine, e_coarse = (f.irradiance(points, normals)[:, :3].mean(1) for f in (
                field, fine.current_field(), coarse.current_field()))
            near_err = np.max(np.abs(e[near] / e_fine[near] - 1))
            far_err = np.max(np.abs(e[far] / e_coarse[far] - 1))
            alone = [field.level_field(k).irradiance(points, normals)[:, :3].mean(1)
                     for k in range(field.level_count)]
            blended = np.all([e != a for a in alone], axis=0)
            band = blended[1:] | blended[:-1]
            steps = np.abs(np.diff(e)) / (0.5 * (e[1:] + e[:-1]))
            seam = f"{steps[band].max():.4f}" if band.any() else "-"
            estimate = shgi.PropagationVolume.estimate_memory_bytes(
                scene, shgi.PropagationSettings(**dict(SEED, **settings)))
            levels = "  ".join(f"{k}: {a:.3f}/{b:.3f}/{c:.3f}"
                               for k, (a, b, c) in per_level(volume.stage_seconds).items())
            name = f"res {resolution}" + (f", {cascades} cascades" if cascades > 1 else "")
            print(f"  {name:<26} {seconds:7.2f} {volume.memory_bytes / 1e6:6.1f} "
                  f"{estimate / 1e6:7.1f} {near_err:9.2e} {far_err:8.2e} {seam:>6}  {levels}")


if __name__ == "__main__":
    main()
