#!/usr/bin/env python3
"""Where a light propagation volume's indirect light lies against the path tracer's, by region
of one scene's image (docs/methods.md, "The sun room's floor"): the DiffInd x DiffCol mean over
the path tracer's in the whole image, on the floors out of the direct light (normals up, the
table's top among them), on the patch of the brightest direct light (more than half the image's
brightest DiffDir), on the walls out of it, and on the ceiling; with the Combined PSNR and, in
brackets, each region's share of the squared error of the displayed image that PSNR reads (the
regions overlap at none but leave out the pixels of other normals: edges, slanted faces). With
--one-bounce: the VPLs of the first hits only (vpl_bounces 1, no glossy VPLs) against the path
tracer with one diffuse bounce and no glossy one (1024 spp, cached beside the others).

The references are bench/propagation_lpv_sweep.py's (cached in --cache).

    PYTHONPATH=build/python python3 bench/propagation_regions.py [--scene sun_room]
        [--orders 1 2] [--configs fix fix_rescaled] [--set '{"damping": false}'] [--one-bounce]
"""

import argparse
import json
import pathlib

import numpy as np

import shgi
from shgi.metrics import auto_exposure, display, psnr
from propagation_lpv_sweep import CONFIGS, SCENES, reference


def regions(preview):
    """Boolean masks over the image, by the preview's normals and direct light."""
    n = preview["Normal"][..., :3]
    direct = preview["DiffDir"][..., :3].mean(-1)
    patch = direct > 0.5 * direct.max()
    return {"all": np.ones_like(patch), "shaded floor": (n[..., 2] > 0.9) & ~patch,
            "patch": patch, "walls": (np.abs(n[..., 2]) < 0.1) & ~patch,
            "ceiling": n[..., 2] < -0.9}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="sun_room", choices=list(SCENES))
    parser.add_argument("--orders", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--configs", nargs="+", default=["fix", "fix_per_transfer",
                                                         "fix_rescaled"])
    parser.add_argument("--set", default="{}", help="PropagationSettings fields, as JSON")
    parser.add_argument("--cache", type=pathlib.Path, default=pathlib.Path("/tmp/shgi_lpv_refs"))
    parser.add_argument("--one-bounce", action="store_true")
    args = parser.parse_args()
    scene, ref = reference(args.scene, args.cache)
    if args.one_bounce:
        path = args.cache / f"{args.scene}_{SCENES[args.scene][0]}_1024_one_bounce.npz"
        if not path.exists():
            traced = shgi.render_path_traced(scene, shgi.PathTracerSettings(
                samples=1024, seed=11, diffuse_bounces=1, glossy_bounces=0))
            np.savez(path, **{key: np.asarray(traced[key])
                              for key in ("Combined", "DiffInd", "DiffCol")})
        ref = dict(np.load(path))
    exact = (ref["DiffInd"][..., :3] * ref["DiffCol"][..., :3]).mean(-1)
    for config in args.configs:
        for order in args.orders:
            settings = dict(CONFIGS[config], **json.loads(args.set))
            if args.one_bounce:
                settings.update(vpl_bounces=1, glossy_vpls=False)
                settings.pop("glossy_bounces", None)
            volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
                seed=5, order=order, **settings))
            volume.refine()
            preview, _ = shgi.render_preview(scene, volume.current_field(),
                                             shgi.PreviewSettings(seed=5))
            preview = {key: np.asarray(preview[key]) for key in
                       ("Combined", "DiffInd", "DiffCol", "DiffDir", "Normal")}
            ind = (preview["DiffInd"][..., :3] * preview["DiffCol"][..., :3]).mean(-1)
            exposure = auto_exposure(ref["Combined"])
            shown = (display(preview["Combined"], exposure)
                     - display(ref["Combined"], exposure)) ** 2
            row = (f"{config:<22} order {order}: "
                   f"{psnr(ref['Combined'], preview['Combined']):5.2f} dB;")
            for label, mask in regions(preview).items():
                row += (f"  {label} {ind[mask].mean() / exact[mask].mean():.3f}"
                        f" [{shown[mask].sum() / shown.sum():.2f}]")
            print(row, flush=True)


if __name__ == "__main__":
    main()
