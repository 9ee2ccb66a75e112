"""Brings the SHGI settings of an opened .blend up to date (bpy; Cycles' versioning.py is the
model): a load_post handler applies settings_upgrade.upgrade to every scene saved with an earlier
layout of ``scene.shgi``, once, and save_pre stamps each scene with the layout it is saved in.

A scene that stored no SHGI settings (every one at its default) is left alone: it takes today's
defaults. Stored enum
values are their numbers; they are set by identifier through RNA, so the properties' ranges and
items apply as to any other value.
"""

import logging

import bpy

from . import settings_upgrade

logger = logging.getLogger("shgi_blender.versioning")


def _stored(group):
    """The ID properties stored on a property group, as a dict (nested groups as dicts)."""
    return {key: (value.to_dict() if hasattr(value, "to_dict") else value)
            for key, value in group.items()}


def _set(group, name, value):
    """Sets a stored value through RNA (an enum's number becomes its identifier)."""
    prop = group.bl_rna.properties[name]
    if prop.type == "ENUM" and isinstance(value, int):
        value = next(item.identifier for item in prop.enum_items if item.value == value)
    setattr(group, name, value)


def upgrade_scene(scene):
    """Applies the settings upgrade to one scene; returns its notes (empty: nothing lost)."""
    # A scene linked from a library cannot be edited here: its own file is upgraded when opened.
    if scene.library is not None:
        return []
    props = scene.shgi
    if not props.keys():  # nothing stored: today's defaults are all it has
        return []
    upgrade = settings_upgrade.upgrade(_stored(props))
    for (group, name), value in upgrade.values.items():
        _set(getattr(props, group) if group else props, name, value)
    for group, name in upgrade.removed:
        del (getattr(props, group) if group else props)[name]
    if props.get("settings_version") != settings_upgrade.SETTINGS_VERSION:
        props.settings_version = settings_upgrade.SETTINGS_VERSION
    return upgrade.notes


@bpy.app.handlers.persistent
def upgrade_settings(*_args):
    """load_post: every scene's settings in today's layout, with the values it was saved with."""
    for scene in bpy.data.scenes:
        for note in upgrade_scene(scene):
            logger.warning("SHGI: scene %r: %s", scene.name, note)


@bpy.app.handlers.persistent
def stamp_settings(*_args):
    """save_pre: records the layout each scene's settings are saved in."""
    for scene in bpy.data.scenes:
        if scene.library is not None:
            continue
        # Stored even when it equals the default, which reads the same whether stored or not.
        if scene.shgi.get("settings_version") != settings_upgrade.SETTINGS_VERSION:
            scene.shgi.settings_version = settings_upgrade.SETTINGS_VERSION


# upgrade_settings runs before the other load_post handlers (solution_files reads settings).
HANDLERS = (("load_post", upgrade_settings), ("save_pre", stamp_settings))


def register():
    for name, handler in HANDLERS:
        getattr(bpy.app.handlers, name).insert(0, handler)


def unregister():
    for name, handler in HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if handler in handlers:
            handlers.remove(handler)
