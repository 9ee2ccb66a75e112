"""Command line: ``python -m shgi bake scene.gltf --out DIR`` bakes lightmaps without Blender.

Lightmaps are sized as the Blender add-on sizes them by default: from a texel density of
shgi.bake.DEFAULT_TEXELS_PER_METRE (--density; --resolution gives a fixed size). A scene no lamp
and no emissive material lights is refused unless --world-light-only asks to bake it.

Exit status: 0 on success, 1 for an error (the message names the input and the fix), 2 for bad
arguments, 130 when interrupted (Ctrl-C cancels the running bake; finished lightmaps stay).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import threading
import time

from . import _shgi
from . import bake as _bake
from . import farm as _farm
from . import method_registry as _methods


def _shard(text: str):
    try:
        i, n = (int(part) for part in text.split("/"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: use i/N, e.g. 0/4") from None
    if not (n >= 1 and 0 <= i < n):
        raise argparse.ArgumentTypeError(f"{text!r}: need N >= 1 and 0 <= i < N")
    return i, n


def _whole(minimum: int):
    """argparse type: an int >= minimum."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"{value} is less than {minimum}")
        return value
    return parse


def _positive(text: str) -> float:
    """argparse type: a finite float > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (value > 0.0 and value != float("inf")):
        raise argparse.ArgumentTypeError(f"{text} is not a positive number")
    return value


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m shgi", description=__doc__.split("\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    bake = commands.add_parser(
        "bake", help="bake lightmaps of a glTF (.gltf/.glb) or OBJ scene",
        description="Bakes lightmaps of a glTF or OBJ scene. Each lightmap is sized from a texel "
                    f"density of {_bake.DEFAULT_TEXELS_PER_METRE:g} texels per metre of its "
                    f"surface ({_bake.MIN_RESOLUTION}..{_bake.MAX_RESOLUTION} texels per side), "
                    "the Blender add-on's default; --density sets another density, --resolution "
                    "N makes every lightmap N x N. A scene without lamps or emissive materials "
                    "is refused (see --world-light-only).")
    bake.add_argument("scene", help="scene file (.gltf, .glb or .obj)")
    bake.add_argument("--out", required=True, help="output folder (created if missing)")
    bake.add_argument("--uv-set", default=None,
                      help="lightmap UV map (default: LightmapUV, else a glTF's TEXCOORD_1 "
                           "'UVMap.001')")
    bake.add_argument("--uv", type=str.upper, default="EXISTING",
                      choices=_bake.LIGHTMAP_UV_SOURCES,
                      help="where the lightmap UV map comes from: EXISTING (objects without it "
                           "are skipped) or XATLAS (objects without it get one from xatlas; "
                           "prints each one's chart count and utilization)")
    bake.add_argument("--objects", default=None,
                      help="comma-separated object names (default: every object with the UV map; "
                           "with --uv xatlas every object)")
    size = bake.add_mutually_exclusive_group()
    size.add_argument("--resolution", type=_whole(1), default=0,
                      help="texels per side of every lightmap (default: sized by --density)")
    size.add_argument("--density", type=_positive, default=_bake.DEFAULT_TEXELS_PER_METRE,
                      help="texels per metre of surface, each lightmap "
                           f"{_bake.MIN_RESOLUTION}..{_bake.MAX_RESOLUTION} texels per side "
                           f"(default {_bake.DEFAULT_TEXELS_PER_METRE:g}, the Blender add-on's "
                           "Texel Density)")
    bake.add_argument("--samples", type=_whole(1), default=256, help="samples per texel (256)")
    bake.add_argument("--content", default="DIRECT_INDIRECT",
                      choices=["DIRECT_INDIRECT", "DIRECT", "INDIRECT", "FULL"])
    bake.add_argument("--method", type=_method_name, default="PATH_TRACE",
                      metavar="{" + ",".join(_bake.sources()) + "}",
                      help="source of indirect light, a method of shgi.methods() (PATH_TRACE: "
                           "path tracing, the ground truth)")
    bake.add_argument("--settings", default=None, metavar="JSON",
                      help="the method's settings as a JSON file of field: value pairs "
                           "(shgi.settings_to_dict; the Blender add-on's Export Bake Settings "
                           "writes one), so a bake here matches the add-on's byte for byte")
    bake.add_argument("--passes", type=_whole(0), default=None,
                      help="refinement passes of the method (default: its final_passes)")
    bake.add_argument("--directional", action="store_true",
                      help="also write SH layers of the incident radiance (SH.c0 .. SH.c3, L1)")
    bake.add_argument("--sh-order", type=int, choices=(1, 2), default=1,
                      help="with --directional: 1 (L1: SH.c0 .. SH.c3, the default) or 2 (L2: "
                           "SH.c0 .. SH.c8, 9 coefficients per channel)")
    bake.add_argument("--final-gather", action="store_true",
                      help="with a --method that solves a field: each sample traces one ray "
                           "that reads the field where it lands (slower; the field's blocks and "
                           "leaks one bounce further away); the field is solved one diffuse "
                           "bounce shallower, so the light keeps its depth")
    bake.add_argument("--filter", action="store_true",
                      help="SHGI's edge-aware denoising filter (the same as --denoise SHGI)")
    bake.add_argument("--denoise", default="NONE", choices=["NONE", "SHGI", "OIDN"],
                      help="denoiser before dilation: OIDN = OpenImageDenoise per UV chart "
                           "(needs the pyoidn module)")
    bake.add_argument("--padding", type=_whole(0), default=4, help="dilation texels (4)")
    bake.add_argument("--seed", type=_whole(0), default=0)
    bake.add_argument("--threads", type=_whole(0), default=0,
                      help="native threads; 0: all cores (on a farm: per worker, default 1)")
    farm = bake.add_mutually_exclusive_group()
    farm.add_argument("--shard", type=_shard, default=None,
                      help="bake only shard i of N (i/N) into OUT/shards")
    farm.add_argument("--merge", type=_whole(1), default=0, metavar="N",
                      help="merge the N shard files in OUT/shards into the lightmaps")
    farm.add_argument("--workers", type=_whole(1), default=0, metavar="N",
                      help="bake on a local Dask cluster of N worker processes (one native "
                           "thread each unless --threads says otherwise), shards as tasks, "
                           "merged into the lightmaps a plain bake writes (docs/farm.md)")
    farm.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                      help="bake on the running Dask cluster of this scheduler instead")
    bake.add_argument("--shards", type=_whole(1), default=0, metavar="K",
                      help="with --workers or --scheduler: shards of the bake (default: "
                           f"{_farm.SHARDS_PER_WORKER} per worker)")
    bake.add_argument("--world-light-only", action="store_true",
                      help="bake a scene without lamps or emissive materials, lit by the "
                           "loader's default world alone (refused without this flag: a glTF "
                           "exporter may have left the scene's lights out)")
    bake.add_argument("--quiet", action="store_true", help="no progress bar")
    return parser


def _method_name(name: str) -> str:
    """--method's value: a method identifier (or an older name), as its identifier."""
    try:
        return _methods.method(name.upper()).identifier
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from error


