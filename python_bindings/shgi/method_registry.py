"""The GI methods every front end offers: one registry, read by shgi.bake, ``python -m shgi`` and
the Blender add-on alike.

A method is a row (:class:`Method`): its identifier (one name everywhere: render method and bake
source), label and description for menus, the number .blend files store for it, older names
still accepted, its settings class, how many refinement passes a final solve runs, and how to
build its solver (a :class:`shgi.GiSolver`). The native methods come from the C++ registry
(``native/methods/method_registry.cpp``); methods prototyped in Python join them with
:func:`register_method`, from a script or from a plugin module named in the environment variable
``SHGI_METHOD_PLUGINS`` (comma-separated module names, imported the first time the registry is
read), so that a new method reaches the CLI and the add-on with no other edit.

    solver = shgi.make_solver("PROBE_GRID", scene, shgi.ProbeGridSettings(seed=1))
    for _ in range(shgi.method("PROBE_GRID").final_passes):
        solver.refine()
    image = shgi.render_preview(scene, solver.current_field())
"""

import dataclasses
import enum
import importlib
import os
import threading
from typing import Callable, Optional, Sequence, Tuple

import numpy as np

from . import _shgi

__all__ = ["Method", "methods", "method", "register_method", "unregister_method",
           "make_solver", "default_settings", "solve", "settings_to_dict", "settings_from_dict",
           "PLUGINS_VARIABLE"]

PLUGINS_VARIABLE = "SHGI_METHOD_PLUGINS"


@dataclasses.dataclass(frozen=True)
class Method:
    """A GI method: a row of the registry."""

    identifier: str
    label: str
    description: str
    number: int                   # the enum value .blend files store; never reused
    settings_type: type           # its settings class (shgi.PathTracerSettings for PATH_TRACE)
    final_passes: int             # refinement passes of a final solve (F12, bake, CLI)
    aliases: Tuple[str, ...] = ()  # older names still accepted
    # make(scene, settings, progress) -> GiSolver; None for a method that solves no field.
    make: Optional[Callable] = None

    @property
    def solves_field(self) -> bool:
        """False for the path tracer, which renders and bakes by path tracing."""
        return self.make is not None


_lock = threading.Lock()
_python_rows = []
_plugins_loaded = False


def _native_row(row) -> Method:
    make = None
    if row.solves_field:
        identifier = row.identifier

        def make(scene, settings, progress=None):
            return _shgi.make_native_solver(identifier, scene, settings, progress)

    return Method(row.identifier, row.label, row.description, row.number,
                  getattr(_shgi, row.settings_type), int(row.final_passes), tuple(row.aliases),
                  make)


def _load_plugins() -> None:
    global _plugins_loaded
    if _plugins_loaded:
        return
    _plugins_loaded = True
    for name in filter(None, (part.strip() for part in
                              os.environ.get(PLUGINS_VARIABLE, "").split(","))):
        try:
            importlib.import_module(name)
        except Exception as error:
            raise ImportError(f"{PLUGINS_VARIABLE} names the module {name!r}, which failed to "
                              f"import ({type(error).__name__}: {error}); fix the module or "
                              f"remove it from {PLUGINS_VARIABLE}") from error


def methods() -> Tuple[Method, ...]:
    """Every method, in menu order: the native ones, then those registered from Python."""
    _load_plugins()
    with _lock:
        python_rows = tuple(_python_rows)
    return tuple(_native_row(row) for row in _shgi.native_methods()) + python_rows


def method(name: str) -> Method:
    """The method named by an identifier or an older alias; ValueError listing the choices."""
    rows = methods()
    for row in rows:
        if name == row.identifier or name in row.aliases:
            return row
    raise ValueError(f"method {name!r} is not known; use one of "
                     f"{', '.join(row.identifier for row in rows)}")


def register_method(identifier: str, label: str, description: str, number: int,
                    settings_type: type, make: Optional[Callable], final_passes: int = 1,
                    aliases: Sequence[str] = ()) -> Method:
    """Adds a method prototyped in Python; make(scene, settings, progress) returns a
    shgi.GiSolver (a Python subclass, or a native solver it builds). ValueError when the
    identifier, an alias or the number is taken or reserved for another method."""
    row = Method(identifier, label, description, int(number), settings_type, int(final_passes),
                 tuple(aliases), make)
    if not (identifier and label and isinstance(settings_type, type)):
        raise ValueError(f"method {identifier!r}: identifier, label and a settings class are "
                         "needed")
    if row.number < 0 or row.final_passes < 0:
        raise ValueError(f"method {identifier!r}: number {number} and final_passes "
                         f"{final_passes} must be >= 0")
    names = {identifier, *row.aliases}
    reserved = dict(_shgi.reserved_method_numbers())
    with _lock:
        for other in tuple(_native_row(r) for r in _shgi.native_methods()) + tuple(_python_rows):
            taken = names & {other.identifier, *other.aliases}
            if taken or other.number == row.number:
                what = f"the name {sorted(taken)[0]!r}" if taken else f"number {number}"
                raise ValueError(f"method {identifier!r}: {what} is taken by method "
                                 f"{other.identifier!r}")
        for other, other_number in reserved.items():
            if other_number == row.number and other != identifier:
                raise ValueError(f"method {identifier!r}: number {number} is reserved for "
                                 f"method {other!r}")
        _python_rows.append(row)
    return row


