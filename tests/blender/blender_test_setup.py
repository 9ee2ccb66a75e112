"""Shared start of the Blender test scripts: their arguments, paths to shgi and the add-on,
enabling the add-on, and a scene reset.

Scripts run as ``blender -b --factory-startup --python-exit-code 1 --python <script> --
<build python dir> <addon dir> [<results json> ...]``; the two folders may also come from the
environment variables SHGI_BUILD_PYTHON and SHGI_ADDON_DIR. A failed check raises, which makes
Blender exit with 1.
"""

import os
import pathlib
import sys
import tempfile

import addon_utils
import bpy

REPO_ROOT = pathlib.Path(__file__).resolve().parents[2]
ADDON = "shgi_blender"


def script_args():
    """The script's own arguments: what follows '--' on Blender's command line."""
    return sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []


def results_path(default_name):
    """The results JSON path given after '--' (third argument), or one in the temp folder."""
    args = script_args()
    return args[2] if len(args) > 2 else os.path.join(tempfile.gettempdir(), default_name)


def add_import_paths():
    """Puts the shgi build folder and the add-on folder at the front of sys.path."""
    args = script_args()
    build = args[0] if len(args) > 0 else os.environ.get(
        "SHGI_BUILD_PYTHON", str(REPO_ROOT / "build" / "python"))
    addon = args[1] if len(args) > 1 else os.environ.get(
        "SHGI_ADDON_DIR", str(REPO_ROOT / "addon"))
    for path in (addon, build):
        sys.path.insert(0, path)


def enable_addon():
    """Enables the add-on (a factory reset disables every add-on the factory set lacks)."""
    if ADDON not in bpy.context.preferences.addons:
        if addon_utils.enable(ADDON, default_set=True, handle_error=None) is None:
            raise AssertionError("the shgi_blender add-on did not enable")


def clear_scene():
    """Removes every object of the factory scene (keeps its world and render settings)."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)


def check_close(what, actual, expected, tolerance):
    """Raises AssertionError naming `what` and both values when they differ by more."""
    actual_values = list(actual) if hasattr(actual, "__len__") else [actual]
    expected_values = list(expected) if hasattr(expected, "__len__") else [expected]
    if len(actual_values) != len(expected_values) or any(
            abs(float(a) - float(e)) > tolerance for a, e in zip(actual_values, expected_values)):
        raise AssertionError(f"{what}: {actual} != expected {expected} (tolerance {tolerance})")
