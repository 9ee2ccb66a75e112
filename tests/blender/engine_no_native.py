"""Without the native module the add-on still registers, explains the fix, and F12 fails cleanly.

``import shgi`` is made to fail (sys.modules["shgi"] = None, as when it is not installed for
Blender's Python). Checks: the add-on enables; the render panel draws the import error and the
fix (drawn into a recording layout); F12 with the SHGI engine raises RuntimeError carrying the
same message (the engine's ERROR report) instead of crashing; Preferences' bug report says
that shgi did not import, and why; the add-on disables cleanly.
Prints ENGINE_NO_NATIVE_OK.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()
sys.modules["shgi"] = None  # any `import shgi` now raises ImportError

import addon_utils  # noqa: E402
import bpy  # noqa: E402
from recording_layout import draw_panel  # noqa: E402

MODULE = "shgi_blender"
FIX = "make install"


def main():
    if addon_utils.enable(MODULE, default_set=True, handle_error=None) is None:
        raise AssertionError("the add-on did not enable without the native module")
    from shgi_blender import native

    if native.available() or FIX not in native.error():
        raise AssertionError(f"native.error() does not give the fix: {native.error()}")
    scene = bpy.context.scene
    scene.render.engine = "SHGI"
    scene.render.resolution_x = scene.render.resolution_y = 16
    text = draw_panel("SHGI_RENDER_PT_method")
    if "cannot be imported" not in text or FIX not in text:
        raise AssertionError(f"the render panel does not show the error and the fix: {text!r}")
    try:
        bpy.ops.render.render(write_still=False)
    except RuntimeError as error:
        if FIX not in str(error):
            raise AssertionError(f"F12 failed without the fix: {error}") from None
    else:
        raise AssertionError("F12 without the native module reported no error")
    from shgi_blender import preferences

    report = preferences.bug_report(bpy.context)
    if "Native module shgi: NOT imported" not in report or FIX not in report:
        raise AssertionError(f"the bug report does not say shgi failed to import: {report}")
    addon_utils.disable(MODULE, default_set=True, handle_error=None)
    if MODULE in bpy.context.preferences.addons:
        raise AssertionError("the add-on did not disable")
    print("ENGINE_NO_NATIVE_OK")


main()
