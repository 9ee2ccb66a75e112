"""The denoiser's guides at equal samples: the same noisy SHGI frames denoised twice, with the
renderers' Denoising Albedo / Normal (which follow specular bounces, as Cycles') and with the
first hit's (DiffCol + GlossCol + TransCol and Normal, SHGI's guides before those passes).

    PYTHONPATH=build/python /opt/shgi/bpy-5.0.1/bin/python bench/denoise_guides.py
        [--scenes caustics,cornell_box,sun_room] [--samples 1,2,4,...] [--seeds 3]
        [--cache build/equal_time_cache]

A benchmark, not a test: nothing is asserted. Each scene is built as bench/equal_time.py builds
it (same resolution, Light Paths and seed), exported by the add-on, path traced by
shgi.PathTracer with the add-on's F12 settings at each sample count and seed, and each frame is
denoised by shgi.frame_denoise.FrameDenoiser with the add-on's F12 choices (Quality High,
Prefilter Fast, albedo and normal guides) once per guide set. PSNR (shgi.metrics.psnr) against
SHGI's cached 4096-spp reference of bench/equal_time.py (--cache; it is never rendered here),
averaged over seeds. The frames are the same for both guide sets, so the difference is the
guides' alone and does not depend on the machine's load.
"""

import argparse
import os
import sys

import bpy

REPO_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path[:0] = [os.path.join(REPO_ROOT, "bench")]

import equal_time  # noqa: E402  (sets sys.path for the add-on, shgi and the scenes)
import numpy as np  # noqa: E402

DEFAULT_SAMPLES = (1, 2, 4, 8, 16, 32, 64, 128, 256)


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", default="caustics,cornell_box,sun_room")
    parser.add_argument("--samples", default=",".join(str(n) for n in DEFAULT_SAMPLES))
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--resolution", default="200x150", help="WxH pixels")
    parser.add_argument("--cache", default=os.path.join(REPO_ROOT, "build", "equal_time_cache"))
    args = parser.parse_args(argv)
    args.scenes = args.scenes.split(",")
    args.samples = [int(n) for n in args.samples.split(",")]
    args.width, args.height = (int(x) for x in args.resolution.lower().split("x"))
    return args


def main():
    args = parse_args()
    import shgi
    from shgi import frame_denoise, metrics
    from shgi_blender import settings
    from shgi_blender.export.scene_export import export_scene

    first_hit_dropped = (frame_denoise.ALBEDO_PASS, frame_denoise.NORMAL_PASS)
    print(f"denoiser guides at equal samples: scenes {args.scenes}, samples {args.samples}, "
          f"{args.seeds} seeds, F12's denoiser (HIGH, FAST prefilter, albedo + normal)")
    with frame_denoise.FrameDenoiser("HIGH", "FAST", "ALBEDO_NORMAL") as denoiser:
        for name in args.scenes:
            scene = equal_time.build_scene(name, args.width, args.height)
            key = f"{name}_{args.width}x{args.height}_shgi_{equal_time.REFERENCE_SAMPLES}spp"
            path = os.path.join(args.cache, f"{key}.npy")
            if not os.path.exists(path):
                raise SystemExit(f"{path}: no cached reference (run bench/equal_time.py first)")
            reference = np.load(path)
            export = export_scene(bpy.context.evaluated_depsgraph_get(), scene)
            native = export.scene
            native.commit()
            print(f"\n{name}: PSNR dB (mean over seeds) of the denoised frame; noisy: undenoised")
            print(f"{'spp':>5s} {'noisy':>7s} {'first-hit guides':>17s} {'renderer guides':>16s}"
                  f" {'gain':>6s}")
            for samples in args.samples:
                scores = {"noisy": [], "first": [], "renderer": []}
                for seed in range(args.seeds):
                    tracer_settings = settings.path_tracer_settings(scene.shgi, shgi)
                    tracer_settings.samples = samples
                    tracer_settings.seed = equal_time.SEED + seed
                    passes = shgi.render_path_traced(native, tracer_settings)
                    scores["noisy"].append(metrics.psnr(reference, passes["Combined"]))
                    ours = denoiser.denoise(passes)["Combined"]
                    first = denoiser.denoise({k: v for k, v in passes.items()
                                              if k not in first_hit_dropped})["Combined"]
                    scores["renderer"].append(metrics.psnr(reference, ours))
                    scores["first"].append(metrics.psnr(reference, first))
                mean = {k: float(np.mean(v)) for k, v in scores.items()}
                print(f"{samples:5d} {mean['noisy']:7.2f} {mean['first']:17.2f} "
                      f"{mean['renderer']:16.2f} {mean['renderer'] - mean['first']:+6.2f}",
                      flush=True)


if __name__ == "__main__":
    main()
