"""The add-on's Preferences (Edit > Preferences > Add-ons > SHGI): Documentation and Report a
Bug. The parts that need no bpy (finding the manual, the report's text) are in help.py."""

import platform
import sys

import bpy
from bpy.props import StringProperty

from . import help as shgi_help
from . import native

# The add-on's package: "shgi_blender", or "bl_ext.<repository>.shgi_blender" as an extension.
ADDON_PACKAGE = __package__


def _open_url(operator, path):
    """Opens `path` with the system's handler; reports the path when that is not possible
    (background Blender, no handler)."""
    try:
        bpy.ops.wm.url_open(url=shgi_help.file_url(path))
    except RuntimeError as error:
        operator.report({"WARNING"}, f"SHGI: could not open {path}: {error}")
        return False
    return True


class SHGI_OT_open_documentation(bpy.types.Operator):
    """Open SHGI's manual (README and reference pages) shipped with the add-on"""

    bl_idname = "shgi.open_documentation"
    bl_label = "Documentation"
    bl_options = {"REGISTER"}

    def execute(self, _context):
        path = shgi_help.find_docs()
        if path is None:
            self.report({"WARNING"}, f"SHGI: {shgi_help.DOCS_MISSING}")
            return {"CANCELLED"}
        _open_url(self, path)
        self.report({"INFO"}, f"SHGI: manual at {path} (reference pages in "
                    f"{path.parent / 'docs'})")
        return {"FINISHED"}


def bug_report(context):
    """The bug report's text for the current Blender, scene and session."""
    from . import bl_info
    from .engine import final_render

    shgi = native.module()
    scene = getattr(context, "scene", None)
    props = getattr(scene, "shgi", None) if scene is not None else None
    settings_lines = []
    if scene is not None:
        settings_lines.append(f"scene {scene.name_full!r}, render engine "
                              f"{scene.render.engine}")
    if props is not None:
        settings_lines += shgi_help.property_lines(props, "scene.shgi")
    error = None if shgi is not None else (native.error() or "unknown error")
    return shgi_help.bug_report_text(
        blender_version=bpy.app.version_string,
        os_name=f"{platform.platform()} ({platform.machine()}), Python "
                f"{sys.version.split()[0]}",
        shgi_version=shgi_help.version_text(bl_info),
        module_path=getattr(shgi, "__file__", None),
        import_error=error,
        settings_lines=settings_lines,
        last_render=final_render.last_render())


class SHGI_OT_report_bug(bpy.types.Operator):
    """Write a bug report (Blender, OS, SHGI version, the scene's SHGI settings, the last \
render's errors) into a text file to attach to your report, and open it"""

    bl_idname = "shgi.report_bug"
    bl_label = "Report a Bug"
    bl_options = {"REGISTER"}

    directory: StringProperty(
        name="Folder", subtype="DIR_PATH", options={"SKIP_SAVE"},
        description="Folder to write the report into (empty: a new temporary folder)")

    def execute(self, context):
        try:
            path = shgi_help.write_bug_report(bug_report(context), self.directory or None)
        except OSError as error:
            self.report({"ERROR"}, f"SHGI: the bug report could not be written: {error}")
            return {"CANCELLED"}
        if not bpy.app.background:
            _open_url(self, path)
        self.report({"INFO"}, f"SHGI: bug report written to {path}: attach it to your report")
        return {"FINISHED"}


class SHGI_AddonPreferences(bpy.types.AddonPreferences):
    bl_idname = ADDON_PACKAGE

    def draw(self, _context):
        layout = self.layout
        row = layout.row()
        row.operator("shgi.open_documentation", icon="HELP")
        row.operator("shgi.report_bug", icon="URL")
        if shgi_help.find_docs() is None:
            layout.label(text="The manual is not bundled with this copy of the add-on",
                         icon="INFO")


CLASSES = (SHGI_OT_open_documentation, SHGI_OT_report_bug, SHGI_AddonPreferences)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
