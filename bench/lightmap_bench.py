"""Lightmap baker figures on the sun room. Prints figures; it is not a test.

    python3 bench/lightmap_bench.py [--resolution 1024] [--samples 64] [--threads 0]
        [--cycles [--cycles-samples 1,2,4,...] [--reference own|shgi|cycles]
                  [--reference-samples N]]

(PYTHONPATH=build/python, or --build-python DIR.) Measured in one run, on examples/scenes.py
sun_room(lightmap=True), every figure from one bake of the floor's resolution^2 lightmap:

* the raw Embree rate: incoherent closest-hit rays (random origins inside the room, uniformly
  random directions) traced in one batch by shgi.Scene.intersect, as bench/bench_scenes.h
  incoherent_ray_rate does in C++. The time includes copying the batch between numpy and the
  native arrays, so it is a little below the C++ figure.
* per source of indirect light (PATH_TRACER, PHOTON_LATTICE, PROBE_GRID, shgi.bake.SOURCES): the
  solve time of its field (default settings), the wall time of the floor's lightmap at
  `samples` per texel (rasterizing the UV map, unocclude, the bake, dilation; no file
  written), texels per second and texel samples per second; for the path tracer also the cost of
  one texel sample in raw rays (ratio of the two rates; a texel sample traces several rays:
  shadow rays, the hemisphere ray and the path beyond it).
* --cycles: Debian's Blender bakes the same floor (bench/cycles_lightmap_bake.py: the same room,
  materials, sun, portal, sky and LightmapUV) with Cycles' DIFFUSE {DIRECT, INDIRECT} bake, the
  units of SHGI's DIRECT_INDIRECT, at increasing sample counts, until its relative RMS error
  reaches the SHGI bake's. The sample count and wall time at which it does are interpolated
  log-log between the two counts around it. Times: Cycles' bpy.ops.object.bake (scene sync,
  BVH, bake; after one untimed warm-up bake) against SHGI's wall time plus its scene commit.
  Errors are against references baked with another seed at --reference-samples:
  - own (default): each baker against its own reference. The error is then the bake's noise,
    and what the two renderers converge to differently does not count against either; that
    systematic difference is printed (the relative RMS between the two references). It is
    concentrated at shadow edges and around the table's footprint: SHGI averages a texel over
    its area and moves samples under the table out of it (unocclude), Cycles does neither.
  - shgi or cycles: both against that one reference; the other baker's error then also holds
    the systematic difference, which its error at the largest counts shows as a floor.
"""

import argparse
import json
import math
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

REPO_ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO_ROOT / "examples"))

# Rays in the batch of the raw rate (bench_scenes.h incoherent_ray_rate's count).
RAY_COUNT = 1 << 21
# Seeds: the bakes measured, and the reference (another seed, so its noise is independent).
BAKE_SEED, REFERENCE_SEED = 0, 1
# Reference bakes take this many times the samples of the bake measured: their noise is then a
# quarter of the bake's and adds 3% to the error measured (errors add in quadrature).
REFERENCE_FACTOR = 16
CYCLES_SAMPLES = "1,2,4,8,16,32,64,128,256,512,1024,2048"


def relative_rms(texels, reference):
    """RMS of the difference over all texels and channels, over the reference's mean."""
    texels, reference = np.asarray(texels, np.float64), np.asarray(reference, np.float64)
    return float(np.sqrt(np.mean((texels - reference) ** 2)) / np.mean(reference))


def arguments():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--resolution", type=int, default=1024, help="floor lightmap side")
    parser.add_argument("--samples", type=int, default=64, help="SHGI samples per texel")
    parser.add_argument("--threads", type=int, default=0, help="0: all cores")
    parser.add_argument("--build-python", default=None,
                        help="folder holding the shgi package (default: PYTHONPATH)")
    parser.add_argument("--cycles", action="store_true",
                        help="also find the Cycles bake of the same error (runs Blender)")
    parser.add_argument("--cycles-samples", default=CYCLES_SAMPLES,
                        help=f"Cycles sample counts to try, ascending ({CYCLES_SAMPLES})")
    parser.add_argument("--reference", choices=["own", "shgi", "cycles"], default="own",
                        help="own: each baker against its own reference (default); shgi or "
                             "cycles: both against that one")
    parser.add_argument("--reference-samples", type=int, default=0,
                        help=f"samples of the reference bakes (0: {REFERENCE_FACTOR} x --samples)")
    args = parser.parse_args()
    if args.build_python:
        sys.path.insert(0, args.build_python)
    return args


