"""What Light Paths > Filter Glossy costs SHGI's path tracer per sample: process CPU time of
shgi.render_path_traced on bench/equal_time.py's scenes with the add-on's F12 settings, Filter
Glossy 0 and 1 alternated (ABAB..., --repeats pairs, the order of each pair swapped every time),
and the ratio of their medians and of their minima. CPU time counts every thread of the process,
so it holds on a loaded machine up to the load's cache and frequency effects, which the
alternation spreads over both. A benchmark, not a test: nothing is asserted.

    PYTHONPATH=build/python /opt/shgi/bpy-5.0.1/bin/python bench/filter_glossy_cost.py
        [--scenes caustics,sun_room] [--samples 16] [--repeats 5] [--resolution 200x150]
        [--save-scenes DIR]

Instruction counts, which no load changes: --save-scenes DIR pickles each scene's native Scene
and the add-on's PathTracerSettings (shgi.pickling) to DIR/<scene>.pkl and stops; then, without
bpy, ``--render DIR/<scene>.pkl --filter-glossy X --samples N`` renders it once, e.g. under
``valgrind --tool=callgrind /usr/bin/python3 bench/filter_glossy_cost.py --render ...`` at 1
and 9 spp for each X: the difference over 8 samples is the instructions of 8 samples.
"""

import argparse
import os
import pickle
import statistics
import sys
import time

REPO_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path[:0] = [os.path.join(REPO_ROOT, "bench")]


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", default="caustics,sun_room")
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--resolution", default="200x150", help="WxH pixels")
    parser.add_argument("--save-scenes", default=None, metavar="DIR",
                        help="pickle each scene and its F12 settings to DIR and stop")
    parser.add_argument("--render", default=None, metavar="PICKLE",
                        help="render a --save-scenes pickle once (no bpy) and stop")
    parser.add_argument("--filter-glossy", type=float, default=1.0, help="for --render")
    args = parser.parse_args(argv)
    args.width, args.height = (int(x) for x in args.resolution.lower().split("x"))
    return args


def render_pickle(args):
    """One render of a --save-scenes pickle at --samples and --filter-glossy, seed 1."""
    import shgi

    with open(args.render, "rb") as file:
        scene, tracer_settings = pickle.load(file)
    scene.commit()
    tracer_settings.samples = args.samples
    tracer_settings.seed = 1
    tracer_settings.filter_glossy = args.filter_glossy
    shgi.render_path_traced(scene, tracer_settings)


def main():
    args = parse_args()
    if args.render:
        render_pickle(args)
        return
    import bpy
    import equal_time  # (sets sys.path for the add-on, shgi and the scenes)
    import shgi
    from shgi_blender import settings
    from shgi_blender.export.scene_export import export_scene

    if args.save_scenes:
        os.makedirs(args.save_scenes, exist_ok=True)
        for name in args.scenes.split(","):
            scene = equal_time.build_scene(name, args.width, args.height)
            native = export_scene(bpy.context.evaluated_depsgraph_get(), scene).scene
            with open(os.path.join(args.save_scenes, f"{name}.pkl"), "wb") as file:
                pickle.dump((native, settings.path_tracer_settings(scene.shgi, shgi)), file)
        return

    print(f"{'scene':10s} {'spp':>4s} {'fg0 ms/spp':>18s} {'fg1 ms/spp':>18s} "
          f"{'ratio (median)':>15s} {'ratio (min)':>12s}")
    for name in args.scenes.split(","):
        scene = equal_time.build_scene(name, args.width, args.height)
        native = export_scene(bpy.context.evaluated_depsgraph_get(), scene).scene
        native.commit()
        seconds = {0.0: [], 1.0: []}
        for repeat in range(args.repeats):
            for value in ((0.0, 1.0) if repeat % 2 == 0 else (1.0, 0.0)):
                tracer_settings = settings.path_tracer_settings(scene.shgi, shgi)
                tracer_settings.samples = args.samples
                tracer_settings.seed = equal_time.SEED
                tracer_settings.filter_glossy = value
                start = time.process_time()
                shgi.render_path_traced(native, tracer_settings)
                seconds[value].append(time.process_time() - start)
        per_sample = {k: [1e3 * s / args.samples for s in v] for k, v in seconds.items()}
        medians = {k: statistics.median(v) for k, v in per_sample.items()}
        minima = {k: min(v) for k, v in per_sample.items()}
        print(f"{name:10s} {args.samples:4d} "
              + " ".join(f"{medians[k]:8.1f} (min {minima[k]:5.1f})" for k in (0.0, 1.0))
              + f" {medians[1.0] / medians[0.0]:15.3f} {minima[1.0] / minima[0.0]:12.3f}",
              flush=True)


if __name__ == "__main__":
    main()
