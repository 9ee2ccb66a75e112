"""The add-on enables, disables and enables again in Blender (register/unregister twice).

Prints ADDON_REGISTER_OK when every check passed.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()

import addon_utils  # noqa: E402
import bpy  # noqa: E402

MODULE = "shgi_blender"


def enabled():
    return MODULE in bpy.context.preferences.addons


def main():
    for attempt in range(2):
        module = addon_utils.enable(MODULE, default_set=True, handle_error=None)
        if module is None or not enabled():
            raise AssertionError(f"enable #{attempt + 1} failed")
        if module.bl_info["name"] != "SHGI" or tuple(module.bl_info["blender"]) > (3, 4, 1):
            raise AssertionError(f"bl_info: {module.bl_info}")
        addon_utils.disable(MODULE, default_set=True, handle_error=None)
        if enabled():
            raise AssertionError(f"disable #{attempt + 1} left the add-on enabled")
    import shgi_blender.export
    if not callable(shgi_blender.export.export_scene):
        raise AssertionError("shgi_blender.export.export_scene is missing")
    print("ADDON_REGISTER_OK")


main()
