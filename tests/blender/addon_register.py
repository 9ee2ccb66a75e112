"""The add-on enables, disables and enables again in Blender (register/unregister three times).

While enabled: the SHGI render engine, scene.shgi with the implemented methods only, the
operators, SHGI in the stock light/material/world panels, presets that set the counts, and
every SHGI panel draws (into recording_layout.RecordingLayout, which checks property and
operator names), and the add-on's Preferences show Documentation and Report a Bug, which work
headless (the report is written; the manual is found in this checkout). After each disable:
none of it is left behind (and stock panels lose SHGI).

Prints ADDON_REGISTER_OK when every check passed.
"""

import os
import sys
from types import SimpleNamespace

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()

import addon_utils  # noqa: E402
import bpy  # noqa: E402
from recording_layout import draw_panel, draw_panel_operators, draw_panel_props  # noqa: E402

MODULE = "shgi_blender"
ENGINE = "SHGI"
METHODS = {"PATH_TRACE", "PHOTON_LATTICE", "PROBE_GRID", "RADIANCE_FIELD", "PROPAGATION",
           "INSTANT_GI"}
STOCK_PANELS = ("EEVEE_MATERIAL_PT_surface", "EEVEE_WORLD_PT_surface", "RENDER_PT_format",
                "RENDER_PT_color_management", "DATA_PT_context_light")
OWN_CLASSES = ("SHGI_RENDER_PT_method", "SHGI_RENDER_PT_photon_lattice",
               "SHGI_RENDER_PT_probe_grid", "SHGI_RENDER_PT_probe_grid_visibility",
               "SHGI_RENDER_PT_radiance_field", "SHGI_RENDER_PT_propagation",
               "SHGI_RENDER_PT_instant_gi",
               "SHGI_LIGHT_PT_light", "SHGI_VIEWLAYER_PT_passes", "SHGI_OT_solve",
               "SHGI_OT_clear_solution", "SHGI_OT_quality_preset", "SHGI_OT_load_solution",
               "SHGI_RENDER_PT_light_paths_max_bounces", "SHGI_RENDER_PT_bake_farm",
               "SHGI_OT_open_documentation", "SHGI_OT_report_bug")
# The buttons of the add-on's Preferences (preferences.py).
PREFERENCES_BUTTONS = {("shgi.open_documentation", "Documentation"),
                       ("shgi.report_bug", "Report a Bug")}
# scene.shgi.probe_grid mirrors ProbeGridSettings: its Visibility panel shows EEVEE's names.
VISIBILITY_PROPERTIES = {"normal_bias": "Bias", "bleed_bias": "Bleed Bias",
                         "visibility_blur": "Blur"}


def enabled():
    return MODULE in bpy.context.preferences.addons


def engine_registered():
    return bpy.types.RenderEngine.bl_rna_get_subclass_py(ENGINE) is not None


def check_registered():
    if not engine_registered():
        raise AssertionError("the SHGI render engine is not registered")
    scene = bpy.context.scene
    scene.render.engine = ENGINE
    methods = {item.identifier for item in
               scene.shgi.bl_rna.properties["method"].enum_items}
    if methods != METHODS:
        raise AssertionError(f"scene.shgi.method offers {methods}, expected {METHODS}")
    for panel in STOCK_PANELS:
        if ENGINE not in getattr(bpy.types, panel).COMPAT_ENGINES:
            raise AssertionError(f"{panel} does not show under SHGI")
    for name in OWN_CLASSES:
        if not hasattr(bpy.types, name):
            raise AssertionError(f"{name} is not registered")
    bpy.ops.shgi.quality_preset(preset="PRODUCTION")
    if (scene.shgi.samples, scene.shgi.photon_lattice.photons) != (1024, 4_000_000):
        raise AssertionError(f"the Production preset set {scene.shgi.samples} samples, "
                             f"{scene.shgi.photon_lattice.photons} photons")
    bpy.ops.shgi.quality_preset(preset="PREVIEW")
    if scene.shgi.samples != 16:
        raise AssertionError(f"the Preview preset set {scene.shgi.samples} samples")
    check_panels_draw(scene)
    check_preferences(scene)
    scene.render.engine = "BLENDER_WORKBENCH"  # every Blender has it (EEVEE's id changed in 4.2)


