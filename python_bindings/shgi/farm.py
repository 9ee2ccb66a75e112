"""Bakes on a Dask cluster: the shards of a bake as tasks, merged here into the lightmaps that a
plain bake writes, byte for byte.

``python -m shgi bake SCENE --out DIR --workers N`` starts a local cluster of N worker processes
(``distributed.LocalCluster``, one native thread each unless ``--threads``); ``--scheduler
tcp://HOST:PORT`` uses a running one (``dask scheduler`` and ``dask worker`` on any hosts). The
optional module is ``dask[distributed]`` (``make deps`` installs it); shgi imports without it.

A bake on the cluster:

1. The client prepares the bake as the command line does (``shgi.__main__._prepare``: scene,
   objects, sizes, options; xatlas layouts), so bad input fails before any worker starts.
2. The scene file and the files it references (glTF buffers and images, OBJ materials and
   textures), and a ``--settings`` file, travel as one *bundle* keyed by the SHA-256 of their
   contents: scattered once (Dask's content-hashed key), written by each worker into its cache
   folder under that hash (checked again there). Workers need no shared disk.
3. Shard i of K is one task: the worker bakes it exactly as ``--shard i/K`` does
   (``_bake_shard_or_all``) and returns the shard files' bytes.
4. Each returned shard is *validated* before it is accepted: every object's file must load, and
   its fingerprint (``bake._shard_meta``: objects, sizes, UV map and source, the
   LightmapSettings that decide texel values) must equal this bake's, as the merge checks.
5. When every shard is in, ``bake.merge_shards`` writes the lightmaps (shards are deterministic,
   so the files equal a plain bake's). Nothing is written into DIR but DIR/shards before then.

Faults (the retry policy): a shard gets at most ``SHARD_ATTEMPTS`` (2) runs. A shard whose
worker is lost (killed, out of memory) is rerun on another worker by Dask's scheduler; the local
cluster allows one such loss per shard (``distributed.scheduler.allowed-failures`` = 1), an
external scheduler its own setting (Dask's default 3). A shard that raises, or whose result
fails validation, is submitted once more by the client. A second failure fails the bake with
``ShardFailed``, naming the shard, the worker and the error.

Cancel: Ctrl-C (``KeyboardInterrupt``) or ``BakeProgress.cancel()`` sets a Dask ``Event`` that
every running task watches (its native bake cancels within 0.2 s), cancels the futures and
closes a local cluster; no lightmap file is written.
"""

from __future__ import annotations

import contextlib
import copy
import hashlib
import itertools
import json
import logging
import os
import pickle
import struct
import subprocess
import sys
import tempfile
import threading
import time
import urllib.parse
import uuid
from typing import Callable, Optional

from . import _shgi
from . import bake as _bake
from . import method_registry as _methods
from .denoise import import_optional

__all__ = ["SHARD_ATTEMPTS", "MAX_SHARDS", "MAX_LOCAL_WORKERS", "ShardFailed", "SceneBundle",
           "scene_bundle", "import_distributed", "local_cluster", "bake_command_on_cluster",
           "run_tasks", "solve_probe_grid", "solve_photon_lattice", "photon_ranges", "SceneBlob",
           "bake_scene_on_cluster", "ProcessCluster", "connect"]

# Runs of one shard before the bake fails (see the module's retry policy).
SHARD_ATTEMPTS = 2
# More shards than this only adds per-task overhead: every shard returns each object's whole
# lightmap arrays (docs/farm.md).
MAX_SHARDS = 4096
# Worker processes of a local cluster (--workers): each holds the scene and ~100 MB of Python,
# so more than this on one machine is a mistake, not a farm.
MAX_LOCAL_WORKERS = 256
# How often the client looks at its futures (Ctrl-C lands between looks) and a task at the
# cancel event: the native bake then stops within its own 0.2 s.
_POLL_SECONDS = 0.1
# Shards of a farm bake per worker when the caller names no number: several, so that a slow or
# lost worker's share is small and the others keep busy (docs/farm.md).
SHARDS_PER_WORKER = 4
# Seconds a client waits for a scheduler's answer.
CONNECT_SECONDS = 10
# Share of the progress bar the shards own; the merge owns the rest.
_SHARDS_SHARE = 0.9


class ShardFailed(RuntimeError):
    """A task of a farm bake failed SHARD_ATTEMPTS times; the message names it and the worker."""


def import_distributed():
    """The ``distributed`` module, or ImportError naming the pip command for this Python."""
    distributed = import_optional("distributed",
                                  "baking on a Dask cluster (--workers, --scheduler)",
                                  package="'dask[distributed]'")
    # multiprocessing (imported by distributed) keeps __main__ as sys.modules["__mp_main__"],
    # which only a spawned child needs (it sets its own). In Blender, __main__ is the module of
    # the script Blender runs, freed when the script ends while the alias still names it:
    # Blender 3.4.1 then crashes when it quits (it looks at every module in sys.modules).
    if sys.modules.get("__mp_main__") is sys.modules.get("__main__"):
        del sys.modules["__mp_main__"]
    return distributed


# --- the scene by content hash --------------------------------------------------------------------

class SceneBundle:
    """A scene file and every file it references, as bytes: ``name`` (the scene file's path
    relative to the bundle), ``files`` {relative path: bytes}, ``digest`` (SHA-256 of all)."""

    def __init__(self, name: str, files: dict):
        self.name = name
        self.files = dict(files)
        self.digest = _digest(self.files)

    @property
    def size(self) -> int:
        return sum(len(data) for data in self.files.values())


