"""Bakes on a Dask cluster (shgi.farm, docs/farm.md), on loopback only: byte-identical to a
single-process bake on a local cluster and on a separately started scheduler and workers, a
worker SIGKILLed mid-shard, Ctrl-C, the retry policy, shard validation, the scene bundle.

`make test` installs dask (make deps) and sets SHGI_REQUIRE_FARM=1: there a missing dask fails
these tests instead of skipping them."""

import importlib.util
import os
import pathlib
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import shgi
from shgi import bake, farm
from blender_support import REPO_ROOT

sys.path.insert(0, str(REPO_ROOT / "examples"))
import scenes  # noqa: E402
import scene_gltf  # noqa: E402

if importlib.util.find_spec("distributed") is None:
    if os.environ.get("SHGI_REQUIRE_FARM") == "1":
        raise ImportError("dask[distributed] is missing: `make deps` installs it")
    pytest.skip("dask[distributed] is not installed (make deps installs it)",
                allow_module_level=True)

pytestmark = pytest.mark.farm

# Small: 9 objects x 16 x 16 texels, tiles of 8 -> 36 tiles; quick shards.
BAKE = ["--resolution", "16", "--samples", "4", "--seed", "3", "--uv-set", "UVMap",
        "--directional"]
# Longer shards, for the tests that act while a shard runs.
SLOW_BAKE = ["--resolution", "32", "--samples", "64", "--seed", "3", "--uv-set", "UVMap"]
CANCEL_SECONDS = 2.0  # the bound for Ctrl-C during a distributed bake


@pytest.fixture(scope="module")
def sun_room_file(tmp_path_factory):
    """The sun room (examples/scenes.py, walls facing in, LightmapUV) as a glTF file."""
    scene = scenes.sun_room(0.25, lightmap=True).scene
    return scene_gltf.write_gltf(scene, tmp_path_factory.mktemp("scene") / "sun_room.gltf")


