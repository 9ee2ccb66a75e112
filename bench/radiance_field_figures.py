"""The figures of docs/methods.md, "Radiance field": agreement with the path tracer, stage
seconds and memory of RADIANCE_FIELD on the project's scenes, with the settings that the text
discusses beside the defaults, and the peak memory of a pass per million photon hits.

    PYTHONPATH=build/python /usr/bin/python3 bench/radiance_field_figures.py

from the repository root; prints Markdown table rows.
"""
import pathlib
import resource
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT / "tests" / "python"))
import scenes  # noqa: E402
import shgi  # noqa: E402
from scene_support import path_traced_reference  # noqa: E402
from shgi.metrics import psnr  # noqa: E402


def indirect_diffuse(passes):
    return float((passes["DiffInd"] * passes["DiffCol"]).mean())


def row(name, scale, samples, fs=None, ps=None):
    fs, ps = fs or {}, ps or {}
    scene, ref = path_traced_reference(getattr(scenes, name), scale, samples)
    t = time.time()
    field = shgi.RadianceField(scene, shgi.RadianceFieldSettings(seed=5, **fs))
    field.refine()
    solve = time.time() - t
    t = time.time()
    prev, _ = shgi.render_preview(scene, field, shgi.PreviewSettings(seed=5, **ps))
    render = time.time() - t
    st = dict(field.stage_seconds)
    print(f"| {name} | {fs or ''} {ps or ''} | {psnr(ref['Combined'], prev['Combined']):.1f} dB | "
          f"{100 * (indirect_diffuse(prev) / indirect_diffuse(ref) - 1):+.1f}% | {st['voxelise']:.2f} | {st['photons']:.2f} | "
          f"{st['radiance_grid']:.2f} | {st['sh_field']:.2f} | {render:.2f} | "
          f"{field.timings['sample_points']} | {field.memory_bytes / 1e6:.1f} MB |", flush=True)

row("cornell_box", 0.25, 2048)
row("sun_room", 0.25, 2048)
row("sun_room", 0.25, 2048, {"resolution": 64})
row("two_rooms", 0.5, 512)
row("two_rooms", 0.5, 512, {"max_bounces": 3}, {"final_gather": True, "samples": 64})
row("cornell_box", 0.25, 2048, {"face_estimator": shgi.FaceEstimator.PAPER})
row("cornell_box", 0.25, 2048, {"use_mips": False})
row("cornell_box", 0.25, 2048, {"glossy_in_grid": False})
row("two_rooms", 0.5, 512, {"occlusion_test": False})
row("cornell_box", 0.25, 2048, {"monte_carlo_gathers": True})
row("sun_room", 0.25, 2048, {"monte_carlo_gathers": True})
row("two_rooms", 0.5, 512, {"monte_carlo_gathers": True})
row("sun_room", 0.25, 2048, {"max_bounces": 3}, {"final_gather": True, "samples": 64})
# Peak memory of a pass per million photons: 2M photons on the Cornell box.
scene = path_traced_reference(scenes.cornell_box, 0.25, 2048)[0]
field = shgi.RadianceField(scene, shgi.RadianceFieldSettings(photons=2_000_000, seed=5))
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
field.refine()
grown = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024
print(f"2M photons: {field.timings['hits']} hits, peak grew {grown:.0f} MiB "
      f"({grown / (field.timings['hits'] / 1e6):.0f} MiB per million hits), "
      f"held {field.memory_bytes / 1e6:.1f} MB")
