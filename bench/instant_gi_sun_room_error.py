#!/usr/bin/env python3
"""Where the sun room's Instant GI error is (issue 50's PSNR >= 32 dB): the test's setting (the
sun room at scale 0.25, 64 x 48 px; the path tracer at 2048 spp, seed 11; Instant GI with the
default settings, 4 passes, preview 16 spp), solved with `--seeds`; `--passes` and
`--passes-per-sample` solve more passes than one sample gathers (each sample new VPLs). Per row:
the Combined PSNR, then per light pass (DiffDir, DiffInd, GlossDir, GlossInd, each the pass x
its colour) its mean against the path tracer's and the PSNR of the image with that pass
replaced by the path tracer's: the gain is that pass's share of the error. A second
path-traced image (seed 12) gives the reference's own noise. A plain script printing a table:
not a test.

    PYTHONPATH=build/python python3 bench/instant_gi_sun_room_error.py [--seeds 5 6 7 8]
        [--samples 16] [--photons-per-set 16] [--passes 4] [--passes-per-sample 4]
"""

import argparse
import pathlib
import sys

import numpy as np

import shgi
from shgi.metrics import psnr

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)

LIGHTS = ("DiffDir", "DiffInd", "GlossDir", "GlossInd")


def light(passes, name):
    return np.asarray(passes[name])[..., :3] * np.asarray(passes[name[:-3] + "Col"])[..., :3]


def row(label, reference, image):
    cells = [f"{label:>14}", f"{psnr(reference['Combined'], image['Combined']):6.2f}"]
    for name in LIGHTS:
        swapped = np.asarray(image["Combined"])[..., :3] - light(image, name) + light(reference,
                                                                                     name)
        mean = light(image, name).mean() / light(reference, name).mean()
        cells.append(f"{mean:6.3f} x {psnr(reference['Combined'], swapped):6.2f}")
    return " | ".join(cells)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[5, 6, 7, 8])
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--photons-per-set", type=int, default=16)
    parser.add_argument("--passes", type=int, default=4)
    parser.add_argument("--passes-per-sample", type=int, default=4)
    args = parser.parse_args()
    builder = scenes.sun_room(0.25)
    builder.scene.commit()
    scene = builder.scene
    reference = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=2048, seed=11))
    print(" " * 14 + " | PSNR   | " + " | ".join(f"{n:>8}: mean, swapped" for n in LIGHTS))
    print(row("path tracer 12", reference,
              shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=2048, seed=12))))
    for seed in args.seeds:
        solver = shgi.InstantGi(scene, shgi.InstantGiSettings(
            seed=seed, photons_per_set=args.photons_per_set,
            passes_per_sample=args.passes_per_sample))
        for _ in range(args.passes):
            solver.refine()
        image, _ = shgi.render_preview(scene, solver.current_field(),
                                       shgi.PreviewSettings(seed=5, samples=args.samples))
        print(row(f"seed {seed}", reference, image))


if __name__ == "__main__":
    main()