def cli(build_python_dir, *args, **popen):
    env = dict(os.environ, PYTHONPATH=str(build_python_dir))
    env.pop("SHGI_PROGRESS", None)
    env.update(popen.pop("env", {}))
    return subprocess.Popen([sys.executable, "-m", "shgi", "bake", *map(str, args)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **popen)


def run_cli(build_python_dir, *args, timeout=240, **popen):
    process = cli(build_python_dir, *args, **popen)
    stdout, stderr = process.communicate(timeout=timeout)
    return process.returncode, stdout, stderr


def written(folder):
    """{file name: bytes} of the lightmaps in `folder` (not the shards)."""
    folder = pathlib.Path(folder)
    return {p.name: p.read_bytes() for p in folder.iterdir() if p.is_file()}


@pytest.fixture(scope="module")
def single_bake(build_python_dir, sun_room_file, tmp_path_factory):
    """The single-process bakes the farm bakes must equal: {"small": files, "slow": files}."""
    result = {}
    for name, args in (("small", BAKE), ("slow", SLOW_BAKE)):
        out = tmp_path_factory.mktemp(f"single-{name}")
        code, _, stderr = run_cli(build_python_dir, sun_room_file, "--out", out, *args)
        assert code == 0, stderr
        result[name] = written(out)
    assert len(result["small"]) == 18  # 9 objects, EXR and PNG
    return result


@pytest.fixture(scope="module")
def dask_cluster(build_python_dir, tmp_path_factory):
    """A `dask scheduler` and two `dask worker` processes (one thread each) on 127.0.0.1:
    (scheduler address, [worker processes])."""
    folder = tmp_path_factory.mktemp("dask")
    scheduler_file = folder / "scheduler.json"
    env = dict(os.environ, PYTHONPATH=str(build_python_dir))
    scheduler = subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
         "--port", "0", "--no-dashboard", "--scheduler-file", str(scheduler_file)],
        env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers = []
    try:
        deadline = time.monotonic() + 60
        while not scheduler_file.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        address = __import__("json").loads(scheduler_file.read_text())["address"]
        for _ in range(2):
            workers.append(subprocess.Popen(
                [sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads",
                 "1", "--host", "127.0.0.1", "--no-dashboard"],
                env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        from distributed import Client
        with Client(address, timeout="60s") as client:
            client.wait_for_workers(2, timeout=60)
        yield address
    finally:
        for process in workers + [scheduler]:
            process.terminate()
        for process in workers + [scheduler]:
            try:
                process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                process.kill()


def test_local_cluster_of_three_workers_bakes_byte_identical(build_python_dir, sun_room_file,
                                                              single_bake, tmp_path):
    out = tmp_path / "farm"
    code, stdout, stderr = run_cli(build_python_dir, sun_room_file, "--out", out, *BAKE,
                                   "--workers", "3", env={"SHGI_PROGRESS": "1"})
    assert code == 0, stderr
    assert written(out) == single_bake["small"]
    # 4 shards per worker by default, each object's shard file in out/shards; the progress
    # counts shards and the texel rate, then the merge.
    assert len(os.listdir(out / "shards")) == 12 * 9
    # (The bar redraws at most 10 times a second: not every count shows.)
    counts = [int(n) for n in re.findall(r"shards (\d+)/12, [\d,]+ texels/s", stderr)]
    assert counts and counts == sorted(counts) and counts[-1] <= 12
    assert "100.0% merge: done" in stderr
    assert "floor: " in stdout


def test_external_scheduler_and_two_workers_bake_byte_identical(build_python_dir, sun_room_file,
                                                                single_bake, dask_cluster,
                                                                tmp_path):
    out = tmp_path / "farm"
    code, _, stderr = run_cli(build_python_dir, sun_room_file, "--out", out, *BAKE,
                              "--scheduler", dask_cluster, "--shards", "5")
    assert code == 0, stderr
    assert written(out) == single_bake["small"]
    assert len(os.listdir(out / "shards")) == 5 * 9


def test_a_worker_killed_while_it_holds_a_shard_still_bakes_byte_identical(
        build_python_dir, sun_room_file, single_bake, dask_cluster, tmp_path):
    from distributed import Client

    out = tmp_path / "farm"
    process = cli(build_python_dir, sun_room_file, "--out", out, *SLOW_BAKE, "--scheduler",
                  dask_cluster, "--shards", "4")
    with Client(dask_cluster, timeout="30s") as client:
        victim = None
        deadline = time.monotonic() + 120
        while victim is None and time.monotonic() < deadline and process.poll() is None:
            busy = {worker: tasks for worker, tasks in client.processing().items()
                    if any(str(task).startswith("shgi-shard-") for task in tasks)}
            if busy:
                victim = sorted(busy)[0]
            time.sleep(0.05)
        assert victim is not None, "no worker took a shard"
        pid = client.run(os.getpid, workers=[victim])[victim]
        os.kill(pid, signal.SIGKILL)
        stdout, stderr = process.communicate(timeout=240)
        assert process.returncode == 0, stderr
        assert written(out) == single_bake["slow"]
        client.wait_for_workers(2, timeout=60)  # the nanny restarted it, for the next tests


def test_every_worker_killed_mid_bake_loses_the_scene_and_the_bake_still_completes(
        build_python_dir, sun_room_file, single_bake, dask_cluster, tmp_path):
    """Both workers SIGKILLed while they hold shards: every copy of the scattered scene is gone
    with them. The restarted workers get it scattered again, and the bake completes
    byte-identical."""
    from distributed import Client

    out = tmp_path / "farm"
    process = cli(build_python_dir, sun_room_file, "--out", out, *SLOW_BAKE, "--scheduler",
                  dask_cluster, "--shards", "4")
    with Client(dask_cluster, timeout="30s") as client:
        busy = {}
        deadline = time.monotonic() + 120
        while len(busy) < 2 and time.monotonic() < deadline and process.poll() is None:
            busy = {worker: tasks for worker, tasks in client.processing().items()
                    if any(str(task).startswith("shgi-shard-") for task in tasks)}
            time.sleep(0.05)
        assert len(busy) == 2, "both workers did not take a shard"
        pids = client.run(os.getpid, workers=sorted(busy))
        for pid in pids.values():
            os.kill(pid, signal.SIGKILL)
        stdout, stderr = process.communicate(timeout=240)
        assert process.returncode == 0, stderr
        assert written(out) == single_bake["slow"]
        client.wait_for_workers(2, timeout=60)  # the nannies restarted them, for the next tests


def test_ctrl_c_during_a_distributed_bake_returns_quickly_leaving_no_lightmap(
        build_python_dir, sun_room_file, tmp_path):
    out = tmp_path / "farm"
    process = cli(build_python_dir, sun_room_file, "--out", out, *SLOW_BAKE, "--workers", "2",
                  env={"SHGI_PROGRESS": "1"})
    # Wait until the shards run (the bar shows "shards 0/8"), then a little into them (less
    # than a worker's first shard takes: it imports shgi and loads the scene first).
    deadline = time.monotonic() + 120
    seen = ""
    while "shards 0/" not in seen and time.monotonic() < deadline:
        seen += os.read(process.stderr.fileno(), 4096).decode(errors="replace")
    time.sleep(0.3)
    assert process.poll() is None, "the bake ended before Ctrl-C"
    start = time.monotonic()
    process.send_signal(signal.SIGINT)
    process.wait(timeout=30)
    elapsed = time.monotonic() - start
    assert process.returncode == 130
    assert elapsed < CANCEL_SECONDS, f"Ctrl-C took {elapsed:.2f} s"
    lightmaps = [p for p in out.rglob("*") if p.suffix in (".exr", ".png")] if out.exists() \
        else []
    assert lightmaps == []


# --- the retry policy, on a local cluster of 2 workers -----------------------------------------

@pytest.fixture(scope="module")
def local_client():
    from distributed import Client

    cluster = farm.local_cluster(2)
    with Client(cluster) as client:
        yield client
    cluster.close()


def test_a_task_failing_once_is_rerun_and_one_failing_twice_names_shard_and_worker(
        local_client):
    def flaky(i, attempt):
        from distributed import get_worker
        if i == 1 and attempt == 1:
            raise RuntimeError("a flaky disk")
        return {"worker": get_worker().address, "value": i * 10}

    def always(i, attempt):
        if i == 2:
            raise RuntimeError("out of memory")
        return {"value": i}

    kept, attempts = {}, []

    def submit(function):
        def make(i, attempt):
            attempts.append((i, attempt))
            return local_client.submit(function, i, attempt, pure=False)
        return make

    def accept(i, result):
        kept[i] = result["value"]
        return 1

    progress = []
    farm.run_tasks(local_client, submit(flaky), 3, accept, lambda d, n: progress.append(d),
                   "shard")
    assert kept == {0: 0, 1: 10, 2: 20}
    assert sorted(attempts) == [(0, 1), (1, 1), (1, 2), (2, 1)]
    assert progress == [1, 2, 3]

    attempts.clear()
    with pytest.raises(farm.ShardFailed,
                       match=r"shard 2 of 3 failed 2 times, last on worker tcp://127\.0\.0\.1:\d+"
                             r": RuntimeError: out of memory"):
        farm.run_tasks(local_client, submit(always), 3, accept, lambda d, n: None, "shard")
    assert attempts.count((2, 1)) == 1 and attempts.count((2, 2)) == 1


def test_a_rejected_result_is_rerun_then_fails_the_bake(local_client):
    def task(i, attempt):
        return {"worker": "tcp://w", "attempt": attempt}

    def accept(i, result):
        if result["attempt"] < 2:
            raise ValueError("baked with samples 16 (merge: 4)")
        return 1

    farm.run_tasks(local_client, lambda i, a: local_client.submit(task, i, a, pure=False), 2,
                   accept, lambda d, n: None, "brick")

    def reject(i, result):
        raise ValueError("baked with samples 16 (merge: 4)")

    with pytest.raises(farm.ShardFailed, match=r"brick 0 of 1 failed 2 times, last on worker "
                                               r"tcp://w: its result was rejected: baked with "
                                               r"samples 16"):
        farm.run_tasks(local_client, lambda i, a: local_client.submit(task, i, a, pure=False),
                       1, reject, lambda d, n: None, "brick")


# --- shard validation and the scene bundle (no cluster) ------------------------------------------

def test_a_shard_with_another_fingerprint_is_rejected_before_it_lands(tmp_path):
    scene = scenes.sun_room(0.25, lightmap=True).scene
    scene.commit()
    jobs = [bake.BakeJob(0, "floor", 16, 16)]
    options = bake.BakeOptions(settings=shgi.LightmapSettings(samples=4, tile_size=8))
    other = bake.BakeOptions(settings=shgi.LightmapSettings(samples=8, tile_size=8))
    [path] = bake.bake_scene(scene, jobs, other, str(tmp_path / "worker"), shard=(0, 2))
    result = {"files": {"floor": pathlib.Path(path).read_bytes()}, "worker": "tcp://w"}
    out = tmp_path / "out"
    with pytest.raises(ValueError, match=r"samples 8 \(merge: 4\)"):
        farm._accept_shard(result, jobs, options, str(out), 0, 2)
    assert not any(out.rglob("*.npz"))  # nothing landed, not even the incoming file
    [path] = bake.bake_scene(scene, jobs, options, str(tmp_path / "worker"), shard=(0, 2))
    result["files"]["floor"] = pathlib.Path(path).read_bytes()
    texels = farm._accept_shard(result, jobs, options, str(out), 0, 2)
    assert texels == 2 * 8 * 8  # 4 tiles of 8 x 8 texels, every other one
    assert sorted(p.name for p in out.rglob("*.npz")) == ["floor.shard-0-of-2.npz"]


def test_scene_bundle_holds_referenced_files_keyed_by_their_content(tmp_path):
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "mesh.bin").write_bytes(b"\1\2\3\4")
    gltf = tmp_path / "scene.gltf"
    gltf.write_text('{"buffers": [{"uri": "data/mesh.bin"}, {"uri": "data:,x"}],'
                    ' "images": [{"uri": "data/wall%20paint.png"}]}')
    (tmp_path / "data" / "wall paint.png").write_bytes(b"png")
    bundle = farm.scene_bundle(str(gltf))
    assert sorted(bundle.files) == ["data/mesh.bin", "data/wall paint.png", "scene.gltf"]
    assert bundle.digest == farm.scene_bundle(str(gltf)).digest
    (tmp_path / "data" / "mesh.bin").write_bytes(b"\1\2\3\5")  # same size, other content
    assert farm.scene_bundle(str(gltf)).digest != bundle.digest
    # On a worker: written under its digest, refused when the contents do not match it.
    path = farm._scene_on_this_machine(bundle)
    assert pathlib.Path(path).read_bytes() == gltf.read_bytes()
    assert bundle.digest in path
    bundle.files["data/mesh.bin"] = b"tampered"
    with pytest.raises(ValueError, match="do not match its digest"):
        farm._scene_on_this_machine(bundle)
    gltf.write_text('{"buffers": [{"uri": "../outside.bin"}]}')
    with pytest.raises(ValueError, match="outside the scene's folder"):
        farm.scene_bundle(str(gltf))
    gltf.write_text('{"buffers": [{"uri": "missing.bin"}]}')
    with pytest.raises(OSError, match="missing.bin"):
        farm.scene_bundle(str(gltf))


def test_shgi_imports_without_dask_and_the_farm_names_the_pip_command(build_python_dir,
                                                                      sun_room_file, tmp_path):
    script = ("import sys; sys.modules['distributed'] = None; sys.modules['dask'] = None\n"
              "import shgi, shgi.bake, shgi.farm\n"
              "from shgi.__main__ import main\n"
              f"sys.exit(main(['bake', {str(sun_room_file)!r}, '--out', {str(tmp_path)!r}, "
              "'--uv-set', 'UVMap', '--workers', '2']))")
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            env=dict(os.environ, PYTHONPATH=str(build_python_dir)), timeout=60)
    assert result.returncode == 1
    assert "needs the Python module 'distributed'" in result.stderr
    assert "pip install" in result.stderr and "'dask[distributed]'" in result.stderr


