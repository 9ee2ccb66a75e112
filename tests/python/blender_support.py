"""Running Blender from tests: Debian's Blender 3.4.1 and Blender as a Python module (PyPI's
`bpy` wheel, 4.2+), whichever Python runs pytest.

BLENDERS lists both; a test that takes the `blender` fixture (conftest.py) runs once on each,
with the Blender's name in its id ("blender-3.4.1", "bpy-5.0.1"). One command line serves both:
``Blender.command(args)`` puts ``blender -b`` or the `bpy` venv's Python and
tests/blender/bpy_module_runner.py in front of Blender's own arguments. The `bpy` module has no
window, so tests driving a window (xvfb-run) run on the Blender program only (WINDOWED_BLENDER).

Debian's Blender embeds the system Python 3.11 but picks its Python home from the first python3
on PATH: under the pyenv interpreter that is pyenv's, and Blender then loses Debian's
site-packages (numpy). blender_env() therefore drops pyenv's folders from PATH. It also drops
PYTHONPATH, which Blender ignores and the bpy module's Python would not.

The Blender-side scripts live in tests/blender (BLENDER_SCRIPTS) and take
``-- <build python dir> <addon dir> [<results json>]``; run_script_once runs one of them once
per session and Blender for all the tests that read its results.
"""

import json
import os
import pathlib
import shutil
import subprocess
import time
from dataclasses import dataclass

import pytest

REPO_ROOT = pathlib.Path(__file__).resolve().parents[2]
BLENDER_SCRIPTS = REPO_ROOT / "tests" / "blender"
ADDON_DIR = REPO_ROOT / "addon"
BPY_RUNNER = BLENDER_SCRIPTS / "bpy_module_runner.py"
# The venv `make deps` makes with PyPI's bpy wheel (the Makefile's BPY_VENV); SHGI_BPY_PYTHON
# names another venv's Python.
DEFAULT_BPY_PYTHON = "/opt/shgi/bpy-5.0.1/bin/python"


def blender_env():
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    env["PATH"] = os.pathsep.join(
        p for p in env.get("PATH", "").split(os.pathsep) if ".pyenv" not in p)
    return env


@dataclass(frozen=True)
class Blender:
    """One Blender the tests run: `name` is the test id, `prefix` the command before Blender's
    arguments, `missing` why it cannot run here (None when it can)."""
    name: str
    prefix: tuple
    missing: str = None

    def command(self, *args):
        return [*self.prefix, *map(str, args)]

    def run(self, *args, timeout=600, env=None):
        """Runs Blender with `args`, its environment blender_env() updated with `env`."""
        return subprocess.run(self.command(*args), capture_output=True, text=True,
                              timeout=timeout, env={**blender_env(), **(env or {})})

    @property
    def version(self):
        """(major, minor, patch) from the name; (0, 0, 0) when unknown."""
        digits = self.name.rpartition("-")[2].split(".")
        return tuple(int(d) for d in digits) if all(d.isdigit() for d in digits) else (0, 0, 0)

    @property
    def is_module(self):
        return self.name.startswith("bpy")

    @property
    def skip_mark(self):
        return pytest.mark.skipif(self.missing is not None, reason=self.missing or "")


def _program_blender():
    program = shutil.which("blender", path=blender_env()["PATH"])
    if program is None:
        return Blender("blender", (), "Blender is not installed (make deps installs it)")
    version = subprocess.run([program, "--version"], capture_output=True, text=True,
                             env=blender_env()).stdout.split()
    return Blender(f"blender-{version[1] if len(version) > 1 else 'unknown'}", (program, "-b"))


def _module_blender():
    python = os.environ.get("SHGI_BPY_PYTHON", DEFAULT_BPY_PYTHON)
    if not os.access(python, os.X_OK):
        return Blender("bpy", (), f"no Python with the bpy module at {python} (make deps "
                                  "makes the venv; SHGI_BPY_PYTHON names another)")
    version = subprocess.run(
        [python, "-c", "import importlib.metadata as m; print(m.version('bpy'))"],
        capture_output=True, text=True)
    if version.returncode != 0:
        return Blender("bpy", (), f"{python} has no bpy module: {version.stderr.strip()}")
    return Blender(f"bpy-{version.stdout.strip()}", (python, str(BPY_RUNNER)))


