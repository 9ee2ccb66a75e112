#!/usr/bin/env python3
"""The light propagation volume in closed rooms with an exact answer (docs/methods.md, "Closed
rooms: the furnace").

- The furnace: a closed box whose six walls all emit radiance Le = 1 and reflect diffusely
  (Lambert, albedo rho, no specular). Every wall point sees only walls, so its irradiance is
  pi Le, and the light the VPLs carry (hits 1 ... vpl_bounces) gives every wall point the same
  indirect irradiance pi Le (rho + ... + rho^B). The field's irradiance over that, per order and
  configuration, on a grid over all six walls: the area mean, and the mean by distance from the
  nearest edge of the wall, in cells (0-0.5, 0.5-1, 1-2, 2-4, 4 and more). Exact light is 1 in
  every band; a ramp from the edges in is the method's, not the room's.
- With --materials: a closed room lit by a point lamp 0.5 m under its ceiling (the two rooms'
  dim room alone), walls Lambert (albedo 0.73, no specular), Lambert with the Principled BSDF's
  default Specular 0.5 on top, or the scenes' Principled plaster of the same base colour:
  DiffInd x DiffCol means of the path tracer and of the preview over each order's field, and
  their ratios.

    PYTHONPATH=build/python python3 bench/propagation_furnace.py [--dims 3 3 2.5]
        [--resolution 16] [--configs NAME ...] [--materials] [--set JSON]

settled_room_excess()'s table (propagation_volume.h): --set '{"distance": 96,
"extend_to_bounds": true}' --configs defaults plain linear plain_linear per_transfer
plain_per_transfer, and with "unclamped_transfer": false for the clamped-then-rescaled rows.
"""

import argparse
import json
import pathlib
import sys

import numpy as np

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
from scenes import closed_room, room_wall_points  # noqa: E402  (examples/scenes.py)

# Configurations on top of PropagationSettings' defaults.
CONFIGS = {
    "defaults": {},
    # The HOLPV's beams unwindowed (the default until 2026-11-29; the LPV is unchanged).
    "plain": {"windowed_reinjection": False},
    # Light carried far enough for the accumulation to settle in the default room (16 cells).
    "distance_96": {"distance": 96.0},
    # Linear everywhere: walls stop negative light too (no clamp where they stop light).
    "linear": {"clamp_at_surfaces": False},
    "plain_linear": {"windowed_reinjection": False, "clamp_at_surfaces": False},
    # Clamped only on the transfers a wall stops in part (clamp_per_transfer: the HOLPV's
    # default since 2026-11-30; the LPV ignores it), and every transfer of such a cell clamped
    # (the HOLPV's default before).
    "per_transfer": {"clamp_per_transfer": True},
    "plain_per_transfer": {"windowed_reinjection": False, "clamp_per_transfer": True},
    "at_walls": {"clamp_per_transfer": False},
    "plain_at_walls": {"windowed_reinjection": False, "clamp_per_transfer": False},
    "extended": {"extend_to_bounds": True},
    "no_damping": {"damping": False},
}
# Distance bands from the nearest edge of a wall, in cells.
BANDS = ((0.0, 0.5), (0.5, 1.0), (1.0, 2.0), (2.0, 4.0), (4.0, float("inf")))
def lambert(albedo, emission=0.0):
    return shgi.Material(name="walls", base_color=(albedo,) * 3,
                         diffuse_model=shgi.DiffuseModel.LAMBERT, specular=0.0,
                         emission_color=(1.0, 1.0, 1.0), emission_strength=emission)


def furnace_profile(dims, resolution, albedo, settings):
    """(area mean, means per BANDS) of the field's irradiance over the exact, per order."""
    scene = closed_room(dims, lambert(albedo, emission=1.0)).scene
    scene.commit()
    points, normals, areas, distances = room_wall_points(dims)
    bounces = settings.get("vpl_bounces", shgi.PropagationSettings().vpl_bounces)
    exact = np.pi * sum(albedo ** k for k in range(1, bounces + 1))
    cells = distances / (max(dims) / resolution)
    rows = {}
    for order in (1, 2):
        volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
            seed=5, order=order, resolution=resolution, photons=200000, **settings))
        volume.refine()
        ratio = volume.current_field().irradiance(points, normals).mean(-1) / exact
        bands = []
        for lo, hi in BANDS:
            mask = (cells >= lo) & (cells < hi)
            bands.append(float((ratio * areas)[mask].sum() / areas[mask].sum())
                         if mask.any() else float("nan"))
        rows[order] = (float((ratio * areas).sum() / areas.sum()), bands)
    return rows


def materials_table(resolution):
    """The dim room alone, Lambert against Principled walls: path tracer and volume means."""
    dims, light = (3.0, 3.0, 2.5), (1.5, 1.5, 2.0)
    glossy = shgi.Material(name="walls", base_color=(0.73,) * 3,
                           diffuse_model=shgi.DiffuseModel.LAMBERT)  # Specular 0.5
    plaster = shgi.Material(name="walls", base_color=(0.73,) * 3)
    for label, material in (("Lambert", lambert(0.73)), ("Lambert + Specular 0.5", glossy),
                            ("Principled", plaster)):
        builder = closed_room(dims, material, light)
        builder.camera(eye=(2.9, 0.2, 1.4), target=(0.0, 2.2, 1.0), lens=18.0, width=128,
                       height=96, scale=0.5)
        scene = builder.scene
        scene.commit()
        ref = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=256, seed=11))
        exact = float((np.asarray(ref["DiffInd"]) * np.asarray(ref["DiffCol"])).mean())
        row = f"{label:<22} path tracer {exact:.3f}"
        for order in (1, 2):
            volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
                seed=5, order=order, resolution=resolution))
            volume.refine()
            preview, _ = shgi.render_preview(scene, volume.current_field(),
                                             shgi.PreviewSettings(seed=5))
            mean = float((np.asarray(preview["DiffInd"]) * np.asarray(preview["DiffCol"])).mean())
            row += f"  order {order} {mean:.3f} ({mean / exact:.3f}x)"
        print(row, flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dims", type=float, nargs=3, default=[3.0, 3.0, 2.5])
    parser.add_argument("--resolution", type=int, default=16)
    parser.add_argument("--albedo", type=float, default=0.5)
    parser.add_argument("--configs", nargs="+", default=list(CONFIGS))
    parser.add_argument("--materials", action="store_true")
    parser.add_argument("--set", default="{}",
                        help="PropagationSettings fields on top of every configuration, as JSON")
    args = parser.parse_args()
    if args.materials:
        materials_table(args.resolution)
        return
    print("bands (cells from the nearest edge): "
          + ", ".join(f"{lo:g}-{hi:g}" for lo, hi in BANDS))
    for name in args.configs:
        rows = furnace_profile(args.dims, args.resolution, args.albedo,
                               dict(CONFIGS[name], **json.loads(args.set)))
        for order, (mean, bands) in rows.items():
            print(f"{name:<16} order {order}: mean {mean:.3f}  by band "
                  + " ".join(f"{b:.2f}" for b in bands), flush=True)
    print(json.dumps({"dims": args.dims, "resolution": args.resolution, "albedo": args.albedo}))


if __name__ == "__main__":
    main()
