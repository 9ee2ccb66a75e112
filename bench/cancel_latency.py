#!/usr/bin/env python3
"""Cancel latency of every long call of the `shgi` Python API: how long after a cancel the call
raises, three ways.

- timer: another thread calls progress.cancel() `--after` seconds into the call;
- callback: the progress callback itself calls cancel() once the call has run `--after` seconds
  (what a UI's callback does when its Cancel button was pressed);
- Ctrl-C: a SIGINT sent `--after` seconds into the call, with no Progress passed (a plain
  script's Ctrl-C; KeyboardInterrupt, see python_bindings/interruptible.h).

Each call is sized to run far longer than `--after` (a call that finishes first is reported as
such). A plain script printing a table: benchmarks are not tests.

    PYTHONPATH=build/python python3 bench/cancel_latency.py [--after 0.5] [--repeat 3] [CALL ...]
"""

import argparse
import os
import pathlib
import signal
import sys
import threading
import time

import numpy as np

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)


def big_mesh_scene(triangles_per_side=1000):
    """A committed-ready scene of one height field of 2 x side^2 triangles (2 M by default)."""
    side = triangles_per_side
    x, y = np.meshgrid(np.linspace(-5, 5, side + 1), np.linspace(-5, 5, side + 1))
    z = 0.1 * np.sin(3 * x) * np.cos(2 * y)
    positions = np.stack([x, y, z], -1).reshape(-1, 3).astype(np.float32)
    i = np.arange(side)[:, None] * (side + 1) + np.arange(side)[None, :]
    quads = np.stack([i, i + 1, i + side + 2, i + side + 1], -1).reshape(-1, 4)
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]).astype(np.int32)
    scene = shgi.Scene()
    scene.add_instance(scene.add_mesh(positions=positions, triangles=triangles), np.eye(4))
    return scene


def make_calls():
    """{name: call(progress)}: each runs for minutes unless cancelled."""
    box = scenes.cornell_box(lightmap=True).scene
    box.commit()
    lattice = shgi.PhotonLattice(box, shgi.PhotonLatticeSettings(photons=20000, seed=1))
    lattice.solve()
    raster = shgi.TexelRasterSettings(width=1024, height=1024)
    texel_map = shgi.rasterize_texels(box, 0, raster)
    texels = shgi.bake_lightmap(box, texel_map, shgi.LightmapSettings(samples=1))
    big = big_mesh_scene()
    return {
        "render_path_traced": lambda p: shgi.render_path_traced(
            box, shgi.PathTracerSettings(samples=10**6), p),
        "PathTracer.render": lambda p: shgi.PathTracer(box).render(10**6, p),
        "render_preview": lambda p: shgi.render_preview(
            box, lattice, shgi.PreviewSettings(samples=10**6), progress=p),
        "PhotonLattice.solve": lambda p: shgi.PhotonLattice(
            box, shgi.PhotonLatticeSettings(photons=10**8, max_bounces=1)).solve(p),
        "PropagationVolume.refine": lambda p: shgi.PropagationVolume(
            box, shgi.PropagationSettings(photons=20000, resolution=96, steps=1000), p).refine(p),
        "PropagationVolume.refine (VPLs)": lambda p: shgi.PropagationVolume(
            box, shgi.PropagationSettings(photons=10**8, resolution=8), p).refine(p),
        "ProbeGrid.update": lambda p: shgi.ProbeGrid(
            box, shgi.ProbeGridSettings(rays_per_probe=2**16)).update(p),
        "rasterize_texels": lambda p: shgi.rasterize_texels(
            box, 0, shgi.TexelRasterSettings(width=2048, height=2048, samples_per_axis=2), p),
        "unocclude": lambda p: shgi.unocclude(
            box, texel_map, shgi.UnoccludeSettings(ray_count=64, search_radius=16), p),
        "bake_lightmap": lambda p: shgi.bake_lightmap(
            box, texel_map, shgi.LightmapSettings(samples=2**16), progress=p),
        "filter_lightmap": lambda p: shgi.filter_lightmap(
            texel_map, texels, shgi.LightmapFilterSettings(iterations=10), p),
        "dilate_lightmap": lambda p: shgi.dilate_lightmap(texels, 10**6, p),
        "Scene.commit": lambda p: big.commit(progress=p),
    }


def timed_cancel(call, after, how):
    """Seconds from the cancel (or SIGINT) to the call's raising; None when it finished."""
    cancelled_at = []

    def cancel(progress):
        if not cancelled_at:
            cancelled_at.append(time.perf_counter())
            if progress is None:
                os.kill(os.getpid(), signal.SIGINT)
            else:
                progress.cancel()

    start = time.perf_counter()
    if how == "callback":
        progress = None

        def callback(fraction, stage):
            if time.perf_counter() - start >= after:
                cancel(progress)

        progress = shgi.Progress(callback, 0.005)
    else:
        progress = shgi.Progress() if how == "timer" else None
        timer = threading.Timer(after, cancel, (progress,))
        timer.start()
    try:
        call(progress)
    except (shgi.Cancelled, KeyboardInterrupt):
        return time.perf_counter() - cancelled_at[0]
    finally:
        if how != "callback":
            timer.cancel()
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--after", type=float, default=0.5, help="seconds before the cancel")
    parser.add_argument("--repeat", type=int, default=3, help="runs per call and way (max kept)")
    parser.add_argument("calls", nargs="*", help="only these calls (default: all)")
    args = parser.parse_args()
    print(f"shgi {shgi.__version__}, {os.cpu_count()} cores; cancel {args.after} s into each "
          f"call; worst of {args.repeat} runs, milliseconds")
    ways = ("timer", "callback", "Ctrl-C")
    print(f"{'call':22s}" + "".join(f"{w:>10s}" for w in ways))
    for name, call in make_calls().items():
        if args.calls and name not in args.calls:
            continue
        row = []
        for how in ways:
            try:
                runs = [timed_cancel(call, args.after, how) for _ in range(args.repeat)]
            except MemoryError:  # sized past this machine's memory: refused up front
                row.append("refused")
                continue
            row.append("finished" if None in runs else f"{1e3 * max(runs):.0f}")
        print(f"{name:22s}" + "".join(f"{r:>10s}" for r in row), flush=True)


if __name__ == "__main__":
    main()
