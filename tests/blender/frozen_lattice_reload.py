"""A frozen Photon Lattice (or Light Propagation) solution outlives its Blender: solved, rendered
and saved with the .blend in one Blender process, the file opened in a new one renders it with
F12 without solving.

Run twice by tests/python/test_blender_engine.py, with ``-- <build python dir> <addon dir>
<results json> <save|reload> <blend path> [PHOTON_LATTICE|PROPAGATION]``:

* save: the Cornell box with the method (one pass); Solve; F12 (its Combined written beside the
  .blend as before.exr); the .blend saved. Records the files saved beside it.
* reload: opens the .blend (the add-on's load_post reads the solution back), then F12. Records
  whether the solution came back (its method, passes, whether it is out of date), the render's
  record (frozen, its timings) and the largest difference of its Combined from before.exr.

Prints FROZEN_LATTICE_OK; the pytest side asserts the figures.
"""

import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import engine_common as common  # noqa: E402
from blender_test_setup import results_path, script_args  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import shgi  # noqa: E402
from shgi_blender.engine import final_render, solution_cache  # noqa: E402

SCALE = 0.25  # the Cornell box at 64 x 64 pixels
SAMPLES = 8
SEED = 1
PHOTONS = 50000  # the check compares renders of one solution, not its quality


def frozen_render(scene, path):
    """F12's Combined and record, which must show a frozen solution."""
    image = common.render_f12(scene, "SHGI", path)["Combined"]
    record = final_render.last_render()
    if record["errors"] or not record["frozen_solution"]:
        raise AssertionError(f"F12 did not render the frozen solution: {record}")
    return image, record


# The method group of each method this script saves.
GROUPS = {"PHOTON_LATTICE": "photon_lattice", "PROPAGATION": "propagation"}


def save(blend, method):
    scene = common.new_scene("cornell_box", SCALE)
    scene.shgi.method = method
    scene.shgi.samples = SAMPLES
    scene.shgi.seed = SEED
    group = getattr(scene.shgi, GROUPS[method])
    group.photons = PHOTONS
    group.passes = 1
    if bpy.ops.shgi.solve() != {"FINISHED"} or solution_cache.get(scene.name_full) is None:
        raise AssertionError("Solve did not store a frozen solution")
    frozen_render(scene, os.path.join(os.path.dirname(blend), "before.exr"))
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    beside = os.path.splitext(blend)[0] + "_shgi"
    return {"saved_files": sorted(os.listdir(beside)) if os.path.isdir(beside) else []}


def reload(blend, method):
    common.setup.enable_addon()
    bpy.ops.wm.open_mainfile(filepath=blend)
    scene = bpy.context.scene
    solution = solution_cache.get(scene.name_full, method)
    results = {"loaded": solution is not None}
    if solution is None:
        return results
    results.update(passes=solution.solver.passes,
                   changed_since=solution_cache.changed_since(scene.name_full, solution),
                   figures=dict(solution.solver.figures()))
    after, record = frozen_render(scene, os.path.join(os.path.dirname(blend), "after.exr"))
    before = common.setup.read_render_exr(os.path.join(os.path.dirname(blend),
                                                       "before.exr"))["Combined"]
    results.update(warnings=record["warnings"], timings=sorted(record["timings"]),
                   mean=common.mean_rgb(before),
                   max_difference=float(np.abs(after - before).max()))
    return results


def main():
    args = script_args()
    mode, blend = args[3:5]
    method = args[5] if len(args) > 5 else "PHOTON_LATTICE"
    shgi.set_max_threads(common.calibration.THREADS)
    results = {"save": save, "reload": reload}[mode](blend, method)
    with open(results_path("frozen_lattice.json"), "w") as out:
        json.dump(results, out, indent=1, default=str)
    print(json.dumps(results, indent=1, default=str))
    print("FROZEN_LATTICE_OK")


main()
