"""The figures of docs/farm.md: a lightmap bake of the project's largest scene (examples/scenes.py
sun_room(lightmap=True), written as glTF by examples/scene_gltf.py) on local Dask clusters of
1, 2 and 4 worker processes with one native thread each, against one process with one thread.

    PYTHONPATH=build/python python3 bench/farm_bench.py [--samples 32] [--shards 16]

Per cluster size: the cluster's start, the bake's wall time (`python -m shgi bake --scheduler`,
so the command's own start, scene load, shards and merge, without the cluster's start), the
peak memory of each worker process (getrusage), and once: the bytes sent per shard (the scene
bundle, once per worker, and the task's arguments) and returned (the shard files), the merge's
time (`--merge K` again on the same shards).
"""

import argparse
import os
import pathlib
import pickle
import resource
import subprocess
import sys
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO / "examples"))


def bake(env, scene, out, samples, *extra):
    """(wall seconds, CPU seconds) of one `python -m shgi bake` (its own process only)."""
    command = [sys.executable, "-m", "shgi", "bake", str(scene), "--out", str(out), "--samples",
               str(samples), "--uv-set", "UVMap", "--quiet", *map(str, extra)]
    before = cpu_seconds(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, env=env, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start, cpu_seconds(resource.RUSAGE_CHILDREN) - before


def cpu_seconds(who=resource.RUSAGE_SELF):
    usage = resource.getrusage(who)
    return usage.ru_utime + usage.ru_stime


def peak_rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=int, default=32)
    parser.add_argument("--shards", type=int, default=16, help="0: one per worker")
    parser.add_argument("--workers", default="1,2,4")
    args = parser.parse_args()

    import scene_gltf
    import scenes
    from distributed import Client

    import shgi
    from shgi import farm

    env = dict(os.environ)
    folder = pathlib.Path(tempfile.mkdtemp(prefix="shgi-farm-bench-"))
    scene = scene_gltf.write_gltf(scenes.sun_room(1.0, lightmap=True).scene,
                                  folder / "sun_room.gltf")
    single, single_cpu = bake(env, scene, folder / "single", args.samples, "--threads", "1")
    texels = sum(shgi.read_exr(path)["Lightmap"][:, :, 0].size
                 for path in (folder / "single").glob("*.exr"))
    print(f"scene {scene.stat().st_size} bytes, {texels} texels, {args.samples} samples")
    print(f"one process, one thread: {single:.1f} s wall, {single_cpu:.1f} s CPU "
          f"({texels / single:,.0f} texels/s)")
    reference = {p.name: p.read_bytes() for p in (folder / "single").iterdir() if p.is_file()}
    # On a busy machine wall times measure the CPU share won; CPU seconds measure the work. The
    # bake on N free cores would take about the client's CPU plus the busiest worker's.
    print("workers | cluster start s | bake s (wall) | speed-up (wall) | client CPU s | "
          "worker CPU s (each) | free-core estimate s | speed-up (estimate) | "
          "peak RSS per worker MB | identical")
    for workers in map(int, args.workers.split(",")):
        start = time.perf_counter()
        cluster = farm.local_cluster(workers)
        started = time.perf_counter() - start
        out = folder / f"farm{workers}"
        with Client(cluster) as client:
            shards = args.shards or workers
            idle = client.run(cpu_seconds)
            seconds, client_cpu = bake(env, scene, out, args.samples, "--scheduler",
                                       cluster.scheduler_address, "--shards", shards)
            busy = client.run(cpu_seconds)
            rss = client.run(peak_rss_mb)
        cluster.close()
        worker_cpu = [busy[w] - idle[w] for w in busy]
        estimate = client_cpu + max(worker_cpu)
        same = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == reference
        print(f"{workers} | {started:.1f} | {seconds:.1f} | {single / seconds:.2f} | "
              f"{client_cpu:.1f} | {', '.join(f'{v:.1f}' for v in worker_cpu)} | "
              f"{estimate:.1f} | {single_cpu / estimate:.2f} | "
              f"{', '.join(f'{v:.0f}' for v in rss.values())} | {same}")
    shards = sorted((folder / f"farm{workers}" / "shards").glob("*.npz"))
    returned = sum(p.stat().st_size for p in shards) / (args.shards or workers)
    bundle = farm.scene_bundle(str(scene))
    argv = pickle.dumps(argparse.Namespace(**{"scene": str(scene), "out": "x", "samples": 32}))
    print(f"sent per shard: task arguments ~{len(argv)} bytes; the scene bundle "
          f"{bundle.size} bytes once per worker")
    print(f"returned per shard: {returned:,.0f} bytes ({returned / texels:.1f} bytes per texel "
          "of the whole bake)")
    merge, merge_cpu = bake(env, scene, folder / f"farm{workers}", args.samples, "--merge",
                            args.shards or workers)
    print(f"merge of {args.shards or workers} shards (the command, with its start and scene "
          f"load): {merge:.1f} s wall, {merge_cpu:.1f} s CPU")


if __name__ == "__main__":
    main()