def test_shards_without_a_cluster_are_refused(build_python_dir,
                                                                      sun_room_file, tmp_path):
    code, _, stderr = run_cli(build_python_dir, sun_room_file, "--out", tmp_path, *BAKE,
                              "--shards", "4")
    assert code == 1 and "--shards splits a farm bake" in stderr
    code, _, stderr = run_cli(build_python_dir, sun_room_file, "--out", tmp_path, *BAKE,
                              "--workers", "2", "--shard", "0/2")
    assert code == 2 and "not allowed with argument" in stderr
    code, _, stderr = run_cli(build_python_dir, sun_room_file, "--out", tmp_path, *BAKE,
                              "--workers", "100000")
    assert code == 1 and "--workers 100000: a local cluster runs at most 256" in stderr
    code, _, stderr = run_cli(build_python_dir, sun_room_file, "--out", tmp_path, *BAKE,
                              "--workers", "2", "--shards", "5000")
    assert code == 1 and "--shards 5000: at most 4096" in stderr


# --- probe grids in bricks ------------------------------------------------------------------------

def test_probe_grid_solved_in_four_bricks_equals_the_single_machine_grid(local_client,
                                                                        sun_room_file, tmp_path):
    settings = shgi.ProbeGridSettings(order=2, rays_per_probe=16, spacing=1.0, seed=7)
    passes = 2
    progress = []
    merged = farm.solve_probe_grid(local_client, str(sun_room_file), settings, passes, 4,
                                   progress=bake.BakeProgress(
                                       lambda f, stage: progress.append(stage)))
    scene = shgi.load_gltf(str(sun_room_file))
    scene.commit()
    grid = shgi.ProbeGrid(scene, settings)
    for _ in range(passes):
        grid.update()
    assert merged.probe_count == grid.probe_count > 4 and merged.passes == passes
    np.testing.assert_array_equal(merged.positions, grid.positions)
    np.testing.assert_array_equal(merged.active, grid.active)
    assert np.array_equal(merged.sh, grid.sh) and np.array_equal(merged.variance, grid.variance)
    assert np.abs(grid.sh).max() > 0  # lit probes: the comparison means something
    # Exported (the add-on's Export Volume format), every file equals the single machine's:
    # the visibility maps too.
    (tmp_path / "farm").mkdir()
    (tmp_path / "one").mkdir()
    merged.export(tmp_path / "farm" / "grid.json")
    grid.field().export(tmp_path / "one" / "grid.json")
    assert written(tmp_path / "farm") == written(tmp_path / "one")
    assert len(written(tmp_path / "one")) >= 3
    assert progress[-1].startswith("bricks 4/4, ")
    # A brick solved with other settings is refused by the splice (placement differs).
    other = shgi.ProbeGridSettings(order=2, rays_per_probe=16, spacing=0.9, seed=7)
    brick = shgi.ProbeGrid(scene, other)
    brick.update_probes(0, 3)
    brick.update_probes(0, 3)
    with pytest.raises(ValueError, match="splice_probes: the brick's probe count"):
        merged.splice(brick.field(), 0, 3)


