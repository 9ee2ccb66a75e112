#!/usr/bin/env python3
"""The photon lattice against the path tracer at the same Light Paths > Glossy limit, in
examples/scenes.py's two_rooms (Principled plaster, Specular 0.5 by default): for each glossy
budget, the dim room's mean Combined and indirect diffuse light (DiffInd x DiffCol) of the
lattice read directly over the path tracer's. With --specular 0 the glossy lobes vanish and the
budget no longer matters. A plain script printing a table: benchmarks are not tests.

    PYTHONPATH=build/python python3 bench/lattice_glossy_budget.py [--specular 0.5]
        [--budgets 0,1,4] [--photons 1000000] [--resolution 32] [--reference-spp 256]
"""

import argparse
import pathlib
import sys

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--specular", type=float, default=None,
                        help="every material's Specular (default: the scene's own)")
    parser.add_argument("--budgets", default="0,1,4")
    parser.add_argument("--photons", type=int, default=1_000_000)
    parser.add_argument("--resolution", type=int, default=32)
    parser.add_argument("--reference-spp", type=int, default=256)
    parser.add_argument("--scale", type=float, default=0.5)
    args = parser.parse_args()

    builder = scenes.two_rooms(args.scale)
    if args.specular is not None:
        for material_id, material in enumerate(builder.scene.materials):
            material.specular = args.specular
            builder.scene.set_material(material_id, material)
    builder.scene.commit()
    scene = builder.scene

    print(f"two rooms at scale {args.scale}, Specular {args.specular or 'as built'}; "
          f"lattice {args.photons} photons, {args.resolution} cells, direct lookup; path tracer "
          f"{args.reference_spp} spp, Diffuse 4")
    print("glossy budget | path tracer Combined, indirect | lattice / path tracer (Combined, "
          "indirect)")
    for budget in (int(b) for b in args.budgets.split(",")):
        reference = shgi.render_path_traced(scene, shgi.PathTracerSettings(
            samples=args.reference_spp, seed=11, glossy_bounces=budget))
        lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(
            seed=5, photons=args.photons, resolution=args.resolution, max_bounces=4,
            glossy_bounces=budget))
        lattice.solve()
        preview, _ = shgi.render_preview(scene, lattice.current_field(),
                                         shgi.PreviewSettings(seed=5, samples=64))
        means = [(float(passes["Combined"][..., :3].mean()),
                  float((passes["DiffInd"] * passes["DiffCol"]).mean()))
                 for passes in (reference, preview)]
        print(f"{budget:13d} | {means[0][0]:.4f}, {means[0][1]:.4f} | "
              f"{means[1][0] / means[0][0]:.3f}, {means[1][1] / means[0][1]:.3f}", flush=True)


if __name__ == "__main__":
    main()
