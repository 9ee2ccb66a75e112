"""Photons and VPLs scattered off a normal-mapped surface against the path tracer: the indirect
diffuse light (DiffInd) of test_instant_gi.py's normal-mapped floor, with and without its normal
map, from Instant GI's brute force (one set of VPLs, unfiltered) over the path tracer's, on the
floor's pixels and on the wall's (masks from the flat floor's Normal pass).

The wall's indirect light is the floor's first-hit VPLs: it reads what the particle weight at a
shading normal (Veach 1997 §5.3, render/shading.h) gives. The floor's is the wall's VPLs gathered
at the floor's bent normals: it reads the gather (SH irradiance about the shading normal, without
the bump shadowing term the path tracer's diffuse lobe takes toward each light).

    PYTHONPATH=build/python python3 bench/normal_map_particle_flux.py [--samples N]
"""

import argparse
import sys
from pathlib import Path

import shgi

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "python"))
import test_instant_gi as floor_test  # noqa: E402


def floor_scene(normal_map):
    scene = floor_test.normal_mapped_floor()
    if not normal_map:
        for i, material in enumerate(scene.materials):
            if material.name == "bumpy":
                material.normal_texture = -1
                scene.set_material(i, material)
        scene.commit()
    return scene


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=64)
    args = parser.parse_args()
    masks = None
    for normal_map in (False, True):
        scene = floor_scene(normal_map)
        reference = shgi.render_path_traced(
            scene, shgi.PathTracerSettings(samples=args.samples, seed=11))
        if masks is None:
            masks = {"floor": reference["Normal"][..., 2] > 0.9,
                     "wall": reference["Normal"][..., 0] < -0.9}
        field = floor_test.solved(scene, passes=4, photons_per_set=16 * 64, sets_x=1, sets_y=1,
                                  filter_mode=shgi.InstantGiFilter.NONE).current_field()
        instant = floor_test.preview(scene, field, samples=4)["DiffInd"][..., :3]
        path = reference["DiffInd"][..., :3]
        print(f"normal map {'on ' if normal_map else 'off'}: Instant GI / path tracer DiffInd: "
              f"image {instant.mean() / path.mean():.4f}, " +
              ", ".join(f"{name} {instant[m].mean() / path[m].mean():.4f}"
                        for name, m in masks.items()))


if __name__ == "__main__":
    main()
