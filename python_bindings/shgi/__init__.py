"""SHGI: spherical-harmonics global illumination for Blender and Python.

The native core (``shgi._shgi``, C++ on Embree, TBB and OpenEXR) is re-exported here:

* scenes from numpy arrays or files: :class:`Scene`, :class:`Mesh`, :class:`Material`,
  :class:`Light`, :class:`World`, :class:`Camera`, :func:`load_gltf`, :func:`load_obj`;
* spherical harmonics in :mod:`shgi.sh` (real, orthonormal, no Condon-Shortley phase);
* images: :func:`read_exr`, :func:`write_exr`, :func:`write_png`;
* long calls take a :class:`Progress` and raise :class:`Cancelled` when it is cancelled.

Conventions (Blender's): right-handed, Z up, metres, linear Rec.709 colour, Cycles' light units.
Bad input raises ``ValueError`` naming the argument; file problems raise ``OSError``.
"""

import logging as _logging
import sys as _sys

from . import _shgi
from ._shgi import *  # noqa: F401,F403  (the native API is the package's API)
from ._shgi import sh

__version__ = _shgi.version()
Cancelled.__module__ = __name__  # noqa: F405  (shown as shgi.Cancelled)

# `import shgi.sh` and `from shgi.sh import eval` work like any submodule.
_sys.modules[__name__ + ".sh"] = sh

_logger = _logging.getLogger("shgi")
_PY_LEVELS = {
    _shgi.LogLevel.DEBUG: _logging.DEBUG,
    _shgi.LogLevel.INFO: _logging.INFO,
    _shgi.LogLevel.WARNING: _logging.WARNING,
    _shgi.LogLevel.ERROR: _logging.ERROR,
}


def _forward_to_logging(level, message):
    _logger.log(_PY_LEVELS.get(level, _logging.WARNING), message)


_shgi.set_log_sink(_forward_to_logging)

# The GI methods: one registry for every front end (shgi.method_registry).
from .method_registry import (  # noqa: E402,F401
    Method,
    default_settings,
    make_solver,
    method,
    methods,
    register_method,
    settings_from_dict,
    settings_to_dict,
    unregister_method,
)

# A Scene and the settings structs pickle (shgi.pickling): a farm's workers get the scene itself.
from . import pickling as _pickling  # noqa: E402

_pickling.register_structs()
