"""pytest setup: import shgi from the build tree (make test sets PYTHONPATH=build/python)."""

import os
import pathlib
import sys

import pytest

REPO_ROOT = pathlib.Path(__file__).resolve().parents[2]
BUILD_PYTHON = pathlib.Path(os.environ.get("SHGI_BUILD_PYTHON", REPO_ROOT / "build" / "python"))

if str(BUILD_PYTHON) not in sys.path and (BUILD_PYTHON / "shgi").is_dir():
    sys.path.insert(0, str(BUILD_PYTHON))


@pytest.fixture(scope="session")
def build_python_dir():
    """The folder holding the freshly built shgi package."""
    return BUILD_PYTHON
