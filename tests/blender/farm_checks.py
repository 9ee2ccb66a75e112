"""Bake > Farm from Blender, in background mode (Debian's Blender 3.4.1, whose Python has dask):
the sun room of examples/blender_scenes.py (facing in, LightmapUV).

``blender -b --factory-startup --python-exit-code 1 --python farm_checks.py --
<build python dir> <addon dir> <results json>``:
1. Dask: four objects baked with Farm "Dask" (Scheduler empty: 2 worker processes started for
   the bake), once with the path tracer and once from the Probe Grid, and the same bakes on
   This Computer; the files of each pair are written to the results (tests/python/
   test_blender_bake.py compares their bytes) with the operators' reports;
2. a Scheduler that is not an address: the bake refuses, naming Bake > Farm > Scheduler;
3. Flamenco: the file saved with Farm "Flamenco" (a bake from here is refused), Write Flamenco
   Job writes the job of the selected objects, and the same objects are baked here with the
   saved settings (the reference the test's run of the job through
   examples/flamenco/preview_job.js must equal).
Blender then quits: importing dask (multiprocessing) in a --python script made Blender 3.4.1
crash at its exit until shgi.farm dropped multiprocessing's alias of the script's module, so
the exit code is part of the check. Prints FARM_CHECKS_OK.
"""

import json
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()
sys.path.insert(0, str(setup.REPO_ROOT / "examples"))
setup.enable_addon()

import bpy  # noqa: E402
import blender_scenes  # noqa: E402

OBJECTS = ("back", "floor", "left_wall_0", "right")
BAKE = {"resolution": 16, "samples": 8, "uv_map": "LightmapUV"}


def select_only(*names):
    bpy.ops.object.select_all(action="DESELECT")
    for name in names:
        bpy.data.objects[name].select_set(True)
    bpy.context.view_layer.objects.active = bpy.data.objects[names[0]]


def files(folder):
    """{name: hex of the bytes} of the lightmaps written into `folder` (not the shards)."""
    out = {}
    for name in sorted(os.listdir(folder)):
        path = os.path.join(folder, name)
        if os.path.isfile(path):
            with open(path, "rb") as file:
                out[name] = file.read().hex()
    return out


def bake(folder, **arguments):
    select_only(*OBJECTS)
    status = sorted(bpy.ops.shgi.bake_lightmaps(output_folder=folder, **BAKE, **arguments))
    return {"status": status, "files": files(folder) if os.path.isdir(folder) else {}}


def main():
    tmpdir = tempfile.mkdtemp(prefix="shgi_farm_checks_")
    blender_scenes.build("sun_room", 0.25, lightmap=True)
    setup.enable_addon()
    scene = bpy.context.scene
    scene.shgi.probe_grid.rays_per_probe = 32
    scene.shgi.probe_grid.passes = 2
    results = {}
    for source in ("PATH_TRACE", "PROBE_GRID"):
        results[source] = {
            "dask": bake(os.path.join(tmpdir, f"{source}-dask"), source=source, farm="DASK",
                         workers=2, shard_count=3),
            "local": bake(os.path.join(tmpdir, f"{source}-local"), source=source)}
    try:
        bake(os.path.join(tmpdir, "bad"), farm="DASK", scheduler="my-farm:8786")
        results["bad_scheduler"] = "baked"
    except RuntimeError as error:  # the operator's ERROR report
        results["bad_scheduler"] = str(error)
    blend = os.path.join(tmpdir, "room.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    scene = bpy.context.scene
    scene.shgi.bake.farm = "FLAMENCO"
    scene.shgi.bake.shard_count = 3
    scene.shgi.bake.samples = 12
    scene.shgi.bake.output_folder = os.path.join(tmpdir, "flamenco")
    bpy.ops.wm.save_mainfile()
    # What the job's merge must write: the same objects baked here with the saved settings.
    select_only(*OBJECTS)
    reference = os.path.join(tmpdir, "flamenco-reference")
    results["flamenco_reference_status"] = sorted(bpy.ops.shgi.bake_lightmaps(
        farm="LOCAL", shard_count=1, output_folder=reference))
    results["flamenco_reference"] = reference
    try:
        bake(os.path.join(tmpdir, "flamenco-bake"))
        results["flamenco_bake"] = "baked"
    except RuntimeError as error:
        results["flamenco_bake"] = str(error)
    job_path = os.path.join(tmpdir, "flamenco", "shgi_flamenco_job.json")
    results["flamenco_status"] = sorted(bpy.ops.shgi.write_flamenco_job())
    with open(job_path) as file:
        results["flamenco_job"] = json.load(file)
    results["blend"] = blend
    with open(setup.results_path("farm_checks.json"), "w") as out:
        json.dump(results, out)
    print("FARM_CHECKS_OK")


main()
