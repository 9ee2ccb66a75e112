"""Lightmap bakes from Blender: the bpy-free parts here, Blender runs below.

Outside Blender (/usr/bin/python3): the bake properties against LightmapSettings and
BakeOptions, the settings they fill, shards and sizes, the worker-thread BakeTask (the same
lightmaps as one shgi.bake.bake_scene call; a field source solves first; a cancel keeps the
lightmaps finished before it) and the pixels handed to Blender images.
Inside Blender: tests/blender/bake_checks.py (background: a closed room's floor baked by Cycles
and by shgi.bake_lightmaps with each source; the refusals; Create UV Map and the material
nodes; shards and Merge Shards; Export Volume), the saved room baked headless with
``--python-expr`` (refused without the native module, cancelled by Ctrl-C), and under Xvfb the
modal bake with Esc. The traps an artist hits: tests/blender/bake_trap_checks.py (the sun room
facing out warned about, shared materials made single-user, a headless bake's log lines,
lightmap nodes without an image dropped on load) and, under Xvfb,
tests/blender/bake_undo_window.py (one undo after a bake shown in materials, Material
Preview, redo, a cancelled bake's undo step).

Acceptance against Cycles' DIFFUSE {DIRECT, INDIRECT} bake of the floor, over the covered
texels: the mean texel difference (the mean over those texels of shgi - Cycles, relative to
Cycles' mean) within 5% for the path tracer and 10% for each field source. PSNR (after
auto-exposure and sRGB, shgi.metrics.psnr) and the mean absolute texel difference are reported,
over all covered texels and over the visible ones (not under the box).
"""

import importlib.util
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import time
from types import SimpleNamespace

import numpy as np
import pytest

import shgi
from shgi import bake as shgi_bake
from blender_support import (ADDON_DIR, BLENDER_SCRIPTS, REPO_ROOT, WINDOWED_BLENDER,
                             blender_env, needs_window, run_blender, run_in_window,
                             run_script_once)
from latency_clock import Latency, LatencyClock

sys.path.insert(0, str(REPO_ROOT / "addon"))
sys.path.insert(0, str(REPO_ROOT / "examples"))

import scenes  # noqa: E402
from shgi_blender import bake_settings, settings  # noqa: E402
from shgi_blender.operators.facing_check import turned_around  # noqa: E402
from shgi_blender.operators.facing_check import warning as facing_warning  # noqa: E402
from shgi_blender.engine import field_solvers  # noqa: E402
from shgi_blender.engine.lightmap_bake import BakeRequest, BakeTask, rgba_pixels  # noqa: E402

# The bake's acceptance (docs/baking.md): mean texel difference against Cycles' bake.
MEAN_TOLERANCE = {"PATH_TRACE": 0.05, "PHOTON_LATTICE": 0.10, "PROBE_GRID": 0.10}
# A lightmap in the wrong row order or UV orientation matches Cycles' worse than the right one:
# mirrored, the floor's box shadow and light fall-off land elsewhere (about 4-11 dB lower in
# the room of bake_checks.py).
ORIENTATION_MARGIN_DB = 3.0
# Lightmap in the EXR (half floats) against the Blender image (float): relative rounding 2^-11.
HALF_TOLERANCE = 1e-3
# docs/architecture.md: cancel returns within 0.2 s (a task polled every 5 ms here).
CANCEL_LATENCY = 0.5
# Esc in a window to the end of the worker: Blender's event loop delivers the key between
# redraws (software OpenGL under Xvfb), then the native cancel (< 0.2 s).
ESC_LATENCY = 1.0
TASK_TIMEOUT = 60.0
# Ctrl-C in a headless bake: sent this long after the bake starts (its export of the saved room
# takes a fraction of it, so the signal finds the worker running), and the bake must return
# within CTRL_C_LATENCY of it (the native cancel, < 0.2 s, after the wait's 0.1 s poll).
CTRL_C_AFTER_SECONDS = 1.5
CTRL_C_LATENCY = 0.5
WINDOW = (640, 480)


def bake_props(**overrides):
    """scene.shgi.bake as a plain object with the property defaults."""
    return SimpleNamespace(**dict(bake_settings.BAKE_PROPERTY_DEFAULTS, **overrides))


def scene_props(**overrides):
    """scene.shgi's light paths and seed with their defaults."""
    return SimpleNamespace(**dict(settings.PROPERTY_DEFAULTS, **overrides))


def lightmap_room():
    """The example Cornell box with walls facing in and LightmapUV, committed."""
    builder = scenes.cornell_box(0.1, lightmap=True)
    builder.scene.commit()
    return builder.scene


def jobs(scene, *names, size=16):
    return shgi_bake.jobs_for_scene(scene, "LightmapUV", size, names=list(names))


# --- settings (no Blender) -------------------------------------------------------------------

def test_bake_properties_mirror_the_native_defaults():
    native = shgi.LightmapSettings()
    built = bake_settings.lightmap_settings(bake_props(), scene_props(), shgi)
    for field in bake_settings.LIGHTMAP_FIELDS:
        assert getattr(built, field) == getattr(native, field), field
    for field, prop in bake_settings.LIGHT_PATH_FIELDS.items():  # Cycles' clamp, not native
        expected = settings.CYCLES_DEFAULTS.get(prop, getattr(native, field))
        assert getattr(built, field) == expected, field
    for field, prop in bake_settings.LIGHTMAP_FIELDS.items():
        assert bake_settings.BAKE_PROPERTY_DEFAULTS[prop] == getattr(native, field), field
    native_fields = {name for name in dir(native) if not name.startswith("_")
                     and name != "validate"}
    mirrored = set(bake_settings.LIGHTMAP_FIELDS) | set(bake_settings.LIGHT_PATH_FIELDS)
    assert native_fields == mirrored  # a new native field needs a property (or a reason)
    options = shgi_bake.BakeOptions()
    for field, prop in bake_settings.OPTION_FIELDS.items():
        assert bake_settings.BAKE_PROPERTY_DEFAULTS[prop] == getattr(options, field), field


