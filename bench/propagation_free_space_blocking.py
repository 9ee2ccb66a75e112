#!/usr/bin/env python3
"""Does the geometry volume block light in free space? The upward light (read facing down) in
the volume's 3rd and 4th layers above the floor, at least 5 cells from the walls and away from
the sun room's table, with occlusion on over off, after 1-12 steps (travel re-injection, both
leak corrections). Light that went through the floor or a wall and came back (the unoccluded
volume's L1/L2 lobes re-enter sideways) needs at least 4 steps to reach these layers, light from
the walls at least 5: a ratio below 1 in the first steps would be over-blocking in free space.

    PYTHONPATH=build/python python3 bench/propagation_free_space_blocking.py sun_room
"""
import pathlib
import sys

import numpy as np

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)
# The defaults before settings layout 6, which this bench's figures in docs/methods.md were
# measured with.
from propagation_lpv_sweep import SEED  # noqa: E402


def ratio(on, off):
    return f"{on / off:.4f}" if off > 0.0 else "no light yet"


def main():
    scene = getattr(scenes, sys.argv[1] if len(sys.argv) > 1 else "sun_room")(0.25).scene
    scene.commit()
    lower, upper = (np.array(corner) for corner in scene.bounds())
    s = (upper - lower).max() / 32
    xs = np.linspace(lower[0] + 5 * s, upper[0] - 5 * s, 9)
    ys = np.linspace(lower[1] + 5 * s, upper[1] - 5 * s, 9)
    # The sun room's table (x 0.1..1.1, y 1.85..2.55) with a margin.
    away = [(x, y) for x in xs for y in ys if not (-0.3 < x < 1.5 and 1.4 < y < 3.0)]
    for order in (1, 2):
        for steps in (1, 3, 6, 12):
            upward = {}
            for occlusion in (True, False):
                volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(seed=5, **dict(
                    SEED, order=order, steps=steps, occlusion=occlusion,
                    occlude_first_step=True, drop_outward_vpls=True, travel_reinjection=True)))
                volume.refine()
                field = volume.current_field()
                upward[occlusion] = []
                for layer in (2, 3):
                    # The lookup moves a cell along the normal (-z): the layer's centre.
                    z = lower[2] + (layer + 1) * s
                    points = np.array([(x, y, z) for x, y in away], np.float32)
                    normals = np.tile(np.float32([0, 0, -1]), (len(points), 1))
                    upward[occlusion].append(float(field.irradiance(points, normals)[:, :3].mean()))
            print(f"order {order}, {steps:>2} steps: upward light, occlusion on / off: layer 2 "
                  f"{ratio(upward[True][0], upward[False][0])}, layer 3 "
                  f"{ratio(upward[True][1], upward[False][1])}", flush=True)


if __name__ == "__main__":
    main()
