"""Shared by the test_hostile_*.py files: load a file in a child Python with an address-space cap
and a timeout, so that a crash (a signal), a hang or a runaway allocation fails a test instead of
taking pytest (or the machine) down."""

import os
import subprocess
import sys
import textwrap

import pytest

from conftest import BUILD_PYTHON

# Enough for the interpreter, numpy and the module, far below the machine: a load that tries to
# allocate without bound meets MemoryError here, not the OOM killer.
ADDRESS_SPACE_CAP = 4 << 30
# A load of these small files takes milliseconds; a child still running after this is a hang.
TIMEOUT_SECONDS = 30

# What the loaders document: OSError naming the file when it is missing, malformed or
# unsupported; ValueError for a bad argument; MemoryError when an allocation fails under the cap.
DOCUMENTED_ERRORS = (OSError, ValueError, MemoryError)

# Under AddressSanitizer (a build with SHGI_SANITIZE=ON, run with LD_PRELOAD=libasan.so) the
# shadow memory alone maps terabytes of address space, so the cap would fail every allocation;
# there, ASan's allocator bounds what one allocation may take (docs/robustness.md).
UNDER_ASAN = "libasan" in os.environ.get("LD_PRELOAD", "")

CHILD_PRELUDE = f"""
import resource, sys
if not {UNDER_ASAN}:
    resource.setrlimit(resource.RLIMIT_AS, ({ADDRESS_SPACE_CAP}, {ADDRESS_SPACE_CAP}))
sys.path.insert(0, {str(BUILD_PYTHON)!r})
import shgi
"""


def load_in_child(path, loader="load_gltf"):
    """Loads `path` with shgi.<loader> in a capped child; returns its verdict, ("loaded", "")
    or (exception type, message), and what it logged (stderr)."""
    code = CHILD_PRELUDE + textwrap.dedent(f"""
        try:
            shgi.{loader}({str(path)!r})
        except Exception as error:
            print(type(error).__name__ + ": " + str(error))
        else:
            print("loaded")
    """)
    try:
        child = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                               timeout=TIMEOUT_SECONDS)
    except subprocess.TimeoutExpired:
        pytest.fail(f"{loader}({path}) still ran after {TIMEOUT_SECONDS} s (a hang)")
    assert child.returncode == 0, (
        f"{loader}({path}) ended the process with {child.returncode} "
        f"(a negative code is a signal):\n{child.stderr[-2000:]}")
    kind, _, message = child.stdout.strip().rpartition("\n")[2].partition(": ")
    return (kind, message), child.stderr