def test_content_items_are_the_native_names():
    identifiers = [item[0] for item in bake_settings.CONTENT_ITEMS]
    assert identifiers == ["DIRECT_INDIRECT", "DIRECT", "INDIRECT", "FULL"]
    for identifier in identifiers:
        assert shgi.LightmapSettings(content=identifier).content == identifier
    # The bake's sources are the registry's methods, with the render method's file numbers (a
    # file saved when the path tracer's source was PATH_TRACER holds 0 and opens as PATH_TRACE).
    sources = [(item[0], item[3]) for item in bake_settings.SOURCE_ITEMS]
    assert sources == [(row.identifier, row.number) for row in shgi.methods()]
    assert sources[:3] == [("PATH_TRACE", 0), ("PHOTON_LATTICE", 1), ("PROBE_GRID", 2)]
    assert set(bake_settings.FIELD_SOURCES) <= set(settings.METHODS_BY_ID)  # solver_recipe


def test_bake_options_follow_the_properties():
    options = bake_settings.bake_options(
        bake_props(samples=12, content="INDIRECT", directional=True, tile_size=8, filter=True,
                   padding=2, uv_map="Bake"),
        scene_props(seed=5, diffuse_bounces=2, max_bounces=3), shgi)
    lightmap = options.settings
    assert (lightmap.samples, lightmap.content, lightmap.directional, lightmap.tile_size) == (
        12, "INDIRECT", True, 8)
    assert (lightmap.seed, lightmap.diffuse_bounces, lightmap.max_bounces) == (5, 2, 3)
    assert (options.uv_set, options.filter, options.padding) == ("Bake", True, 2)
    assert options.denoise == "NONE"  # Denoise with the SHGI filter: BakeOptions.filter
    oidn = bake_settings.bake_options(bake_props(filter=True, denoiser="OIDN"), scene_props(), shgi)
    assert (oidn.filter, oidn.denoise) == (False, "OIDN")
    off = bake_settings.bake_options(bake_props(filter=False, denoiser="OIDN"), scene_props(), shgi)
    assert (off.filter, off.denoise) == (False, "NONE")
    with pytest.raises(ValueError, match="Bake > Farm > Tile Size = 2: use 4 .. 1024"):
        bake_settings.bake_options(bake_props(tile_size=2), scene_props(), shgi)
    # SH Order (under Directional) is LightmapSettings.sh_order; refusals name the panel.
    l2 = bake_settings.bake_options(bake_props(directional=True, sh_order=2), scene_props(), shgi)
    assert (l2.settings.directional, l2.settings.sh_order) == (True, 2)
    assert bake_settings.bake_options(bake_props(), scene_props(), shgi).settings.sh_order == 1
    with pytest.raises(ValueError, match="Bake > SH Order = 3"):
        bake_settings.bake_options(bake_props(sh_order=3), scene_props(), shgi)


def test_shards_and_sizes():
    assert bake_settings.shard(bake_props()) is None
    assert bake_settings.shard(bake_props(shard_index=2, shard_count=3)) == (2, 3)
    with pytest.raises(ValueError, match="0..2"):
        bake_settings.shard(bake_props(shard_index=3, shard_count=3))
    scene = lightmap_room()
    floor = [inst.name for inst in scene.instances].index("floor")
    assert bake_settings.lightmap_size(bake_props(resolution=48), scene, floor) == 48
    assert bake_settings.lightmap_size(bake_props(texel_density=20.0), scene, floor) == \
        shgi_bake.resolution_for_density(scene, floor, 20.0)
    with pytest.raises(ValueError, match="both 0"):
        bake_settings.lightmap_size(bake_props(texel_density=0.0), scene, floor)


def test_resolution_ends_where_the_bake_refuses():
    """The Resolution property's max is the native lightmap side limit, read from shgi: one
    texel more is refused by name, the limit itself rasterizes. Its soft max is the largest
    side a texel density picks; the largest Texel Density Blender stores gives that side."""
    limit = shgi.MAX_LIGHTMAP_RESOLUTION
    assert bake_settings.resolution_range(shgi) == {"max": limit,
                                                    "soft_max": shgi_bake.MAX_RESOLUTION}
    assert bake_settings.resolution_range(None) == {}  # the add-on registers without shgi
    scene = lightmap_room()
    floor = [inst.name for inst in scene.instances].index("floor")
    with pytest.raises(ValueError, match=rf"^instance 'floor': TexelRasterSettings.width = "
                                         rf"{limit + 1} is outside \[1, {limit}\]; bake larger "
                                         r"lightmaps in tiles"):
        shgi.rasterize_texels(scene, floor, shgi.TexelRasterSettings(width=limit + 1, height=1))
    widest = shgi.rasterize_texels(scene, floor, shgi.TexelRasterSettings(
        width=limit, height=1, samples_per_axis=1))
    assert (widest.width, widest.height) == (limit, 1)
    blender_float_max = float(np.finfo(np.float32).max)
    assert bake_settings.lightmap_size(bake_props(texel_density=blender_float_max), scene,
                                       floor) == shgi_bake.MAX_RESOLUTION


def test_rgba_pixels_keep_the_rows_and_add_alpha():
    color = np.arange(2 * 3 * 3, dtype=np.float32).reshape(2, 3, 3)  # row 0 at v = 0
    pixels = rgba_pixels(color).reshape(2, 3, 4)
    np.testing.assert_array_equal(pixels[..., :3], color)  # Image.pixels starts at v = 0 too
    assert (pixels[..., 3] == 1.0).all() and rgba_pixels(color).dtype == np.float32


# --- the bake task (no Blender) ----------------------------------------------------------------

def run_task(request):
    task = BakeTask(shgi, request).start()
    assert task.wait(TASK_TIMEOUT) and task.error is None and not task.cancelled, task.error
    return task


