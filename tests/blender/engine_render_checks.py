"""F12 with the SHGI engine against F12 with Cycles on the project's two scenes.

For the Cornell box and the sun room (examples/blender_scenes.py at SCALE) this script
1. checks that exporting the bpy scene gives the scene examples/scenes.py builds;
2. renders Cycles (CYCLES_SAMPLES spp) and SHGI with each method through F12 (PROBE_GRID on
   the Cornell box only) and records, per method: Combined PSNR after auto-exposure and sRGB,
   the Combined mean ratio, the DiffInd x DiffCol mean ratio, the pass names of both results
   and the render record;
3. sun room: solves a frozen photon lattice with the Solve operator, checks the panel's
   figures, renders it through F12 from the scene camera and from a moved camera, and clears it;
4. Cornell box: adds an Irradiance Volume object, renders PROBE_GRID through F12 ("PROBE_GRID
   volume") and with a frozen solution, and records where the probes went against the
   object's cells;
5. turns view-layer passes off and on and checks that F12's result follows them.
The pytest side (tests/python/test_blender_engine.py) asserts the figures; this script asserts
only what needs Blender (the export, the frozen solution) and prints ENGINE_RENDER_OK.
"""

import json
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import engine_common as common  # noqa: E402
import blender_test_setup as setup  # noqa: E402
from blender_test_setup import check_close, results_path  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import shgi  # noqa: E402
from shgi.metrics import psnr  # noqa: E402
import scenes  # noqa: E402  (examples/scenes.py, on the path through engine_common)
from mathutils import Matrix  # noqa: E402
from recording_layout import draw_panel  # noqa: E402
from shgi_blender.engine import final_render, passes, solution_cache  # noqa: E402
from shgi_blender.export import export_scene  # noqa: E402

SCALE = 0.25  # 64 x 64 (Cornell box) and 64 x 48 (sun room) pixels
CYCLES_SAMPLES = 1024
# Samples of the path tracer; the lattice renders with the Medium quality preset (64 spp,
# 400k photons, a 24-cell lattice), what an artist would pick for a final preview.
PATH_TRACE_SAMPLES = 1024
QUALITY_PRESET = "MEDIUM"
SEED = 1
# Data passes enabled besides the calibration reset's light passes.
EXTRA_PASS_FLAGS = ("use_pass_z", "use_pass_normal")
# Export agreement with examples/scenes.py: float32 round trips of the same arithmetic.
EXPORT_TOLERANCE = 1e-5
CAMERA_NUDGE = Matrix.Translation((0.05, 0.0, 0.0))
PASS_TOGGLE_CASE = ("Depth", "DiffInd")
METHODS = {"cornell_box": ("PATH_TRACE", "PHOTON_LATTICE", "PROBE_GRID", "RADIANCE_FIELD",
                           "INSTANT_GI"),
           "sun_room": ("PATH_TRACE", "PHOTON_LATTICE")}
# The Irradiance Volume object of the Cornell box: 7 x 6 x 5 probes in most of the room (the
# box spans x -1..1, y 0..2, z 0..2); some fall inside the blocks and get relocated or disabled.
VOLUME_LOCATION = (0.0, 1.0, 1.0)
VOLUME_SCALE = (0.95, 0.9, 0.92)
VOLUME_RESOLUTION = (7, 6, 5)
# float32 round trips of the object's matrix, in metres.
VOLUME_MATRIX_TOLERANCE = 1e-5


