#!/usr/bin/env python3
"""Where Instant GI's per-interleave-phase residual comes from (tests/python/test_instant_gi.py,
test_sh_filter_residual_per_interleave_phase_is_under_one_percent): the normal-mapped floor's
DiffInd through the SH filter (or `--mode`) against brute force (the same VPLs in one set), for
each solve seed, and averaged over the seeds. Set noise (sets weighed unevenly where the window
is cut) has a mean of zero over seeds and differs between the column phases; a bias of the
filter (a window blurring the light, or off centre where an edge cuts it) survives the average
and is the same in every column phase. Prints each seed's largest residual per phase, the
residuals of the seed-averaged images per phase (rows: y mod 4, columns: x mod 4), and the
seed-averaged images' ratio per image row. A plain script printing a table: not a test.

    PYTHONPATH=build/python python3 bench/instant_gi_phase_residual.py [--seeds 20 21 ... 35]
        [--mode SH|IRRADIANCE|STRICT|NONE] [--rows 16] [--gather-cut-windows]
        [--near-field-reach K]

Besides the largest residual per phase it prints its two parts: the mean over the 16 phases
(a bias of the whole image) and the largest departure of a phase from that mean (a pattern of
the phases: sets or rows showing through).
"""

import argparse
import pathlib
import sys

import numpy as np

import shgi

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "python"))
import test_instant_gi as floor_test  # noqa: E402  (the test's scene and settings)


def diffind(scene, seed, **fields):
    field = floor_test.solved(scene, passes=2, seed=seed, **fields).current_field()
    return floor_test.preview(scene, field, samples=4)["DiffInd"][..., :3].sum(-1)


def phase_residuals(image, brute):
    return np.array([[image[j::4, i::4].mean() / brute[j::4, i::4].mean() - 1.0
                      for i in range(4)] for j in range(4)])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=list(range(20, 36)))
    parser.add_argument("--mode", default="SH")
    parser.add_argument("--rows", type=int, default=16, help="image rows to print ratios of")
    parser.add_argument("--gather-cut-windows", action="store_true",
                        help="InstantGiSettings.gather_cut_windows on")
    parser.add_argument("--near-field-reach", type=float,
                        default=shgi.InstantGiSettings().near_field_reach,
                        help="InstantGiSettings.near_field_reach (default: the setting's)")
    args = parser.parse_args()
    scene = floor_test.normal_mapped_floor()
    images, brutes = [], []
    for seed in args.seeds:
        image = diffind(scene, seed, photons_per_set=32,
                        filter_mode=getattr(shgi.InstantGiFilter, args.mode),
                        gather_cut_windows=args.gather_cut_windows,
                        near_field_reach=args.near_field_reach)
        brute = diffind(scene, seed, photons_per_set=16 * 32, sets_x=1, sets_y=1,
                        filter_mode=shgi.InstantGiFilter.NONE)
        residuals = phase_residuals(image, brute)
        rmse = float(np.sqrt(((image - brute) ** 2).mean()) / brute.mean())
        print(f"seed {seed}: largest residual per phase {np.abs(residuals).max():.4f} (mean "
              f"{residuals.mean():+.4f}, pattern {np.abs(residuals - residuals.mean()).max():.4f}),"
              f" relative RMSE {rmse:.4f}")
        images.append(image)
        brutes.append(brute)
    image, brute = np.mean(images, axis=0), np.mean(brutes, axis=0)
    residuals = phase_residuals(image, brute)
    print(f"{args.mode}, mean over {len(args.seeds)} seeds: largest residual per phase "
          f"{np.abs(residuals).max():.4f}; per phase (rows y mod 4, columns x mod 4):")
    print(np.array2string(residuals, precision=4, suppress_small=True))
    ratios = image.mean(axis=1) / brute.mean(axis=1)
    print("per image row, mean over seeds:",
          " ".join(f"{y}:{r:.3f}" for y, r in enumerate(ratios[:args.rows])))


if __name__ == "__main__":
    main()