def test_bake_task_equals_one_bake_scene_call(tmp_path):
    scene = lightmap_room()
    options = shgi_bake.BakeOptions(settings=shgi.LightmapSettings(samples=8, seed=3))
    request = BakeRequest(scene, jobs(scene, "floor", "back"), options, str(tmp_path / "task"))
    task = run_task(request)
    finished = task.take_finished()
    assert [lightmap.name for lightmap in finished] == ["floor", "back"]  # jobs_for_scene order
    assert task.take_finished() == [] and task.fraction == pytest.approx(1.0)
    assert set(task.timings) == {"commit", "bake"}
    expected = shgi_bake.bake_scene(scene, request.jobs, options, str(tmp_path / "direct"))
    for got, want in zip(finished, expected):
        np.testing.assert_array_equal(got.color, want.color, err_msg=got.name)
        assert (tmp_path / "task" / f"{got.name}.exr").read_bytes() == \
            (tmp_path / "direct" / f"{got.name}.exr").read_bytes()


def test_bake_task_solves_a_field_source_first(tmp_path):
    scene = lightmap_room()
    recipe = field_solvers.SolverRecipe(field_solvers.LatticeSolver,
                                        shgi.PhotonLatticeSettings(photons=20000, seed=2), 1)
    options = shgi_bake.BakeOptions(settings=shgi.LightmapSettings(samples=4))
    task = run_task(BakeRequest(scene, jobs(scene, "floor"), options, str(tmp_path), recipe))
    assert task.timings["solve"] > 0.0 and task.fraction == pytest.approx(1.0)
    lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(photons=20000, seed=2))
    lattice.solve()
    expected = shgi_bake.bake_scene(scene, jobs(scene, "floor"), options, str(tmp_path / "d"),
                                    lattice)
    np.testing.assert_array_equal(task.take_finished()[0].color, expected[0].color)


def test_cancel_keeps_the_lightmaps_finished_before(tmp_path):
    """Two objects, the second 1024 times larger: cancelled while it bakes, the first stays
    (queued and written), the second leaves no file."""
    scene = lightmap_room()
    options = shgi_bake.BakeOptions(settings=shgi.LightmapSettings(samples=256))
    request = BakeRequest(scene, jobs(scene, "floor", size=8) + jobs(scene, "back", size=256),
                          options, str(tmp_path))
    task = BakeTask(shgi, request).start()
    deadline = time.perf_counter() + TASK_TIMEOUT
    finished = []
    while not finished and time.perf_counter() < deadline:
        finished = task.take_finished()
        time.sleep(0.005)
    assert [lightmap.name for lightmap in finished] == ["floor"]
    assert task.running, "the large object finished before the cancel: make it larger"
    clock = LatencyClock()
    task.cancel()
    assert task.wait(10)
    latency = clock.read()
    assert latency.seconds < CANCEL_LATENCY, str(latency)
    assert task.cancelled and task.error is None and task.take_finished() == []
    assert sorted(path.name for path in tmp_path.iterdir()) == ["floor.exr", "floor.png"]


# --- Bake > Farm (no Blender) ------------------------------------------------------------------

# The Dask farm's tests need dask[distributed]; `make test` sets SHGI_REQUIRE_FARM=1, where a
# missing dask fails them instead.
needs_dask = pytest.mark.skipif(
    importlib.util.find_spec("distributed") is None and os.environ.get("SHGI_REQUIRE_FARM") != "1",
    reason="dask[distributed] is not installed (make deps installs it)")


def test_farm_settings_name_the_target_and_refuse_a_bad_address():
    assert bake_settings.farm_target(bake_props()) is None  # This Computer
    assert bake_settings.farm_target(bake_props(farm="FLAMENCO")) is None
    assert bake_settings.farm_target(bake_props(farm="DASK", workers=3)) == \
        bake_settings.FarmTarget("", 3, 0)  # Shards 1: four per worker
    assert bake_settings.farm_target(bake_props(
        farm="DASK", scheduler=" tcp://10.0.0.2:8786 ", shard_count=12)) == \
        bake_settings.FarmTarget("tcp://10.0.0.2:8786", 2, 12)
    for address in ("10.0.0.2:8786", "tcp://10.0.0.2", "tcp://:8786", "tcp://host:port"):
        with pytest.raises(ValueError, match=r"Bake > Farm > Scheduler .* is not an address "
                                             r"like tcp://"):
            bake_settings.farm_target(bake_props(farm="DASK", scheduler=address))
    with pytest.raises(ValueError, match=r"Bake > Farm > Workers must lie in 1\.\.256"):
        bake_settings.farm_target(bake_props(farm="DASK", workers=0))
    from shgi import farm
    assert bake_settings.SHARDS_PER_WORKER == farm.SHARDS_PER_WORKER  # the panel's hint


@needs_dask
@pytest.mark.farm
def test_bake_task_on_a_dask_farm_equals_the_bake_here(tmp_path):
    """The add-on's BakeTask with Farm "Dask" (2 worker processes it starts, 3 shards): the
    same files as the task baking here, from the path tracer and from a field its workers
    solve; progress ends with the merge."""
    scene = lightmap_room()
    options = shgi_bake.BakeOptions(settings=shgi.LightmapSettings(samples=4, seed=3))
    recipe = field_solvers.SolverRecipe(field_solvers.LatticeSolver,
                                        shgi.PhotonLatticeSettings(photons=20000, seed=2), 1)
    for name, field in (("path", None), ("lattice", recipe)):
        here = run_task(BakeRequest(scene, jobs(scene, "floor", "back"), options,
                                    str(tmp_path / f"{name}-here"), field))
        farm = run_task(BakeRequest(scene, jobs(scene, "floor", "back"), options,
                                    str(tmp_path / f"{name}-farm"), field,
                                    farm=bake_settings.FarmTarget("", 2, 3)))
        assert [lightmap.name for lightmap in farm.take_finished()] == ["floor", "back"]
        assert farm.fraction == pytest.approx(1.0) and "connect" in farm.timings
        files = sorted(path.name for path in (tmp_path / f"{name}-here").iterdir())
        assert files == ["back.exr", "back.png", "floor.exr", "floor.png"]
        for file in files:
            assert (tmp_path / f"{name}-farm" / file).read_bytes() == \
                (tmp_path / f"{name}-here" / file).read_bytes(), (name, file)
        assert here.take_finished() != []


