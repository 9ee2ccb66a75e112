#!/usr/bin/env python3
"""The main job (`make demo`): path-trace the project's Cornell box and sun room with SHGI.

Both scenes are built with the scripting API (examples/scenes.py) and rendered by the reference
path tracer, whose light units are calibrated against Cycles. For each scene it writes
<out>/<scene>.exr with every pass in Blender's names (Combined, DiffDir, DiffInd, DiffCol,
GlossDir, ..., Emit, Env, Normal, Depth) and <out>/<scene>.png (Combined, sRGB), then prints
size, samples, time and path samples per second.

Usage: python3 examples/demo.py [--out DIR] [--samples N] [--scale S] [--seed S]
"""

import argparse
import pathlib
import sys
import time

import shgi

import scenes

SCENES = {"cornell_box": scenes.cornell_box, "sun_room": scenes.sun_room}


def render_scene(name, builder, samples, seed, out_dir):
    scene = builder.scene
    scene.commit()
    settings = shgi.PathTracerSettings(samples=samples, seed=seed)
    progress = shgi.Progress()
    start = time.perf_counter()
    passes = shgi.render_path_traced(scene, settings, progress=progress)
    seconds = time.perf_counter() - start

    exr_path, png_path = out_dir / f"{name}.exr", out_dir / f"{name}.png"
    shgi.write_exr(str(exr_path), passes)
    shgi.write_png(str(png_path), passes["Combined"])
    height, width = passes["Combined"].shape[:2]
    path_samples = width * height * samples
    print(f"{name:12s} {width}x{height} px, {samples} spp, {seconds:6.2f} s, "
          f"{path_samples / seconds / 1e6:5.2f} M path samples/s -> {exr_path.name} "
          f"({len(passes)} passes), {png_path.name}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("demo_output"))
    parser.add_argument("--samples", type=int, default=128)
    parser.add_argument("--scale", type=float, default=1.0, help="resolution multiplier")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    print(f"SHGI {shgi.__version__}, reference path tracer, {shgi.max_threads()} threads")
    for name, make in SCENES.items():
        render_scene(name, make(args.scale), args.samples, args.seed, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
