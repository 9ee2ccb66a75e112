#!/usr/bin/env python3
"""The probe grid's Visibility > Blur against its leak (docs/methods.md, "SH probe grids"):
examples/scenes.py's two_rooms (a 2000 W lamp behind a 0.1 m wall), native defaults but the
blur. The dim room's indirect diffuse light (DiffInd x DiffCol) over the path tracer's, read at
the first surface (6 passes, 16 spp) and through a final gather (probe bounces 2, 8 passes,
64 spp), as test_probe_grid.py reads them. A plain script printing a table.

    PYTHONPATH=build/python python3 bench/probe_visibility_blur.py [--blurs 0.15 0.10 0.05]
"""

import argparse
import pathlib
import sys

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)


def indirect(passes):
    return float((passes["DiffInd"] * passes["DiffCol"]).mean())


def dim_room(scene, reference, blur, final_gather):
    grid = shgi.ProbeGrid(scene, shgi.ProbeGridSettings(
        seed=5, visibility_blur=blur, **({"bounces": 2} if final_gather else {})))
    for _ in range(8 if final_gather else 6):
        grid.update()
    preview, _ = shgi.render_preview(scene, grid.field(), shgi.PreviewSettings(
        seed=5, **({"samples": 64, "final_gather": True} if final_gather else {})))
    return indirect(preview) / indirect(reference)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--blurs", type=float, nargs="+", default=[0.15, 0.10, 0.08, 0.05])
    parser.add_argument("--reference-spp", type=int, default=512)
    args = parser.parse_args()
    builder = scenes.two_rooms(0.5)
    builder.scene.commit()
    reference = shgi.render_path_traced(builder.scene, shgi.PathTracerSettings(
        samples=args.reference_spp, seed=11))
    print("| Blur (rad) | direct lookup | final gather |\n|---|---|---|")
    for blur in args.blurs:
        print(f"| {blur:.2f} | {dim_room(builder.scene, reference, blur, False):.3f} | "
              f"{dim_room(builder.scene, reference, blur, True):.3f} |", flush=True)


if __name__ == "__main__":
    main()
