"""A .blend saved with the add-on's first settings layout opens with every value it was saved
with (versioning.py), once; the Light Paths of that file reach the probe grid and the photon
lattice; a scene saved with today's layout opens untouched.

The file is fixtures/settings_v1.blend (written by fixtures/make_settings_v1.py with the add-on
of that time; fixtures/settings_v1.json lists its values under their names then). EXPECTED_PATHS
below says where each of them lives now, written out here rather than read from the add-on's
own table, so that a wrong table fails the test.

Prints SETTINGS_VERSIONING_OK when every check passed and writes the values it read to the
results JSON.
"""

import json
import os
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()

import bpy  # noqa: E402

FIXTURE = os.path.join(HERE, "fixtures", "settings_v1.blend")
FIXTURE_VALUES = os.path.join(HERE, "fixtures", "settings_v1.json")
# The first layout's scene.shgi properties that moved -> where they are now (below scene.shgi).
MOVED_PATHS = {
    "photons": "photon_lattice.photons",
    "resolution": "photon_lattice.resolution",
    "order": "photon_lattice.order",
    "caustics": "photon_lattice.caustics",
    "caustic_resolution": "photon_lattice.caustic_resolution",
    "interpolation": "photon_lattice.interpolation",
    "blur_passes": "photon_lattice.blur_passes",
    "world_in_field": "photon_lattice.world_in_field",
    "viewport_photon_passes": "photon_lattice.viewport_passes",
    "probe_passes": "probe_grid.passes",
    "viewport_probe_passes": "probe_grid.viewport_passes",
}
# The first layout's probe_grid properties that Light Paths took over.
DROPPED_PROBE_GRID = ("bounces", "clamp")
FLOAT_TOLERANCE = 1e-6  # stored as 32-bit floats


def expected_paths(saved):
    """{path below scene.shgi: value} of the values the fixture was saved with."""
    expected = {MOVED_PATHS.get(name, name): value for name, value in saved["shgi"].items()}
    expected.update({f"probe_grid.{name}": value
                     for name, value in saved["shgi.probe_grid"].items()
                     if name not in DROPPED_PROBE_GRID})
    return expected


def read(props, path):
    for part in path.split("."):
        props = getattr(props, part)
    return props


def check_values(scene, expected, when):
    """The values at each path, checked against `expected`; returns {path: value read}."""
    values = {}
    for path, value in expected.items():
        actual = read(scene.shgi, path)
        values[path] = actual
        same = (abs(actual - value) <= FLOAT_TOLERANCE if isinstance(value, float)
                else actual == value)
        if not same:
            raise AssertionError(f"{when}: scene.shgi.{path} is {actual!r}, saved as {value!r}")
    return values


def check_old_names_gone(scene, when):
    stale = [name for name in MOVED_PATHS if name in scene.shgi.keys()]
    stale += [f"probe_grid.{name}" for name in DROPPED_PROBE_GRID
              if name in scene.shgi.probe_grid.keys()]
    if stale:
        raise AssertionError(f"{when}: the old properties {stale} are still stored")


def native_light_paths(scene):
    """What Light Paths gives each method's native settings."""
    import shgi
    from shgi_blender import settings

    grid = settings.probe_grid_settings(scene.shgi, shgi)
    lattice = settings.photon_lattice_settings(scene.shgi, shgi)
    return {"probe_grid.bounces": grid.bounces, "probe_grid.clamp": grid.clamp,
            "photon_lattice.max_bounces": lattice.max_bounces}


def check_new_scene(results, folder):
    """A scene of today's layout, its final passes left at the default, saved and opened: the
    default stays (it is not taken for the first layout's default)."""
    import shgi
    import shgi.bake
    from shgi_blender import settings

    scene = bpy.context.scene
    results["new_scene_passes"] = scene.shgi.probe_grid.passes
    results["bake_probe_grid_passes"] = shgi.bake.PROBE_GRID_PASSES
    results["fallback_probe_grid_passes"] = settings.FINAL_PASSES_FALLBACK["PROBE_GRID"]
    scene.shgi.samples = 33  # something stored
    path = os.path.join(folder, "today.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    results["today_reopened"] = {"samples": scene.shgi.samples,
                                 "probe_grid.passes": scene.shgi.probe_grid.passes,
                                 "settings_version": scene.shgi.get("settings_version")}