def test_flamenco_job_holds_the_bake_panel_and_the_selection():
    job = bake_settings.flamenco_job(bake_props(samples=64, shard_count=8, source="PROBE_GRID"),
                                     ["wall", "floor"], "/farm/room.blend", "/farm/out",
                                     "room lightmaps")
    assert (job["name"], job["type"]) == ("room lightmaps", "shgi-bake")
    settings = job["settings"]
    assert (settings["objects"], settings["samples"], settings["shard_count"],
            settings["source"]) == ("floor, wall", 64, 8, "PROBE_GRID")
    assert (settings["runner"], settings["blendfile"], settings["output_folder"]) == (
        "blender", "/farm/room.blend", "/farm/out")
    # Every setting is one the job type declares (a key it does not know would be dropped).
    script = (REPO_ROOT / "examples" / "flamenco" / "shgi_bake.js").read_text()
    declared = set(re.findall(r'\{ key: "(\w+)"', script))
    assert set(settings) <= declared, set(settings) - declared


# --- inside Blender ----------------------------------------------------------------------------

def bake_results(blender, build_python_dir, tmp_path_factory):
    return run_script_once("bake_checks.py", "BAKE_CHECKS_OK", build_python_dir,
                           tmp_path_factory, blender=blender,
                           shown_line=lambda line: line.startswith(("shgi ", "Cycles ")))


def test_room_faces_inwards(blender, build_python_dir, tmp_path_factory):
    results = bake_results(blender, build_python_dir, tmp_path_factory)
    assert results["inward_quads"] == ["ceiling", "floor", "wall_east", "wall_north",
                                       "wall_south", "wall_west"]
    assert results["cycles"]["mask_texels"] == 64 * 64  # the floor's UVs cover the square


@pytest.mark.parametrize("source", list(MEAN_TOLERANCE))
def test_floor_bake_matches_cycles(blender, source, build_python_dir, tmp_path_factory):
    results = bake_results(blender, build_python_dir, tmp_path_factory)
    row, cycles = results["sources"][source], results["cycles"]
    covered, visible = row["covered"], row["visible"]
    print(f"\n{source}: covered texels mean difference {100 * covered['mean_difference']:+.2f}%,"
          f" PSNR {covered['psnr']:.2f} dB; visible texels mean difference "
          f"{100 * visible['mean_difference']:+.2f}%, PSNR {visible['psnr']:.2f} dB; shgi "
          f"{row['seconds']:.2f} s at {row['samples']} samples, Cycles {cycles['seconds']:.2f} s "
          f"at {cycles['samples']} samples")
    assert covered["texels"] == cycles["mask_texels"]
    assert abs(covered["mean_difference"]) <= MEAN_TOLERANCE[source], covered
    orientation = row["orientation_psnr"]
    assert orientation["as_baked"] >= max(orientation["v_mirrored"],
                                          orientation["u_mirrored"]) + ORIENTATION_MARGIN_DB
    assert row["exr_vs_image"] <= HALF_TOLERANCE
    assert row["files"] == ["floor.exr", "floor.png"]


def test_properties_hold_the_defaults_in_blender(blender, build_python_dir, tmp_path_factory):
    results = bake_results(blender, build_python_dir, tmp_path_factory)
    for key in ("group_defaults", "bake_lightmaps_defaults", "merge_lightmap_shards_defaults"):
        assert results[key] == bake_settings.BAKE_PROPERTY_DEFAULTS, key
    # Resolution ends at the native limit (the panel offers no size the bake refuses).
    expected = [shgi.MAX_LIGHTMAP_RESOLUTION, shgi_bake.MAX_RESOLUTION]
    assert results["resolution_range"] == {owner: expected for owner in (
        "scene.shgi.bake", "bake_lightmaps", "merge_lightmap_shards")}


def test_baked_images_are_float_and_packed(blender, build_python_dir, tmp_path_factory):
    """Float images packed into the .blend file; baked again, they pack the new texels (read
    back from the packed data they equal the last bake's EXR)."""
    image = bake_results(blender, build_python_dir, tmp_path_factory)["image"]
    assert (image["size"], image["is_float"], image["packed"]) == ([64, 64], True, True)
    assert image["packed_vs_last_exr"] <= HALF_TOLERANCE


@pytest.mark.parametrize("case, words", [
    ("nothing_selected", ["no mesh object is selected"]),
    ("only_a_light", ["no mesh object is selected"]),
    ("missing_uv_map", ["'box'", "no UV map 'LightmapUV'", "Create UV Map"]),
    ("no_light", ["no light", "add a light"]),
    ("hidden_for_render", ["'wall_north'", "hidden for render"]),
    ("nan_uv", ["object 'floor' was left out of the exported scene",
                "UV map 'LightmapUV': corner 0 is (nan,", "values must be finite",
                "fix it or deselect it"]),
    ("zero_scale", ["object 'floor' was left out of the exported scene", "a scale of 0"]),
    ("faceless_create_uv", ["object 'points'", "has no faces", "deselect it"]),
    ("unsaved_relative_folder", ["'//lightmaps'", "not been saved", "absolute folder"]),
])
def test_bake_refusals_name_the_problem_and_fix(blender, case, words, build_python_dir,
                                                tmp_path_factory):
    results = bake_results(blender, build_python_dir, tmp_path_factory)
    message = results["errors"][case]
    assert message.startswith("Error: SHGI bake: ")
    for word in words:
        assert word in message, message
    assert "'floor'" not in results["errors"]["missing_uv_map"]  # the floor has its UV map
    assert "hidden for render" not in results["errors"]["nan_uv"]  # the real reason only
    assert results["faceless_uv_maps"] == []  # the refused Create UV Map leaves no UV map
    assert "Traceback" not in message
    assert results["file_path_while_refused"] == "" and not results["refused_files"]