def _digest(files: dict) -> str:
    sha = hashlib.sha256()
    for name in sorted(files):
        data = files[name]
        sha.update(name.encode("utf-8") + b"\0" + struct.pack("<Q", len(data)))
        sha.update(data)
    return sha.hexdigest()


def scene_bundle(path: str, extra: Optional[dict] = None) -> SceneBundle:
    """The bundle of the scene file `path`: it and the files it references (glTF buffers and
    images, OBJ material libraries and their textures), paths relative to its folder; `extra`
    {name: bytes} travels with it (a settings file). OSError naming a missing file, ValueError
    for a reference that leaves the scene's folder (workers could not place it)."""
    folder, name = os.path.split(os.path.abspath(path))
    files = {name: _read(path)}
    pending = [name]
    while pending:
        current = pending.pop()
        for reference in _references(current, files[current]):
            relative = os.path.normpath(os.path.join(os.path.dirname(current), reference))
            if os.path.isabs(relative) or relative.split(os.sep)[0] == "..":
                raise ValueError(f"{path}: '{reference}' lies outside the scene's folder; copy "
                                 "it beside the scene so that farm workers receive it")
            if relative not in files:
                files[relative] = _read(os.path.join(folder, relative))
                pending.append(relative)
    for key, data in (extra or {}).items():
        files[key] = data
    return SceneBundle(name, files)


def _read(path: str) -> bytes:
    try:
        with open(path, "rb") as file:
            return file.read()
    except OSError as error:
        raise OSError(f"scene file {path}: {error.strerror or error}") from error


def _references(name: str, data: bytes) -> list:
    """Relative paths a scene file names: glTF/GLB buffer and image URIs (not data: URIs), OBJ
    mtllib files, MTL texture maps."""
    lower = name.lower()
    if lower.endswith((".gltf", ".glb")):
        try:
            document = json.loads(_gltf_json(data, lower.endswith(".glb")))
        except (ValueError, struct.error):
            return []  # the loader reports a malformed file, with its own message
        uris = [item.get("uri") for key in ("buffers", "images")
                for item in document.get(key, []) if isinstance(item, dict)]
        return [urllib.parse.unquote(uri) for uri in uris
                if isinstance(uri, str) and uri and not uri.startswith("data:")]
    if lower.endswith((".obj", ".mtl")):
        keys = ("mtllib",) if lower.endswith(".obj") else (
            "map_kd", "map_ks", "map_ke", "map_ns", "map_d", "map_bump", "bump", "norm", "disp")
        found = []
        for line in data.decode("utf-8", "replace").splitlines():
            words = line.split()
            if len(words) >= 2 and words[0].lower() in keys:
                found.append(words[-1])  # options come first; the file name is last
        return found
    return []


def _gltf_json(data: bytes, binary: bool) -> bytes:
    if not binary:
        return data
    length, kind = struct.unpack_from("<II", data, 12)  # the first chunk holds the JSON
    if kind != 0x4E4F534A:
        raise ValueError("GLB without a JSON chunk")
    return data[20:20 + length]


def _scene_on_this_machine(bundle: SceneBundle) -> str:
    """Writes the bundle into this machine's cache folder under its digest (once; checked
    against the digest first) and returns the scene file's path there."""
    if _digest(bundle.files) != bundle.digest:
        raise ValueError(f"the scene bundle's contents do not match its digest {bundle.digest}")
    root = os.path.join(tempfile.gettempdir(), "shgi-farm-scenes")
    folder = os.path.join(root, bundle.digest)
    if not os.path.isdir(folder):
        os.makedirs(root, exist_ok=True)
        staging = tempfile.mkdtemp(dir=root, prefix=".incoming-")
        for name, data in bundle.files.items():
            target = os.path.join(staging, name)
            os.makedirs(os.path.dirname(target), exist_ok=True)
            with open(target, "wb") as file:
                file.write(data)
        try:
            os.rename(staging, folder)  # atomic: another task of this machine may race us
        except OSError:
            if not os.path.isdir(folder):
                raise
    return os.path.join(folder, bundle.name)


# --- tasks on the workers -------------------------------------------------------------------------

def _watch_cancel(distributed, cancel_name: str, cancel: Callable[[], None]):
    """Starts a thread that calls cancel() once the client sets the Event `cancel_name`; returns
    a function that stops the thread."""
    client = distributed.get_client()
    event = distributed.Event(cancel_name, client=client)
    done = threading.Event()

    def watch():
        while not done.is_set():
            try:
                if event.wait(timeout=_POLL_SECONDS * 5):
                    cancel()
                    return
            except Exception:  # the scheduler is gone: this worker is going too
                return

    thread = threading.Thread(target=watch, name="shgi-farm-cancel", daemon=True)
    thread.start()
    return done.set


def _run_cancellable(cancel_name: str, threads: int, work, progress):
    """work() on this worker with `threads` native threads, cancelled when the client sets the
    Event `cancel_name`; returns (result, worker address, seconds)."""
    distributed = import_distributed()
    _shgi.set_max_threads(threads)
    stop = _watch_cancel(distributed, cancel_name, progress.cancel)
    start = time.perf_counter()
    try:
        return work(), distributed.get_worker().address, time.perf_counter() - start
    finally:
        stop()


