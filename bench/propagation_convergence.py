#!/usr/bin/env python3
"""The light propagation volume against the path tracer as the steps grow, with the leak
corrections on (occlude_first_step, drop_outward_vpls: no compensation left), for the seed's
face-normal re-injection and for travel_reinjection (docs/methods.md, "Why the accumulation does
not converge"). Per scene, order and step count: DiffInd x DiffCol mean over the path tracer's
and the Combined PSNR (16-spp preview); for the Cornell box also its floor's and ceiling's
DiffInd over the reference's. The references are test_propagation.py's (the Cornell box and the
sun room at scale 0.25, 2048 spp; the two rooms at 0.5, 512 spp). A plain script printing a table.

    PYTHONPATH=build/python python3 bench/propagation_convergence.py [--steps 8 16 24 32]
        [--reference-spp 2048]
"""

import argparse
import pathlib
import sys

import numpy as np

import shgi
from shgi.metrics import psnr

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)
# The defaults before settings layout 6, which this bench's figures in docs/methods.md were
# measured with.
from propagation_lpv_sweep import SEED  # noqa: E402

SCENES = {"cornell_box": (0.25, 1.0), "sun_room": (0.25, 1.0), "two_rooms": (0.5, 0.25)}


def indirect(passes):
    return float((np.asarray(passes["DiffInd"]) * np.asarray(passes["DiffCol"])).mean())


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, nargs="+", default=[8, 16, 24, 32])
    parser.add_argument("--reference-spp", type=int, default=2048,
                        help="the two rooms get a quarter of it")
    args = parser.parse_args()
    print(f"{'scene':<12} {'order':>5} {'re-injection':<12} {'steps':>5} {'mean':>6} "
          f"{'PSNR':>6} {'floor':>6} {'ceiling':>7}")
    for name, (scale, spp_share) in SCENES.items():
        scene = getattr(scenes, name)(scale).scene
        scene.commit()
        ref = shgi.render_path_traced(scene, shgi.PathTracerSettings(
            samples=max(1, int(args.reference_spp * spp_share)), seed=11))
        normal_z = np.asarray(ref["Normal"])[..., 2]
        floor, ceiling = normal_z > 0.9, normal_z < -0.9
        ref_diff = np.asarray(ref["DiffInd"])
        for order in (1, 2):
            for travel in (False, True):
                for steps in args.steps:
                    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(seed=5, **dict(
                        SEED, order=order, steps=steps, occlude_first_step=True,
                        drop_outward_vpls=True, travel_reinjection=travel)))
                    volume.refine()
                    preview, _ = shgi.render_preview(scene, volume.current_field(),
                                                     shgi.PreviewSettings(seed=5))
                    row = (f"{name:<12} {order:>5} {'travel' if travel else 'face normal':<12} "
                           f"{steps:>5} {indirect(preview) / indirect(ref):>6.3f} "
                           f"{psnr(ref['Combined'], preview['Combined']):>6.2f}")
                    if name == "cornell_box":
                        diff = np.asarray(preview["DiffInd"])
                        row += (f" {diff[floor].mean() / ref_diff[floor].mean():>6.2f}"
                                f" {diff[ceiling].mean() / ref_diff[ceiling].mean():>7.2f}")
                    print(row, flush=True)


if __name__ == "__main__":
    main()
