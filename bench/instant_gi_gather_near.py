"""Instant GI read through a final gather as the add-on renders it (F12 through RenderJob, the
add-on's default settings, Final Gather on, 16 samples, scale 0.5), the code path of
test_blender_engine.py's test_instant_gi_f12_with_final_gather_on_agrees_with_the_path_tracer:
per seed, Combined and DiffInd x DiffCol means over a 512-spp path tracer's (seed 11, no clamp,
no Filter Glossy; cached in --cache), the relative RMSE of the Combined, the VPLs a gather lookup
reads (InstantGiField.lookup_counts of the frame's last sample) and the process CPU of the job;
then their means over the seeds. Overrides, one at a time: Light Paths > Clamp and Filter
Glossy, Light Paths per Set, InstantGiSettings.gather_near_radius. A benchmark, not a test.

    PYTHONPATH=build/python python3 bench/instant_gi_gather_near.py --scene two_rooms \\
        --seeds 0 1 2 3 4 5 6 7 [--radius 0.25] [--clamp 0] [--filter-glossy 0] [--pps 64]
"""

import argparse
import os
import resource
import sys

import numpy as np

REPO_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path[:0] = [os.path.join(REPO_ROOT, "addon"), os.path.join(REPO_ROOT, "examples")]

import shgi  # noqa: E402
import scenes  # noqa: E402
from shgi_blender import settings  # noqa: E402
from shgi_blender.engine import field_solvers  # noqa: E402
from shgi_blender.engine.render_job import RenderJob  # noqa: E402

REFERENCE_SAMPLES, REFERENCE_SEED, SCALE = 512, 11, 0.5


def cpu_seconds():
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def reference(name, scene, cache):
    path = os.path.join(cache, f"{name}_{SCALE}_{REFERENCE_SAMPLES}.npz")
    if not os.path.exists(path):
        os.makedirs(cache, exist_ok=True)
        passes = shgi.render_path_traced(
            scene, shgi.PathTracerSettings(samples=REFERENCE_SAMPLES, seed=REFERENCE_SEED))
        np.savez(path, **{k: np.asarray(passes[k]) for k in ("Combined", "DiffInd", "DiffCol")})
    return np.load(path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scene", default="two_rooms")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--radius", type=float, help="gather_near_radius (m)")
    parser.add_argument("--clamp", type=float, help="Light Paths > Clamp")
    parser.add_argument("--filter-glossy", type=float, help="Light Paths > Filter Glossy")
    parser.add_argument("--pps", type=int, help="Instant GI > Light Paths per Set")
    parser.add_argument("--cache", default="/tmp/shgi_gather_near")
    args = parser.parse_args()
    builder = getattr(scenes, args.scene)(SCALE)
    builder.scene.commit()
    scene = builder.scene
    ref = reference(args.scene, scene, args.cache)
    ref_combined = ref["Combined"][..., :3]
    ref_indirect = (ref["DiffInd"] * ref["DiffCol"]).mean()
    rows = []
    for seed in args.seeds:
        light_paths = {k: v for k, v in (("clamp_indirect", args.clamp),
                                         ("filter_glossy", args.filter_glossy)) if v is not None}
        props = settings.default_properties(shgi, method="INSTANT_GI", samples=args.samples,
                                            seed=seed, **light_paths)
        props.instant_gi.final_gather = True
        if args.pps:
            props.instant_gi.photons_per_set = args.pps
        recipe = field_solvers.solver_recipe(props, shgi)
        if args.radius is not None:
            recipe.settings.gather_near_radius = args.radius
        start = cpu_seconds()
        job = RenderJob(shgi, scene, args.samples,
                        preview_settings=settings.preview_settings(props, shgi),
                        solver_recipe=recipe).start()
        assert job.wait(1200) and job.error is None, job.error
        cpu = cpu_seconds() - start
        image = job.last_snapshot().passes
        combined = image["Combined"][..., :3]
        counts = job.solution.field.lookup_counts
        row = (float(combined.mean() / ref_combined.mean()),
               float((image["DiffInd"] * image["DiffCol"]).mean() / ref_indirect),
               float(np.sqrt(((combined - ref_combined) ** 2).mean()) / ref_combined.mean()),
               counts["vpls"] / max(counts["lookups"], 1))
        rows.append(row)
        print(f"{args.scene} seed {seed}: Combined {row[0]:.4f}, DiffInd x DiffCol {row[1]:.4f}, "
              f"relative RMSE {row[2]:.4f}, VPLs per lookup {row[3]:.1f}, CPU {cpu:.2f} s",
              flush=True)
    mean = np.mean(rows, axis=0)
    print(f"mean over seeds {args.seeds}: Combined {mean[0]:.4f}, DiffInd x DiffCol "
          f"{mean[1]:.4f}, relative RMSE {mean[2]:.4f}, VPLs per lookup {mean[3]:.1f}")


if __name__ == "__main__":
    main()