def _bake_shard_task(bundle: SceneBundle, args, shard: int, shards: int, threads: int,
                     cancel_name: str) -> dict:
    """One shard of a bake, on a worker: {"files": {object name: shard file bytes}, "worker",
    "seconds"}. `args`: the bake command's arguments (its paths are replaced by this
    worker's)."""
    from . import __main__ as cli

    scene_path = _scene_on_this_machine(bundle)
    with tempfile.TemporaryDirectory(prefix="shgi-shard-") as out:
        local = copy.copy(args)
        local.scene, local.out, local.shard, local.merge = scene_path, out, (shard, shards), 0
        if args.settings is not None:
            local.settings = os.path.join(os.path.dirname(scene_path), _SETTINGS_NAME)
        progress = _bake.BakeProgress()

        def work():
            scene, jobs, options = cli._prepare(local)
            _, paths = cli._bake_shard_or_all(local, scene, jobs, options, progress)
            files = {}
            for job, path in zip(jobs, paths):
                with open(path, "rb") as file:
                    files[job.name] = file.read()
            return files

        files, worker, seconds = _run_cancellable(cancel_name, threads, work, progress)
    return {"files": files, "worker": worker, "seconds": seconds}


# A --settings file's name inside the scene bundle (beside the scene).
_SETTINGS_NAME = ".shgi-method-settings.json"


# --- the client -----------------------------------------------------------------------------------

def local_cluster(workers: int, threads_per_worker: int = 1):
    """A LocalCluster of `workers` processes on 127.0.0.1, one Dask thread each; a shard may
    lose one worker and be rerun (the module's retry policy). The scheduler's HTTP server (its
    dashboard, with bokeh) takes a free port, not 8787, which another cluster may hold."""
    distributed = import_distributed()
    import dask

    with dask.config.set({"distributed.scheduler.allowed-failures": SHARD_ATTEMPTS - 1}):
        return distributed.LocalCluster(n_workers=workers, threads_per_worker=threads_per_worker,
                                        processes=True, host="127.0.0.1",
                                        dashboard_address="127.0.0.1:0", silence_logs=logging.ERROR)


class ProcessCluster:
    """A Dask scheduler in this process and `workers` worker processes started as ``python -m
    distributed.cli.dask_worker`` with the interpreter `python`, each able to import this shgi
    (its folder on their PYTHONPATH). For hosts where local_cluster's multiprocessing spawn does
    not work: in Blender, spawn would start sys.executable (whatever Python Blender found) and
    run Blender's __main__, the script Blender runs, again in every worker. The workers stop
    when close() is called, and on their own `death_timeout` seconds after the scheduler goes
    (Blender quitting or crashing leaves no worker behind)."""

    def __init__(self, workers: int, threads_per_worker: int = 1, python: Optional[str] = None,
                 death_timeout: float = 10.0):
        if not (isinstance(workers, int) and 1 <= workers <= MAX_LOCAL_WORKERS):
            raise ValueError(f"workers must be a whole number in 1..{MAX_LOCAL_WORKERS}, got "
                             f"{workers!r}")
        distributed = import_distributed()
        import dask

        self.python = python or sys.executable
        with dask.config.set({"distributed.scheduler.allowed-failures": SHARD_ATTEMPTS - 1}):
            self._scheduler = distributed.LocalCluster(
                n_workers=0, processes=False, protocol="tcp", host="127.0.0.1",
                dashboard_address="127.0.0.1:0",
                silence_logs=logging.ERROR)
        self.scheduler_address = self._scheduler.scheduler_address
        package_root = os.path.dirname(os.path.dirname(os.path.abspath(_shgi.__file__)))
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(
            filter(None, (package_root, os.environ.get("PYTHONPATH")))))
        self.processes = []
        try:
            for i in range(workers):
                self.processes.append(subprocess.Popen(
                    [self.python, "-m", "distributed.cli.dask_worker", self.scheduler_address,
                     "--nthreads", str(threads_per_worker), "--nworkers", "1",
                     "--no-dashboard", "--name", f"shgi-{i}",
                     "--death-timeout", str(death_timeout)],
                    env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL, start_new_session=True))
        except OSError as error:
            self.close()
            raise OSError(f"could not start Dask workers with the Python {self.python!r}: "
                          f"{error}") from error

    def close(self) -> None:
        for process in self.processes:
            if process.poll() is None:
                process.terminate()
        for process in self.processes:
            try:
                process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        self._scheduler.close()


def _client_of(distributed, scheduler: str, cancelled: Callable[[], bool]):
    """A Client of the scheduler at `scheduler`, made on a thread so that cancelled() is looked
    at every _POLL_SECONDS while Dask tries for up to CONNECT_SECONDS (shgi.Cancelled; a client
    that connects after that is closed by its thread)."""
    outcome, lock = {}, threading.Lock()

    def make():
        try:
            client = distributed.Client(scheduler, timeout=f"{CONNECT_SECONDS}s")
        except Exception as error:  # an address Dask cannot parse, or no answer
            outcome["error"] = error
            return
        with lock:
            if outcome.get("abandoned"):
                client.close()
            else:
                outcome["client"] = client

    thread = threading.Thread(target=make, name="shgi-farm-connect", daemon=True)
    thread.start()
    while thread.is_alive():
        if cancelled():
            with lock:
                outcome["abandoned"] = True
                client = outcome.pop("client", None)
            if client is not None:
                client.close()
            raise _shgi.Cancelled("bake cancelled")
        thread.join(_POLL_SECONDS)
    if "error" in outcome:
        error = outcome["error"]
        raise OSError(f"no Dask scheduler answers at {scheduler!r} ({error}); start one with "
                      "`dask scheduler` and workers with `dask worker ADDRESS`") from error
    return outcome["client"]


