#!/usr/bin/env python3
"""Instant GI's glossy light against the path tracer, read from the L2 SH and from the VPLs
(glossy_from_vpls), on the agreement tests' Cornell box and sun room (scale 0.25, 2048-spp
references kept in --cache as bench/lattice_glossy_scenes.py keeps them; default solve, 16-spp
preview, seed 5): DiffInd x DiffCol and GlossInd x GlossCol means over the path tracer's and
Combined PSNR. A pixel's SH holds light from above its surface only; docs/methods.md ("Instant
GI's glossy light at the horizon") has the figures before and after the lobes read it clipped at
the horizon.

    PYTHONPATH=build/python python3 bench/instant_gi_glossy_horizon.py [--cache /tmp/shgi_refs]
"""

import argparse

import shgi
from lattice_glossy_scenes import scene_and_reference  # bench/ (the script's own folder)
from shgi.metrics import psnr


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cache", default="/tmp/shgi_refs")
    args = parser.parse_args()
    for name in ("cornell_box", "sun_room"):
        scene, reference = scene_and_reference(name, args.cache)
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
