"""What an artist meets in F12 and the panels, inside Blender (one Blender start).

1. Render Region: the Cornell box rendered with a border, with and without Crop to Render
   Region, against the full frame. Records the result sizes, where SHGI put the region, the
   Combined PSNR and mean ratio of the region against the same pixels of the full frame (the
   region's pixels are seeded by their index in the region, so its noise is its own), whether
   the uncropped result holds exactly the cropped one at the region and nothing elsewhere.

2. Last Render panel: the rows it draws after a render (label and value of each), with the
   render's timings.
3. Frozen solution: a Probe Grid solved on the Cornell box, then its light moved: the F12
   warnings and the probe grid panel's text and buttons before and after the move.
4. Saved solution: re-solved, rendered, saved in a .blend, the file reopened: whether the
   solution came back from the file beside it, frozen and not out of date, and how its F12
   differs from the render before the save; then Export Volume, Clear and Load Solution of
   the exported volume, and how that render differs.
5. Panels: the Quality menu's text and the matching preset on a new scene; where the Max
   Bounces and Farm settings are drawn (panel, parent panel); every tooltip of the add-on's
   properties, enum items and operators; the width in pixels (blf, the UI font at 11 pt) of
   every property label the SHGI panels draw beside a value, and of the text Blender showed
   for a label it cut ("Viewport Sa…").

The pytest side (tests/python/test_blender_engine.py) asserts the figures; this script raises
only where a check needs Blender state, and prints ENGINE_UI_OK.
"""

import json
import os
import sys
import tempfile
import time
from types import SimpleNamespace

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import engine_common as common  # noqa: E402
from blender_test_setup import results_path  # noqa: E402
from recording_layout import (draw_panel, draw_panel_operators, draw_panel_props,  # noqa: E402
                              draw_panel_rows)

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import shgi  # noqa: E402
from shgi.metrics import psnr  # noqa: E402
from shgi_blender import presets  # noqa: E402
from shgi_blender.engine import final_render, solution_cache  # noqa: E402
from shgi_blender.ui import wrapped_text  # noqa: E402

SCALE = 0.25  # the Cornell box at 64 x 64 pixels
REGION_SAMPLES = 256
SEED = 1
# Render > Output > Render Region: min_x, min_y, max_x, max_y (fractions of the frame, y up).
BORDER = (0.3, 0.2, 0.8, 0.65)
# A quick probe grid: the checks compare renders of one solution, not its quality.
PROBE_SETTINGS = {"rays_per_probe": 64}
PROBE_PASSES = 2
FROZEN_SAMPLES = 8
LIGHT_MOVE = (0.3, 0.0, 0.0)


def render_combined(scene, path):
    return common.render_f12(scene, "SHGI", path)["Combined"]


def region_of(image, record):
    """The pixels of the region the record names, cut from a full-frame image (row 0 on top)."""
    (x, top), (width, height) = record["region"], record["size"]
    return image[top:top + height, x:x + width]


def check_render_region(tmpdir):
    scene = common.new_scene("cornell_box", SCALE)
    scene.shgi.method = "PATH_TRACE"
    scene.shgi.samples = REGION_SAMPLES
    scene.shgi.seed = SEED
    full = render_combined(scene, os.path.join(tmpdir, "full.exr"))
    render = scene.render
    render.use_border = True
    (render.border_min_x, render.border_min_y, render.border_max_x,
     render.border_max_y) = BORDER
    results = {"full_size": list(full.shape[1::-1])}
    images = {}
    for crop in (True, False):
        render.use_crop_to_border = crop
        images[crop] = render_combined(scene, os.path.join(tmpdir, f"region_{crop}.exr"))
        record = final_render.last_render()
        if record["errors"] or "region" not in record:
            raise AssertionError(f"F12 with a Render Region: {record}")
        reference = region_of(full, record)
        cropped = images[crop] if crop else region_of(images[crop], record)
        results["crop" if crop else "no_crop"] = {
            "result_size": list(images[crop].shape[1::-1]), "region": record["region"],
            "region_size": list(record["size"]), "warnings": record["warnings"],
            "psnr": psnr(reference, cropped),
            "mean_ratio": common.mean_rgb(cropped) / common.mean_rgb(reference)}
    record = final_render.last_render()
    outside = images[False].copy()
    (x, top), (width, height) = record["region"], record["size"]
    outside[top:top + height, x:x + width] = 0.0
    results["uncropped_holds_cropped"] = bool(np.array_equal(
        region_of(images[False], record), images[True]))
    results["uncropped_outside_max"] = float(np.abs(outside).max())
    render.use_border = False
    return results


