"""Command line: ``python -m shgi bake scene.gltf --out DIR`` bakes lightmaps without Blender.

Exit status: 0 on success, 1 for an error (the message names the input and the fix), 2 for bad
arguments, 130 when interrupted (Ctrl-C cancels the running bake; finished lightmaps stay).
"""

from __future__ import annotations

import argparse
import os
import sys
import threading
import time

from . import _shgi
from . import bake as _bake


def _shard(text: str):
    try:
        i, n = (int(part) for part in text.split("/"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--shard {text!r}: use i/N, e.g. 0/4")
    if not (n >= 1 and 0 <= i < n):
        raise argparse.ArgumentTypeError(f"--shard {text}: need N >= 1 and 0 <= i < N")
    return i, n


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m shgi", description=__doc__.split("\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    bake = commands.add_parser("bake", help="bake lightmaps of a glTF (.gltf/.glb) or OBJ scene")
    bake.add_argument("scene", help="scene file (.gltf, .glb or .obj)")
    bake.add_argument("--out", required=True, help="output folder (created if missing)")
    bake.add_argument("--uv-set", default=None,
                      help="lightmap UV map (default: LightmapUV, else a glTF's TEXCOORD_1 "
                           "'UVMap.001')")
    bake.add_argument("--objects", default=None,
                      help="comma-separated object names (default: every object with the UV map)")
    size = bake.add_mutually_exclusive_group()
    size.add_argument("--resolution", type=int, default=0, help="texels per side (256)")
    size.add_argument("--density", type=float, default=0.0, help="texels per metre")
    bake.add_argument("--samples", type=int, default=256, help="samples per texel (256)")
    bake.add_argument("--content", default="DIRECT_INDIRECT",
                      choices=["DIRECT_INDIRECT", "DIRECT", "INDIRECT", "FULL"])
    bake.add_argument("--method", default="PATH_TRACER",
                      choices=["PATH_TRACER", "PHOTON_LATTICE", "PROBE_GRID"],
                      help="source of indirect light (PATH_TRACER: ground truth)")
    bake.add_argument("--directional", action="store_true", help="also write L1 SH layers")
    bake.add_argument("--filter", action="store_true", help="edge-aware denoising filter")
    bake.add_argument("--padding", type=int, default=4, help="dilation texels (4)")
    bake.add_argument("--seed", type=int, default=0)
    bake.add_argument("--threads", type=int, default=0, help="0: all cores")
    farm = bake.add_mutually_exclusive_group()
    farm.add_argument("--shard", type=_shard, default=None,
                      help="bake only shard i of N (i/N) into OUT/shards")
    farm.add_argument("--merge", type=int, default=0, metavar="N",
                      help="merge the N shard files in OUT/shards into the lightmaps")
    bake.add_argument("--quiet", action="store_true", help="no progress bar")
    return parser


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


def _uv_set(scene, requested):
    if requested:
        return requested
    names = set()
    for mesh in scene.meshes:
        names.update(mesh.uv_sets)
    for candidate in ("LightmapUV", "UVMap.001"):
        if candidate in names:
            return candidate
    raise ValueError("no mesh has a lightmap UV map ('LightmapUV', or a second glTF UV set "
                     f"TEXCOORD_1); the scene has {sorted(names) or 'no UV maps'}; pass "
                     "--uv-set NAME")


def _field(scene, method: str, seed: int, progress):
    if method == "PATH_TRACER":
        return None
    if method == "PHOTON_LATTICE":
        lattice = _shgi.PhotonLattice(scene, _shgi.PhotonLatticeSettings(seed=seed))
        lattice.solve(progress.native(0.0, 0.0, "photon lattice"))
        return lattice
    grid = _shgi.ProbeGrid(scene, _shgi.ProbeGridSettings(seed=seed),
                           progress.native(0.0, 0.0, "probe grid"))
    for _ in range(8):
        grid.update(progress.native(0.0, 0.0, "probe grid"))
    return grid.field()


class _Bar:
    """A one-line progress bar on stderr, redrawn at most 10 times a second."""

    def __init__(self, enabled: bool):
        self.enabled = enabled and sys.stderr.isatty() or enabled and "SHGI_PROGRESS" in os.environ
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


def _bake(args) -> int:
    if args.threads:
        _shgi.set_max_threads(args.threads)
    scene = _load(args.scene)
    uv_set = _uv_set(scene, args.uv_set)
    names = [n.strip() for n in args.objects.split(",")] if args.objects else None
    jobs = _bake.jobs_for_scene(scene, uv_set, args.resolution, args.density, names)
    settings = _shgi.LightmapSettings(samples=args.samples, content=args.content,
                                      directional=args.directional, seed=args.seed)
    options = _bake.BakeOptions(settings=settings, uv_set=uv_set, filter=args.filter,
                                padding=args.padding)
    bar = _Bar(not args.quiet)
    progress = _bake.BakeProgress(bar)
    result = {}

    def work():
        try:
            if args.merge:
                result["value"] = _bake.merge_shards(scene, jobs, options, args.out, args.merge,
                                                     progress)
            else:
                field = _field(scene, args.method, args.seed, progress)
                result["value"] = _bake.bake_scene(scene, jobs, options, args.out, field,
                                                   args.shard, progress)
        except BaseException as error:  # handed to the main thread
            result["error"] = error

    # The bake runs on a worker so that Ctrl-C on the main thread can cancel it.
    worker = threading.Thread(target=work, name="shgi-bake")
    worker.start()
    try:
        while worker.is_alive():
            worker.join(0.1)
    except KeyboardInterrupt:
        progress.cancel()
        worker.join()
        bar.done()
        print("cancelled", file=sys.stderr)
        return 130
    bar.done()
    if "error" in result:
        raise result["error"]
    for item in result["value"]:
        if isinstance(item, str):
            print(item)
        else:
            print(f"{item.name}: {' '.join(item.paths)}")
    return 0


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    try:
        return _bake(args)
    except _shgi.Cancelled:
        print("cancelled", file=sys.stderr)
        return 130
    except (ValueError, OSError, RuntimeError) as error:
        print(f"shgi bake: error: {error}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