def _method_settings(method: str, path, seed: int):
    """The settings of `method` from the JSON file `path` (None: its defaults with `seed`)."""
    row = _methods.method(method)
    if path is None or not row.solves_field:
        return None
    try:
        with open(path, encoding="utf-8") as file:
            values = json.load(file)
    except (OSError, ValueError) as error:
        raise ValueError(f"--settings {path}: {error}") from error
    if not isinstance(values, dict):
        raise ValueError(f"--settings {path}: expected a JSON object of field: value pairs")
    return _methods.settings_from_dict(row.settings_type, values)


def _load(path: str):
    lower = path.lower()
    if lower.endswith((".gltf", ".glb")):
        scene = _shgi.load_gltf(path)
    elif lower.endswith(".obj"):
        scene = _shgi.load_obj(path)
    else:
        raise ValueError(f"{path}: not a .gltf, .glb or .obj file")
    if not scene.committed:
        scene.commit()
    return scene


def _uv_set(scene, requested, lightmap_uvs: str):
    """The UV map to bake: `requested`, else LightmapUV, else a glTF's TEXCOORD_1; with XATLAS
    any name (meshes without it get it), LightmapUV when the scene has neither."""
    generate = lightmap_uvs == "XATLAS"
    names = set()
    for mesh in scene.meshes:
        names.update(mesh.uv_sets)
    if requested:
        if requested not in names and not generate:
            raise ValueError(f"no mesh has the UV map '{requested}'; the scene has "
                             f"{sorted(names) or 'no UV maps'}")
        return requested
    for candidate in ("LightmapUV", "UVMap.001"):
        if candidate in names:
            return candidate
    if generate:
        return "LightmapUV"
    raise ValueError("no mesh has a lightmap UV map ('LightmapUV', or a second glTF UV set "
                     f"TEXCOORD_1); the scene has {sorted(names) or 'no UV maps'}; pass "
                     "--uv-set NAME, or --uv xatlas to lay one out")