def last_render_panel():
    """The rows the Last Render panel draws for the last render, and that render's timings."""
    return {"rows": draw_panel_rows("SHGI_RENDER_PT_last_render"),
            "timings": final_render.last_render()["timings"]}


def probe_grid_scene():
    scene = common.new_scene("cornell_box", SCALE)
    scene.shgi.method = "PROBE_GRID"
    scene.shgi.samples = FROZEN_SAMPLES
    scene.shgi.seed = SEED
    scene.shgi.probe_grid.passes = PROBE_PASSES
    for name, value in PROBE_SETTINGS.items():
        setattr(scene.shgi.probe_grid, name, value)
    return scene


def solve(scene):
    if bpy.ops.shgi.solve() != {"FINISHED"} or solution_cache.get(scene.name_full) is None:
        raise AssertionError("Solve did not store a frozen solution")


def frozen_render(scene, path):
    """F12's Combined and record, which must show a frozen solution."""
    image = render_combined(scene, path)
    record = final_render.last_render()
    if record["errors"] or not record["frozen_solution"]:
        raise AssertionError(f"F12 did not render the frozen solution: {record}")
    return image, record


def panel_state():
    """The probe grid panel's text and whether it offers Re-solve."""
    text = draw_panel("SHGI_RENDER_PT_probe_grid")
    return {"text": text, "buttons": draw_panel_operators("SHGI_RENDER_PT_probe_grid"),
            "label_widths": {label: text_width(label) for label in text.split(" | ")}}


def check_stale_solution(tmpdir):
    scene = probe_grid_scene()
    solve(scene)
    results = {"before": {"panel": panel_state()}}
    _, record = frozen_render(scene, os.path.join(tmpdir, "frozen.exr"))
    results["before"]["warnings"] = record["warnings"]
    light = next(obj for obj in scene.objects if obj.type == "LIGHT")
    light.location = [a + b for a, b in zip(light.location, LIGHT_MOVE)]
    bpy.context.view_layer.update()
    results["after"] = {"panel": panel_state(), "light": light.name}
    _, record = frozen_render(scene, os.path.join(tmpdir, "stale.exr"))
    results["after"]["warnings"] = record["warnings"]
    return scene, results