def test_create_uv_map_and_material_nodes(blender, build_python_dir, tmp_path_factory):
    results = bake_results(blender, build_python_dir, tmp_path_factory)
    uv = results["create_uv"]
    assert uv["uv_maps"] == ["UVMap", "LightmapUV"] and uv["active_uv_map"] == "UVMap"
    assert 0.0 <= uv["uv_range"][0] < uv["uv_range"][1] <= 1.0
    nodes = results["materials"]
    assert nodes["nodes"] == ["SHGI Lightmap", "SHGI Lightmap Albedo", "SHGI Lightmap Emission",
                              "SHGI Lightmap Mix", "SHGI Lightmap UV"]
    assert nodes["image"] == "box_shgi_lightmap" and nodes["uv_node_map"] == "LightmapUV"
    assert nodes["surface_from"] == "SHGI Lightmap Mix" and nodes["active_node"] == "SHGI Lightmap"
    assert "SHGI fallback" not in nodes["exported_materials"]
    assert nodes["shared_material_nodes"] == []  # 'white' is shared by four objects
    # Make Materials Single-User (the default): the ceiling shows its lightmap in a copy.
    assert nodes["single_user"] == {
        "ceiling_material": "white ceiling", "ceiling_image": "ceiling_shgi_lightmap",
        "white_users": ["wall_east", "wall_north", "wall_south"], "white_nodes": []}
    assert nodes["after_removal"] == {"nodes": [], "surface_from": "Principled BSDF"}


def test_create_uv_map_with_xatlas(blender, build_python_dir, tmp_path_factory):
    """A copy of the box without the lightmap UV map: Create UV Map with the xatlas layout
    gives one inside the unit square whose triangles do not overlap (256^2 samples), then the
    bake runs on it."""
    layout = bake_results(blender, build_python_dir, tmp_path_factory)["xatlas"]
    print(f"\nxatlas on {blender.name}: UV triangles cover {100 * layout['uv_area']:.1f}% of "
          "the square")
    assert layout["uv_maps"] == ["UVMap", "LightmapUV"]
    assert 0.0 <= layout["uv_range"][0] < layout["uv_range"][1] <= 1.0
    assert layout["overlapping_samples"] == 0
    # Without overlaps the samples inside a triangle measure the sum of the triangles' areas
    # (to the grid's resolution along the charts' edges).
    assert layout["covered_share"] == pytest.approx(layout["uv_area"], abs=0.02)
    assert layout["uv_area"] > 0.0
    assert layout["files"] == ["box_xatlas.exr", "box_xatlas.png"]
    assert layout["lightmap_mean"] > 0.0


def test_oidn_denoises_a_bake_inside_blender(blender, build_python_dir, tmp_path_factory):
    """Denoiser OpenImageDenoise in the Bake panel, inside each Blender: the floor at 4 samples
    keeps its light (mean within 5%) and loses most of its texel-to-texel noise."""
    oidn = bake_results(blender, build_python_dir, tmp_path_factory)["oidn"]
    raw, denoised = oidn["raw"], oidn["oidn"]
    print(f"\nOIDN on {blender.name}: roughness {raw['roughness']:.4f} -> "
          f"{denoised['roughness']:.4f}, mean {raw['mean']:.4f} -> {denoised['mean']:.4f}")
    assert denoised["mean"] == pytest.approx(raw["mean"], rel=0.05)
    assert denoised["roughness"] < 0.5 * raw["roughness"]


def test_shards_merge_into_the_single_bake(blender, build_python_dir, tmp_path_factory):
    shards = bake_results(blender, build_python_dir, tmp_path_factory)["shards"]
    assert shards["shard_files"] == ["box.shard-0-of-2.npz", "box.shard-1-of-2.npz",
                                     "floor.shard-0-of-2.npz", "floor.shard-1-of-2.npz"]
    assert shards["merge_status"] == ["FINISHED"]
    assert shards["identical"] == {"box.exr": True, "box.png": True, "floor.exr": True,
                                   "floor.png": True}


def test_export_volume_writes_the_solved_field(blender, build_python_dir, tmp_path_factory):
    results = bake_results(blender, build_python_dir, tmp_path_factory)
    volumes = results["volumes"]
    assert volumes["PROBE_GRID"]["files"] == ["volume.json", "volume_volume0.exr",
                                              "volume_volume0_visibility.exr"]
    assert volumes["PHOTON_LATTICE"]["files"] == ["volume.json", "volume_caustic.exr",
                                                  "volume_global.exr"]
    for method in ("PROBE_GRID", "PHOTON_LATTICE"):
        row = volumes[method]
        assert row["status"] == ["FINISHED"] and row["frozen"], row
        assert {"format", "version", "sh", "frame"} <= set(row["json_keys"]), row
    assert "solves no volume" in volumes["PATH_TRACE_error"]
    refused = volumes["no_geometry_error"]
    assert refused.startswith("Error: SHGI export volume: nothing to export, the solve failed: "
                              "the scene has no geometry SHGI can render"), refused
    assert "Traceback" not in refused
    assert "2 selected mesh objects to bake" in results["panel"]


def run_headless(blender, blend_path, build_python_dir, expression, before_enabling=""):
    """`blender -b <blend> --factory-startup --python-exit-code 1 --python-expr` that enables
    the add-on (as a farm task does), then runs `expression`."""
    code = (f"import sys; {before_enabling}"
            f"sys.path[:0] = [{str(build_python_dir)!r}, {str(ADDON_DIR)!r}]; "
            "import addon_utils; "
            "assert addon_utils.enable('shgi_blender', default_set=True, handle_error=None); "
            f"import bpy; {expression}")
    return blender.run(blend_path, "--factory-startup", "--python-exit-code", "1",
                       "--python-expr", code, timeout=300)


def test_headless_bake_of_the_saved_file(blender, build_python_dir, tmp_path_factory):
    """The saved room (floor selected) baked by a plain command line: the default output
    folder //lightmaps lies beside the .blend file. A refused bake exits with code 1."""
    blend = pathlib.Path(bake_results(blender, build_python_dir, tmp_path_factory)["blend_path"])
    result = run_headless(blender, blend, build_python_dir,
                          "print('HEADLESS', bpy.ops.shgi.bake_lightmaps(resolution=16, "
                          "samples=4))")
    assert result.returncode == 0 and "HEADLESS {'FINISHED'}" in result.stdout, \
        result.stdout[-3000:] + result.stderr[-2000:]
    out = blend.parent / "lightmaps"
    assert sorted(path.name for path in out.iterdir()) == ["floor.exr", "floor.png"]
    assert shgi.read_exr(str(out / "floor.exr"))["Lightmap"].shape == (16, 16, 3)
    refused = run_headless(blender, blend, build_python_dir,
                           "bpy.ops.object.select_all(action='DESELECT'); "
                           "bpy.ops.shgi.bake_lightmaps()")
    assert refused.returncode == 1, refused.stdout[-3000:]
    assert "no mesh object is selected" in refused.stdout + refused.stderr


