"""pytest setup: import shgi from the build tree (make test sets PYTHONPATH=build/python), and
the bpy-free modules of tests/blender (image_metrics) that tests share with the Blender scripts."""

import os
import pathlib
import sys

import pytest

from blender_support import BLENDER_SCRIPTS, REPO_ROOT


def _build_python_dir():
    """SHGI_BUILD_PYTHON, else the first PYTHONPATH entry holding shgi, else build/python."""
    if "SHGI_BUILD_PYTHON" in os.environ:
        return pathlib.Path(os.environ["SHGI_BUILD_PYTHON"])
    for entry in filter(None, os.environ.get("PYTHONPATH", "").split(os.pathsep)):
        if (pathlib.Path(entry) / "shgi").is_dir():
            return pathlib.Path(entry)
    return REPO_ROOT / "build" / "python"


BUILD_PYTHON = _build_python_dir()
if (BUILD_PYTHON / "shgi").is_dir():
    sys.path.insert(0, str(BUILD_PYTHON))
sys.path.append(str(BLENDER_SCRIPTS))


@pytest.fixture(scope="session")
def build_python_dir():
    """The folder holding the freshly built shgi package."""
    return BUILD_PYTHON