def check_saved_solution(scene, tmpdir):
    """Re-solve, render, save, reopen, render; Export Volume, Clear, Load, render."""
    solve(scene)
    before, _ = frozen_render(scene, os.path.join(tmpdir, "saved_before.exr"))
    blend = os.path.join(tmpdir, "frozen.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    bpy.ops.wm.open_mainfile(filepath=blend)
    scene = bpy.context.scene
    solution = solution_cache.get(scene.name_full, "PROBE_GRID")
    results = {"saved_files": sorted(os.listdir(os.path.join(tmpdir, "frozen_shgi"))),
               "loaded": solution is not None}
    if solution is None:
        return results
    results["changed_since"] = solution_cache.changed_since(scene.name_full, solution)
    after, record = frozen_render(scene, os.path.join(tmpdir, "saved_after.exr"))
    results.update(warnings=record["warnings"], max_difference=float(np.abs(after - before).max()),
                   mean=common.mean_rgb(before))
    volume = os.path.join(tmpdir, "volume.json")
    if bpy.ops.shgi.export_volume(filepath=volume) != {"FINISHED"}:
        raise AssertionError("Export Volume failed")
    bpy.ops.shgi.clear_solution()
    if bpy.ops.shgi.load_solution(filepath=volume) != {"FINISHED"}:
        raise AssertionError("Load Solution failed")
    loaded, record = frozen_render(scene, os.path.join(tmpdir, "loaded.exr"))
    results["load_volume_max_difference"] = float(np.abs(loaded - before).max())
    return results


# Text Blender showed for "Viewport Samples" in the render panel at the default width: the
# label column holds at least this much.
CUT_LABEL_SEEN = "Viewport Sa\u2026"
UI_POINTS = 11
SHGI_PANELS = ("SHGI_RENDER_PT_method", "SHGI_RENDER_PT_light_paths",
               "SHGI_RENDER_PT_light_paths_max_bounces", "SHGI_RENDER_PT_photon_lattice",
               "SHGI_RENDER_PT_probe_grid", "SHGI_RENDER_PT_probe_grid_visibility",
               "SHGI_RENDER_PT_bake", "SHGI_RENDER_PT_bake_farm", "SHGI_RENDER_PT_last_render")


def text_width(text):
    import blf

    if bpy.app.version < (4, 0, 0):
        blf.size(0, UI_POINTS, 72)
    else:
        blf.size(0, UI_POINTS)
    return blf.dimensions(0, text)[0]


def tooltips():
    """{where: text} of every tooltip of scene.shgi's groups, their enum items and the
    add-on's operators."""
    texts = {}
    groups = {"scene.shgi": bpy.context.scene.shgi, "probe_grid": bpy.context.scene.shgi.probe_grid,
              "bake": bpy.context.scene.shgi.bake}
    for group_name, group in groups.items():
        for prop in group.bl_rna.properties:
            texts[f"{group_name}.{prop.identifier}"] = prop.description
            for item in getattr(prop, "enum_items", ()):
                texts[f"{group_name}.{prop.identifier}.{item.identifier}"] = item.description
    for name in dir(bpy.types):
        if name.startswith("SHGI_OT_"):
            texts[name] = getattr(bpy.types, name).bl_rna.description
    return texts


def panel_labels(scene):
    """({property label: width in pixels}, {label text: width}) of what the SHGI panels draw,
    for each method; booleans' labels sit in the value column and are left out of the first."""
    context = SimpleNamespace(scene=scene, engine="SHGI", selected_objects=[])
    props, texts = {}, {}
    for method in ("PATH_TRACE", "PHOTON_LATTICE", "PROBE_GRID"):
        scene.shgi.method = method
        for show in (False, True):  # with the overlay settings and legend
            scene.shgi.show_probes = scene.shgi.show_lattice_samples = show
            for panel in SHGI_PANELS:
                for group, name, text in draw_panel_props(panel, context):
                    if group.bl_rna.properties[name].type != "BOOLEAN":
                        props[text] = text_width(text)
                for text in draw_panel(panel, context).split(" | "):
                    texts[text] = text_width(text)
    return props, texts


def check_panels():
    scene = common.new_scene("cornell_box", SCALE)
    scene.render.engine = "SHGI"
    context = SimpleNamespace(scene=scene, engine="SHGI", selected_objects=[])
    types = bpy.types
    results = {
        "matching_preset": presets.matching_preset(scene.shgi),
        "quality_menu": [text for idname, text in draw_panel_operators(
            "SHGI_RENDER_PT_method", context) if idname == "shgi.quality_preset"],
        "sub_panels": {name: [getattr(types, name).bl_label, getattr(types, name).bl_parent_id]
                       for name in ("SHGI_RENDER_PT_light_paths_max_bounces",
                                    "SHGI_RENDER_PT_bake_farm")},
        "props": {name: [prop for _group, prop, _text in draw_panel_props(name, context)]
                  for name in ("SHGI_RENDER_PT_light_paths",
                               "SHGI_RENDER_PT_light_paths_max_bounces",
                               "SHGI_RENDER_PT_bake", "SHGI_RENDER_PT_bake_farm")},
        "tooltips": tooltips(),
        "cut_label_width": text_width(CUT_LABEL_SEEN),
        "text_budget": wrapped_text.DEFAULT_REGION_PIXELS - wrapped_text.MARGIN_PIXELS,
    }
    results["label_widths"], results["text_widths"] = panel_labels(scene)
    return results


def main():
    out = results_path("shgi_engine_ui.json")
    shgi.set_max_threads(common.calibration.THREADS)
    start = time.perf_counter()
    results = {}
    with tempfile.TemporaryDirectory(prefix="shgi_engine_ui_") as tmpdir:
        results["render_region"] = check_render_region(tmpdir)
        results["last_render_panel"] = last_render_panel()
        scene, results["stale_solution"] = check_stale_solution(tmpdir)
        results["saved_solution"] = check_saved_solution(scene, tmpdir)
        results["panels"] = check_panels()
    with open(out, "w") as f:
        json.dump(results, f, indent=1, default=str)
    print(json.dumps(results, indent=1, default=str))
    print(f"\nENGINE_UI_OK in {time.perf_counter() - start:.1f} s -> {out}", flush=True)


main()
