#!/usr/bin/env python3
"""The photon lattice's cost per quality preset: reset (measuring the cells' surfaces and, since
the visibility masks, which cells see each other), one solve, and memory, on the project's
two rooms, Cornell box and sun room (examples/scenes.py), best of three. Compare two builds by
running it with each on PYTHONPATH. A plain script printing a table: benchmarks are not tests.

    PYTHONPATH=build/python python3 bench/lattice_cost.py
"""

import pathlib
import sys
import time

import shgi

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT / "addon"))
import scenes  # noqa: E402  (examples/scenes.py)
from shgi_blender.presets import QUALITY_PRESETS  # noqa: E402

RUNS = 3


def main():
    print("| scene | preset | reset s | solve s | memory MB |")
    print("|---|---|---|---|---|")
    for name in ("two_rooms", "cornell_box", "sun_room"):
        scene = getattr(scenes, name)(0.5).scene
        scene.commit()
        for preset, values in QUALITY_PRESETS.items():
            settings = shgi.PhotonLatticeSettings(
                seed=5, photons=values["photon_lattice.photons"],
                resolution=values["photon_lattice.resolution"],
                caustic_resolution=values["photon_lattice.caustic_resolution"])
            lattice = shgi.PhotonLattice(scene, settings)
            reset = solve = float("inf")
            for _ in range(RUNS):
                start = time.perf_counter()
                lattice.reset()
                reset = min(reset, time.perf_counter() - start)
                start = time.perf_counter()
                lattice.solve()
                solve = min(solve, time.perf_counter() - start)
            print(f"| {name} | {preset} | {reset:.3f} | {solve:.3f} | "
                  f"{lattice.memory_bytes / 2**20:.1f} |", flush=True)


if __name__ == "__main__":
    main()
