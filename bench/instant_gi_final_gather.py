#!/usr/bin/env python3
"""Instant GI's F12 with Final Gather on, as the add-on renders it (engine/render_job.RenderJob,
default settings, `--samples` 16): Combined and DiffInd x DiffCol means over the path tracer's
(`--reference-samples` 512, seed 7) on the Cornell box and the two rooms' dim room (scale 0.5),
for Final Gather off, on, and on with the field solved one diffuse bounce shallower (the add-on's
accounting before settings.UNGATHERED_METHODS: the renderer makes no gather for this field, so
that field lacks its last bounce), each at Per Sample 4 and 64. A plain script printing a table:
not a test (test_blender_engine.py holds the gathered rows to 5%).

    PYTHONPATH=build/python python3 bench/instant_gi_final_gather.py
"""

import argparse
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT / "addon"))
import shgi  # noqa: E402
import scenes  # noqa: E402  (examples/scenes.py)
from shgi_blender import settings  # noqa: E402
from shgi_blender.engine import field_solvers  # noqa: E402
from shgi_blender.engine.render_job import RenderJob  # noqa: E402


def means(passes):
    return (float(passes["Combined"][..., :3].mean()),
            float((passes["DiffInd"] * passes["DiffCol"]).mean()))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--reference-samples", type=int, default=512)
    parser.add_argument("--per-sample", type=int, nargs="+", default=[4, 64])
    args = parser.parse_args()
    print("| scene | final gather | per sample | VPL bounces | Combined / path tracer | "
          "DiffInd x DiffCol / path tracer |")
    print("|---|---|---|---|---|---|")
    for name in ("cornell_box", "two_rooms"):
        scene = getattr(scenes, name)(0.5).scene
        scene.commit()
        reference = means(shgi.render_path_traced(
            scene, shgi.PathTracerSettings(samples=args.reference_samples, seed=7)))
        for gather, shallow in ((False, False), (True, False), (True, True)):
            for per_sample in args.per_sample:
                props = settings.default_properties(shgi, method="INSTANT_GI")
                props.samples = args.samples
                props.instant_gi.final_gather = gather
                props.instant_gi.passes_per_sample = per_sample
                recipe = field_solvers.solver_recipe(props, shgi, gather=True if shallow else None)
                job = RenderJob(shgi, scene, args.samples,
                                preview_settings=settings.preview_settings(props, shgi),
                                solver_recipe=recipe).start()
                job.wait(3600)
                if job.error is not None:
                    raise job.error
                m = means(job.last_snapshot().passes)
                label = "on, field one bounce shallower" if shallow else ("on" if gather else "off")
                print(f"| {name} | {label} | {per_sample} | {recipe.settings.vpl_bounces} | "
                      f"{m[0] / reference[0]:.3f} | {m[1] / reference[1]:.3f} |", flush=True)


if __name__ == "__main__":
    main()
