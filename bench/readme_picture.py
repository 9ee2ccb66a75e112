"""The README's first picture: Cycles + OpenImageDenoise beside SHGI's denoised F12 at the same
wall time, on the Cornell box, each with its PSNR against its own renderer's converged reference
(bench/equal_time.py's scoring). Cycles renders `--cycles-samples` samples; SHGI's default method
then gets Cycles' measured F12 time as its Time Limit. Writes a PNG of the two halves (each
exposed by its reference's auto-exposure) and prints the figures for the caption. A plain script:
benchmarks are not tests.

    /opt/shgi/bpy-5.0.1/bin/python bench/readme_picture.py [--resolution 320x240]
        [--cycles-samples 4] [--reference-samples 1024] [--out docs/images/equal_time_cornell.png]
"""

import argparse
import os
import sys
from types import SimpleNamespace

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import equal_time  # noqa: E402  (bench/equal_time.py: scenes, F12, references)

import numpy as np  # noqa: E402


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution", default="320x240")
    parser.add_argument("--cycles-samples", type=int, default=4)
    parser.add_argument("--reference-samples", type=int, default=1024)
    parser.add_argument("--out", default=os.path.join(equal_time.REPO_ROOT, "docs", "images",
                                                      "equal_time_cornell.png"))
    parser.add_argument("--cache", default=os.path.join(equal_time.REPO_ROOT, "build",
                                                        "equal_time_cache"))
    args = parser.parse_args(argv)
    width, height = (int(x) for x in args.resolution.lower().split("x"))
    refs = SimpleNamespace(cache=args.cache)
    import bpy  # noqa: F401  (loaded by equal_time)
    import addon_utils

    if equal_time.ADDON not in bpy.context.preferences.addons:
        addon_utils.enable(equal_time.ADDON, default_set=True, handle_error=None)
    import shgi
    from shgi import metrics
    from shgi_blender import settings

    method = settings.METHODS[0].identifier  # the add-on's default method
    scene = equal_time.build_scene("cornell_box", width, height)
    key = f"cornell_box_{width}x{height}_{{}}_{args.reference_samples}spp"
    cycles_ref, _ = equal_time.reference(
        scene, key.format("cycles"), "CYCLES",
        lambda s: equal_time.use_cycles(s, args.reference_samples, False), refs)
    shgi_ref, _ = equal_time.reference(  # keyed by SHGI's pixel filter (Cycles' is its default)
        scene, key.format("shgi" + equal_time.pixel_filter_tag(scene.shgi)), "SHGI",
        lambda s: equal_time.use_shgi(s, "PATH_TRACE", args.reference_samples), refs)
    exr = os.path.join(args.cache, "render.exr")
    equal_time.use_cycles(scene, args.cycles_samples, True)
    equal_time.render_f12(scene, "CYCLES", exr)  # warm-up: kernels and OIDN load untimed
    cycles_seconds, cycles = equal_time.render_f12(scene, "CYCLES", exr)
    equal_time.use_shgi(scene, method, equal_time.TIME_LIMITED_SAMPLES,
                        time_limit=cycles_seconds, denoise=True)
    equal_time.render_f12(scene, "SHGI", exr)  # warm-up
    shgi_seconds, ours = equal_time.render_f12(scene, "SHGI", exr)
    halves = [image * metrics.auto_exposure(ref)
              for image, ref in ((cycles, cycles_ref), (ours, shgi_ref))]
    gap = np.ones((height, 4, 3))
    shgi.write_png(args.out, np.concatenate([halves[0], gap, halves[1]], axis=1)
                   .astype(np.float32))
    print(f"Cycles + OIDN, {args.cycles_samples} spp: {cycles_seconds:.2f} s, "
          f"{metrics.psnr(cycles_ref, cycles):.1f} dB; SHGI {method} with Time Limit "
          f"{cycles_seconds:.2f} s, denoised: {shgi_seconds:.2f} s, "
          f"{metrics.psnr(shgi_ref, ours):.1f} dB; {width}x{height}, references "
          f"{args.reference_samples} spp -> {args.out}")


if __name__ == "__main__":
    main()
