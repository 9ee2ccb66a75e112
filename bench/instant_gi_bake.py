"""INSTANT_GI lightmap bakes: VPL sets interleaved over the texels and filtered within UV charts
(issue 50, item 7; docs/baking.md) against the same VPLs gathered whole at every texel (one set
holding them all: what every texel did before), on the sun room's floor and back wall
(examples/scenes.sun_room, LightmapUV), indirect light only. Prints wall time of the bake (the
solve apart), the lightmap means against a path-traced bake of --reference samples, and the
relative RMS error per texel against it; then the interleaved bake with `--more` times the VPLs,
which costs about what the whole gather does.

    PYTHONPATH=build/python python3 bench/instant_gi_bake.py [--resolution 32] [--reference 1024]
"""
import argparse
import os
import sys
import tempfile
import time

import numpy as np

import shgi
from shgi import bake

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))
import scenes  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution", type=int, default=32)
    parser.add_argument("--reference", type=int, default=1024, help="path-traced samples")
    parser.add_argument("--photons", type=int, default=16, help="photons per set (4 x 4 sets)")
    parser.add_argument("--more", type=int, default=4, help="VPL factor of the last row")
    args = parser.parse_args()
    scene = scenes.sun_room(0.25, lightmap=True).scene
    scene.commit()
    index = {inst.name: i for i, inst in enumerate(scene.instances)}
    jobs = [bake.BakeJob(index[n], n, args.resolution, args.resolution) for n in ("floor", "back")]
    options = bake.BakeOptions(settings=shgi.LightmapSettings(samples=args.reference,
                                                              content="INDIRECT"))

    def run(field, samples):
        options.settings.samples = samples
        start = time.perf_counter()
        baked = bake.bake_scene(scene, jobs, options, tempfile.mkdtemp(), field)
        return baked, time.perf_counter() - start

    reference, seconds = run(None, args.reference)
    ref_means = [lm.color[lm.coverage > 0].mean() for lm in reference]
    print(f"path tracer, {args.reference} samples: {seconds:.2f} s; means floor "
          f"{ref_means[0]:.4f}, back {ref_means[1]:.4f}")
    print(f"{'field':44s} {'bake s':>7s} {'floor/PT':>9s} {'back/PT':>8s} {'rms floor':>10s} "
          f"{'rms back':>9s}")
    rows = [("4 x 4 sets, interleaved + filtered", 4, args.photons, "SH"),
            ("4 x 4 sets, each texel its own set", 4, args.photons, "NONE"),
            ("1 set, gathered whole (the same VPLs)", 1, 16 * args.photons, "SH"),
            (f"4 x 4 sets, interleaved, {args.more}x the VPLs", 4, args.more * args.photons, "SH")]
    for label, sets, photons, mode in rows:
        settings = shgi.default_settings("INSTANT_GI")
        settings.sets_x = settings.sets_y = sets
        settings.photons_per_set = photons
        settings.filter_mode = getattr(shgi.InstantGiFilter, mode)
        field = bake.solve_field(scene, "INSTANT_GI", settings=settings)
        baked, seconds = run(field, 1)
        ratios, errors = [], []
        for lm, ref, mean in zip(baked, reference, ref_means):
            covered = ref.coverage > 0
            ratios.append(lm.color[covered].mean() / mean)
            errors.append(np.sqrt(((lm.color - ref.color)[covered] ** 2).mean()) / mean)
        print(f"{label:44s} {seconds:7.2f} {ratios[0]:9.3f} {ratios[1]:8.3f} {errors[0]:10.3f} "
              f"{errors[1]:9.3f}")


if __name__ == "__main__":
    main()