def test_ctrl_c_cancels_a_headless_bake(blender, build_python_dir, tmp_path_factory,
                                        tmp_path):
    """A headless bake far too long to finish, interrupted once by SIGINT (Ctrl-C) as it runs:
    the bake stops within CTRL_C_LATENCY, returns CANCELLED with its report, and Blender lives
    on to run the rest of the script."""
    blend = bake_results(blender, build_python_dir, tmp_path_factory)["blend_path"]
    expression = (
        f"sys.path.append({str(BLENDER_SCRIPTS)!r}); from latency_clock import LatencyClock; "
        "import os, signal, threading; sent = {}; "
        "interrupt = lambda: (sent.update(clock=LatencyClock()), "
        "os.kill(os.getpid(), signal.SIGINT)); "
        f"threading.Timer({CTRL_C_AFTER_SECONDS}, interrupt).start(); "
        f"status = bpy.ops.shgi.bake_lightmaps(output_folder={str(tmp_path)!r}, "
        "resolution=256, samples=1024); "
        "latency = sent['clock'].read(); "
        "print('CTRL_C', sorted(status), latency.wall, latency.stolen)")
    result = run_headless(blender, blend, build_python_dir, expression)
    output = result.stdout + result.stderr
    assert result.returncode == 0, output[-3000:]
    line = next(line for line in result.stdout.splitlines() if line.startswith("CTRL_C"))
    status, wall, stolen = line.split(" ", 1)[1].rsplit(" ", 2)
    latency = Latency(float(wall), float(stolen))
    print(f"\nCtrl-C on {blender.name}: the bake returned {latency} after SIGINT")
    assert status == "['CANCELLED']" and latency.seconds < CTRL_C_LATENCY, line
    assert "SHGI bake: cancelled" in output, output[-3000:]


def test_headless_bake_without_the_native_module(blender, build_python_dir, tmp_path_factory):
    """`import shgi` made to fail: the bake refuses with the native module's error and fix."""
    blend = bake_results(blender, build_python_dir, tmp_path_factory)["blend_path"]
    result = run_headless(blender, blend, build_python_dir, "bpy.ops.shgi.bake_lightmaps()",
                          before_enabling="sys.modules['shgi'] = None; ")
    output = result.stdout + result.stderr
    assert result.returncode == 1, output[-3000:]
    assert "SHGI bake: The SHGI native module cannot be imported" in output, output[-3000:]
    assert "make install" in output


@needs_window
def test_modal_bake_keeps_the_finished_lightmaps_when_esc_cancels(build_python_dir, tmp_path):
    """A modal bake of two objects: the first one's files come while it runs, its image only
    at the end (one undo step for all the bake's data); Esc cancels the second and keeps the
    first; a second modal bake runs to its end."""
    out = tmp_path / "bake_window.json"
    result = run_in_window("bake_checks.py", WINDOW, build_python_dir, ADDON_DIR, out, "window",
                           options=("--enable-event-simulate",))
    assert result.returncode == 0 and "BAKE_WINDOW_OK" in result.stdout, \
        result.stdout[-4000:] + result.stderr[-2000:]
    r = json.loads(out.read_text())
    cancel = Latency(**r["cancel_latency"])
    print(f"\nmodal bake: first lightmap after {r['first_image_seconds']:.2f} s, cancelled in "
          f"{cancel}")
    assert r["invoke_status"] == ["RUNNING_MODAL"] and r["worker_running_at_esc"]
    assert r["images_while_running"] == []
    assert cancel.seconds < ESC_LATENCY, str(cancel)
    assert r["cancelled"] == {"images": ["box_shgi_lightmap"], "files": ["box.exr", "box.png"]}
    assert r["finished"] == {"size": [16, 16], "files": ["floor.exr", "floor.png"]}


# --- Bake > Farm in Blender (tests/blender/farm_checks.py) -------------------------------------

def addon_installed_for(tmp_path, build_python_dir):
    """Environment variables under which Blender starts with the add-on enabled in its user
    preferences and shgi in the add-on's vendor folder, as a farm worker's Blender is set up
    (examples/flamenco/README.md): a copy of the add-on in a user scripts folder."""
    scripts, config = tmp_path / "scripts", tmp_path / "config"
    addon = scripts / "addons" / "shgi_blender"
    shutil.copytree(ADDON_DIR / "shgi_blender", addon,
                    ignore=shutil.ignore_patterns("__pycache__", "vendor"))
    (addon / "vendor").mkdir()
    (addon / "vendor" / "shgi").symlink_to(pathlib.Path(build_python_dir) / "shgi")
    env = {"BLENDER_USER_SCRIPTS": str(scripts), "BLENDER_USER_CONFIG": str(config)}
    enable = ("import addon_utils, bpy; addon_utils.enable('shgi_blender', default_set=True); "
              "bpy.ops.wm.save_userpref()")
    result = WINDOWED_BLENDER.run("--python-exit-code", "1", "--python-expr", enable, env=env)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    return env