def check_export_matches_scripting_api(name, scene):
    """The exported bpy scene equals examples/scenes.py's scene (lights, materials, camera...)."""
    exported = export_scene(bpy.context.evaluated_depsgraph_get(), scene).scene
    expected = getattr(scenes, name)(SCALE).scene
    exported.commit()
    expected.commit()
    for index, (a, b) in enumerate(zip(exported.bounds(), expected.bounds())):
        check_close(f"{name}: bounds[{index}]", a, b, EXPORT_TOLERANCE)
    triangles = [sum(len(mesh.triangles) for mesh in s.meshes) for s in (exported, expected)]
    if triangles[0] != triangles[1]:
        raise AssertionError(f"{name}: {triangles[0]} triangles exported, {triangles[1]} built")
    colors = [sorted(tuple(round(c, 5) for c in m.base_color) for m in s.materials)
              for s in (exported, expected)]
    if colors[0] != colors[1]:
        raise AssertionError(f"{name}: material colours {colors[0]} != {colors[1]}")
    default_ior = principled_default_ior()
    for field in ("roughness", "specular", "metallic", "ior"):
        values = {round(getattr(m, field), 5) for m in exported.materials}
        values |= {round(default_ior if field == "ior" else getattr(m, field), 5)
                   for m in expected.materials}
        if len(values) != 1:
            raise AssertionError(f"{name}: material {field} differs: {values}")
    _check_lights(name, exported.lights, expected.lights)
    for field in ("lens", "sensor_width", "resolution_x", "resolution_y"):
        check_close(f"{name}: camera.{field}",
                                             getattr(exported.camera, field),
                                             getattr(expected.camera, field), EXPORT_TOLERANCE)
    check_close(
        f"{name}: camera matrix", np.ravel(exported.camera.world_from_camera),
        np.ravel(expected.camera.world_from_camera), EXPORT_TOLERANCE)
    check_close(
        f"{name}: world", (*exported.world.color, exported.world.strength),
        (*expected.world.color, expected.world.strength), EXPORT_TOLERANCE)


def principled_default_ior():
    """The IOR of a new Principled BSDF. examples/blender_scenes.py leaves its materials at
    Blender's defaults: scenes.py's (shgi.Material's) 1.45 in Blender 3.4, but 1.5 in Blender
    5.0, where the default "Specular IOR Level" 0.5 at IOR 1.5 is the same specular 0.5."""
    material = bpy.data.materials.new("principled_defaults")
    material.use_nodes = True
    ior = material.node_tree.nodes["Principled BSDF"].inputs["IOR"].default_value
    bpy.data.materials.remove(material)
    return ior


def _check_lights(name, exported, expected):
    by_name = {light.name: light for light in exported}
    if sorted(by_name) != sorted(light.name for light in expected):
        raise AssertionError(f"{name}: lights {sorted(by_name)} != "
                             f"{sorted(light.name for light in expected)}")
    for light in expected:
        other = by_name[light.name]
        fields = ["type", "visible_camera", "portal"]
        fields += ["strength", "angle"] if light.type == shgi.LightType.SUN else [
            "shape", "size_x", "size_y"] + ([] if light.portal else ["power"])
        for field in fields:
            a, b = getattr(other, field), getattr(light, field)
            if field == "power" and light.type == shgi.LightType.AREA:
                # blender_scenes gives the Blender light scenes.py's power, in Blender's units
                b = setup.native_area_power(b)
            if isinstance(a, float):
                check_close(f"{name}: {light.name}.{field}", a, b,
                                                     EXPORT_TOLERANCE)
            elif a != b:
                raise AssertionError(f"{name}: {light.name}.{field} is {a}, expected {b}")
        check_close(
            f"{name}: {light.name} matrix", np.ravel(other.world_from_light),
            np.ravel(light.world_from_light), EXPORT_TOLERANCE)


def compare(reference, image):
    """The figures of one SHGI render against the Cycles reference."""
    def lit_diffuse(passes):
        return common.mean_rgb(passes["DiffInd"] * passes["DiffCol"])

    return {"psnr": psnr(reference["Combined"], image["Combined"]),
            "mean_ratio": common.mean_rgb(image["Combined"]) / common.mean_rgb(
                reference["Combined"]),
            "diffind_ratio": lit_diffuse(image) / lit_diffuse(reference),
            "passes": sorted(image)}


def render_method(scene, method, reference, tmpdir, label=None):
    scene.shgi.method = method
    bpy.ops.shgi.quality_preset(preset=QUALITY_PRESET)
    if method == "PATH_TRACE":
        scene.shgi.samples = PATH_TRACE_SAMPLES
    scene.shgi.seed = SEED
    start = time.perf_counter()
    image = common.render_f12(scene, "SHGI", os.path.join(tmpdir, f"{label or method}.exr"))
    row = compare(reference, image)
    row["seconds"] = time.perf_counter() - start
    row["record"] = final_render.last_render()
    return row, image


