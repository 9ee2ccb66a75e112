#!/usr/bin/env python3
"""Where the light propagation volume's error lies: per surface class of the sun room and the two
rooms (the floor, split on the sun room into its sunlit patch, more than half the floor's
brightest direct light, and the rest; the ceiling; the walls), for each order at the defaults, the
mean of DiffInd x DiffCol over the path tracer's, its RMSE over the path tracer's mean there, and
the class's share of the image's squared error of that product. The references are
propagation_lpv_sweep.py's (cached in --cache); the masks come from the preview's Normal and
DiffDir (exact direct light).

    PYTHONPATH=build/python python3 bench/propagation_surface_error.py [--plain] [--extended]
        [--edges]

The HOLPV's re-injected beams have band 2 windowed (windowed_reinjection, the default; --windowed
is accepted and changes nothing), with --plain not; with --extended the cells outside the scene's
bounds take the inside cells' light (extend_to_bounds).
With --edges the classes are instead the pixels by their distance to the nearest edge of the
image's surfaces (where the facing, the Normal pass's largest axis and its sign, changes): 1-2,
3-4 and 5 or more pixels.
"""

import argparse
import pathlib

import numpy as np

import shgi
from propagation_lpv_sweep import reference


# Pixel distances to the nearest surface edge that --edges groups the image by.
EDGE_BANDS = ((1, 2), (3, 4), (5, None))


def edge_distance(normal):
    """Per pixel, the Chebyshev distance (pixels, up to the last band's start) to the nearest
    pixel of another facing (largest axis of the normal and its sign)."""
    axis = np.abs(normal).argmax(-1)
    facing = 2 * axis + (np.take_along_axis(normal, axis[..., None], -1)[..., 0] > 0)
    far = EDGE_BANDS[-1][0]
    distance = np.full(facing.shape, far)
    for d in range(far - 1, 0, -1):
        padded = np.pad(facing, d, mode="edge")
        other = np.zeros(facing.shape, bool)
        for dy in range(2 * d + 1):
            for dx in range(2 * d + 1):
                other |= padded[dy:dy + facing.shape[0], dx:dx + facing.shape[1]] != facing
        distance[other] = d
    return distance


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cache", type=pathlib.Path, default=pathlib.Path("/tmp/shgi_lpv_refs"))
    parser.add_argument("--windowed", action="store_true")
    parser.add_argument("--plain", action="store_true")
    parser.add_argument("--extended", action="store_true")
    parser.add_argument("--edges", action="store_true")
    args = parser.parse_args()
    for name in ("sun_room", "two_rooms"):
        scene, ref = reference(name, args.cache)
        exact = np.asarray(ref["DiffInd"]) * np.asarray(ref["DiffCol"])
        for order in (1, 2):
            volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
                seed=5, order=order, windowed_reinjection=not args.plain,
                extend_to_bounds=args.extended))
            volume.refine()
            preview, _ = shgi.render_preview(scene, volume.current_field(),
                                             shgi.PreviewSettings(seed=5))
            indirect = np.asarray(preview["DiffInd"]) * np.asarray(preview["DiffCol"])
            up = np.asarray(preview["Normal"])[..., 2]
            direct = np.asarray(preview["DiffDir"])[..., :3].mean(-1)
            floor = up > 0.9
            classes = {"ceiling": up < -0.9, "walls": np.abs(up) < 0.1}
            if args.edges:
                distance = edge_distance(np.asarray(preview["Normal"])[..., :3])
                classes = {(f"{lo}-{hi} px" if hi else f"{lo}+ px"):
                           (distance >= lo) & (distance <= (hi or lo)) for lo, hi in EDGE_BANDS}
            elif name == "sun_room":
                lit = floor & (direct > 0.5 * direct[floor].max())
                classes.update({"sunlit floor": lit, "shaded floor": floor & ~lit})
            else:
                classes["floor"] = floor
            squared = ((indirect - exact) ** 2).sum()
            row = f"{name} order {order}:"
            for label, mask in classes.items():
                mean = exact[mask].mean()
                row += (f"  {label} {indirect[mask].mean() / mean:.3f}"
                        f" (RMSE {np.sqrt(((indirect[mask] - exact[mask]) ** 2).mean()) / mean:.2f},"
                        f" {((indirect[mask] - exact[mask]) ** 2).sum() / squared:.2f})")
            print(row, flush=True)


if __name__ == "__main__":
    main()
