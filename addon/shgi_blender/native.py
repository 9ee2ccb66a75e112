"""The native module ``shgi``, imported once, with an error message an artist can act on.

Where ``shgi`` comes from: the add-on zip of ``make dist`` (Blender 3.4 to 4.1) carries it in
shgi_blender/vendor/, which goes first on sys.path; the 4.2+ extension lists it as a wheel that
Blender installs; a development setup installs it with ``make install``.

The add-on registers even when ``import shgi`` fails (not installed for Blender's Python, a
numpy ABI mismatch, a missing shared library): the render engine then refuses to render with
``error()`` and the render panel shows the same text. Nothing here imports bpy.
"""

import importlib
import importlib.util
import os
import sys

VENDOR_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "vendor")

_state = {"module": None, "error": None, "tried": False}


def module():
    """The ``shgi`` module, or None when it cannot be imported (see error())."""
    if not _state["tried"]:
        _state["tried"] = True
        if os.path.isdir(VENDOR_DIR) and VENDOR_DIR not in sys.path:
            sys.path.insert(0, VENDOR_DIR)
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
            f"({_state['error']}). Fix: install the SHGI add-on zip or extension built by "
            f"`make dist` (it carries the module), or run `make install` in the SHGI "
            f"repository (it installs `shgi` where Blender's Python finds it, e.g. "
            f"/usr/local/lib/python{python}/dist-packages for Debian's Blender), then restart "
            f"Blender.")


def available():
    """True when ``shgi`` imports."""
    return module() is not None


def denoiser_error():
    """Why renders cannot be denoised (the optional module pyoidn is missing), with the fix; None
    when they can. Looked up without importing pyoidn."""
    if importlib.util.find_spec("pyoidn") is not None:
        return None
    command = f"{sys.executable} -m pip install pyoidn"
    if module() is not None:  # the command for this Python, as shgi's own messages give it
        from shgi.denoise import pip_command

        command = pip_command("pyoidn")
    return (f"Denoising needs OpenImageDenoise, the Python module pyoidn, which {sys.executable} "
            f"cannot import: renders are shown without denoising. Fix: `{command}` (or `make "
            "deps` in the SHGI repository), then restart Blender.")
