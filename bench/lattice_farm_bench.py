"""The photon-lattice figures of docs/farm.md: a photon lattice of the project's largest scene
(examples/scenes.py sun_room(lightmap=True), written as glTF by examples/scene_gltf.py) solved in
photon batches on local Dask clusters of 1 and 2 worker processes with one native thread each
(shgi.farm.solve_photon_lattice), against one process with one thread.

    PYTHONPATH=build/python python3 bench/lattice_farm_bench.py [--photons 1000000] [--passes 2]
        [--batches 8] [--workers 1,2]

Per cluster size: the solve's wall time (without the cluster's start), the client's CPU, each
worker's CPU (getrusage in the worker), the merge (PhotonLattice.solve_batches of every pass, on
the client) and whether the lattices equal the single process's bit for bit. Once: the bytes a
batch returns per pass (PhotonBatch.to_bytes of batch 0) and the stored photons behind them.
"""

import argparse
import pathlib
import resource
import sys
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO / "examples"))


def cpu_seconds():
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--photons", type=int, default=1_000_000)
    parser.add_argument("--passes", type=int, default=2)
    parser.add_argument("--batches", type=int, default=8)
    parser.add_argument("--workers", default="1,2")
    args = parser.parse_args()

    import numpy as np
    import scene_gltf
    import scenes
    from distributed import Client

    import shgi
    from shgi import bake, farm

    folder = pathlib.Path(tempfile.mkdtemp(prefix="shgi-lattice-farm-"))
    path = str(scene_gltf.write_gltf(scenes.sun_room(lightmap=True).scene,
                                     folder / "sun_room.gltf"))
    settings = shgi.PhotonLatticeSettings(photons=args.photons, seed=1, world_in_field=True)
    scene = shgi.load_gltf(path)
    scene.commit()

    shgi.set_max_threads(1)
    start, cpu = time.perf_counter(), cpu_seconds()
    single = shgi.PhotonLattice(scene, settings)
    for _ in range(args.passes):
        single.solve()
    single_wall, single_cpu = time.perf_counter() - start, cpu_seconds() - cpu
    print(f"sun room, {args.photons} photons x {args.passes} passes, {args.batches} batches")
    print(f"one process, one thread: {single_wall:.2f} s wall, {single_cpu:.2f} s CPU; "
          f"{single.timings['photons_stored']} photons stored in the last pass")

    batch = shgi.trace_photon_batch(scene, settings, 0, *farm.photon_ranges(
        args.photons, args.batches)[0])
    size = len(batch.to_bytes())
    print(f"a batch returns per pass: {size} bytes ({batch.photons_stored} stored photons of "
          f"{batch.end - batch.begin} emitted; {size / (batch.end - batch.begin):.2f} bytes per "
          f"emitted photon)")

    print("| workers | wall | client CPU | CPU per worker | merge (client) | identical |")
    print("|---|---|---|---|---|---|")
    for workers in map(int, args.workers.split(",")):
        cluster = farm.local_cluster(workers)
        with Client(cluster) as client:
            before = client.run(cpu_seconds)
            marks = []
            progress = bake.BakeProgress(
                lambda f, stage: marks.append((time.perf_counter(), stage)))
            start, cpu = time.perf_counter(), cpu_seconds()
            lattice = farm.solve_photon_lattice(client, path, settings, args.passes,
                                                args.batches, progress=progress)
            wall, client_cpu = time.perf_counter() - start, cpu_seconds() - cpu
            after = client.run(cpu_seconds)
        cluster.close()
        merge_start = next(t for t, stage in marks if stage.startswith("merging"))
        merge = start + wall - merge_start
        identical = all(np.array_equal(lattice.lattices[n]["sh"], single.lattices[n]["sh"])
                        for n in ("global", "caustic"))
        per_worker = ", ".join(f"{after[w] - before[w]:.2f}" for w in sorted(after))
        print(f"| {workers} | {wall:.2f} s | {client_cpu:.2f} s | {per_worker} s | "
              f"{merge:.2f} s | {'yes' if identical else 'NO'} |")


if __name__ == "__main__":
    main()
