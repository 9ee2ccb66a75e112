#!/usr/bin/env python3
"""The main job (`make demo`): render the project's Cornell box and sun room, and bake the sun room.

Both scenes are built with the scripting API (examples/scenes.py) and rendered by the reference
path tracer, whose light units are calibrated against Cycles. For each scene it writes
<out>/<scene>.exr with every pass in Blender's names (Combined, DiffDir, DiffInd, DiffCol,
GlossDir, ..., Emit, Env, Normal, Depth) and <out>/<scene>.png (Combined, sRGB), then prints
size, samples, time and path samples per second.

Then each GI solver previews the same scene at its default settings: the photon lattice (seed
000: one solve() of 200,000 photons) and the probe grid (seed 002: PROBE_UPDATES update()
passes), each followed by render_preview (exact direct light, indirect light from the solved
field, 16 samples per pixel). It writes <out>/<scene>_<solver>.exr and .png and prints the
solve and render times, how far the mean indirect diffuse light (DiffInd x DiffCol) is from the
path tracer's, and the PSNR of Combined against the path-traced image (the tests' measure: sRGB
after the path-traced image's auto-exposure) beside the PSNR the path tracer itself reaches in
the same time (as many samples per pixel as fit). Both use another seed than the path-traced
image's, and both PSNRs include that image's own noise, so they are lower bounds; their
difference is the point.

Last it bakes lightmaps of the sun room's floor and walls (examples/scenes.py
sun_room(lightmap=True)) with the path tracer into <out>/lightmaps/<object>.exr and .png
(shgi.bake; layers in docs/baking.md), printing texels per second.

Usage: python3 examples/demo.py [--out DIR] [--samples N] [--scale S] [--seed S]
                                [--bake-resolution N] [--bake-samples N]
"""

import argparse
import pathlib
import sys
import time

import shgi
import shgi.bake
from shgi.metrics import psnr

import scenes

SCENES = {"cornell_box": scenes.cornell_box, "sun_room": scenes.sun_room}
# Probe grid passes before its preview: what the tests give it to agree with the path tracer.
PROBE_UPDATES = 6


def path_trace(scene, samples, seed):
    """The path tracer's passes and its seconds."""
    settings = shgi.PathTracerSettings(samples=samples, seed=seed)
    start = time.perf_counter()
    passes = shgi.render_path_traced(scene, settings, progress=shgi.Progress())
    return passes, time.perf_counter() - start


def render_scene(name, scene, samples, seed, out_dir):
    """The path-traced passes (written out) and the seconds one sample per pixel took."""
    passes, seconds = path_trace(scene, samples, seed)
    write_passes(out_dir, name, passes)
    height, width = passes["Combined"].shape[:2]
    path_samples = width * height * samples
    print(f"{name:12s} {width}x{height} px, {samples} spp, {seconds:6.2f} s, "
          f"{path_samples / seconds / 1e6:5.2f} M path samples/s -> {name}.exr "
          f"({len(passes)} passes), {name}.png")
    return passes, seconds / samples


def write_passes(out_dir, stem, passes):
    shgi.write_exr(str(out_dir / f"{stem}.exr"), passes)
    shgi.write_png(str(out_dir / f"{stem}.png"), passes["Combined"])


def indirect_diffuse(passes):
    return float((passes["DiffInd"][..., :3] * passes["DiffCol"][..., :3]).mean())


def solve_photon_lattice(scene, seed):
    lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(seed=seed))
    lattice.solve()
    return lattice


def solve_probe_grid(scene, seed):
    grid = shgi.ProbeGrid(scene, shgi.ProbeGridSettings(seed=seed))
    for _ in range(PROBE_UPDATES):
        grid.update()
    return grid.field()


SOLVERS = {"photon_lattice": solve_photon_lattice, "probe_grid": solve_probe_grid}


def preview_scene(name, scene, reference, sample_seconds, seed, out_dir):
    """Each solver's preview of the scene, compared with the path-traced passes `reference`, and
    the path tracer given the same time (`sample_seconds` per sample per pixel). Both use another
    seed than the reference's: with its own, a preview's camera rays and light samples would
    repeat the reference's first samples, and their shared noise would raise the PSNR."""
    other_seed = seed + 1
    for solver, solve in SOLVERS.items():
        start = time.perf_counter()
        field = solve(scene, other_seed)
        solved = time.perf_counter()
        settings = shgi.PreviewSettings(seed=other_seed)
        passes, _ = shgi.render_preview(scene, field, settings)
        done = time.perf_counter()
        write_passes(out_dir, f"{name}_{solver}", passes)
        difference = indirect_diffuse(passes) / indirect_diffuse(reference) - 1.0
        quality = psnr(reference["Combined"], passes["Combined"])
        equal_samples = max(1, int((done - start) / sample_seconds))
        equal_time, _ = path_trace(scene, equal_samples, other_seed)
        print(f"{name:12s} {solver:14s} solve {solved - start:4.2f} s + preview "
              f"{settings.samples} spp {done - solved:4.2f} s: indirect diffuse "
              f"{100 * difference:+4.1f}%, PSNR {quality:.1f} dB (path tracer, same time, "
              f"{equal_samples} spp: {psnr(reference['Combined'], equal_time['Combined']):.1f} dB)"
              f" -> {name}_{solver}.exr, .png")


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
        scene = make(args.scale).scene
        scene.commit()
        reference, sample_seconds = render_scene(name, scene, args.samples, args.seed, args.out)
        preview_scene(name, scene, reference, sample_seconds, args.seed, args.out)
    bake_sun_room(args.bake_resolution, args.bake_samples, args.seed, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
