#!/usr/bin/env python3
"""Instant GI's glossy light against the path tracer, read from the L2 SH and from the VPLs
(glossy_from_vpls), on the agreement tests' Cornell box and sun room (scale 0.25, 2048-spp
references as bench/lattice_glossy_scenes.py keeps them in --cache; default solve, 16-spp
preview, seed 5): DiffInd x DiffCol and GlossInd x GlossCol means over the path tracer's and
Combined PSNR. A pixel's SH holds light from above its surface only; docs/methods.md ("Instant
GI's glossy light at the horizon") has the figures before and after the lobes read it clipped at
the horizon.

    PYTHONPATH=build/python python3 bench/instant_gi_glossy_horizon.py [--cache /tmp/shgi_refs]
"""

import argparse
import pathlib
import sys

import numpy as np

import shgi
from shgi.metrics import psnr

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)

PASSES = ("Combined", "DiffInd", "DiffCol", "GlossInd", "GlossCol")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cache", default="/tmp/shgi_refs")
    args = parser.parse_args()
    cache = pathlib.Path(args.cache)
    cache.mkdir(parents=True, exist_ok=True)
    for name in ("cornell_box", "sun_room"):
        builder = getattr(scenes, name)(0.25)
        builder.scene.commit()
        scene = builder.scene
        path = cache / f"{name}_0.25_2048.npz"
        if not path.exists():
            passes = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=2048, seed=11))
            np.savez(path, **{p: passes[p] for p in PASSES})
        reference = np.load(path)
        for from_vpls in (False, True):
            solver = shgi.InstantGi(scene, shgi.InstantGiSettings(seed=5,
                                                                  glossy_from_vpls=from_vpls))
            for _ in range(4):
                solver.refine()
            preview, _ = shgi.render_preview(scene, solver.current_field(),
                                             shgi.PreviewSettings(seed=5))

            def ratio(a, b):
                return float((preview[a] * preview[b]).mean()) / float(
                    (reference[a] * reference[b]).mean())
            print(f"{name:12s} glossy_from_vpls={from_vpls!s:5s} DiffInd x DiffCol "
                  f"{ratio('DiffInd', 'DiffCol'):.3f}, GlossInd x GlossCol "
                  f"{ratio('GlossInd', 'GlossCol'):.3f}, Combined PSNR "
                  f"{psnr(reference['Combined'], preview['Combined']):.2f} dB", flush=True)


if __name__ == "__main__":
    main()