def check_frozen_solution(scene, reference, tmpdir, results):
    """Solve once, render the frozen lattice from two cameras, clear (non-interactive mode)."""
    key = scene.name_full
    scene.shgi.method = "PHOTON_LATTICE"
    status = bpy.ops.shgi.solve("INVOKE_DEFAULT")  # no window: it runs to the end
    if status != {"FINISHED"} or solution_cache.get(key) is None:
        raise AssertionError("Solve did not store a frozen solution")
    solution = solution_cache.get(key)
    if solution.memory_bytes <= 0 or "emit_trace" not in solution.timings:
        raise AssertionError(f"frozen solution lacks figures: {solution.timings}")
    panel = draw_panel("SHGI_RENDER_PT_photon_lattice")
    if not all(text in panel for text in ("Frozen solution", "Emit + trace", "Memory")):
        raise AssertionError(f"the photon lattice panel lacks the solution's figures: {panel}")
    row, image = render_method(scene, "PHOTON_LATTICE", reference, tmpdir, "frozen")
    if not row["record"]["frozen_solution"] or "export" in row["record"]["timings"]:
        raise AssertionError(f"F12 did not render the frozen solution: {row['record']}")
    results["PHOTON_LATTICE frozen"] = row
    scene.camera.matrix_world = CAMERA_NUDGE @ scene.camera.matrix_world
    _, moved = render_method(scene, "PHOTON_LATTICE", reference, tmpdir, "frozen_moved")
    if not final_render.last_render()["frozen_solution"] or np.allclose(
            moved["Combined"], image["Combined"]):
        raise AssertionError("a camera move did not change the frozen solution's render")
    scene.camera.matrix_world = CAMERA_NUDGE.inverted() @ scene.camera.matrix_world
    if bpy.ops.shgi.clear_solution() != {"FINISHED"} or solution_cache.get(key) is not None:
        raise AssertionError("Clear left the frozen solution")


def add_irradiance_volume(scene):
    """The Irradiance Volume object of the checks, placed in the room."""
    obj = setup.add_irradiance_volume(scene, "probe_volume", VOLUME_RESOLUTION)
    obj.location, obj.scale = VOLUME_LOCATION, VOLUME_SCALE
    bpy.context.view_layer.update()
    return obj


def probe_placement(positions, obj, max_offset):
    """Where probes went against the object's cell centres: the largest per-axis offset from
    the nearest centre in probe spacings, and how many sit on a centre."""
    matrix = np.array(obj.matrix_world, np.float64)
    counts = np.array(VOLUME_RESOLUTION)
    axes = [(2.0 * np.arange(n) + 1.0) / n - 1.0 for n in counts]
    local = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    centres = local @ matrix[:3, :3].T + matrix[:3, 3]
    spacing = 2.0 * np.linalg.norm(matrix[:3, :3], axis=0) / counts
    positions = np.asarray(positions, np.float64)
    offsets = np.abs(positions[:, None, :] - centres[None, :, :]) / spacing
    nearest = offsets.max(axis=2).min(axis=1)
    return {"expected_probes": int(counts.prod()), "relocation_bound_spacings": max_offset,
            "max_offset_spacings": float(nearest.max()),
            "at_centre": int((nearest < 1e-4).sum())}


