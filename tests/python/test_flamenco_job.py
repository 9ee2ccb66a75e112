"""The Flamenco job type of examples/flamenco (shgi_bake.js) outside Flamenco: both scripts parse
(`node --check`), and a job of the "python" runner compiled by preview_job.js and run task by
task on this machine (shards, then the merge) writes the files one bake writes, byte for byte.
The "blender" runner's job, as the add-on's Write Flamenco Job writes it, is run the same way
by test_blender_bake.py (test_bake_panel_farm_dask_and_flamenco_in_blender).

`make deps` installs nodejs."""

import json
import pathlib
import re
import subprocess
import sys

import pytest

import shgi

from blender_support import REPO_ROOT

sys.path.insert(0, str(REPO_ROOT / "examples"))
import scenes  # noqa: E402
import scene_gltf  # noqa: E402

FLAMENCO = REPO_ROOT / "examples" / "flamenco"


def test_the_job_type_scripts_parse():
    for script in ("shgi_bake.js", "preview_job.js"):
        result = subprocess.run(["node", "--check", str(FLAMENCO / script)],
                                capture_output=True, text=True)
        assert result.returncode == 0, result.stderr


@pytest.mark.parametrize("sh_order", [1, 2])
def test_a_python_runner_job_bakes_its_shards_and_merges_them_into_one_bake(build_python_dir,
                                                                             tmp_path, sh_order):
    """Also at sh_order 2 (L2 directional lightmaps: the job passes --sh-order 2)."""
    scene = scenes.sun_room(0.25, lightmap=True).scene
    scene_file = scene_gltf.write_gltf(scene, tmp_path / "room.gltf")
    env = {"PYTHONPATH": str(build_python_dir), "PATH": "/usr/bin:/bin"}
    settings = {"runner": "python", "scene_file": str(scene_file), "python_exe": sys.executable,
                "output_folder": str(tmp_path / "job"), "shard_count": 3,
                "uv_map": "UVMap", "resolution": 16, "samples": 4,
                "objects": "floor, back, right", "directional": True}
    if sh_order != 1:
        settings["sh_order"] = sh_order
    run = subprocess.run(["node", str(FLAMENCO / "preview_job.js"), json.dumps(settings),
                          "--run"], capture_output=True, text=True, env=env, timeout=300)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    tasks = re.findall(r"^task (\S+) \(misc\)", run.stdout, re.MULTILINE)
    assert tasks == ["bake-shard-0", "bake-shard-1", "bake-shard-2", "merge"]
    one = subprocess.run([sys.executable, "-m", "shgi", "bake", str(scene_file), "--out",
                          str(tmp_path / "one"), "--samples", "4", "--uv-set", "UVMap",
                          "--resolution", "16", "--objects", "floor,back,right",
                          "--directional", "--sh-order", str(sh_order), "--quiet"],
                         capture_output=True, text=True, env=env, timeout=300)
    assert one.returncode == 0, one.stderr
    names = sorted(p.name for p in (tmp_path / "one").iterdir() if p.is_file())
    assert names == ["back.exr", "back.png", "floor.exr", "floor.png", "right.exr", "right.png"]
    for name in names:
        assert (tmp_path / "job" / name).read_bytes() == (tmp_path / "one" / name).read_bytes()
    layers = shgi.read_exr(tmp_path / "job" / "floor.exr")
    assert sum(name.startswith("SH.") for name in layers) == (sh_order + 1) ** 2
