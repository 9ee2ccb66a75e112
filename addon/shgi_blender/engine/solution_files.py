"""Frozen solutions against the scene and the .blend file (bpy side, Blender's main thread).

* Edits: a depsgraph_update_post handler counts each scene's edits that change its light
  (solution_cache.edit_description: a moved light or object, a changed mesh, light, material
  or world; not the camera or render settings), so that F12 and the panel can say that a frozen
  solution no longer shows the scene.
* Saving: after the .blend is written (save_post: Blender 3.4 tells its save_pre handlers no
  path, and a first save has none before), each scene's Probe Grid, Photon Lattice or Light
  Propagation solution is written beside it, to ``<file>_shgi/<scene>.json`` and the field's
  files next to it
  (solution_cache.save_solution); the file of a scene without one is removed, so that an older
  solution does not come back.
* Loading: after a file opens (load_post), each scene's solution file beside it is read back
  (a probe field with the scene's probe lookup settings); a file that cannot be read is named
  in the panel
  (``load_problem``).
"""

import logging
import os

import bpy

from .. import native, settings
from . import solution_cache

logger = logging.getLogger("shgi_blender.engine")
SIDECAR_SUFFIX = "_shgi"

_load_problems = {}


def load_problem(key):
    """Why scene `key`'s saved solution was not read when its file opened, or None."""
    return _load_problems.get(key)


def _describe(update):
    data = update.id
    is_camera = getattr(data, "type", None) == "CAMERA" or isinstance(data, bpy.types.Camera)
    return solution_cache.edit_description(type(data).__name__, data.name, is_camera,
                                           update.is_updated_transform,
                                           update.is_updated_geometry,
                                           update.is_updated_shading)


@bpy.app.handlers.persistent
def note_edits(scene, depsgraph):
    """depsgraph_update_post: counts the updates that change the scene's light."""
    key = scene.name_full
    for update in depsgraph.updates:
        what = _describe(update)
        if what is not None:
            solution_cache.note_edit(key, what)


def solution_path(blend_path, scene):
    """Where the solution of `scene` is saved for the .blend at blend_path."""
    stem = os.path.splitext(blend_path)[0]
    return os.path.join(stem + SIDECAR_SUFFIX, bpy.path.clean_name(scene.name) + ".json")


def _blend_path(file_path):
    """The .blend a save or load handler is about: its argument (Blender 4+), else the open
    file's path."""
    return file_path if isinstance(file_path, str) and file_path else bpy.data.filepath


@bpy.app.handlers.persistent
def save_solutions(file_path=None, *_args):
    """save_post: writes each scene's frozen solution beside the saved .blend."""
    blend_path = _blend_path(file_path)
    if not blend_path:
        return
    for scene in bpy.data.scenes:
        solution = solution_cache.get(scene.name_full)
        path = solution_path(blend_path, scene)
        try:
            if solution is not None and solution.method in solution_cache.FIELD_FILES:
                os.makedirs(os.path.dirname(path), exist_ok=True)
                solution_cache.save_solution(solution, path)
            elif os.path.exists(path):
                os.remove(path)
        except (OSError, ValueError) as error:
            logger.warning("SHGI: the frozen solution of scene %r was not saved to %s: %s",
                           scene.name, path, error)


@bpy.app.handlers.persistent
def load_solutions(file_path=None, *_args):
    """load_post: reads each scene's solution saved beside the opened .blend."""
    _load_problems.clear()
    shgi = native.module()
    blend_path = _blend_path(file_path)
    if shgi is None or not blend_path:
        return
    for scene in bpy.data.scenes:
        path = solution_path(blend_path, scene)
        if not os.path.exists(path):
            continue
        try:
            solution = solution_cache.load_solution(
                shgi, path, settings.probe_lookup_settings(scene.shgi, shgi))
        except (OSError, ValueError, KeyError) as error:
            _load_problems[scene.name_full] = (
                f"The solution saved in {path} was not read ({error}): Solve again")
            continue
        solution_cache.store(scene.name_full, solution)


HANDLERS = (("depsgraph_update_post", note_edits), ("save_post", save_solutions),
            ("load_post", load_solutions))


def register():
    for name, handler in HANDLERS:
        getattr(bpy.app.handlers, name).append(handler)


def unregister():
    for name, handler in HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if handler in handlers:
            handlers.remove(handler)