@contextlib.contextmanager
def connect(scheduler: Optional[str] = None, workers: int = 0, threads_per_worker: int = 1,
            python: Optional[str] = None, cancelled: Callable[[], bool] = lambda: False,
            start_seconds: float = 60.0):
    """A distributed.Client of the cluster at `scheduler` (tcp://HOST:PORT), or of a
    ProcessCluster of `workers` processes on this machine when `scheduler` is empty, waiting
    until they have joined (shgi.Cancelled when cancelled() turns true meanwhile). Closes the
    client, and a cluster it started, on leaving."""
    distributed = import_distributed()
    cluster = None
    if scheduler:
        client = _client_of(distributed, scheduler, cancelled)
    else:
        cluster = ProcessCluster(workers, threads_per_worker, python)
        client = distributed.Client(cluster.scheduler_address, timeout=f"{CONNECT_SECONDS}s")
    try:
        if cluster is not None:
            deadline = time.perf_counter() + start_seconds
            while len(client.scheduler_info()["workers"]) < workers:
                if cancelled():
                    raise _shgi.Cancelled("bake cancelled")
                failed = [p.returncode for p in cluster.processes if p.poll() is not None]
                if failed or time.perf_counter() > deadline:
                    raise OSError(f"the Dask workers did not start with the Python "
                                  f"{cluster.python!r} (exit codes {failed}); it needs "
                                  "dask[distributed] (make deps installs it) and numpy")
                time.sleep(_POLL_SECONDS)
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


class _Scattered:
    """A value on every worker under its content hash (client.scatter, broadcast), scattered
    again when every copy has been lost with the workers that held it: workers that join later
    fetch it from a peer, but a cluster whose workers all died (and were restarted by their
    nannies) has no peer left, and tasks that need it would be cancelled for lost dependencies."""

    def __init__(self, client, value):
        self._client, self._value = client, value
        self._future = None

    def future(self):
        if self._future is None or self._future.status != "finished":
            [self._future] = self._client.scatter([self._value], hash=True, broadcast=True)
        return self._future


def _submitter(client, shared, task, name: str, count: int, args_of: Callable[[int], tuple]):
    """submit(i, attempt) for run_tasks: task(<shared>, *args_of(i)) under a key unique to the
    run and the submission ("shgi-{name}-{i}-of-{count}-..."). `shared` is keyed by its content
    and held by every worker, so that a lost worker loses no copy that others need (workers that
    join later fetch it from a peer), and scattered again when every copy was lost
    (_Scattered)."""
    scattered = _Scattered(client, shared)
    run_id = uuid.uuid4().hex[:8]
    serial = itertools.count()

    def submit(i: int, attempt: int):
        return client.submit(task, scattered.future(), *args_of(i), pure=False,
                             key=f"shgi-{name}-{i}-of-{count}-{run_id}-{attempt}-{next(serial)}")

    return submit


# A task cancelled because its inputs were lost with their workers is submitted again without
# counting as a failed run, at most this many times.
LOST_INPUT_RESUBMITS = 3


def run_tasks(client, submit: Callable[[int, int], object], count: int,
              accept: Callable[[int, dict], int], on_progress: Callable[[int, int], None],
              what: str, cancelled: Callable[[], bool] = lambda: False,
              cancel_event=None) -> None:
    """Runs `count` tasks on the cluster: submit(i, attempt) makes task i's future; accept(i,
    result) validates and keeps its result (ValueError/OSError: rejected) and returns how many
    items it held (texels, probes); on_progress(done, items) after each. A task that fails
    (raises, or is rejected) is submitted again, up to SHARD_ATTEMPTS runs; then ShardFailed
    names `what` i, the worker and the error. A task cancelled for lost dependencies (its inputs
    died with every worker holding them) is submitted again without counting as a run, up to
    LOST_INPUT_RESUBMITS times: submit must then send the inputs again (_Scattered); it may be
    called twice with the same (i, attempt), and its keys must differ. Raises KeyboardInterrupt
    (after cancelling every future) when cancelled() turns true. Whatever ends it early also
    sets `cancel_event` (the Dask Event the running tasks watch), when given."""
    futures = {submit(i, 1): (i, 1) for i in range(count)}
    lost_inputs = dict.fromkeys(range(count), 0)
    done = items = 0
    try:
        while futures:
            if cancelled():
                raise KeyboardInterrupt
            finished = [future for future in futures if future.done()]
            if not finished:
                time.sleep(_POLL_SECONDS)  # Ctrl-C lands here
            for future in finished:
                i, attempt = futures.pop(future)
                error, worker = _outcome(future, client)
                if error is None:
                    result = future.result()
                    worker = result.get("worker", worker)
                    try:
                        items += accept(i, result)
                        done += 1
                        on_progress(done, items)
                        continue
                    except (ValueError, OSError) as rejected:
                        error = f"its result was rejected: {rejected}"
                if "lost dependencies" in error and lost_inputs[i] < LOST_INPUT_RESUBMITS:
                    # Its inputs died with their workers (submit scatters them again): not the
                    # task's failure.
                    lost_inputs[i] += 1
                    futures[submit(i, attempt)] = (i, attempt)
                    continue
                if attempt >= SHARD_ATTEMPTS or error.startswith("KilledWorker"):
                    raise ShardFailed(f"{what} {i} of {count} failed {SHARD_ATTEMPTS} times, "
                                      f"last on worker {worker}: {error}")
                futures[submit(i, attempt + 1)] = (i, attempt + 1)
    except BaseException:
        if cancel_event is not None:
            cancel_event.set()
        client.cancel(list(futures), force=True)
        raise


def _outcome(future, client):
    """(error text or None, worker address) of a finished future."""
    if future.status == "finished":
        return None, "?"
    try:
        future.result(timeout=5)
        return None, "?"
    except Exception as error:  # a task's own error, or Dask's KilledWorker
        worker = getattr(getattr(error, "last_worker", None), "address", None)
        if worker is None:
            worker = _failed_on(future, client)
        return f"{type(error).__name__}: {error}", worker


