"""Calibration of SHGI's reference path tracer against Cycles, run inside Blender.

tests/blender/calibration_lights.py (point, spot, sun, area rectangle and disk, emissive mesh,
world, lights seen by the camera) and tests/blender/calibration_materials.py (Principled diffuse,
Diffuse BSDF, glossy metal, rough glass) and tests/blender/calibration_normal_maps.py (a
tangent-space Normal Map node on a plane under a sun, a point and an area light, and in a room;
a Bump node of an image's heights under a sun and a point light)
render each case with Cycles and with
shgi.render_path_traced on the exported scene and write per-case image means as JSON. Each
script runs once (one Blender start); each case is one test here.

A case passes when the mean of Combined agrees within 2% and every listed pass within 3%, and
both renderers' standard errors of those means are below a quarter of the tolerance (so that
the comparison is meaningful).
"""

import math

import pytest

from blender_support import BLENDERS, run_script_once

SCRIPTS = {
    "calibration_lights.py": ("CALIBRATION_LIGHTS_DONE", [
        "point", "point_exposure", "spot", "sun", "area", "area_disk", "emissive_mesh", "world",
        "light_camera_visible", "light_camera_default"]),
    "calibration_materials.py": ("CALIBRATION_MATERIALS_DONE", [
        "diffuse", "diffuse_gloss_passes", "diffuse_bsdf",
        "glossy_metal", "glossy_metal_gloss_passes", "glass"]),
    "calibration_normal_maps.py": ("CALIBRATION_NORMAL_MAPS_DONE", [
        "normal_map_sun", "normal_map_half_strength", "normal_map_blender_object_space",
        "normal_map_point", "normal_map_area",
        "normal_map_room", "bump_map_sun", "bump_map_point_inverted"]),
}

CASES = [(script, case) for script, (_, cases) in SCRIPTS.items() for case in cases]


def _param(blender, script, case):
    return pytest.param(blender, script, case, marks=[blender.skip_mark, pytest.mark.blender],
                        id=f"{blender.name}-{script[:-3]}-{case}")


def _script_results(script, blender, build_python_dir, tmp_path_factory):
    """Runs a calibration script once per session and Blender; its per-case results."""
    return run_script_once(script, SCRIPTS[script][0], build_python_dir, tmp_path_factory,
                           blender=blender,
                           shown_line=lambda line: line.startswith(("==", "   ")))


@pytest.mark.parametrize("blender, script, case",
                         [_param(b, s, c) for b in BLENDERS for s, c in CASES])
def test_cycles_calibration(blender, script, case, build_python_dir, tmp_path_factory):
    results = _script_results(script, blender, build_python_dir, tmp_path_factory)
    assert case in results, f"{script} did not report case {case!r}"
    if "skipped" in results[case]:  # a setting this Blender does not have
        pytest.skip(results[case]["skipped"])
    rows = [row for row in results[case]["rows"] if row["tolerance"] is not None]
    assert rows, f"{case}: no compared passes"
    for row in rows:
        tol = row["tolerance"]
        for renderer in ("cycles", "shgi"):
            rel_se = row[f"{renderer}_rel_se"]
            assert rel_se < tol / 4, (
                f"{case} {row['pass']}: {renderer} standard error of the mean {100 * rel_se:.2f}% "
                f"is not below a quarter of the {100 * tol:.0f}% tolerance; raise the samples")
    failures = [f"{row['pass']}: Cycles {row['cycles']:.6g}, SHGI {row['shgi']:.6g}, "
                f"{100 * row['rel_error']:+.2f}% (tolerance {100 * row['tolerance']:.0f}%)"
                for row in rows if not abs(row["rel_error"]) <= row["tolerance"]
                or math.isnan(row["rel_error"])]
    assert not failures, f"{case} disagrees with Cycles:\n  " + "\n  ".join(failures)
