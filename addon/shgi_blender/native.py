"""The native module ``shgi``, imported once, with an error message an artist can act on.

The add-on registers even when ``import shgi`` fails (not installed for Blender's Python, a
numpy ABI mismatch, a missing shared library): the render engine then refuses to render with
``error()`` and the render panel shows the same text. Nothing here imports bpy.
"""

import importlib
import sys

_state = {"module": None, "error": None, "tried": False}


def module():
    """The ``shgi`` module, or None when it cannot be imported (see error())."""
    if not _state["tried"]:
        _state["tried"] = True
        try:
            _state["module"] = importlib.import_module("shgi")
        except Exception as error:  # an ImportError, or a native module failing to load
            _state["error"] = f"{type(error).__name__}: {error}"
    return _state["module"]


def error():
    """Why ``import shgi`` failed, with the fix; None when it worked."""
    if module() is not None:
        return None
    python = f"{sys.version_info.major}.{sys.version_info.minor}"
    return (f"The SHGI native module cannot be imported into Blender's Python {python} "
            f"({_state['error']}). Fix: run `make install` in the SHGI repository (it installs "
            f"`shgi` where Blender's Python finds it, e.g. /usr/local/lib/python{python}/"
            f"dist-packages for Debian's Blender), then restart Blender.")


def available():
    """True when ``shgi`` imports."""
    return module() is not None
