"""Shared start of the Blender test scripts: paths to shgi and the add-on, and a scene reset.

Scripts run as ``blender -b --factory-startup --python-exit-code 1 --python <script> --
<build python dir> <addon dir>``; the two folders may also come from the environment variables
SHGI_BUILD_PYTHON and SHGI_ADDON_DIR. A failed check raises, which makes Blender exit with 1.
"""

import os
import pathlib
import sys

import bpy

REPO_ROOT = pathlib.Path(__file__).resolve().parents[2]


def add_import_paths():
    """Puts the shgi build folder and the add-on folder at the front of sys.path."""
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    build = args[0] if len(args) > 0 else os.environ.get(
        "SHGI_BUILD_PYTHON", str(REPO_ROOT / "build" / "python"))
    addon = args[1] if len(args) > 1 else os.environ.get(
        "SHGI_ADDON_DIR", str(REPO_ROOT / "addon"))
    for path in (addon, build):
        sys.path.insert(0, path)


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