# --- photon lattices in photon batches -----------------------------------------------------------

def lattice_settings(**fields):
    """A small lattice of the sun room, with the sky's direct light in the field (the room has no
    mirrors: the global lattice carries the light, the caustic lattice stays empty)."""
    values = dict(photons=30000, seed=5, resolution=8, max_bounces=3, world_in_field=True)
    values.update(fields)
    return shgi.PhotonLatticeSettings(**values)


def test_photon_lattice_solved_in_four_batches_exports_the_single_machine_files(
        local_client, sun_room_file, tmp_path):
    settings = lattice_settings()
    passes = 2
    stages = []
    merged = farm.solve_photon_lattice(local_client, str(sun_room_file), settings, passes, 4,
                                       progress=bake.BakeProgress(
                                           lambda f, stage: stages.append(stage)))
    scene = shgi.load_gltf(str(sun_room_file))
    scene.commit()
    single = shgi.PhotonLattice(scene, settings)
    for _ in range(passes):
        single.solve()
    assert merged.passes == single.passes == passes
    for name in ("global", "caustic"):
        assert np.array_equal(merged.lattices[name]["sh"], single.lattices[name]["sh"]), name
    assert np.abs(single.lattices["global"]["sh"]).max() > 0  # lit: the comparison means something
    for key in ("photons_emitted", "photons_stored", "bounces"):
        assert merged.timings[key] == single.timings[key], key
    # Exported (the add-on's Export Volume format), every file equals the single machine's.
    from shgi.volume_export import export_lattice
    (tmp_path / "farm").mkdir()
    (tmp_path / "one").mkdir()
    export_lattice(merged, tmp_path / "farm" / "lattice.json")
    export_lattice(single, tmp_path / "one" / "lattice.json")
    assert written(tmp_path / "farm") == written(tmp_path / "one")
    assert len(written(tmp_path / "one")) == 3  # the JSON, the global and caustic EXRs
    assert any(stage.startswith("batches 4/4, ") for stage in stages)
    assert stages[-1].startswith("merging pass 2/2")


