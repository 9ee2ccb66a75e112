#!/usr/bin/env python3
"""Light the propagation volume puts where none arrives (docs/methods.md, "Light propagation
volumes"): scenes whose exact indirect light in the camera's view is 0, so that whatever the
volume shows there crossed a wall.

- two rooms, only the bright lamp on: the dim room's light, against the dim room's own indirect
  light (only the dim lamp on, path traced);
- the sun room with its window shut (a plaster quad over it, sky off): the light inside,
  against the open sun room's indirect light (path traced).

Per order, with the seed's unoccluded first step, with occlude_first_step, with damping and
with drop_outward_vpls.
DiffInd x DiffCol means over the 16-spp preview. A plain script printing a table.

    PYTHONPATH=build/python python3 bench/propagation_leaks.py [--reference-spp 256]
"""

import argparse
import pathlib
import sys

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)
# The defaults before settings layout 6, which this bench's figures in docs/methods.md were
# measured with.
from propagation_lpv_sweep import SEED  # noqa: E402

VARIANTS = [("first step unoccluded", {}), ("occlude_first_step", {"occlude_first_step": True}),
            ("damping", {"damping": True}), ("drop_outward_vpls", {"drop_outward_vpls": True})]


def indirect(passes):
    return float((passes["DiffInd"] * passes["DiffCol"]).mean())


def committed(builder):
    builder.scene.commit()
    return builder.scene


def volume_indirect(scene, order, extra):
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(seed=5, order=order,
                                                                    **dict(SEED, **extra)))
    volume.refine()
    preview, _ = shgi.render_preview(scene, volume.current_field(), shgi.PreviewSettings(seed=5))
    return indirect(preview)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--reference-spp", type=int, default=256)
    args = parser.parse_args()
    traced = shgi.PathTracerSettings(samples=args.reference_spp, seed=11)
    cases = []
    own = indirect(shgi.render_path_traced(committed(scenes.two_rooms(0.5, bright_power=0.0)),
                                           traced))
    cases.append(("two rooms, bright lamp only", committed(scenes.two_rooms(0.5, dim_power=0.0)),
                  own))
    open_room = indirect(shgi.render_path_traced(committed(scenes.sun_room(0.25)), traced))
    shut = committed(scenes.sun_room(0.25, window_shut=True))
    shut_reference = indirect(shgi.render_path_traced(shut, traced))
    cases.append(("sun room, window shut", shut, open_room))
    print(f"shut sun room, path traced: {shut_reference / open_room:.4f} x the open room's")
    print("| scene | order | " + " | ".join(name for name, _ in VARIANTS) + " |")
    print("|---|---|" + "---|" * len(VARIANTS))
    for label, scene, against in cases:
        for order in (1, 2):
            figures = [volume_indirect(scene, order, extra) / against for _, extra in VARIANTS]
            print(f"| {label} | {'LPV' if order == 1 else 'HOLPV'} | " +
                  " | ".join(f"{f:.3f}" for f in figures) + " |", flush=True)


if __name__ == "__main__":
    main()