def check_irradiance_volume(scene, reference, tmpdir, results):
    """The Irradiance Volume object becomes the probe grid's volume, in F12 and in Solve."""
    obj = add_irradiance_volume(scene)
    row, image = render_method(scene, "PROBE_GRID", reference, tmpdir, "probe_volume")
    results["PROBE_GRID volume"] = row
    placement = probe_placement(row["record"]["probe_positions"], obj,
                                scene.shgi.probe_grid.max_offset)
    placement.update(resolution=list(VOLUME_RESOLUTION),
                     f12_probes=len(row["record"]["probe_positions"]))
    if bpy.ops.shgi.solve() != {"FINISHED"}:
        raise AssertionError("Solve failed for PROBE_GRID")
    solution = solution_cache.get(scene.name_full, "PROBE_GRID")
    volume = solution.field.volumes[0]
    placement["solve_probes"] = solution.field.probe_count
    placement["volume_matrix_error"] = float(np.abs(
        np.asarray(volume.world_from_volume) - np.array(obj.matrix_world)).max())
    if tuple(volume.resolution) != VOLUME_RESOLUTION:
        raise AssertionError(f"the grid's volume has {volume.resolution} probes, the object "
                             f"{VOLUME_RESOLUTION}")
    if "Irradiance Volume place" not in draw_panel("SHGI_RENDER_PT_probe_grid"):
        raise AssertionError("the probe grid panel does not name the Irradiance Volume")
    _, frozen = render_method(scene, "PROBE_GRID", reference, tmpdir, "probe_volume_frozen")
    record = final_render.last_render()
    if not record["frozen_solution"] or not np.allclose(frozen["Combined"], image["Combined"],
                                                        atol=0.05):
        raise AssertionError(f"F12 did not render the frozen probe grid like F12: {record}")
    bpy.ops.shgi.clear_solution()
    bpy.data.objects.remove(obj)
    results["irradiance_volume"] = placement


def check_pass_toggles(scene, tmpdir):
    """F12's result holds exactly Combined and the passes the view layer enables."""
    layer = scene.view_layers[0]
    for info in passes.PASSES[1:]:
        setattr(layer, info.view_layer_flag, info.name in PASS_TOGGLE_CASE)
    scene.shgi.method = "PATH_TRACE"
    scene.shgi.samples = 2
    names = set(common.render_f12(scene, "SHGI", os.path.join(tmpdir, "toggles.exr")))
    if names != {"Combined", *PASS_TOGGLE_CASE}:
        raise AssertionError(f"with {PASS_TOGGLE_CASE} enabled F12 gave {sorted(names)}")


def run_scene(name, tmpdir):
    scene = common.new_scene(name, SCALE)
    for flag in EXTRA_PASS_FLAGS:
        setattr(scene.view_layers[0], flag, True)
    check_export_matches_scripting_api(name, scene)
    scene.cycles.samples = CYCLES_SAMPLES
    scene.cycles.seed = SEED
    start = time.perf_counter()
    reference = common.render_f12(scene, "CYCLES", os.path.join(tmpdir, f"{name}_cycles.exr"))
    results = {"cycles": {"seconds": time.perf_counter() - start, "passes": sorted(reference),
                          "samples": CYCLES_SAMPLES,
                          "size": list(reference["Combined"].shape[1::-1])}}
    for method in METHODS[name]:
        results[method], _ = render_method(scene, method, reference, tmpdir)
    if name == "sun_room":
        check_frozen_solution(scene, reference, tmpdir, results)
    else:
        check_irradiance_volume(scene, reference, tmpdir, results)
        check_pass_toggles(scene, tmpdir)
    return results


def print_table(results):
    print(f"\n{'scene':<12}{'method':<24}{'spp':>6}{'PSNR dB':>9}{'mean':>8}"
          f"{'DiffInd*Col':>13}{'seconds':>9}")
    for name, rows in results.items():
        cycles = rows["cycles"]
        print(f"{name:<12}{'Cycles':<24}{cycles['samples']:>6}{'':>9}{'1':>8}{'1':>13}"
              f"{cycles['seconds']:>9.2f}")
        for method, row in rows.items():
            if method in ("cycles", "irradiance_volume"):
                continue
            print(f"{name:<12}{method:<24}{row['record']['samples']:>6}{row['psnr']:>9.2f}"
                  f"{row['mean_ratio']:>8.4f}{row['diffind_ratio']:>13.4f}{row['seconds']:>9.2f}")


def main():
    out = results_path("shgi_engine_render.json")
    shgi.set_max_threads(common.calibration.THREADS)
    start = time.perf_counter()
    results = {}
    with tempfile.TemporaryDirectory(prefix="shgi_engine_") as tmpdir:
        for name in ("cornell_box", "sun_room"):
            results[name] = run_scene(name, tmpdir)
    print_table(results)
    with open(out, "w") as f:
        json.dump(results, f, indent=1, default=str)
    print(f"\nENGINE_RENDER_OK in {time.perf_counter() - start:.1f} s -> {out}", flush=True)


main()