def _failed_on(future, client) -> str:
    """The worker a failed task last ran on, from the scheduler's story of its key."""
    try:
        for event in reversed(client.story(future.key)):
            for item in event:
                if isinstance(item, str) and item.startswith("tcp://"):
                    return item
    except Exception:
        pass
    return "unknown"


def bake_command_on_cluster(args, progress: _bake.BakeProgress, workers: int = 0,
                            scheduler: Optional[str] = None, threads: int = 1, shards: int = 0,
                            run=None) -> list:
    """The bake of command-line `args` (``python -m shgi bake``'s) on a local cluster of
    `workers` processes, or on the cluster of `scheduler`; returns the merged Lightmaps.
    `shards` 0: SHARDS_PER_WORKER per worker. `run(work, progress)` runs the merge (the CLI's
    _run_on_worker, so that Ctrl-C cancels it). Progress: "shards d/K, R texels/s"."""
    from . import __main__ as cli

    distributed = import_distributed()
    if not (isinstance(threads, int) and threads >= 1):
        raise ValueError(f"threads per worker must be a whole number >= 1, got {threads!r}")
    scene, jobs, options = cli._prepare(args)  # refuses bad input before a worker starts
    jobs = _bake.generate_lightmap_uvs(scene, jobs, options, progress)
    extra = {}
    if args.settings is not None:
        extra[_SETTINGS_NAME] = _read(args.settings)
    bundle = scene_bundle(args.scene, extra)
    cluster = None
    if scheduler:
        client = _client_of(distributed, scheduler, lambda: progress.cancelled)
    else:
        cluster = local_cluster(workers)
        try:
            client = distributed.Client(cluster, timeout=f"{CONNECT_SECONDS}s")
        except BaseException:
            cluster.close()
            raise
    try:
        shards = _bake_shards_on(client, distributed, _bake_shard_task, bundle, (args,), jobs,
                                 options, args.out, shards, threads, progress)
    finally:
        # Cancelled or failed: the tasks were cancelled and watch the cancel event, so a local
        # cluster's workers stop within about a second (measured: 1.0 s for 2 workers).
        client.close()
        if cluster is not None:
            cluster.close()
    merge = _bake.BakeProgress(lambda fraction, stage: _report(
        progress, _SHARDS_SHARE + (1.0 - _SHARDS_SHARE) * fraction, f"merge: {stage}"))
    return (run or (lambda work, _: work()))(
        lambda: _bake.merge_shards(scene, jobs, options, args.out, shards, merge), merge)


def _report(progress: _bake.BakeProgress, fraction: float, stage: str) -> None:
    progress.fraction, progress.stage = fraction, stage
    if progress.callback is not None:
        progress.callback(fraction, stage)


def _bake_shards_on(client, distributed, task, shared, task_args: tuple, jobs, options,
                    out_dir: str, shards: int, threads: int, progress) -> int:
    """Bakes a bake's shards on the client's cluster into out_dir/shards: shard i is the task
    task(<shared, scattered>, *task_args, i, shards, threads, cancel name), which returns the
    shard files' bytes (_accept_shard checks them). `shards` 0: SHARDS_PER_WORKER per worker.
    Returns the number of shards."""
    if not shards:
        shards = SHARDS_PER_WORKER * max(1, len(client.scheduler_info()["workers"]))
    cancel_name = f"shgi-cancel-{uuid.uuid4().hex}"
    cancel = distributed.Event(cancel_name, client=client)
    submit = _submitter(client, shared, task, "shard", shards,
                        lambda i: (*task_args, i, shards, threads, cancel_name))

    def accept(i: int, result: dict) -> int:
        return _accept_shard(result, jobs, options, out_dir, i, shards)

    start = time.perf_counter()

    def on_progress(done: int, texels: int) -> None:
        rate = texels / max(time.perf_counter() - start, 1e-9)
        _report(progress, _SHARDS_SHARE * done / shards,
                f"shards {done}/{shards}, {rate:,.0f} texels/s")

    _report(progress, 0.0, f"shards 0/{shards}")
    run_tasks(client, submit, shards, accept, on_progress, "shard", lambda: progress.cancelled,
              cancel)
    cancel.set()  # every task is done: their cancel watchers return now, not at a cluster's close
    return shards


def _accept_shard(result: dict, jobs, options, out_dir: str, shard: int, shards: int) -> int:
    """Checks a returned shard (every object's file loads and carries this bake's fingerprint)
    and only then moves it into out_dir/shards; returns its baked texels."""
    files = result.get("files") or {}
    if sorted(files) != sorted(job.name for job in jobs):
        raise ValueError(f"it holds objects {sorted(files)}, the bake has "
                         f"{sorted(job.name for job in jobs)}")
    staged, texels = [], 0
    for job in jobs:
        path = _bake.shard_path(out_dir, job.name, shard, shards)
        incoming = path + ".incoming.npz"
        _bake.make_output_folder(os.path.dirname(path))
        with open(incoming, "wb") as file:
            file.write(files[job.name])
        staged.append((incoming, path))
        try:
            part, meta = _bake._load_shard(incoming)
            _bake._check_shard_meta(incoming, meta,
                                    _bake._shard_meta(jobs, job, options, shard, shards, None))
        except (OSError, ValueError):
            for name, _ in staged:
                os.remove(name)
            raise
        texels += int(part.baked.sum())
    for incoming, path in staged:
        os.replace(incoming, path)
    return texels


# --- a scene built in this process (the add-on's export, a script's) ----------------------------