def check_panels_draw(scene):
    """Every SHGI panel draws for each method; the light panel shows the Portal option."""
    light = bpy.data.lights.new("panel_light", "AREA")
    light_object = bpy.data.objects.new("panel_light", light)
    context = SimpleNamespace(scene=scene, engine=ENGINE, light=light, object=light_object,
                              view_layer=scene.view_layers[0], screen=None)
    for method in sorted(METHODS):
        scene.shgi.method = method
        for name in ("SHGI_RENDER_PT_method", "SHGI_RENDER_PT_light_paths",
                     "SHGI_RENDER_PT_last_render", "SHGI_VIEWLAYER_PT_passes"):
            draw_panel(name, context)
    scene.shgi.method = "PHOTON_LATTICE"
    draw_panel("SHGI_RENDER_PT_photon_lattice", context)
    from shgi_blender import settings

    scene.shgi.method = "RADIANCE_FIELD"
    draw_panel("SHGI_RENDER_PT_radiance_field", context)
    scene.shgi.method = "PROPAGATION"

    shown = {name for _, name, _ in draw_panel_props("SHGI_RENDER_PT_propagation", context)}
    if shown != set(settings.PROPAGATION_DEFAULTS) | {"passes", "viewport_passes",
                                                      "final_gather"}:
        raise AssertionError(f"the light propagation panel shows {sorted(shown)}")
    scene.shgi.method = "INSTANT_GI"
    shown = {name for _, name, _ in draw_panel_props("SHGI_RENDER_PT_instant_gi", context)}
    if shown != set(settings.INSTANT_GI_DEFAULTS) | {"passes", "viewport_passes",
                                                     "bake_passes", "final_gather"}:
        raise AssertionError(f"the instant GI panel shows {sorted(shown)}")
    scene.shgi.method = "PROBE_GRID"
    text = draw_panel("SHGI_RENDER_PT_probe_grid", context)
    if "probes fill the scene" not in text:
        raise AssertionError("the probe grid panel does not say its volume is fitted")
    if "Bounces and Clamp follow Light Paths" not in text:
        raise AssertionError(f"the probe grid panel does not say where its bounces and clamp "
                             f"are set: {text!r}")
    draw_panel("SHGI_RENDER_PT_probe_grid_visibility", context)
    check_method_groups()
    check_light_path_limits(scene, context)
    draw_panel("SHGI_LIGHT_PT_light", context)
    scene.view_layers[0].use_pass_mist = True
    if "Mist" not in draw_panel("SHGI_VIEWLAYER_PT_passes", context):
        raise AssertionError("the passes panel does not name the Mist pass SHGI leaves out")
    scene.view_layers[0].use_pass_mist = False
    bpy.data.objects.remove(light_object)
    bpy.data.lights.remove(light)


def check_preferences(scene):
    """The Preferences draw Documentation and Report a Bug; the report holds the scene's
    settings and the manual is found (this checkout's README.md)."""
    preferences = bpy.context.preferences.addons[MODULE].preferences
    if preferences is None:
        raise AssertionError("the add-on has no AddonPreferences")
    buttons = set(draw_panel_operators(type(preferences), SimpleNamespace(scene=scene)))
    if not PREFERENCES_BUTTONS <= buttons:
        raise AssertionError(f"the Preferences show {buttons}, not {PREFERENCES_BUTTONS}")
    from shgi_blender import help as shgi_help
    from shgi_blender import preferences as shgi_preferences

    text = shgi_preferences.bug_report(SimpleNamespace(scene=scene))
    for expected in (f"Blender: {bpy.app.version_string}", "scene.shgi.method = ",
                     "scene.shgi.bake.bake_side = ", "Native module shgi: imported from"):
        if expected not in text:
            raise AssertionError(f"the bug report lacks {expected!r}:\n{text}")
    import shutil
    import tempfile

    folder = tempfile.mkdtemp(prefix="shgi_register_")
    try:
        if bpy.ops.shgi.report_bug(directory=folder) != {"FINISHED"}:
            raise AssertionError("Report a Bug did not finish")
        with open(os.path.join(folder, shgi_help.REPORT_NAME), encoding="utf-8") as report:
            if "SHGI bug report" not in report.read():
                raise AssertionError("Report a Bug wrote no report")
    finally:
        shutil.rmtree(folder)
    if shgi_help.find_docs() is None:
        raise AssertionError(f"no manual found for the add-on in {shgi_help.ADDON_DIR}")