def test_a_photon_batch_with_other_settings_is_refused(sun_room_file):
    """By the farm's check of a returned batch (before it is accepted, so the batch is rerun),
    and by PhotonLattice.solve_batches itself."""
    from shgi.method_registry import settings_to_dict

    scene = shgi.load_gltf(str(sun_room_file))
    scene.commit()
    settings, other = lattice_settings(photons=2000), lattice_settings(photons=2000, resolution=9)
    wanted = settings_to_dict(settings)
    batch = shgi.trace_photon_batch(scene, other, 0, 0, 2000)
    result = {"settings": wanted, "batches": [batch.to_bytes()]}
    with pytest.raises(ValueError, match=r"its pass 0 was traced with settings .*'resolution': 9"):
        farm._accept_photon_batches(result, wanted, 1, 0, 2000, 0)
    with pytest.raises(ValueError, match=r"it was traced with settings .*'resolution': 9"):
        farm._accept_photon_batches(dict(result, settings=settings_to_dict(other)), wanted, 1,
                                    0, 2000, 0)
    with pytest.raises(ValueError, match=r"holds pass 0, photons \[0, 1000\); wanted pass 0, "
                                         r"\[0, 2000\)"):
        part = shgi.trace_photon_batch(scene, settings, 0, 0, 1000)
        farm._accept_photon_batches(dict(result, batches=[part.to_bytes()]), wanted, 1, 0,
                                    2000, 0)
    with pytest.raises(OSError, match=r"batch 0, pass 0.*not an SHGI photon batch"):
        farm._accept_photon_batches(dict(result, batches=[b"not a batch"]), wanted, 1, 0,
                                    2000, 0)
    lattice = shgi.PhotonLattice(scene, settings)
    with pytest.raises(ValueError, match="other settings than the lattice's "
                                         r"\(resolution 9 instead of 8\)"):
        lattice.solve_batches([batch])
    assert lattice.passes == 0
    # The lattice's own batches, in any order and after a pickle, make its first pass.
    import pickle
    halves = [shgi.trace_photon_batch(scene, settings, 0, 1000, 2000),
              shgi.trace_photon_batch(scene, settings, 0, 0, 1000)]
    with pytest.raises(ValueError, match="batch 1 is None"):
        lattice.solve_batches([halves[0], None])
    lattice.solve_batches(pickle.loads(pickle.dumps(halves)))
    single = shgi.PhotonLattice(scene, settings)
    single.solve()
    assert np.array_equal(lattice.lattices["global"]["sh"], single.lattices["global"]["sh"])


