#!/usr/bin/env python3
"""Where a light propagation volume's displayed error lies, and what a changed radiance scale
would give (docs/methods.md, "Closed rooms: the furnace").

- Per configuration and order (default: the two rooms), the Combined PSNR against the path
  tracer, and the PSNR with one region of the image replaced by the path tracer's: the patch of
  the brightest direct light (more than half the image's brightest DiffDir), then the other
  pixels by their distance to the nearest edge of the image's surfaces (1-2, 3-4, 5 or more
  pixels; bench/propagation_surface_error.py's edges).
- With --scale f, the indirect diffuse light scaled after rendering (Combined + (f - 1) DiffInd x
  DiffCol: exact for the mean, the PSNR as if the volume's radiance scale were f times its own),
  on all three scenes: the mean over the path tracer's and the PSNR.

The references are bench/propagation_lpv_sweep.py's (cached in --cache).

    PYTHONPATH=build/python python3 bench/propagation_error_budget.py [--scenes two_rooms]
        [--orders 1 2] [--set '{"extend_to_bounds": true}'] [--scale 0.778]
"""

import argparse
import json
import pathlib

import numpy as np

import shgi
from shgi.metrics import psnr
from propagation_lpv_sweep import SCENES, reference
from propagation_surface_error import edge_distance


def render(name, order, settings, cache):
    scene, ref = reference(name, cache)
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(seed=5, order=order,
                                                                    **settings))
    volume.refine()
    preview, _ = shgi.render_preview(scene, volume.current_field(), shgi.PreviewSettings(seed=5))
    return ref, {key: np.asarray(preview[key]) for key in
                 ("Combined", "DiffInd", "DiffCol", "DiffDir", "Normal")}


def budget_row(ref, preview):
    """The PSNR, and the PSNR with each region replaced by the reference's."""
    distance = edge_distance(preview["Normal"][..., :3])
    direct = preview["DiffDir"][..., :3].mean(-1)
    patch = direct > 0.5 * direct.max()
    regions = {"patch": patch, "1-2 px": (distance <= 2) & ~patch,
               "3-4 px": (distance > 2) & (distance < 5) & ~patch, "5+ px": (distance >= 5) & ~patch}
    row = f"{psnr(ref['Combined'], preview['Combined']):.2f} dB; region exact:"
    for label, mask in regions.items():
        fixed = preview["Combined"].copy()
        fixed[mask, :3] = ref["Combined"][mask, :3]
        row += f"  {label} ({mask.mean():.2f} of the pixels) {psnr(ref['Combined'], fixed):.2f}"
    return row


def scaled_row(ref, preview, scale):
    """The mean over the path tracer's and the PSNR with the indirect diffuse light x scale."""
    indirect = preview["DiffInd"][..., :3] * preview["DiffCol"][..., :3]
    exact = ref["DiffInd"][..., :3] * ref["DiffCol"][..., :3]
    combined = preview["Combined"].copy()
    combined[..., :3] += (scale - 1.0) * indirect
    return f"{scale * indirect.mean() / exact.mean():.3f} {psnr(ref['Combined'], combined):.2f} dB"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=None)
    parser.add_argument("--orders", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--set", default="{}", help="PropagationSettings fields, as JSON")
    parser.add_argument("--scale", type=float, default=None)
    parser.add_argument("--cache", type=pathlib.Path, default=pathlib.Path("/tmp/shgi_lpv_refs"))
    args = parser.parse_args()
    settings = json.loads(args.set)
    names = args.scenes or (list(SCENES) if args.scale is not None else ["two_rooms"])
    for order in args.orders:
        for name in names:
            ref, preview = render(name, order, settings, args.cache)
            row = (scaled_row(ref, preview, args.scale) if args.scale is not None
                   else budget_row(ref, preview))
            print(f"order {order} {name} {args.set}: {row}", flush=True)


if __name__ == "__main__":
    main()