def check_method_groups():
    """A new scene's scene.shgi.photon_lattice and scene.shgi.probe_grid hold their native
    structs' defaults and, with Light Paths' defaults, build them (Diffuse 4 gives the probe
    grid its native 3 bounces); the probe grid's UI names are EEVEE's."""
    import shgi
    from shgi_blender import settings

    scene = bpy.data.scenes.new("shgi_defaults")
    try:
        check_group_defaults(scene, settings, shgi)
    finally:
        bpy.data.scenes.remove(scene)


def check_group_defaults(scene, settings, shgi):

    builders = {"PHOTON_LATTICE": settings.photon_lattice_settings,
                "PROBE_GRID": settings.probe_grid_settings,
                "RADIANCE_FIELD": settings.radiance_field_settings,
                "PROPAGATION": settings.propagation_settings,
                "INSTANT_GI": settings.instant_gi_settings}
    for solver, group in settings.METHOD_SETTINGS.items():
        native = getattr(shgi, group.native_type)()
        built = builders[solver](scene.shgi, shgi, gather=False)  # as read at the surface
        props = getattr(scene.shgi, group.prop)
        for name in group.defaults:
            value = getattr(props, name)
            expected = getattr(native, name)
            if isinstance(value, str):  # an enum property: the native member's name
                expected = expected.name
            elif abs(float(value) - float(expected)) <= 1e-6:
                expected = value
            if value != expected:
                raise AssertionError(f"{group.prop}.{name} is {value}, native default {expected}")
        for name, value in group.light_paths.items():
            # Cycles' default where the add-on takes it (Clamp Indirect), else the native one.
            expected = settings.CYCLES_DEFAULTS.get(value.prop, getattr(native, name))
            if getattr(built, name) != expected:
                raise AssertionError(f"Light Paths' defaults give {group.native_type}.{name} "
                                     f"{getattr(built, name)}, expected {expected}")
    grid = scene.shgi.probe_grid
    for name, label in VISIBILITY_PROPERTIES.items():
        if grid.bl_rna.properties[name].name != label:
            raise AssertionError(f"probe_grid.{name} is labelled "
                                 f"{grid.bl_rna.properties[name].name!r}, not {label!r}")


def check_light_path_limits(scene, context):
    """Under each field method, Max Bounces says which limits the method cannot follow."""
    from shgi_blender import settings

    for solver, group in settings.METHOD_SETTINGS.items():
        scene.shgi.method = solver
        text = draw_panel("SHGI_RENDER_PT_light_paths_max_bounces", context)
        if f"{group.label}:" not in text:
            raise AssertionError(f"Max Bounces under {solver} does not name the limits the "
                                 f"method cannot follow: {text!r}")
    scene.shgi.method = "PATH_TRACE"
    if ":" in draw_panel("SHGI_RENDER_PT_light_paths_max_bounces", context):
        raise AssertionError("Max Bounces names limits a method cannot follow under Path Tracing")


def check_unregistered():
    if engine_registered():
        raise AssertionError("the SHGI render engine is still registered")
    if hasattr(bpy.types.Scene, "shgi"):
        raise AssertionError("scene.shgi is still defined")
    for panel in STOCK_PANELS:
        if ENGINE in getattr(bpy.types, panel).COMPAT_ENGINES:
            raise AssertionError(f"{panel} still lists SHGI")
    for name in OWN_CLASSES:
        if hasattr(bpy.types, name):
            raise AssertionError(f"{name} is still registered")
    # A handler left behind would run the old add-on's code on every file opened or saved.
    for kind in ("load_post", "save_pre", "save_post", "depsgraph_update_post"):
        left = [handler.__module__ for handler in getattr(bpy.app.handlers, kind)
                if handler.__module__.startswith(MODULE)]
        if left:
            raise AssertionError(f"{kind} still holds handlers of {left}")


def main():
    for attempt in range(3):
        module = addon_utils.enable(MODULE, default_set=True, handle_error=None)
        if module is None or not enabled():
            raise AssertionError(f"enable #{attempt + 1} failed")
        if module.bl_info["name"] != "SHGI" or tuple(module.bl_info["blender"]) > (3, 4, 1):
            raise AssertionError(f"bl_info: {module.bl_info}")
        check_registered()
        addon_utils.disable(MODULE, default_set=True, handle_error=None)
        if enabled():
            raise AssertionError(f"disable #{attempt + 1} left the add-on enabled")
        check_unregistered()
    import shgi_blender.export
    if not callable(shgi_blender.export.export_scene):
        raise AssertionError("shgi_blender.export.export_scene is missing")
    print("ADDON_REGISTER_OK")


main()
