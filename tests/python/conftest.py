"""pytest setup: import shgi from the build tree (make test sets PYTHONPATH=build/python), the
bpy-free modules of tests/blender (latency_clock, recording_layout) that tests share with the
Blender scripts, the `blender` fixture (each Blender of blender_support.BLENDERS in turn) and, after the run, a
summary of the Blender tests per Blender version."""

import collections
import os
import re
import pathlib
import signal
import sys

import pytest

from blender_support import BLENDER_SCRIPTS, BLENDERS, REPO_ROOT, blender_params


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

# A run started with SIGINT ignored (a background job of a non-interactive shell, `make test &`)
# would pass that on to every child, and the tests that send a child SIGINT as Ctrl-C would wait
# for a cancel that never comes (engine_cancel.py under the bpy module hung for its whole
# timeout). Python's own handler, as in an interactive run, makes children start with SIGINT's
# default action (exec resets handled signals, not ignored ones).
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.fixture(scope="session")
def build_python_dir():
    """The folder holding the freshly built shgi package."""
    return BUILD_PYTHON


def pytest_configure(config):
    config.addinivalue_line("markers", "blender: runs Blender (the program or the bpy module)")
    config.addinivalue_line("markers", "dist: installs the packages of `make dist`")
    config.addinivalue_line(
        "markers", "farm: starts Dask clusters of worker processes (the second interpreter of "
        "`make test-python` skips it: the same Python code, whose time goes to cluster starts)")
    config.addinivalue_line(
        "markers", "reference: spends its time computing a long path-traced reference (the "
        "second interpreter of `make test-python` skips it: same native code, whose numpy "
        "interface the other tests cover)")


@pytest.fixture(params=blender_params())
def blender(request):
    """A blender_support.Blender: the test runs once per Blender version."""
    return request.param


def pytest_terminal_summary(terminalreporter):
    """Per Blender: how many of its tests passed, failed or were skipped, and the tests whose
    outcome differs between the Blenders (the same tests must pass on each)."""
    names = [b.name for b in BLENDERS]
    outcomes = collections.defaultdict(dict)  # test id without the Blender -> {blender: outcome}
    for outcome in ("passed", "failed", "error", "skipped", "xfailed", "xpassed"):
        for report in terminalreporter.stats.get(outcome, []):
            nodeid = getattr(report, "nodeid", "")
            for name in names:
                pattern = rf"(?<=[\[-]){re.escape(name)}(?=[\]-])"
                if re.search(pattern, nodeid) and report.when in ("call", "setup"):
                    test = re.sub(pattern, "*", nodeid)
                    if outcomes[test].get(name) in (None, "passed"):
                        outcomes[test][name] = outcome
    if not outcomes:
        return
    terminalreporter.section("Blender versions")
    for name in names:
        counts = collections.Counter(o[name] for o in outcomes.values() if name in o)
        terminalreporter.write_line(
            f"{name}: " + ", ".join(f"{counts[k]} {k}" for k in sorted(counts)))
    differing = sorted(test for test, o in outcomes.items()
                       if len(o) == len(names) and len(set(o.values())) > 1)
    for test in differing:
        terminalreporter.write_line(f"  differs: {test} {outcomes[test]}")