def sun_room(shgi, scenes):
    """The committed sun room with LightmapUV, the floor's instance id, the commit's seconds."""
    scene = scenes.sun_room(1.0, lightmap=True).scene
    start = time.perf_counter()
    scene.commit()
    seconds = time.perf_counter() - start
    floor = [inst.name for inst in scene.instances].index("floor")
    return scene, floor, seconds


def ray_rate(scene):
    """Incoherent closest-hit rays per second through Scene.intersect (one batch)."""
    rng = np.random.default_rng(1)
    low, high = (np.asarray(corner, np.float64) for corner in scene.bounds())
    centre, half = (low + high) / 2, (high - low) / 2
    origins = (centre + (2 * rng.random((RAY_COUNT, 3)) - 1) * 0.99 * half).astype(np.float32)
    directions = rng.normal(size=(RAY_COUNT, 3))
    directions = (directions / np.linalg.norm(directions, axis=1, keepdims=True)).astype(
        np.float32)
    scene.intersect(origins, directions)  # warm-up
    start = time.perf_counter()
    scene.intersect(origins, directions)
    return RAY_COUNT / (time.perf_counter() - start)


def bake_floor(shgi, bake, scene, floor, resolution, samples, seed, field=None):
    """(Lightmap of the floor, wall seconds): rasterize, unocclude, bake, dilate."""
    options = bake.BakeOptions(settings=shgi.LightmapSettings(samples=samples, seed=seed))
    job = bake.BakeJob(floor, "floor", resolution, resolution)
    start = time.perf_counter()
    texel_map, texels = bake.bake_object(scene, job, options, field)
    lightmap = bake.finish(texel_map, texels, options, job.name)
    return lightmap, time.perf_counter() - start


def source_figures(shgi, bake, scene, floor, args, rays_per_second):
    """Prints one line per source of indirect light; returns the path tracer's Lightmap and
    wall seconds (the bake Cycles is compared with)."""
    print(f"floor lightmap {args.resolution} x {args.resolution}, {args.samples} samples per "
          "texel (wall: rasterize + unocclude + bake + dilate)")
    path_traced = None
    for source in bake.SOURCES:
        start = time.perf_counter()
        field = bake.solve_field(scene, source, BAKE_SEED)
        solve = time.perf_counter() - start
        lightmap, seconds = bake_floor(shgi, bake, scene, floor, args.resolution, args.samples,
                                       BAKE_SEED, field)
        texels = int((lightmap.coverage > 0).sum())
        line = (f"  {source:<15} solve {solve:7.2f} s  wall {seconds:7.2f} s  "
                f"{texels / seconds:10.4g} texels/s  {texels * args.samples / seconds:10.4g} "
                "texel samples/s")
        if field is None:
            path_traced = (lightmap, seconds)
            cost = rays_per_second / (texels * args.samples / seconds)
            line += f"  (one texel sample costs {cost:.2f} raw rays)"
        print(line)
    return path_traced


def blender_env():
    """Debian's Blender takes its Python home from the first python3 on PATH: drop pyenv's
    folders so it keeps Debian's (tests/python/blender_support.py explains)."""
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join(
        p for p in env.get("PATH", "").split(os.pathsep) if ".pyenv" not in p)
    return env


def run_cycles(shgi, work, args, samples, seed, reference=None, target_error=None):
    """Runs bench/cycles_lightmap_bake.py in Blender; its list of bakes."""
    defaults = shgi.LightmapSettings()  # Cycles' Light Paths limits as SHGI's bake uses them
    request = {
        "resolution": args.resolution, "samples": samples, "seed": seed, "out": str(work),
        "reference": reference, "target_error": target_error, "repo": str(REPO_ROOT),
        "build_python": str(pathlib.Path(shgi.__file__).parents[1]),
        "light_paths": {name: getattr(defaults, name) for name in (
            "max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces")},
    }
    request_path = work / f"request_{seed}.json"
    request_path.write_text(json.dumps(request))
    command = [shutil.which("blender"), "-b", "--factory-startup", "--python-exit-code", "1",
               "--python", str(REPO_ROOT / "bench" / "cycles_lightmap_bake.py"), "--",
               str(request_path)]
    if args.threads:
        command[1:1] = ["--threads", str(args.threads)]
    result = subprocess.run(command, capture_output=True, text=True, env=blender_env())
    if result.returncode != 0:
        raise RuntimeError(f"Blender failed (exit {result.returncode}):\n"
                           f"{result.stdout[-3000:]}\n{result.stderr[-3000:]}")
    return json.loads((work / "cycles.json").read_text())["bakes"]