class SceneBlob:
    """A Scene pickled (shgi.pickling) with the SHA-256 of its bytes: what a bake of a scene made
    in memory sends to the workers, scattered once under that hash."""

    def __init__(self, scene: "_shgi.Scene"):
        self.data = pickle.dumps(scene, protocol=pickle.HIGHEST_PROTOCOL)
        self.digest = hashlib.sha256(self.data).hexdigest()

    @property
    def size(self) -> int:
        return len(self.data)


# On a worker: the scene of the last SceneBlob it got, committed once, and the fields solved on
# it, so the shards a worker runs share one BVH build and one solve ({digest: (scene, fields)}).
_worker_scenes: dict = {}
_worker_lock = threading.Lock()


def _worker_scene(blob: SceneBlob, recipe: Optional[tuple], progress) -> tuple:
    """(committed scene, field or None) of a blob on this worker; recipe: (method, settings,
    passes) of the field, None for the path tracer."""
    with _worker_lock:
        entry = _worker_scenes.get(blob.digest)
        if entry is None:
            if hashlib.sha256(blob.data).hexdigest() != blob.digest:
                raise ValueError(f"the scene's bytes do not match their digest {blob.digest}")
            scene = pickle.loads(blob.data)
            scene.commit(progress=progress.native(0.0, 0.0, "Building BVH"))
            _worker_scenes.clear()  # one scene per worker process: a new bake drops the last
            entry = _worker_scenes[blob.digest] = (scene, {})
        scene, fields = entry
        if recipe is None:
            return scene, None
        method, settings, passes = recipe
        key = (method, pickle.dumps(settings), passes)
        if key not in fields:
            native = progress.native(0.0, 0.0, f"solving {method}")
            solver = _methods.solve(method, scene, settings, passes, native)
            fields[key] = solver.current_field()
        return scene, fields[key]


def _scene_shard_task(blob: SceneBlob, jobs, options, recipe: Optional[tuple], shard: int,
                      shards: int, threads: int, cancel_name: str) -> dict:
    """One shard of bake_scene_on_cluster, on a worker: {"files": {object name: shard file
    bytes}, "worker", "seconds"}."""
    progress = _bake.BakeProgress()

    def work():
        scene, field = _worker_scene(blob, recipe, progress)
        with tempfile.TemporaryDirectory(prefix="shgi-shard-") as out:
            paths = _bake.bake_scene(scene, jobs, options, out, field, (shard, shards), progress)
            files = {}
            for job, path in zip(jobs, paths):
                files[job.name] = _read(path)
            return files

    files, worker, seconds = _run_cancellable(cancel_name, threads, work, progress)
    return {"files": files, "worker": worker, "seconds": seconds}


def bake_scene_on_cluster(client, scene: "_shgi.Scene", jobs, options: _bake.BakeOptions,
                          out_dir: str, recipe: Optional[tuple] = None, shards: int = 0,
                          threads: int = 1, progress: Optional[_bake.BakeProgress] = None,
                          on_lightmap: Optional[Callable] = None) -> list:
    """shgi.bake.bake_scene of a scene built in this process, its shards baked on the cluster
    of `client` (a distributed.Client); returns the merged Lightmaps, written into out_dir
    byte-identical to bake_scene's (on_lightmap(lightmap) as each is merged).

    The scene travels pickled (SceneBlob); each worker commits it and solves the field once.
    recipe: (method, settings, passes) of the field that gives the indirect light, solved on the
    workers as shgi.method_registry.solve does (settings as they are: a final gather's
    shallower settings are the caller's, as the add-on's recipe holds them); None: the path
    tracer. shards 0: SHARDS_PER_WORKER per worker. Progress, retries, validation and cancel as
    the command line's farm bake (the module's docstring); nothing but out_dir/shards is
    written before every shard is in."""
    distributed = import_distributed()
    progress = progress or _bake.BakeProgress()
    if not (isinstance(threads, int) and threads >= 1):
        raise ValueError(f"threads per worker must be a whole number >= 1, got {threads!r}")
    if not (isinstance(shards, int) and 0 <= shards <= MAX_SHARDS):
        raise ValueError(f"shards must be a whole number in 0..{MAX_SHARDS}, got {shards!r}")
    if recipe is not None:
        method, settings, passes = recipe
        row = _methods.method(method)  # ValueError naming the choices
        if not row.solves_field:
            recipe = None
        else:
            recipe = (row.identifier, settings, passes)
    _bake._check_jobs(scene, jobs)
    options.settings.validate()
    _bake.denoise_method(options)
    _bake._check_padding(options)
    try:
        shards = _bake_shards_on(client, distributed, _scene_shard_task, SceneBlob(scene),
                                 (jobs, options, recipe), jobs, options, out_dir, shards, threads,
                                 progress)
    except KeyboardInterrupt:
        if progress.cancelled:  # cancel(), not Ctrl-C: as bake_scene ends
            raise _shgi.Cancelled("bake cancelled") from None
        raise

    def on_merge(fraction: float, stage: str) -> None:
        if progress.cancelled:
            merge.cancel()  # the merge's native call stops within one object
        _report(progress, _SHARDS_SHARE + (1.0 - _SHARDS_SHARE) * fraction, f"merge: {stage}")

    merge = _bake.BakeProgress(on_merge)
    lightmaps = []
    for lightmap in _bake.merge_shards(scene, jobs, options, out_dir, shards, merge):
        lightmaps.append(lightmap)
        if on_lightmap is not None:
            on_lightmap(lightmap)
    return lightmaps


# --- solves split into tasks (probe bricks, photon batches) -------------------------------------

