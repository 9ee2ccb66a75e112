"""The add-on's Preferences in a real window: Documentation and Report a Bug, clicked there.

Runs Blender with a window under Xvfb (Debian's Blender program; the bpy module has none):

    BROWSER=<recorder> BLENDER_USER_SCRIPTS=<scripts> xvfb-run -a blender --factory-startup \
        --window-geometry 0 0 <W> <H> --python tests/blender/preferences_window.py -- \
        <build python dir> <addon dir> <results json> <report folder>

<scripts>/addons/shgi_blender is the add-on (a link to it), installed where an artist's is, so
that the Preferences list it (an add-on imported from sys.path only is listed as missing and
its preferences are not drawn). Blender opens URLs with Python's webbrowser, which runs the
program $BROWSER names: the test's recorder writes each URL it is given into a log instead of
opening anything. The steps run from a timer on Blender's main thread while the window draws:
1. opens the Preferences window (Edit > Preferences) at Add-ons, the SHGI entry expanded, and
   redraws it, counting the calls of the add-on's AddonPreferences.draw;
2. runs shgi.open_documentation and shgi.report_bug (into <report folder>) with the Preferences
   window, area and region as their context, as a click on each button does (INVOKE_DEFAULT).
Records how often the Preferences drew, each operator's result and the report file's first line;
tests/python/test_addon_help.py asserts them with the URLs the recorder logged. Prints
PREFERENCES_WINDOW_OK; a failed step writes its error and exits with 1.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()

import addon_utils  # noqa: E402
import bpy  # noqa: E402

STEP_SECONDS = 0.5
RESULTS_PATH = setup.results_path("preferences_window.json")
REPORT_FOLDER = setup.script_args()[3]
RESULTS = {}
DRAWS = {"count": 0}


def count_preference_draws():
    """Counts the calls of the add-on's AddonPreferences.draw (Blender looks it up per draw)."""
    from shgi_blender import preferences

    draw = preferences.SHGI_AddonPreferences.draw

    def counted(self, context):
        DRAWS["count"] += 1
        return draw(self, context)

    preferences.SHGI_AddonPreferences.draw = counted


def preferences_area():
    """(window, area, region) of the Preferences window, or None while it is not open."""
    for window in bpy.context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == "PREFERENCES":
                region = next(r for r in area.regions if r.type == "WINDOW")
                return window, area, region
    return None


def in_preferences(operator, *args, **kwargs):
    """Runs bpy.ops `operator` with the Preferences window, area and region as its context."""
    window, area, region = preferences_area()
    with bpy.context.temp_override(window=window, area=area, region=region):
        return sorted(operator(*args, **kwargs))


def steps():
    setup.enable_addon()
    main_window = bpy.context.window_manager.windows[0]
    with bpy.context.temp_override(window=main_window):
        bpy.ops.screen.userpref_show()
    yield STEP_SECONDS
    if preferences_area() is None:
        raise AssertionError("Edit > Preferences opened no Preferences window")
    bpy.context.preferences.active_section = "ADDONS"
    bpy.context.window_manager.addon_search = "SHGI"
    listed = next(module for module in addon_utils.modules() if module.__name__ == setup.ADDON)
    addon_utils.module_bl_info(listed)["show_expanded"] = True
    count_preference_draws()
    in_preferences(bpy.ops.wm.redraw_timer, type="DRAW_WIN_SWAP", iterations=2)
    yield STEP_SECONDS
    RESULTS["preferences_section"] = bpy.context.preferences.active_section
    RESULTS["preferences_draws"] = DRAWS["count"]
    RESULTS["documentation"] = in_preferences(bpy.ops.shgi.open_documentation, "INVOKE_DEFAULT")
    RESULTS["report_bug"] = in_preferences(bpy.ops.shgi.report_bug, "INVOKE_DEFAULT",
                                           directory=REPORT_FOLDER)
    yield STEP_SECONDS
    from shgi_blender import help as shgi_help

    report = os.path.join(REPORT_FOLDER, shgi_help.REPORT_NAME)
    with open(report, encoding="utf-8") as handle:
        RESULTS["report_first_line"] = handle.readline().strip()
    RESULTS["report_path"] = report
    RESULTS["manual_path"] = str(shgi_help.find_docs())


# The factory settings open the splash (Quick Setup) over the 3D view after this script runs.
bpy.context.preferences.view.show_splash = False
setup.run_steps_in_window(steps(), RESULTS, RESULTS_PATH, "PREFERENCES_WINDOW_OK",
                          echo_results=True)
