"""Each field method's preview on test_instant_gi.py's normal-mapped floor against the path
tracer: the floor's indirect diffuse light (DiffInd), with and without its normal map, from
every registered field method at its default settings (Instant GI also as brute force: one set
of VPLs, unfiltered), over the path tracer's, on the floor's pixels (mask from the flat floor's
Normal pass).

A field's diffuse light is its SH radiance through the pixel's diffuse lobe; where a normal map
bent the lobe's normal, the lobe's bump shadowing toward each direction is part of it
(render/bump_irradiance.h), as the path tracer applies it toward each light. The ratio with the
map over the ratio without shows what the normal map alone changes.

    PYTHONPATH=build/python python3 bench/normal_map_field_gather.py [--samples N]
        [--methods INSTANT_GI,PHOTON_LATTICE,...] [--passes 4]
"""

import argparse
import sys
from pathlib import Path

import shgi

sys.path.insert(0, str(Path(__file__).resolve().parent))
import normal_map_particle_flux as flux  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "python"))
import test_instant_gi as floor_test  # noqa: E402

METHODS = ("INSTANT_GI", "INSTANT_GI_BRUTE_FORCE", "PHOTON_LATTICE", "PROBE_GRID",
           "RADIANCE_FIELD", "PROPAGATION")


def field(method, scene, passes):
    if method == "INSTANT_GI_BRUTE_FORCE":
        return floor_test.solved(scene, passes=passes, photons_per_set=16 * 64, sets_x=1,
                                 sets_y=1, filter_mode=shgi.InstantGiFilter.NONE).current_field()
    solver = shgi.make_solver(method, scene, shgi.method(method).settings_type(seed=5))
    for _ in range(passes):
        solver.refine()
    return solver.current_field()


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=256)
    parser.add_argument("--passes", type=int, default=4)
    parser.add_argument("--methods", default=",".join(METHODS))
    args = parser.parse_args()
    ratios = {}
    floor = None
    for normal_map in (False, True):
        scene = flux.floor_scene(normal_map)
        reference = shgi.render_path_traced(
            scene, shgi.PathTracerSettings(samples=args.samples, seed=11))
        if floor is None:
            floor = reference["Normal"][..., 2] > 0.9
        path = reference["DiffInd"][..., :3][floor].mean()
        for method in args.methods.split(","):
            image = floor_test.preview(scene, field(method, scene, args.passes), samples=4)
            ratios[method, normal_map] = image["DiffInd"][..., :3][floor].mean() / path
    for method in args.methods.split(","):
        flat, bumped = ratios[method, False], ratios[method, True]
        print(f"{method:24s} floor DiffInd / path tracer: flat {flat:.4f}, normal map "
              f"{bumped:.4f} ({bumped / flat:.4f} x flat)")


if __name__ == "__main__":
    main()