def test_a_cancelled_photon_lattice_solve_on_the_cluster_raises_cancelled(local_client,
                                                                          sun_room_file):
    import threading

    settings = lattice_settings(photons=4_000_000)  # batches of several seconds each
    timers = []

    def on_progress(fraction, stage):
        if not timers:  # the client is measuring the lattice; the batches start right after
            timers.append(threading.Timer(1.0, progress.cancel))
            timers[0].start()

    progress = bake.BakeProgress(on_progress)
    with pytest.raises(shgi.Cancelled):
        farm.solve_photon_lattice(local_client, str(sun_room_file), settings, 2, 4,
                                  progress=progress)
    timers[0].join()
    # The cancelled tasks left the workers free: a small solve runs next.
    small = farm.solve_photon_lattice(local_client, str(sun_room_file),
                                      lattice_settings(photons=2000), 1, 2)
    assert small.passes == 1


# --- a scene built in this process (the add-on's bake on Dask) ---------------------------------

def in_memory_bake(scene, samples=4):
    """(jobs, options): the floor, back and right walls of the sun room, 16 texels, directional."""
    jobs = bake.jobs_for_scene(scene, "LightmapUV", 16, names=["floor", "back", "right"])
    options = bake.BakeOptions(settings=shgi.LightmapSettings(samples=samples, seed=3,
                                                              directional=True))
    return jobs, options


