#!/usr/bin/env python3
"""The photon lattice against the path tracer on the agreement tests' scenes
(tests/python/test_photon_lattice.py: Cornell box and sun room at scale 0.25, 2048 spp reference,
default lattice and preview settings, the same seeds): DiffInd x DiffCol's mean error, Combined
PSNR, and the glossy indirect light's ratio (GlossInd x GlossCol means), which the tests do not
print. References are kept in --cache between runs (the path tracer does not change). A plain
script printing a table: benchmarks are not tests.

    PYTHONPATH=build/python python3 bench/lattice_glossy_scenes.py [--cache /tmp/shgi_refs]
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


def scene_and_reference(name, cache):
    """The agreement tests' scene `name` at scale 0.25 and its 2048-spp path-traced PASSES, kept
    in the folder `cache` between runs (bench/instant_gi_glossy_horizon.py reads them too)."""
    builder = getattr(scenes, name)(0.25)
    builder.scene.commit()
    scene = builder.scene
    cache = pathlib.Path(cache)
    cache.mkdir(parents=True, exist_ok=True)
    path = cache / f"{name}_0.25_2048.npz"
    if not path.exists():
        passes = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=2048, seed=11))
        np.savez(path, **{p: passes[p] for p in PASSES})
    return scene, np.load(path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cache", default="/tmp/shgi_refs")
    args = parser.parse_args()
    for name in ("cornell_box", "sun_room"):
        scene, reference = scene_and_reference(name, args.cache)
        lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(seed=5))
        lattice.solve()
        preview, _ = shgi.render_preview(scene, lattice, shgi.PreviewSettings(seed=5))

        def ratio(a, b):
            return float((preview[a] * preview[b]).mean()) / float(
                (reference[a] * reference[b]).mean())
        print(f"{name}: DiffInd x DiffCol {100 * (ratio('DiffInd', 'DiffCol') - 1):+.1f}%, "
              f"Combined PSNR {psnr(reference['Combined'], preview['Combined']):.1f} dB, "
              f"GlossInd x GlossCol {ratio('GlossInd', 'GlossCol'):.3f}", flush=True)


if __name__ == "__main__":
    main()
