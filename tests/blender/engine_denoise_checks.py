"""F12's denoiser and Time Limit, in Blender (3.4.1 and the bpy module).

1. Denoise on, for every built-in method on the Cornell box at 4 samples: the Render Result
   holds Cycles' Noisy Image, Denoising Albedo and Denoising Normal beside Combined; the
   denoised Combined keeps the Noisy Image's mean within 1%, is finite, and is closer (PSNR)
   to a 256-sample render than the Noisy Image is; the Last Render record says it was denoised.
2. Without the pyoidn module (hidden from import) F12 still renders, with a warning naming the
   module, and no error.
3. Time Limit 1 s on a path-traced render asked for 10^6 samples and on a Probe Grid solve of
   64 passes: the job stops at the limit with some samples done, denoised. Records what each
   render's job took (export excluded, as the limit is counted), for the test to check.

Prints ENGINE_DENOISE_OK and writes what it measured to the results JSON.
"""

import json
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import engine_common as common  # noqa: E402

import blender_test_setup as setup  # noqa: E402
import numpy as np  # noqa: E402

from shgi import metrics  # noqa: E402
from shgi_blender.engine import final_render  # noqa: E402

SCALE = 0.5
SAMPLES = 4
REFERENCE_SAMPLES = 256
METHODS = ("PATH_TRACE", "PHOTON_LATTICE", "PROBE_GRID")
DENOISE_PASSES = ("Noisy Image", "Denoising Albedo", "Denoising Normal")
TIME_LIMIT = 1.0


def cornell():
    scene = common.new_scene("cornell_box", SCALE)
    scene.shgi.photon_lattice.photons = 50000
    scene.shgi.probe_grid.rays_per_probe = 64
    return scene


def denoised_renders(folder, results):
    scene = cornell()
    for method in METHODS:
        scene.shgi.method = method
        scene.shgi.use_denoising = False
        scene.shgi.samples = REFERENCE_SAMPLES
        reference = common.render_f12(scene, "SHGI", os.path.join(folder, f"{method}_ref.exr"))
        scene.shgi.use_denoising = True
        scene.shgi.samples = SAMPLES
        passes = common.render_f12(scene, "SHGI", os.path.join(folder, f"{method}.exr"))
        record = final_render.last_render()
        combined, noisy = passes["Combined"], passes["Noisy Image"]
        results[method] = {
            "passes": sorted(passes), "denoised": record.get("denoised"),
            "errors": record["errors"], "warnings": record["warnings"],
            "mean_ratio": float(combined[..., :3].mean() / noisy[..., :3].mean()),
            "finite": bool(np.isfinite(combined).all()),
            "psnr_noisy": metrics.psnr(reference["Combined"], noisy),
            "psnr_denoised": metrics.psnr(reference["Combined"], combined),
            "denoise_seconds": record["timings"].get("denoise"),
        }
        print(method, results[method])


def without_pyoidn(folder, results):
    scene = cornell()
    scene.shgi.method = "PATH_TRACE"
    scene.shgi.samples = SAMPLES
    scene.shgi.use_denoising = True
    hidden = sys.modules.get("pyoidn", "absent")
    sys.modules["pyoidn"] = None  # `import pyoidn` raises ImportError
    try:
        passes = common.render_f12(scene, "SHGI", os.path.join(folder, "no_pyoidn.exr"))
    finally:
        if hidden == "absent":
            del sys.modules["pyoidn"]
        else:
            sys.modules["pyoidn"] = hidden
    record = final_render.last_render()
    results["without_pyoidn"] = {"errors": record["errors"], "warnings": record["warnings"],
                                 "denoised": record.get("denoised"),
                                 "mean": float(passes["Combined"][..., :3].mean()),
                                 "noisy_is_combined": bool(np.array_equal(
                                     passes["Noisy Image"], passes["Combined"]))}


def time_limited(folder, results):
    scene = cornell()
    scene.shgi.use_denoising = True
    scene.shgi.time_limit = TIME_LIMIT
    cases = {"PATH_TRACE": {"samples": 10 ** 6}, "PROBE_GRID": {"samples": 10 ** 6}}
    scene.shgi.probe_grid.passes = 64
    for method, values in cases.items():
        scene.shgi.method = method
        for name, value in values.items():
            setattr(scene.shgi, name, value)
        for attempt in range(2):  # the second knows the denoiser's time on this machine
            common.render_f12(scene, "SHGI", os.path.join(folder, f"limit_{method}.exr"))
            record = final_render.last_render()
            timings = record["timings"]
            results[f"limit_{method}_{attempt}"] = {
                "job_seconds": timings["total"] - timings.get("export", 0.0),
                "timings": timings, "samples": record["samples"],
                "denoised": record.get("denoised"), "errors": record["errors"],
                "cancelled": record["cancelled"]}
            print(method, attempt, results[f"limit_{method}_{attempt}"])


def main():
    results = {}
    folder = tempfile.mkdtemp()
    denoised_renders(folder, results)
    without_pyoidn(folder, results)
    time_limited(folder, results)
    with open(setup.results_path("engine_denoise.json"), "w") as out:
        json.dump(results, out, indent=1, default=str)
    print("ENGINE_DENOISE_OK")


if __name__ == "__main__":
    main()
