"""Hashes of every pass of the preview renderer and the path tracer, for checking that a
change to the frame's code is bit for bit (docs/frame-pipeline.md: "the 52 pass hashes"): the
four example rooms (examples/scenes.py, scale 0.25) with no field, a photon lattice and a probe
grid, Combined-only and all passes, tiles of 16 and 6 pixels, 2 samples, and the path tracer (2
samples). Run it before and after a change and diff the outputs. A check, not a test: the
hashes belong to one build of one machine.

    PYTHONPATH=build/python python3 bench/preview_pass_hashes.py > before.txt
"""

import hashlib
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))
import scenes  # noqa: E402
import shgi  # noqa: E402

ROOMS = {"cornell": scenes.cornell_box, "sun": scenes.sun_room, "two": scenes.two_rooms,
         "hall": scenes.hall}


def digest(passes):
    h = hashlib.sha256()
    for name, values in sorted(passes.items()):
        h.update(name.encode())
        h.update(np.ascontiguousarray(values).tobytes())
    return h.hexdigest()[:16]


def main():
    lines = []
    for room, make in ROOMS.items():
        scene = make(scale=0.25).scene
        scene.commit()
        lattice = shgi.PhotonLattice(scene,
                                     shgi.PhotonLatticeSettings(photons=20000, resolution=16))
        lattice.solve()
        grid = shgi.ProbeGrid(scene, shgi.ProbeGridSettings())
        grid.update()
        for field_name, field in (("none", None), ("lattice", lattice), ("grid", grid)):
            for combined_only in (True, False):
                for tile in (16, 6):
                    renderer = shgi.PreviewRenderer(scene, shgi.PreviewSettings(
                        seed=1, tile_size=tile, combined_only=combined_only))
                    renderer.render(field, 2)
                    lines.append(f"{room} {field_name} combined_only={combined_only} "
                                 f"tile={tile} {digest(renderer.passes())}")
        tracer = shgi.PathTracer(scene, shgi.PathTracerSettings(seed=1))
        tracer.render(2)
        lines.append(f"{room} path_tracer {digest(tracer.passes())}")
    print("\n".join(lines))
    print(len(lines), "hashes")


if __name__ == "__main__":
    main()