@needs_dask
@pytest.mark.farm
@pytest.mark.blender
@WINDOWED_BLENDER.skip_mark
def test_bake_panel_farm_dask_and_flamenco_in_blender(build_python_dir, tmp_path):
    """Debian's Blender 3.4.1 (whose Python has dask): Farm "Dask" bakes byte-identical to This
    Computer; a bad Scheduler is refused by name; Blender quits cleanly after importing dask;
    Write Flamenco Job writes a job that, run task by task (preview_job.js --run: prepare, three
    shards, merge, each a Blender with the add-on as a farm worker has it), writes the lightmaps
    a bake here writes."""
    out = tmp_path / "farm_checks.json"
    result = run_blender(BLENDER_SCRIPTS / "farm_checks.py", build_python_dir, ADDON_DIR, out,
                         timeout=300)
    log = result.stdout[-4000:] + result.stderr[-2000:]
    assert result.returncode == 0 and "FARM_CHECKS_OK" in result.stdout, log
    r = json.loads(out.read_text())
    for source in ("PATH_TRACE", "PROBE_GRID"):
        dask, here = r[source]["dask"], r[source]["local"]
        assert dask["status"] == here["status"] == ["FINISHED"], source
        assert len(here["files"]) == 8 and dask["files"] == here["files"], source
    assert "Info: SHGI bake: 4 lightmaps baked on 2 Dask workers here" in result.stdout
    assert "Bake > Farm > Scheduler 'my-farm:8786' is not an address like tcp://" in \
        r["bad_scheduler"]
    assert "Farm is Flamenco: Write Flamenco Job writes the job" in r["flamenco_bake"]
    assert r["flamenco_status"] == r["flamenco_reference_status"] == ["FINISHED"]
    job = r["flamenco_job"]
    assert job["settings"]["blendfile"] == r["blend"] and job["settings"]["shard_count"] == 3
    job_file = tmp_path / "job.json"
    job_file.write_text(json.dumps(job))
    env = {**blender_env(), **addon_installed_for(tmp_path, build_python_dir)}
    run = subprocess.run(["node", str(REPO_ROOT / "examples" / "flamenco" / "preview_job.js"),
                          f"@{job_file}", "--run"], capture_output=True, text=True, env=env,
                         timeout=600)
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-4000:]
    tasks = re.findall(r"^task (\S+) \(blender\)", run.stdout, re.MULTILINE)
    assert tasks == ["prepare", "bake-shard-0", "bake-shard-1", "bake-shard-2", "merge"]
    merged = pathlib.Path(job["settings"]["output_folder"])
    reference = pathlib.Path(r["flamenco_reference"])
    names = sorted(p.name for p in reference.iterdir() if p.suffix in (".exr", ".png"))
    assert len(names) == 8
    for name in names:
        assert (merged / name).read_bytes() == (reference / name).read_bytes(), name


# --- the traps of tests/blender/bake_trap_checks.py --------------------------------------------

# The sun room's objects (examples/blender_scenes.py), in bake order.
SUN_ROOM_OBJECTS = ["back", "ceiling", "floor", "front", "left_wall_0", "left_wall_1",
                    "left_wall_2", "left_wall_3", "right", "table"]
# The floor of the outward room sees only the world under it: its lightmap (irradiance / pi)
# is the world's colour, to the noise of 16 samples.
WORLD_COLOR_TOLERANCE = 0.05
# The floor of the room facing out, baked with every quad turned around, against the floor of
# the room built facing in (64 samples, a Lightmap Pack layout mirrored between the two): the
# same light to the noise of the mean.
SAME_ROOM_TOLERANCE = 0.05
_TRAP_RUNS = {}


def trap_results(blender, build_python_dir, tmp_path_factory):
    """(results JSON, Blender's output) of bake_trap_checks.py on `blender`, once a session."""
    if blender.name not in _TRAP_RUNS:
        out = tmp_path_factory.mktemp(f"bake_traps-{blender.name}") / "bake_traps.json"
        result = run_blender(BLENDER_SCRIPTS / "bake_trap_checks.py", build_python_dir,
                             ADDON_DIR, out, blender=blender, timeout=300)
        output = result.stdout + result.stderr
        _TRAP_RUNS[blender.name] = (
            json.loads(out.read_text()) if result.returncode == 0 and out.exists() else None,
            output)
    results, output = _TRAP_RUNS[blender.name]
    assert results is not None and "BAKE_TRAPS_OK" in output, output[-6000:]
    return results, output


def bake_output(output, folder_name):
    """The part of Blender's output from the bake into folder `folder_name` to the next bake."""
    part = output.split(f"/{folder_name}: ", 1)[1]
    return part.split("\nBAKE ", 1)[0]


def test_outward_facing_room_is_warned_and_inward_room_bakes_its_light(
        blender, build_python_dir, tmp_path_factory):
    """The sun room as the renderers build it faces out: baking its floor warns, naming the
    floor and the fixes, and the floor's lightmap holds the world's light under it. Built for
    bakes (facing in), it bakes without the warning and holds the room's light. Facing out
    but baked with Bake Side "Facing the Scene", every quad is turned around for the bake and
    the floor holds the light of the room facing in."""
    results, output = trap_results(blender, build_python_dir, tmp_path_factory)
    world = np.array(results["world_color"])
    outward, inward = bake_output(output, "outward"), bake_output(output, "inward")
    assert results["outward"]["status"] == ["FINISHED"]
    assert facing_warning("floor") in outward, outward
    assert "'floor'" in facing_warning("floor") and "Recalculate Inside" in facing_warning("x")
    assert "Bake Side to Facing the Scene" in facing_warning("x")
    np.testing.assert_allclose(results["outward"]["floor_mean"], world,
                               rtol=WORLD_COLOR_TOLERANCE)
    assert results["inward"]["status"] == ["FINISHED"]
    assert "faces away from the scene" not in inward, inward
    floor = np.array(results["inward"]["floor_mean"])
    assert np.abs(floor / world - 1.0).max() > 5 * WORLD_COLOR_TOLERANCE, floor
    assert floor.min() > 0.0
    turned = bake_output(output, "outward_facing_scene")
    assert results["outward_facing_scene"]["status"] == ["FINISHED"]
    assert facing_warning("floor") not in turned
    assert turned_around("floor", baked=True) in turned, turned
    for name in SUN_ROOM_OBJECTS:
        if name not in ("floor", "table"):  # the table's box faces out rightly
            assert turned_around(name, baked=False) in turned, (name, turned)
    assert "'table'" not in turned
    np.testing.assert_allclose(results["outward_facing_scene"]["floor_mean"], floor,
                               rtol=SAME_ROOM_TOLERANCE)


def test_closed_room_facing_out_is_found_by_where_it_is_seen_from(
        blender, build_python_dir, tmp_path_factory):
    """A room that is one closed cube with its normals out sees only itself from behind, as a
    solid box does: the camera and the lamp inside it seeing its back name it. Turned in, or a
    box seen from outside, nothing is named; nor a facade facing the camera and lamp outside
    with a wardrobe behind it, whose back rays all hit the wardrobe."""
    results, _output = trap_results(blender, build_python_dir, tmp_path_factory)
    assert results["closed_room_out"] == ["room"]
    assert results["closed_room_in"] == []
    assert results["box_seen_from_outside"] == []
    assert results["facade"] == []