def test_a_scene_built_in_memory_bakes_on_the_cluster_byte_identical(local_client, tmp_path):
    """shgi.farm.bake_scene_on_cluster: the pickled scene goes to the workers, which solve the
    field themselves; the merged files equal one bake_scene call, for the path tracer and for a
    probe grid."""
    scene = scenes.sun_room(0.25, lightmap=True).scene
    scene.commit()
    jobs, options = in_memory_bake(scene)
    grid = shgi.ProbeGridSettings(rays_per_probe=16, spacing=1.0, seed=3)
    for name, recipe in (("path", None), ("grid", ("PROBE_GRID", grid, 2))):
        field = None if recipe is None else bake.solve_field(scene, "PROBE_GRID", 3, None,
                                                             grid, 2)
        bake.bake_scene(scene, jobs, options, str(tmp_path / f"{name}-one"), field)
        stages, merged = [], []
        lightmaps = farm.bake_scene_on_cluster(
            local_client, scene, jobs, options, str(tmp_path / f"{name}-farm"), recipe,
            shards=5, progress=bake.BakeProgress(lambda f, stage: stages.append(stage)),
            on_lightmap=merged.append)
        assert [lightmap.name for lightmap in lightmaps] == ["floor", "back", "right"]
        assert merged == lightmaps
        assert any(stage.startswith("shards 5/5, ") for stage in stages)
        one = written(tmp_path / f"{name}-one")
        assert len(one) == 6 and written(tmp_path / f"{name}-farm") == one, name


def test_a_cancelled_scene_bake_on_the_cluster_raises_cancelled_and_writes_no_lightmap(
        local_client, tmp_path):
    scene = scenes.sun_room(0.25, lightmap=True).scene
    scene.commit()
    jobs, options = in_memory_bake(scene, samples=4096)
    progress = bake.BakeProgress(lambda f, stage: stage.startswith("shards") and
                                 progress.cancel())
    with pytest.raises(shgi.Cancelled):
        farm.bake_scene_on_cluster(local_client, scene, jobs, options, str(tmp_path / "out"),
                                   shards=4, progress=progress)
    left = [p for p in (tmp_path / "out").rglob("*") if p.suffix in (".exr", ".png")]
    assert left == []


def alive(pid):
    """Whether process `pid` runs (a zombie does not)."""
    try:
        return not pathlib.Path(f"/proc/{pid}/stat").read_text().split(") ")[1].startswith("Z")
    except FileNotFoundError:
        return False


def test_connect_starts_worker_processes_and_names_a_scheduler_that_does_not_answer():
    """farm.connect without an address starts worker processes with this Python (what the
    add-on does inside Blender, where multiprocessing's spawn cannot); they run shgi and are
    gone after. An address where no scheduler answers fails naming it."""
    with farm.connect(workers=2) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        assert client.submit(lambda: __import__("shgi").version()).result() == shgi.version()
        processes = [worker for worker in client.run(os.getpid).values()]
    assert len(set(processes)) == 2 and os.getpid() not in processes
    deadline = time.monotonic() + 30  # a worker's nanny stops it once its own process ends
    while any(alive(pid) for pid in processes) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not any(alive(pid) for pid in processes)
    with pytest.raises(OSError, match=r"no Dask scheduler answers at 'tcp://127\.0\.0\.1:9'"):
        with farm.connect("tcp://127.0.0.1:9"):
            pass
    # Cancelled while Dask still tries to reach it (the add-on's Esc): Cancelled, not the error.
    looks = []
    with pytest.raises(shgi.Cancelled):
        with farm.connect("tcp://127.0.0.1:9", cancelled=lambda: looks.append(1) or
                          len(looks) > 3):
            pass