def _run_scene_tasks(client, scene_path: str, task, task_args: list, accept, what: str,
                     plural: str, unit: str, share: float, progress: _bake.BakeProgress) -> None:
    """Runs task i = task(<the scene bundle of scene_path>, *task_args[i], cancel event name) on
    the client's cluster by run_tasks: the scene travels by content hash (scattered to every
    worker once), accept(i, result) validates and keeps a result and returns its items, a task
    that fails or is rejected runs once more, and progress reports "{plural} d/N, R {unit}/s"
    over [0, share]. progress.cancel() raises shgi.Cancelled and Ctrl-C KeyboardInterrupt, after
    setting the event the running tasks watch and cancelling every task."""
    distributed = import_distributed()
    count = len(task_args)
    bundle = scene_bundle(scene_path)
    cancel_name = f"shgi-cancel-{uuid.uuid4().hex}"
    cancel = distributed.Event(cancel_name, client=client)
    submit = _submitter(client, bundle, task, plural, count,
                        lambda i: (*task_args[i], cancel_name))

    start = time.perf_counter()

    def on_progress(done: int, items: int) -> None:
        rate = items / max(time.perf_counter() - start, 1e-9)
        _report(progress, share * done / count, f"{plural} {done}/{count}, {rate:,.1f} {unit}/s")

    try:
        run_tasks(client, submit, count, accept, on_progress, what, lambda: progress.cancelled,
                  cancel)
    except KeyboardInterrupt:
        if progress.cancelled:  # cancel(), not Ctrl-C: as bake_scene_on_cluster ends
            raise _shgi.Cancelled(f"{what} tasks cancelled") from None
        raise


# --- probe grids in bricks of probes --------------------------------------------------------------