def crossing(bakes, target):
    """(samples, seconds) where the error falls to `target`, log-log interpolated between the
    last count above it and the first at or below it; None when no count reached it."""
    for before, after in zip([None] + bakes[:-1], bakes):
        if after["error"] > target:
            continue
        if before is None:
            return after["samples"], after["seconds"]
        # log(error) is close to linear in log(samples) (error ~ samples^-1/2 for noise).
        t = (math.log(target) - math.log(before["error"])) / (
            math.log(after["error"]) - math.log(before["error"]))

        def log_lerp(key):
            return math.exp((1 - t) * math.log(before[key]) + t * math.log(after[key]))

        return log_lerp("samples"), log_lerp("seconds")
    return None


def cycles_comparison(shgi, bake, scene, floor, args, shgi_lightmap, shgi_seconds):
    reference_samples = args.reference_samples or REFERENCE_FACTOR * args.samples
    with tempfile.TemporaryDirectory(prefix="shgi_lightmap_bench_") as folder:
        work = pathlib.Path(folder)
        references = {}  # baker -> path of its reference bake
        start = time.perf_counter()
        if args.reference in ("own", "shgi"):
            lightmap, _ = bake_floor(shgi, bake, scene, floor, args.resolution,
                                     reference_samples, REFERENCE_SEED)
            references["shgi"] = str(work / "shgi_reference.npy")
            np.save(references["shgi"], lightmap.color)
        if args.reference in ("own", "cycles"):
            [reference] = run_cycles(shgi, work, args, [reference_samples], REFERENCE_SEED)
            references["cycles"] = str(work / "cycles_reference.npy")
            shutil.move(reference["path"], references["cycles"])
        print(f"references: {', '.join(references)} at {reference_samples} samples, seed "
              f"{REFERENCE_SEED} ({time.perf_counter() - start:.1f} s)")
        if len(references) == 2:
            difference = relative_rms(np.load(references["cycles"]), np.load(references["shgi"]))
            print(f"  systematic difference Cycles vs SHGI reference: relative RMS {difference:.4f}"
                  " (with both references' noise)")
        shgi_reference = references.get("shgi", references.get("cycles"))
        cycles_reference = references.get("cycles", references.get("shgi"))
        target = relative_rms(shgi_lightmap.color, np.load(shgi_reference))
        print(f"  SHGI    {args.samples:6d} samples  {shgi_seconds:8.2f} s  "
              f"relative RMS error {target:.4f}  (wall + commit)")
        counts = [int(n) for n in args.cycles_samples.split(",")]
        bakes = run_cycles(shgi, work, args, counts, BAKE_SEED, cycles_reference, target)
        for entry in bakes:
            print(f"  Cycles  {entry['samples']:6d} samples  {entry['seconds']:8.2f} s  "
                  f"relative RMS error {entry['error']:.4f}")
        last = np.load(bakes[-1]["path"])
        print(f"  mean Cycles / mean SHGI ({bakes[-1]['samples']} vs {args.samples} samples): "
              f"{float(last.mean() / shgi_lightmap.color.mean()):.4f}")
    match = crossing(bakes, target)
    if match is None:
        print(f"Cycles did not reach SHGI's error {target:.4f} within {bakes[-1]['samples']} "
              "samples; try larger --cycles-samples")
        return
    samples, seconds = match
    print(f"Cycles reaches SHGI's error at ~{samples:.0f} samples in ~{seconds:.2f} s: "
          f"SHGI is {seconds / shgi_seconds:.2f}x as fast at equal error")


def main():
    args = arguments()
    import scenes  # noqa: E402  (examples/scenes.py; imports shgi)
    import shgi
    from shgi import bake

    if args.threads:
        shgi.set_max_threads(args.threads)
    scene, floor, commit = sun_room(shgi, scenes)
    print(f"shgi {shgi.version()}, sun room: commit {commit:.3f} s, threads "
          f"{args.threads or os.cpu_count()}")
    rays_per_second = ray_rate(scene)
    print(f"embree incoherent closest-hit (Scene.intersect batch of {RAY_COUNT}): "
          f"{rays_per_second:.4g} rays/s")
    shgi_lightmap, shgi_seconds = source_figures(shgi, bake, scene, floor, args, rays_per_second)
    if args.cycles:
        # Cycles' bake time includes building its BVH, so SHGI's includes the commit.
        cycles_comparison(shgi, bake, scene, floor, args, shgi_lightmap, shgi_seconds + commit)


if __name__ == "__main__":
    main()
