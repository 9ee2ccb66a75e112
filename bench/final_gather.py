#!/usr/bin/env python3
"""Field methods read at the first surface or through a final gather, on examples/scenes.py's
scenes: per method, mode and sample count, the render time, PSNR against a 1024-spp path-traced
reference (noisy and denoised by shgi.frame_denoise with Prefilter Fast) and the frame's mean
over the reference's. The figures behind settings.FINAL_GATHER_DEFAULTS (docs/methods.md). A
plain script printing a table: benchmarks are not tests.

    PYTHONPATH=build/python python3 bench/final_gather.py [--scenes cornell_box sun_room two_rooms]
        [--scale 0.5] [--spp 16 64] [--reference-spp 1024]
"""

import argparse
import pathlib
import sys
import time

import shgi
from shgi import metrics
from shgi.frame_denoise import denoise_frame

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)

# Each field solved as the add-on solves it for Light Paths > Diffuse 4: through a final gather
# one bounce less (addon/shgi_blender/settings.py, light_path_fields), so that every path has
# the path tracer's 4 diffuse bounces.
SOLVERS = {
    "photon lattice": (lambda scene, gather: shgi.PhotonLattice(
        scene, shgi.PhotonLatticeSettings(max_bounces=4 - gather)), 1),
    "probe grid": (lambda scene, gather: shgi.ProbeGrid(
        scene, shgi.ProbeGridSettings(bounces=3 - gather)), 8),
}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=["cornell_box", "sun_room", "two_rooms"])
    parser.add_argument("--scale", type=float, default=0.5)
    parser.add_argument("--spp", type=int, nargs="+", default=[16, 64])
    parser.add_argument("--reference-spp", type=int, default=1024)
    args = parser.parse_args()
    print("| scene | method | final gather | spp | render s | PSNR noisy | PSNR denoised | "
          "mean / reference |")
    print("|---|---|---|---|---|---|---|---|")
    for name in args.scenes:
        scene = getattr(scenes, name)(args.scale).scene
        scene.commit()
        reference = shgi.render_path_traced(
            scene, shgi.PathTracerSettings(samples=args.reference_spp, seed=7))["Combined"]
        for method, (make, passes) in SOLVERS.items():
            for gather in (False, True):
                solver = make(scene, int(gather))
                for _ in range(passes):
                    solver.refine()
                for spp in args.spp:
                    start = time.perf_counter()
                    frame, _ = shgi.render_preview(scene, solver.current_field(),
                                                   shgi.PreviewSettings(samples=spp, seed=1,
                                                                        final_gather=gather))
                    seconds = time.perf_counter() - start
                    denoised = denoise_frame(frame, prefilter="FAST")["Combined"]
                    mean = frame["Combined"][..., :3].mean() / reference[..., :3].mean()
                    print(f"| {name} | {method} | {'on' if gather else 'off'} | {spp} | "
                          f"{seconds:.2f} | {metrics.psnr(reference, frame['Combined']):.2f} | "
                          f"{metrics.psnr(reference, denoised):.2f} | {mean:.3f} |", flush=True)


if __name__ == "__main__":
    main()