WINDOWED_BLENDER = _program_blender()
BLENDERS = [WINDOWED_BLENDER, _module_blender()]
BLENDER = WINDOWED_BLENDER.prefix[0] if WINDOWED_BLENDER.missing is None else None

XVFB_RUN = shutil.which("xvfb-run")


def needs_window(test):
    """Marks a test that drives Blender's window under xvfb-run (the Blender program only)."""
    skip = pytest.mark.skipif(XVFB_RUN is None or BLENDER is None,
                              reason="xvfb-run or Blender is missing (make deps installs both)")
    return pytest.mark.blender(skip(test))


def run_in_window(script, size, *args, options=(), timeout=300, env=None):
    """Runs BLENDER_SCRIPTS/`script` in a Blender window of `size` (width, height) on a virtual
    screen (xvfb-run), with Blender `options` before --python and `args` after '--'
    (environment variables `env` added to blender_env())."""
    width, height = size
    command = [XVFB_RUN, "-a", "-s", f"-screen 0 {width + 160}x{height + 80}x24", BLENDER,
               "--factory-startup", *options, "--window-geometry", "0", "0", str(width),
               str(height), "--python", str(BLENDER_SCRIPTS / script), "--", *map(str, args)]
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                          env={**blender_env(), **(env or {})})


def blender_params():
    """pytest.param per Blender, skipped with the reason when that Blender is missing."""
    return [pytest.param(b, id=b.name, marks=[b.skip_mark, pytest.mark.blender])
            for b in BLENDERS]


def run_blender(script, *args, blender=WINDOWED_BLENDER, timeout=600, exit_code=1, env=None):
    """Runs `blender -b --factory-startup --python-exit-code <exit_code> --python script --
    args` on `blender` (environment variables `env` added): it exits with `exit_code` when the
    script raises."""
    command = ["--factory-startup", "--python-exit-code", exit_code, "--python", script]
    if args:
        command += ["--", *args]
    return blender.run(*command, timeout=timeout, env=env)


_SCRIPT_RUNS = {}


def run_script_once(script, marker, build_python_dir, tmp_path_factory, *,
                    blender=WINDOWED_BLENDER, exit_code=1, passing_codes=(0,), shown_line=None,
                    timeout=600):
    """Runs BLENDER_SCRIPTS/`script` once per session on `blender`; the results JSON it wrote,
    or None.

    The script gets the build folder, the add-on folder and a results JSON path after '--'. The
    run passes when the exit code is in `passing_codes` and `marker` is in its output; then the
    lines of the output for which `shown_line(line)` holds are printed. A failed run raises
    AssertionError with the end of the log, again for every later test that asks.
    """
    key = (script, blender.name)
    if key not in _SCRIPT_RUNS:
        name = pathlib.Path(script).stem
        out = tmp_path_factory.mktemp(f"{name}-{blender.name}") / f"{name}.json"
        start = time.perf_counter()
        result = run_blender(BLENDER_SCRIPTS / script, build_python_dir, ADDON_DIR, out,
                             blender=blender, timeout=timeout, exit_code=exit_code)
        seconds = time.perf_counter() - start
        log = result.stdout[-6000:] + result.stderr[-3000:]
        if result.returncode not in passing_codes or marker not in result.stdout:
            _SCRIPT_RUNS[key] = AssertionError(
                f"{script} on {blender.name} failed (exit {result.returncode}, "
                f"{seconds:.1f} s):\n{log}")
        else:
            print(f"\n{script} on {blender.name}: {seconds:.1f} s")
            if shown_line is not None:
                print("\n".join(filter(shown_line, result.stdout.splitlines())))
            _SCRIPT_RUNS[key] = json.loads(out.read_text()) if out.exists() else None
    if isinstance(_SCRIPT_RUNS[key], Exception):
        raise _SCRIPT_RUNS[key]
    return _SCRIPT_RUNS[key]