def versioned_light_paths(layout, prop, value):
    """Clamp Indirect, Filter Glossy and F12's denoising Prefilter of a scene stamped with
    `layout` after versioning, `prop` set to `value` first (None: left at its default, nothing
    stored)."""
    from shgi_blender import versioning

    scene = bpy.data.scenes.new(f"layout_{layout}_{prop}_{value}")
    scene.shgi["settings_version"] = layout
    scene.shgi.samples = 21  # something stored
    if value is not None:
        setattr(scene.shgi, prop, value)
    versioning.upgrade_scene(scene)
    read = {"clamp_indirect": scene.shgi.clamp_indirect,
            "filter_glossy": scene.shgi.filter_glossy,
            "denoising_prefilter": scene.shgi.denoising_prefilter,
            "settings_version": scene.shgi.get("settings_version")}
    bpy.data.scenes.remove(scene)
    return read


def versioned_propagation(layout, steps):
    """Light Propagation's Steps, Distance and switches of a scene stamped with `layout` after
    versioning, its Steps set to `steps` first (None: the group left at its defaults)."""
    from shgi_blender import versioning

    scene = bpy.data.scenes.new(f"layout_{layout}_propagation_{steps}")
    scene.shgi["settings_version"] = layout
    scene.shgi.samples = 21  # something stored
    if steps is not None:
        scene.shgi.propagation.steps = steps
    versioning.upgrade_scene(scene)
    group = scene.shgi.propagation
    read = {name: getattr(group, name) for name in (
        "steps", "distance", "damping", "occlude_first_step", "drop_outward_vpls",
        "travel_reinjection", "unclamped_transfer", "clamp_at_surfaces")}
    bpy.data.scenes.remove(scene)
    return read


def check_third_layout_clamp(results):
    """A scene stamped with layout 3 that left Clamp Indirect at that layout's default (0, off)
    keeps 0 after versioning, though a new scene clamps at Cycles' 10; one that set it keeps
    its value. A scene stamped with layout 4, before Filter Glossy, keeps it off (0), though a
    new scene filters at Cycles' 1; one that set it keeps its value. Light Propagation's
    layout-5 defaults likewise."""
    from shgi_blender import settings_upgrade

    results["new_scene_clamp"] = bpy.context.scene.shgi.clamp_indirect
    results["new_scene_filter_glossy"] = bpy.context.scene.shgi.filter_glossy
    results["layout_3_clamp"] = {name: versioned_light_paths(3, "clamp_indirect", value)
                                 for name, value in (("left", None), ("set", 7.5))}
    results["layout_4_filter_glossy"] = {name: versioned_light_paths(4, "filter_glossy", value)
                                         for name, value in (("left", None), ("set", 0.5))}
    # Layout 8's F12 denoiser prefiltered Fast: a scene that left it keeps Fast.
    results["new_scene_prefilter"] = bpy.context.scene.shgi.denoising_prefilter
    results["layout_8_prefilter"] = {
        name: versioned_light_paths(8, "denoising_prefilter", value)["denoising_prefilter"]
        for name, value in (("left", None), ("set", "NONE"))}
    # A scene stamped with layout 5 keeps Light Propagation's defaults of then (8 steps, the
    # corrections off), whether it left the group alone or set its Steps; a new scene has today's.
    results["new_scene_propagation"] = versioned_propagation(
        settings_upgrade.SETTINGS_VERSION, None)
    results["layout_5_propagation"] = {name: versioned_propagation(5, steps)
                                       for name, steps in (("left", None), ("set", 16))}


def main():
    setup.enable_addon()
    from shgi_blender import versioning

    with open(FIXTURE_VALUES) as file:
        saved = json.load(file)
    expected = expected_paths(saved)
    results = {"blender": bpy.app.version_string, "fixture_blender": saved["blender"]}
    with tempfile.TemporaryDirectory() as folder:
        check_new_scene(results, folder)
        check_third_layout_clamp(results)

        bpy.ops.wm.open_mainfile(filepath=FIXTURE)
        scene = bpy.context.scene
        results["values"] = check_values(scene, expected, "opened")
        check_old_names_gone(scene, "opened")
        results["settings_version"] = scene.shgi.get("settings_version")
        results["native"] = native_light_paths(scene)

        versioning.upgrade_settings()  # a second run must change nothing
        check_values(scene, expected, "after a second versioning run")

        path = os.path.join(folder, "upgraded.blend")
        bpy.ops.wm.save_as_mainfile(filepath=path)
        bpy.ops.wm.open_mainfile(filepath=path)
        scene = bpy.context.scene
        results["reopened"] = check_values(scene, expected, "saved and opened again")
        check_old_names_gone(scene, "saved and opened again")
    results["expected"] = expected
    with open(setup.results_path("settings_versioning.json"), "w") as out:
        json.dump(results, out, indent=1)
    print("SETTINGS_VERSIONING_OK")


main()
