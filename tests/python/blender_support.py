"""Running Debian's Blender from tests, whichever Python runs pytest.

Debian's Blender embeds the system Python 3.11 but picks its Python home from the first python3
on PATH: under the pyenv interpreter that is pyenv's, and Blender then loses Debian's
site-packages (numpy). run_blender therefore drops pyenv's folders from PATH.

The Blender-side scripts live in tests/blender (BLENDER_SCRIPTS) and take
``-- <build python dir> <addon dir> [<results json>]``; run_script_once runs one of them once
per session for all the tests that read its results.
"""

import json
import os
import pathlib
import shutil
import subprocess
import time

import pytest

BLENDER = shutil.which("blender")
REPO_ROOT = pathlib.Path(__file__).resolve().parents[2]
BLENDER_SCRIPTS = REPO_ROOT / "tests" / "blender"
ADDON_DIR = REPO_ROOT / "addon"

needs_blender = pytest.mark.skipif(BLENDER is None,
                                   reason="Blender is not installed (make deps installs it)")


def blender_env():
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join(
        p for p in env.get("PATH", "").split(os.pathsep) if ".pyenv" not in p)
    return env


def run_blender(script, *args, timeout=600, exit_code=1):
    """Runs `blender -b --factory-startup --python-exit-code <exit_code> --python script --
    args`: Blender exits with `exit_code` when the script raises."""
    command = [BLENDER, "-b", "--factory-startup", "--python-exit-code", str(exit_code),
               "--python", str(script)]
    if args:
        command += ["--", *map(str, args)]
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                          env=blender_env())


_SCRIPT_RUNS = {}


def run_script_once(script, marker, build_python_dir, tmp_path_factory, *, exit_code=1,
                    passing_codes=(0,), shown_line=None, timeout=600):
    """Runs BLENDER_SCRIPTS/`script` once per session; the results JSON it wrote, or None.

    The script gets the build folder, the add-on folder and a results JSON path after '--'. The
    run passes when Blender's exit code is in `passing_codes` and `marker` is in its output;
    then the lines of the output for which `shown_line(line)` holds are printed. A failed run
    raises AssertionError with the end of the log, again for every later test that asks.
    """
    if script not in _SCRIPT_RUNS:
        name = pathlib.Path(script).stem
        out = tmp_path_factory.mktemp(name) / f"{name}.json"
        start = time.perf_counter()
        result = run_blender(BLENDER_SCRIPTS / script, build_python_dir, ADDON_DIR, out,
                             timeout=timeout, exit_code=exit_code)
        seconds = time.perf_counter() - start
        log = result.stdout[-6000:] + result.stderr[-3000:]
        if result.returncode not in passing_codes or marker not in result.stdout:
            _SCRIPT_RUNS[script] = AssertionError(
                f"{script} failed (exit {result.returncode}, {seconds:.1f} s):\n{log}")
        else:
            print(f"\n{script}: {seconds:.1f} s")
            if shown_line is not None:
                print("\n".join(filter(shown_line, result.stdout.splitlines())))
            _SCRIPT_RUNS[script] = json.loads(out.read_text()) if out.exists() else None
    if isinstance(_SCRIPT_RUNS[script], Exception):
        raise _SCRIPT_RUNS[script]
    return _SCRIPT_RUNS[script]
