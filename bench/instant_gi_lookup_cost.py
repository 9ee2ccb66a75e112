"""What one Instant GI preview sample costs as passes are solved: process CPU time of
PreviewRenderer.render(field, 1) on bench/equal_time.py's caustics scene (glass and gold spheres:
many lookups beyond the first surfaces, through glass and off mirrors) with the add-on's F12
settings, for fields of --passes passes (one solver refined on), and the lookups and VPLs read
beyond the first surfaces (InstantGiField.lookup_counts, where the build has it). CPU time counts
every thread of the process, so it holds on a loaded machine up to cache and frequency effects.
A benchmark, not a test: nothing is asserted.

    PYTHONPATH=build/python /opt/shgi/bpy-5.0.1/bin/python bench/instant_gi_lookup_cost.py \\
        --save-scenes /tmp/ig_scenes [--scenes caustics] [--resolution 200x150]
    PYTHONPATH=build/python python3 bench/instant_gi_lookup_cost.py \\
        --render /tmp/ig_scenes/caustics.pkl [--passes 4 16 32 64] [--samples 8]

The first step (bpy) pickles each scene's native Scene, the add-on's InstantGiSettings and
PreviewSettings (shgi.pickling); the second (no bpy) renders them.
"""

import argparse
import os
import pickle
import resource
import statistics
import sys

REPO_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path[:0] = [os.path.join(REPO_ROOT, "bench")]


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", default="caustics")
    parser.add_argument("--resolution", default="200x150", help="WxH pixels")
    parser.add_argument("--save-scenes", default=None, metavar="DIR",
                        help="pickle each scene and its F12 settings to DIR and stop (bpy)")
    parser.add_argument("--render", default=None, metavar="PICKLE",
                        help="time a --save-scenes pickle's samples (no bpy)")
    parser.add_argument("--passes", type=int, nargs="+", default=[4, 16, 32, 64])
    parser.add_argument("--samples", type=int, default=8,
                        help="samples timed per field, each a render(field, 1)")
    args = parser.parse_args(argv)
    args.width, args.height = (int(x) for x in args.resolution.lower().split("x"))
    return args


def cpu_seconds():
    usage = resource.getrusage(resource.RUSAGE_SELF)  # every thread of the process
    return usage.ru_utime + usage.ru_stime


def save_scenes(args):
    import bpy
    import equal_time  # (sets sys.path for the add-on, shgi and the scenes)
    import shgi
    from shgi_blender import settings
    from shgi_blender.export.scene_export import export_scene

    os.makedirs(args.save_scenes, exist_ok=True)
    for name in args.scenes.split(","):
        scene = equal_time.build_scene(name, args.width, args.height)
        scene.shgi.method = "INSTANT_GI"
        native = export_scene(bpy.context.evaluated_depsgraph_get(), scene).scene
        with open(os.path.join(args.save_scenes, f"{name}.pkl"), "wb") as file:
            pickle.dump((native, settings.instant_gi_settings(scene.shgi, shgi),
                         settings.preview_settings(scene.shgi, shgi)), file)


def render(args):
    import shgi

    with open(args.render, "rb") as file:
        scene, instant_settings, preview_settings = pickle.load(file)
    scene.commit()
    solver = shgi.InstantGi(scene, instant_settings)
    print(f"{'passes':>6s} {'CPU s/sample (median)':>22s} {'min':>7s} {'lookups/sample':>15s} "
          f"{'VPLs read/sample':>17s}")
    for passes in sorted(args.passes):
        while solver.passes < passes:
            solver.refine()
        field = solver.current_field()
        renderer = shgi.PreviewRenderer(scene, preview_settings)
        seconds, lookups, vpls = [], [], []
        for _ in range(args.samples):
            start = cpu_seconds()
            renderer.render(field, 1)
            seconds.append(cpu_seconds() - start)
            if hasattr(field, "lookup_counts"):
                counts = field.lookup_counts
                lookups.append(counts["lookups"])
                vpls.append(counts["vpls"])
        count = (f"{statistics.mean(lookups):15.0f} {statistics.mean(vpls):17.0f}" if lookups
                 else f"{'-':>15s} {'-':>17s}")
        print(f"{passes:6d} {statistics.median(seconds):22.3f} {min(seconds):7.3f} {count}",
              flush=True)


def main():
    args = parse_args()
    if args.save_scenes:
        save_scenes(args)
    elif args.render:
        render(args)
    else:
        sys.exit("give --save-scenes DIR (bpy) or --render PICKLE")


if __name__ == "__main__":
    main()