def test_show_in_materials_makes_shared_materials_single_user(blender, build_python_dir,
                                                              tmp_path_factory):
    """Nine of the sun room's ten objects share "plaster": with Make Materials Single-User
    (the default) each object shows its own lightmap in a material of its own and the result
    says so; turned off, the shared material is left alone with a warning per object and the
    result counts only the material shown."""
    results, output = trap_results(blender, build_python_dir, tmp_path_factory)
    single = results["single_user"]
    assert single["status"] == ["FINISHED"]
    assert sorted(single["objects"]) == SUN_ROOM_OBJECTS
    for name, view in single["objects"].items():
        assert view["image"] == f"{name}_shgi_lightmap", (name, view)
    materials = [view["material"] for view in single["objects"].values()]
    assert len(set(materials)) == len(SUN_ROOM_OBJECTS), materials
    assert ("10 lightmaps baked into" in bake_output(output, "single_user")
            and "shown in 10 materials (8 of them single-user copies of shared materials)"
            in bake_output(output, "single_user")), bake_output(output, "single_user")
    shared = results["left_shared"]
    assert shared["status"] == ["FINISHED"]
    shown = {name for name, view in shared["objects"].items() if view["image"]}
    assert shown == {"table"}  # the one object with a material of its own
    assert {view["material"] for name, view in shared["objects"].items()
            if name != "table"} == {"plaster"}
    text = bake_output(output, "left_shared")
    assert "shown in 1 material; 9 warnings" in text, text
    assert text.count("turn on Make Materials Single-User") == 9


def test_headless_bake_logs_each_lightmap_and_tenth(blender, build_python_dir,
                                                    tmp_path_factory):
    """A background bake (execute) of the ten objects prints a line per finished lightmap, in
    bake order, and one per 10% of progress, for a farm's log."""
    _results, output = trap_results(blender, build_python_dir, tmp_path_factory)
    lines = bake_output(output, "single_user").splitlines()
    done = [line for line in lines if " done (" in line and line.startswith("SHGI bake: ")]
    assert done == [f"SHGI bake: {name} done ({k} of 10 lightmaps)"
                    for k, name in enumerate(SUN_ROOM_OBJECTS, 1)], lines
    tenths = [int(line.split()[2][:-1]) for line in lines
              if line.startswith("SHGI bake: ") and line.split()[2].endswith("%")]
    assert tenths == list(range(10, 101, 10)), lines


def test_lightmap_nodes_without_an_image_are_dropped_on_load(blender, build_python_dir,
                                                             tmp_path_factory):
    """A material whose lightmap image is gone, saved and opened again, shows its own surface
    again, without the lightmap nodes (no image-less lightmap node reaches a renderer)."""
    results, _output = trap_results(blender, build_python_dir, tmp_path_factory)
    assert results["imageless"] == {"material": "plaster floor", "nodes": [],
                                    "surface_from": "Principled BSDF"}


@needs_window
def test_undo_after_a_bake_shown_in_materials_then_material_preview(build_python_dir, tmp_path):
    """The sun room's ten objects baked modally with Show in Materials (Create UV Map for the
    table), one undo, Material Preview: Blender lives, and the undo took back the UV map, the
    images, the material copies and the nodes together (the state before the bake); a redo
    gives the bake's state back whole; the bake is not offered to Adjust Last Operation. Then a
    bake of two new rugs cancelled by Esc keeps what
    it finished as one undo step. No state has a lightmap node without its image."""
    out = tmp_path / "bake_undo_window.json"
    result = run_in_window("bake_undo_window.py", WINDOW, build_python_dir, ADDON_DIR, out,
                           options=("--enable-event-simulate",))
    log = result.stdout[-4000:] + result.stderr[-2000:]
    assert result.returncode == 0 and "BAKE_UNDO_WINDOW_OK" in result.stdout, log
    r = json.loads(out.read_text())
    before, baked = r["before_bake"], r["after_bake"]
    assert r["invoke_status"] == ["RUNNING_MODAL"]
    # Adjust Last Operation / Repeat Last would bake again with the UI waiting: not offered.
    assert "SHGI_OT_bake_lightmaps" not in r["registered_after_bake"], r["registered_after_bake"]
    assert baked["images"] == sorted(f"{name}_shgi_lightmap" for name in SUN_ROOM_OBJECTS)
    assert sorted(baked["nodes"].values()) == baked["images"]  # each shown in a material
    assert "LightmapUV" in baked["objects"]["table"]["uv_maps"]
    assert "LightmapUV" not in before["objects"]["table"]["uv_maps"]
    assert r["undo_status"] == ["FINISHED"] and r["after_undo"] == before
    assert r["shading"] == "MATERIAL" and r["after_material_preview"] == before
    assert r["redo_status"] == ["FINISHED"] and r["after_redo"] == baked
    # A bake cancelled by Esc keeps the first rug's image, and both rugs got the UV map: one
    # undo step, which one undo takes back whole.
    rugs_before, cancelled = r["before_cancelled_bake"], r["after_cancelled_bake"]
    assert r["cancel_invoke_status"] == ["RUNNING_MODAL"] and r["worker_running_at_esc"]
    assert cancelled["images"] == sorted(baked["images"] + ["rug_a_shgi_lightmap"])
    for rug in ("rug_a", "rug_b"):
        assert rugs_before["objects"][rug]["uv_maps"] == [], rug
        assert cancelled["objects"][rug]["uv_maps"] == ["LightmapUV"], rug
    assert r["cancelled_undo_status"] == ["FINISHED"]
    assert r["after_cancelled_undo"] == rugs_before
    for step in ("before_bake", "after_bake", "after_undo", "after_material_preview",
                 "after_redo", "before_cancelled_bake", "after_cancelled_bake",
                 "after_cancelled_undo"):
        assert r[step]["problems"] == [], (step, r[step]["problems"])
