#!/usr/bin/env python3
"""What each Quality preset gives each field method: F12 as the add-on renders it (its
settings, final gather, samples and denoiser, through engine/render_job.RenderJob without
Blender) on the Cornell box and on the two rooms (a 2000 W lamp behind a thin wall), against
SHGI's path tracer. Prints, per method and preset: the Cornell box's denoised PSNR, its CPU
seconds (solve + render + denoise, both cores), and the dim room's undenoised mean Combined and
indirect diffuse light (DiffInd x DiffCol) over the path tracer's, read through a final gather
(the issue's target: within 5% at every preset, for every method). A plain script printing a
table: benchmarks are not tests.

    PYTHONPATH=build/python python3 bench/preset_quality.py [--methods PHOTON_LATTICE,...]
        [--presets DEFAULT,PREVIEW,...] [--scale 0.5] [--max-samples 256] [--reference-spp 1024]

Samples above --max-samples are cut to it (Production's 1024 would take the run minutes per
row; the cut is printed). CPU seconds are process time, so they hold on a loaded machine.
"""

import argparse
import pathlib
import sys
import time

import shgi
from shgi import metrics

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT / "addon"))
import scenes  # noqa: E402  (examples/scenes.py)
from shgi_blender import presets, settings  # noqa: E402
from shgi_blender.engine import field_solvers  # noqa: E402
from shgi_blender.engine.render_job import RenderJob  # noqa: E402

METHODS = ("PHOTON_LATTICE", "PROBE_GRID", "RADIANCE_FIELD", "PROPAGATION", "INSTANT_GI")
SEED = 3


def preset_props(method, preset, max_samples):
    """scene.shgi of a new scene with `method` and `preset`'s values (samples cut to
    max_samples)."""
    props = settings.default_properties(shgi, method=method)
    if preset != "DEFAULT":
        presets.apply_preset(props, preset)
    props.seed = SEED
    props.samples = min(props.samples, max_samples)
    return props


def render(scene, props, denoise=True):
    """(passes, CPU seconds) of F12 of `props` as the add-on renders it."""
    start = time.process_time()
    job = RenderJob(shgi, scene, props.samples,
                    preview_settings=settings.preview_settings(props, shgi),
                    solver_recipe=field_solvers.solver_recipe(props, shgi),
                    denoising=settings.denoising(props) if denoise else None).start()
    if not job.wait(3600) or job.error is not None:
        raise RuntimeError(f"{props.method}: {job.error}")
    return job.last_snapshot().passes, time.process_time() - start


def means(passes):
    return (float(passes["Combined"][..., :3].mean()),
            float((passes["DiffInd"] * passes["DiffCol"]).mean()))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--methods", default=",".join(METHODS))
    parser.add_argument("--presets", default=",".join(presets.QUALITY_PRESETS))
    parser.add_argument("--scale", type=float, default=0.5)
    parser.add_argument("--max-samples", type=int, default=256)
    parser.add_argument("--reference-spp", type=int, default=1024)
    args = parser.parse_args()
    cornell = scenes.cornell_box(args.scale).scene
    rooms = scenes.two_rooms(args.scale).scene
    for scene in (cornell, rooms):
        scene.commit()
    references = {name: shgi.render_path_traced(scene, shgi.PathTracerSettings(
        samples=args.reference_spp, seed=7)) for name, scene in (("cornell", cornell),
                                                                 ("rooms", rooms))}
    dim_reference = means(references["rooms"])
    print("| method | preset | samples | Cornell box PSNR (denoised) | CPU s | dim room Combined "
          "/ path tracer (final gather) | dim room indirect / path tracer |")
    print("|---|---|---|---|---|---|---|")
    for method in args.methods.split(","):
        for preset in args.presets.split(","):
            props = preset_props(method, preset, args.max_samples)
            frame, seconds = render(cornell, props)
            psnr = metrics.psnr(references["cornell"]["Combined"], frame["Combined"])
            getattr(props, settings.METHOD_SETTINGS[method].prop).final_gather = True
            dim = means(render(rooms, props, denoise=False)[0])
            cut = "" if props.samples == preset_props(method, preset, 10 ** 9).samples else " (cut)"
            print(f"| {method} | {preset} | {props.samples}{cut} | {psnr:.2f} | {seconds:.2f} | "
                  f"{dim[0] / dim_reference[0]:.3f} | {dim[1] / dim_reference[1]:.3f} |",
                  flush=True)


if __name__ == "__main__":
    main()