def unregister_method(identifier: str) -> bool:
    """Removes a method registered from Python; False when there was none by that name."""
    with _lock:
        for i, row in enumerate(_python_rows):
            if row.identifier == identifier:
                del _python_rows[i]
                return True
    return False


def default_settings(name: str, seed: Optional[int] = None):
    """The method's settings with their defaults (and `seed`, when given)."""
    settings = method(name).settings_type()
    if seed is not None:
        settings.seed = seed
    return settings


def make_solver(name: str, scene, settings=None, progress=None):
    """The solver of method `name` on a committed scene (settings None: the defaults).
    ValueError for the path tracer, which solves no field."""
    row = method(name)
    if not row.solves_field:
        raise ValueError(f"method {row.identifier!r} solves no field: render with "
                         "shgi.render_path_traced and bake with shgi.bake_lightmap")
    if settings is not None and not isinstance(settings, row.settings_type):
        raise TypeError(f"settings of method {row.identifier} must be "
                        f"{row.settings_type.__name__}, got {type(settings).__name__}")
    return row.make(scene, settings, progress)


def solve(name: str, scene, settings=None, passes: Optional[int] = None, progress=None):
    """make_solver, then `passes` refinement passes (None: the method's final_passes)."""
    row = method(name)
    solver = make_solver(row.identifier, scene, settings, progress)
    for _ in range(row.final_passes if passes is None else passes):
        solver.refine(progress)
    return solver


def _fields(settings_type: type) -> list:
    """The field names of a settings class: its data properties (native structs) or, for a
    Python dataclass, its dataclass fields."""
    if dataclasses.is_dataclass(settings_type):
        return [field.name for field in dataclasses.fields(settings_type)]
    return sorted(name for name in dir(settings_type)
                  if isinstance(getattr(settings_type, name), property)
                  and getattr(settings_type, name).fset is not None)


def _plain(value):
    """A field's value as JSON-ready data: enums by member name, vectors and matrices as lists,
    nested structs (ProbeVolume) as dicts."""
    if isinstance(value, (bool, int, float, str)) or value is None:
        return value
    if hasattr(value, "__members__") or isinstance(value, enum.Enum):
        return value.name
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(item) for item in value]
    return {"type": type(value).__name__,
            **{name: _plain(getattr(value, name)) for name in _fields(type(value))}}


def settings_to_dict(settings) -> dict:
    """Every field of a settings struct as JSON-ready data (``python -m shgi bake --settings``
    reads it back with settings_from_dict)."""
    return {name: _plain(getattr(settings, name)) for name in _fields(type(settings))}


def _typed(value, like):
    """`value` (from settings_to_dict) as the type of the default `like`."""
    if hasattr(type(like), "__members__"):
        members = type(like).__members__
        if value not in members:
            raise ValueError(f"{value!r} is not one of {', '.join(members)}")
        return members[value]
    if isinstance(value, dict):
        nested = getattr(_shgi, value.get("type", ""), None)
        if nested is None:
            raise ValueError(f"unknown struct type {value.get('type')!r}")
        return settings_from_dict(nested, {k: v for k, v in value.items() if k != "type"})
    if isinstance(value, list):
        if isinstance(like, np.ndarray):
            return np.asarray(value, like.dtype)
        if isinstance(like, list):
            return [_typed(item, None) for item in value]
        return tuple(value)
    return value


def settings_from_dict(settings_type: type, values: dict):
    """A settings struct from settings_to_dict's data; ValueError naming an unknown field or a
    bad value."""
    known = _fields(settings_type)
    unknown = sorted(set(values) - set(known))
    if unknown:
        raise ValueError(f"{settings_type.__name__} has no field {', '.join(unknown)}; its fields "
                         f"are {', '.join(known)}")
    settings = settings_type()
    for name, value in values.items():
        try:
            setattr(settings, name, _typed(value, getattr(settings, name)))
        except (TypeError, ValueError) as error:
            raise ValueError(f"{settings_type.__name__}.{name}: {error}") from error
    return settings