def _check_lamps(scene, path: str) -> None:
    """ValueError when no lamp and no emissive material light the scene: glTF and OBJ files
    hold no world, so only the loader's dim default world would light the bake."""
    if _bake.has_lamps_or_emitters(scene):
        return
    raise ValueError(
        f"{path}: no lamp and no emissive material lights the scene, only the loader's default "
        "world would (the lightmaps would be nearly black); its lights may have been left out "
        "by the exporter (Blender's glTF exporter writes point, spot and sun lights only with "
        "Include > Punctual Lights, and no area lights): export them, add an emissive "
        "material, or pass --world-light-only to bake with the world's light alone")


class _Bar:
    """A one-line progress bar on stderr, redrawn at most 10 times a second."""

    def __init__(self, enabled: bool):
        # On a terminal, or where SHGI_PROGRESS=1 asks for it (a farm's log, a test).
        forced = os.environ.get("SHGI_PROGRESS", "0") not in ("", "0")
        self.enabled = enabled and (sys.stderr.isatty() or forced)
        self.last = 0.0

    def __call__(self, fraction: float, stage: str) -> None:
        now = time.monotonic()
        if not self.enabled or (now - self.last < 0.1 and fraction < 1.0):
            return
        self.last = now
        filled = int(30 * fraction)
        sys.stderr.write(f"\r[{'#' * filled}{'.' * (30 - filled)}] {100 * fraction:5.1f}% "
                         f"{stage[:60]:<60}")
        sys.stderr.flush()

    def done(self) -> None:
        if self.enabled:
            sys.stderr.write("\n")


def _prepare(args):
    """(scene, jobs, options) of a bake command: the scene loaded and checked, the objects and
    their sizes, the bake options. A farm's workers prepare from the same arguments (shgi.farm)."""
    scene = _load(args.scene)
    if not args.world_light_only:
        _check_lamps(scene, args.scene)
    uv_set = _uv_set(scene, args.uv_set, args.uv)
    names = [n.strip() for n in args.objects.split(",") if n.strip()] if args.objects else None
    density = 0.0 if args.resolution else args.density
    jobs = _bake.jobs_for_scene(scene, uv_set, args.resolution, density, names, args.uv)
    settings = _shgi.LightmapSettings(samples=args.samples, content=args.content,
                                      directional=args.directional, sh_order=args.sh_order,
                                      seed=args.seed,
                                      final_gather=args.final_gather)
    options = _bake.BakeOptions(settings=settings, uv_set=uv_set, filter=args.filter,
                                denoise=args.denoise, padding=args.padding, lightmap_uvs=args.uv)
    return scene, jobs, options


def _bake_shard_or_all(args, scene, jobs, options, progress):
    """(jobs with their UV layouts, results) of a plain bake, a --shard or a --merge."""
    # UV layouts first: a solved field belongs to the scene with its final meshes.
    laid_out = _bake.generate_lightmap_uvs(scene, jobs, options, progress)
    if args.merge:
        return laid_out, _bake.merge_shards(scene, laid_out, options, args.out, args.merge,
                                            progress)
    field = _bake.solve_field(scene, args.method, args.seed, progress,
                              _method_settings(args.method, args.settings, args.seed),
                              args.passes, gather=args.final_gather)
    return laid_out, _bake.bake_scene(scene, laid_out, options, args.out, field, args.shard,
                                      progress)


