#!/usr/bin/env python3
"""The main job (`make demo`): render the project's Cornell box and sun room, and bake the sun room.

Both scenes are built with the scripting API (examples/scenes.py) and rendered by the reference
path tracer, whose light units are calibrated against Cycles. For each scene it writes
<out>/<scene>.exr with every pass in Blender's names (Combined, DiffDir, DiffInd, DiffCol,
GlossDir, ..., Emit, Env, Normal, Depth) and <out>/<scene>.png (Combined, sRGB), then prints
size, samples, time and path samples per second. Then it bakes lightmaps of the sun room's
floor and walls (examples/scenes.py sun_room(lightmap=True)) with the path tracer into
<out>/lightmaps/<object>.exr and .png (shgi.bake; layers in docs/baking.md), printing texels per
second.

Usage: python3 examples/demo.py [--out DIR] [--samples N] [--scale S] [--seed S]
                                [--bake-resolution N] [--bake-samples N]
"""

import argparse
import pathlib
import sys
import time

import shgi
import shgi.bake

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


def bake_sun_room(resolution, samples, seed, out_dir):
    scene = scenes.sun_room(lightmap=True).scene
    scene.commit()
    names = ["floor", "back", "right", "left_wall_0", "left_wall_1"]
    jobs = shgi.bake.jobs_for_scene(scene, "LightmapUV", resolution=resolution, names=names)
    options = shgi.bake.BakeOptions(settings=shgi.LightmapSettings(samples=samples, seed=seed),
                                    filter=True)
    start = time.perf_counter()
    lightmaps = shgi.bake.bake_scene(scene, jobs, options, str(out_dir / "lightmaps"))
    seconds = time.perf_counter() - start
    texels = sum(int(lm.coverage.astype(bool).sum()) for lm in lightmaps)
    print(f"{'bake':12s} sun room, {len(lightmaps)} lightmaps of {resolution}x{resolution}, "
          f"{samples} samples/texel, {seconds:6.2f} s, {texels / seconds / 1e3:6.1f} k texels/s "
          f"-> lightmaps/{{{','.join(lm.name for lm in lightmaps)}}}.exr, .png")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("demo_output"))
    parser.add_argument("--samples", type=int, default=128)
    parser.add_argument("--scale", type=float, default=1.0, help="resolution multiplier")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--bake-resolution", type=int, default=128, help="texels per side")
    parser.add_argument("--bake-samples", type=int, default=128, help="samples per texel")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    print(f"SHGI {shgi.__version__}, reference path tracer, {shgi.max_threads()} threads")
    for name, make in SCENES.items():
        render_scene(name, make(args.scale), args.samples, args.seed, args.out)
    bake_sun_room(args.bake_resolution, args.bake_samples, args.seed, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