def solve_probe_grid(client, scene_path: str, settings: "_shgi.ProbeGridSettings", passes: int,
                     bricks: int, threads: int = 1,
                     progress: Optional[_bake.BakeProgress] = None) -> "_shgi.ProbeField":
    """A probe grid of the scene file `scene_path` solved on the client's cluster: its probes
    split into `bricks` bricks of consecutive probes, each a task that updates its brick for
    `passes` passes (ProbeGrid.update_probes), merged with ProbeField.splice into the field a
    single machine's ProbeGrid(scene, settings) and `passes` update() calls give, bit for bit.
    Export it with ProbeField.export (the add-on's Export Volume format). Progress: "bricks
    d/B, P probes/s"; the retry policy and cancel of the lightmap shards (_run_scene_tasks)."""
    from . import __main__ as cli
    from .method_registry import settings_to_dict

    import_distributed()
    settings.validate()
    for name, value, low in (("passes", passes, 1), ("bricks", bricks, 1), ("threads", threads, 1)):
        if not (isinstance(value, int) and value >= low):
            raise ValueError(f"{name} must be a whole number >= {low}, got {value!r}")
    progress = progress or _bake.BakeProgress()
    scene = cli._load(scene_path)
    # Placement here too: the probe count splits the bricks (placement is deterministic, so the
    # workers place the same probes; splice checks it).
    probes = _shgi.ProbeGrid(scene, settings, progress.native(0.0, 0.0, "placing probes"))
    count = probes.probe_count
    bricks = min(bricks, count)
    ranges = [(count * i // bricks, count * (i + 1) // bricks - count * i // bricks)
              for i in range(bricks)]
    wanted = settings_to_dict(settings)
    fields = {}

    def accept(i: int, result: dict) -> int:
        if result.get("settings") != wanted:
            raise ValueError(f"it was solved with settings {result.get('settings')}, the grid's "
                             f"are {wanted}")
        field = _field_from_files(result["files"])
        if field.passes != passes or field.probe_count != count:
            raise ValueError(f"it holds {field.probe_count} probes after {field.passes} passes, "
                             f"the grid {count} after {passes}")
        fields[i] = field
        return ranges[i][1]

    _run_scene_tasks(client, scene_path, _probe_brick_task,
                     [(wanted, passes, first, size, threads) for first, size in ranges], accept,
                     "brick", "bricks", "probes", 1.0, progress)
    merged = fields[0]
    for i in range(1, bricks):
        merged = merged.splice(fields[i], *ranges[i])
    return merged


def _probe_brick_task(bundle: SceneBundle, settings: dict, passes: int, first: int, count: int,
                      threads: int, cancel_name: str) -> dict:
    """Probes first .. first + count - 1 of a probe grid, on a worker: {"files": the grid's
    export (ProbeField.export, float EXR: exact), "settings", "worker", "seconds"}."""
    from . import __main__ as cli
    from .method_registry import settings_from_dict, settings_to_dict

    scene_path = _scene_on_this_machine(bundle)
    grid_settings = settings_from_dict(_shgi.ProbeGridSettings, settings)
    progress = _bake.BakeProgress()

    def work():
        scene = cli._load(scene_path)
        grid = _shgi.ProbeGrid(scene, grid_settings, progress.native(0.0, 0.0, "placing"))
        for k in range(passes):
            grid.update_probes(first, count, progress.native(k / passes, (k + 1) / passes,
                                                             "updating probes"))
        with tempfile.TemporaryDirectory(prefix="shgi-probes-") as folder:
            grid.field().export(os.path.join(folder, "brick.json"))
            files = {}
            for name in os.listdir(folder):
                with open(os.path.join(folder, name), "rb") as file:
                    files[name] = file.read()
        return files

    files, worker, seconds = _run_cancellable(cancel_name, threads, work, progress)
    return {"files": files, "settings": settings_to_dict(grid_settings), "worker": worker,
            "seconds": seconds}


def _field_from_files(files: dict) -> "_shgi.ProbeField":
    """The ProbeField of a brick's export files (OSError/ValueError when they are damaged)."""
    with tempfile.TemporaryDirectory(prefix="shgi-probes-") as folder:
        for name, data in files.items():
            if os.path.basename(name) != name:
                raise ValueError(f"a brick file named {name!r}")
            with open(os.path.join(folder, name), "wb") as file:
                file.write(data)
        return _shgi.ProbeField.import_exr(os.path.join(folder, "brick.json"))


# --- photon lattices in photon batches ------------------------------------------------------------

def photon_ranges(photons: int, batches: int) -> list:
    """[(begin, end)] of `batches` runs of consecutive photons covering [0, photons), as even as
    whole photons allow (at most `photons` batches)."""
    batches = min(batches, photons)
    return [(photons * i // batches, photons * (i + 1) // batches) for i in range(batches)]


def solve_photon_lattice(client, scene_path: str, settings: "_shgi.PhotonLatticeSettings",
                         passes: int, batches: int, threads: int = 1,
                         progress: Optional[_bake.BakeProgress] = None) -> "_shgi.PhotonLattice":
    """A photon lattice of the scene file `scene_path` solved on the client's cluster: each pass's
    photons split into `batches` batches of consecutive photon indices, each a task that traces
    its photons for every one of the `passes` passes (shgi.trace_photon_batch) and returns the
    stored photons; here each pass's batches are merged in photon order (PhotonLattice.
    solve_batches) into the lattice that PhotonLattice(scene, settings) and `passes` solve()
    calls give, bit for bit. Export it with shgi.volume_export.export_lattice (the add-on's
    Export Volume). Progress: "batches d/B, P photons/s", then the merge; the retry policy and
    cancel of the lightmap shards (_run_scene_tasks)."""
    from . import __main__ as cli
    from .method_registry import settings_to_dict

    import_distributed()
    settings.validate()
    for name, value, low in (("passes", passes, 1), ("batches", batches, 1),
                             ("threads", threads, 1)):
        if not (isinstance(value, int) and value >= low):
            raise ValueError(f"{name} must be a whole number >= {low}, got {value!r}")
    progress = progress or _bake.BakeProgress()
    scene = cli._load(scene_path)
    # The lattice's cells measured first, so that a scene or settings it refuses fail before any
    # task runs (a fraction of a second: 0.07 s on the sun room).
    lattice = _shgi.PhotonLattice(scene, settings,
                                  progress.native(0.0, 0.0, "measuring the lattice"))
    ranges = photon_ranges(settings.photons, batches)
    count = len(ranges)
    wanted = settings_to_dict(settings)
    traced = {}

    def accept(i: int, result: dict) -> int:
        traced[i] = _accept_photon_batches(result, wanted, passes, *ranges[i], i)
        return (ranges[i][1] - ranges[i][0]) * passes

    _run_scene_tasks(client, scene_path, _photon_batch_task,
                     [(wanted, passes, begin, end, threads) for begin, end in ranges], accept,
                     "batch", "batches", "photons", _SHARDS_SHARE, progress)
    share = (1.0 - _SHARDS_SHARE) / passes
    for k in range(passes):
        lo = _SHARDS_SHARE + k * share
        lattice.solve_batches([traced[i][k] for i in range(count)],
                              progress.native(lo, lo + share, f"merging pass {k + 1}/{passes}"))
        for i in range(count):
            traced[i][k] = None  # its photons are in the lattice now
    return lattice


def _accept_photon_batches(result: dict, wanted: dict, passes: int, begin: int, end: int,
                           i: int) -> list:
    """The PhotonBatch of each pass in batch i's result, after checking that they are this
    lattice's: its settings, every pass, photons [begin, end) (ValueError; OSError for bytes
    that are not a batch)."""
    from .method_registry import settings_to_dict

    if result.get("settings") != wanted:
        raise ValueError(f"it was traced with settings {result.get('settings')}, the lattice's "
                         f"are {wanted}")
    data = result.get("batches")
    if not isinstance(data, list) or len(data) != passes:
        raise ValueError(f"it holds {len(data) if isinstance(data, list) else 'no'} passes, the "
                         f"lattice {passes}")
    batches = []
    for k, bytes_ in enumerate(data):
        batch = _shgi.PhotonBatch.from_bytes(bytes_, f"batch {i}, pass {k}")
        if settings_to_dict(batch.settings) != wanted:
            raise ValueError(f"its pass {k} was traced with settings "
                             f"{settings_to_dict(batch.settings)}, the lattice's are {wanted}")
        if (batch.pass_index, batch.begin, batch.end) != (k, begin, end):
            raise ValueError(f"its pass {k} holds pass {batch.pass_index}, photons "
                             f"[{batch.begin}, {batch.end}); wanted pass {k}, [{begin}, {end})")
        batches.append(batch)
    return batches


def _photon_batch_task(bundle: SceneBundle, settings: dict, passes: int, begin: int, end: int,
                       threads: int, cancel_name: str) -> dict:
    """Photons [begin, end) of every pass of a photon lattice, on a worker: {"batches": [the
    PhotonBatch bytes of pass 0, 1, ...], "settings", "worker", "seconds"}."""
    from . import __main__ as cli
    from .method_registry import settings_from_dict, settings_to_dict

    scene_path = _scene_on_this_machine(bundle)
    lattice_settings = settings_from_dict(_shgi.PhotonLatticeSettings, settings)
    progress = _bake.BakeProgress()

    def work():
        scene = cli._load(scene_path)
        return [_shgi.trace_photon_batch(scene, lattice_settings, k, begin, end,
                                         progress.native(k / passes, (k + 1) / passes,
                                                         "tracing photons")).to_bytes()
                for k in range(passes)]

    batches, worker, seconds = _run_cancellable(cancel_name, threads, work, progress)
    return {"batches": batches, "settings": settings_to_dict(lattice_settings),
            "worker": worker, "seconds": seconds}