def _bake_command(args) -> int:
    if args.workers or args.scheduler:
        return _farm_command(args)
    if args.shards:
        raise ValueError("--shards splits a farm bake: give --workers N or --scheduler ADDRESS "
                         "too (or --shard i/N to bake one shard here)")
    if args.threads:
        _shgi.set_max_threads(args.threads)
    scene, jobs, options = _prepare(args)
    bar = _Bar(not args.quiet)
    progress = _bake.BakeProgress(bar)

    def work():
        return _bake_shard_or_all(args, scene, jobs, options, progress)

    interrupted = False
    try:
        laid_out, results = _run_on_worker(work, progress)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        bar.done()  # ends the bar's line before anything else is printed
    if interrupted:
        print("cancelled", file=sys.stderr)
        return 130
    for job in laid_out:
        if job.uv_layout is not None:
            print(f"{job.name}: {_bake.describe_uv_layout(job.uv_layout)}")
    for item in results:
        if isinstance(item, str):
            print(item)
        else:
            print(f"{item.name}: {' '.join(item.paths)}")
    return 0


def _farm_command(args) -> int:
    """A bake on a Dask cluster (shgi.farm): shards as tasks, then the merge here."""
    if args.shards > _farm.MAX_SHARDS:
        raise ValueError(f"--shards {args.shards}: at most {_farm.MAX_SHARDS} (each shard returns "
                         "its objects' whole arrays; see docs/farm.md)")
    if args.workers > _farm.MAX_LOCAL_WORKERS:
        raise ValueError(f"--workers {args.workers}: a local cluster runs at most "
                         f"{_farm.MAX_LOCAL_WORKERS} worker processes on this machine; for more, "
                         "start a Dask cluster over several hosts and pass --scheduler")
    bar = _Bar(not args.quiet)
    progress = _bake.BakeProgress(bar)
    interrupted = False
    try:
        lightmaps = _farm.bake_command_on_cluster(
            args, progress, workers=args.workers, scheduler=args.scheduler,
            threads=args.threads or 1, shards=args.shards, run=_run_on_worker)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        bar.done()
    if interrupted:
        print("cancelled", file=sys.stderr)
        return 130
    for item in lightmaps:
        print(f"{item.name}: {' '.join(item.paths)}")
    return 0


def _run_on_worker(work, progress):
    """Runs work() on a worker thread, so that Ctrl-C on the main thread can cancel it through
    `progress`; returns what work() returned or raises what it raised. After a Ctrl-C, waits
    until the cancelled work has stopped and raises KeyboardInterrupt."""
    outcome = {}
    finished = threading.Event()

    def run():
        try:
            outcome["value"] = work()
        except BaseException as error:  # handed to the main thread
            outcome["error"] = error
        finally:
            finished.set()

    worker = threading.Thread(target=run, name="shgi-bake")
    worker.start()
    # Event.wait, not Thread.join(timeout): in Python 3.11 a KeyboardInterrupt landing inside
    # join() marks the thread as stopped while it still runs; the interpreter then exits under
    # a running bake and the process aborts (std::terminate).
    try:
        while not finished.wait(0.1):
            pass
    except KeyboardInterrupt:
        progress.cancel()
        while not finished.is_set():
            try:
                finished.wait()
            except KeyboardInterrupt:  # another Ctrl-C: the cancel is already on its way
                pass
        worker.join()
        raise
    worker.join()
    if "error" in outcome:
        raise outcome["error"]
    return outcome["value"]


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    try:
        return _bake_command(args)
    except _shgi.Cancelled:
        print("cancelled", file=sys.stderr)
        return 130
    except (ValueError, OSError, RuntimeError, ImportError) as error:
        print(f"shgi bake: error: {error}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
