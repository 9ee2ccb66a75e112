"""What the native code refuses reaches the artist named as Blender shows it, and the panels offer
only values the native code accepts.

1. Ranges: every number property of scene.shgi, scene.shgi.probe_grid and scene.shgi.bake that
   fills a native setting, set through RNA to its hard minimum and to its hard maximum, gives
   native settings that pass the native checks (settings.py, bake_settings.py) — but for Light
   Paths > Diffuse 0 under the Photon Lattice, refused by name. Recorded: each refusal.
2. F12 of the Cornell box (32 x 32 px) that must fail, each recorded with its message: an
   Irradiance Volume scaled to 0 along x (Probe Grid), Light Paths > Diffuse 0 (Photon Lattice),
   and a Visibility Blur of 0 from a file saved before the range was tightened (written as the
   raw ID property, which RNA does not clamp).
Writes the results JSON; prints ENGINE_REFUSALS_OK.
"""

import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import engine_common as common  # noqa: E402
from blender_test_setup import add_irradiance_volume, results_path  # noqa: E402

import bpy  # noqa: E402
import shgi  # noqa: E402
from shgi_blender import bake_settings, settings  # noqa: E402
from shgi_blender.engine import final_render  # noqa: E402

SCALE = 0.125  # 32 x 32 px
SAMPLES = 2
NUMBER_TYPES = ("INT", "FLOAT")


def native_builds(scene):
    """{property group path: (the group, the names it feeds into native settings, a function
    building every native setting the group feeds)}."""
    props = scene.shgi

    def scene_settings():  # Light Paths feeds every method
        settings.path_tracer_settings(props, shgi)
        settings.preview_settings(props, shgi)
        settings.photon_lattice_settings(props, shgi)
        settings.probe_grid_settings(props, shgi)
        bake_settings.bake_options(props.bake, props, shgi)

    bake_names = [*bake_settings.LIGHTMAP_FIELDS.values(), *bake_settings.OPTION_FIELDS.values()]
    return {
        "scene.shgi": (props, list(settings.PROPERTY_DEFAULTS), scene_settings),
        "scene.shgi.photon_lattice": (props.photon_lattice,
                                      list(settings.PHOTON_LATTICE_DEFAULTS),
                                      lambda: settings.photon_lattice_settings(props, shgi)),
        "scene.shgi.probe_grid": (props.probe_grid, list(settings.PROBE_GRID_DEFAULTS),
                                  lambda: settings.probe_grid_settings(props, shgi)),
        "scene.shgi.bake": (props.bake, bake_names,
                            lambda: bake_settings.bake_options(props.bake, props, shgi)),
    }


def range_refusals(scene):
    """{"<group>.<property> = <value>": message} for the hard limits the native checks refuse,
    and the number of limits tried."""
    refusals, tried = {}, 0
    for path, (group, names, build) in native_builds(scene).items():
        for name in names:
            rna = group.bl_rna.properties[name]
            if rna.type not in NUMBER_TYPES:
                continue
            default = getattr(group, name)
            for limit in (rna.hard_min, rna.hard_max):
                setattr(group, name, limit)  # RNA stores what the panel would
                tried += 1
                try:
                    build()
                except ValueError as error:
                    refusals[f"{path}.{name} = {getattr(group, name)}"] = str(error)
                finally:
                    setattr(group, name, default)
    return refusals, tried


def refused_f12(scene, method):
    """The message F12 fails with (RuntimeError in background), checked against the record."""
    scene.shgi.method = method
    scene.shgi.samples = SAMPLES
    scene.render.engine = "SHGI"
    try:
        bpy.ops.render.render(write_still=False)
    except RuntimeError as error:
        record = final_render.last_render()
        if not any(message in str(error) for message in record["errors"]):
            raise AssertionError(f"F12 failed with {error}, not the engine's {record['errors']}")
        return str(error)
    raise AssertionError(f"F12 of {method} did not fail")


def zero_scale_volume():
    scene = common.new_scene("cornell_box", SCALE)
    volume = add_irradiance_volume(scene, "flat_volume", (2, 2, 2))
    volume.location = (0.0, 1.0, 1.0)
    volume.scale = (0.0, 1.0, 1.0)
    return refused_f12(scene, "PROBE_GRID")


def no_diffuse_bounces():
    scene = common.new_scene("cornell_box", SCALE)
    scene.shgi.diffuse_bounces = 0
    return refused_f12(scene, "PHOTON_LATTICE")


def saved_visibility_blur():
    scene = common.new_scene("cornell_box", SCALE)
    grid = scene.shgi.probe_grid
    # The ID properties behind the group (Blender 5.0 keeps them apart from custom properties).
    stored = grid.bl_system_properties_get() if hasattr(grid, "bl_system_properties_get") \
        else grid
    stored["visibility_blur"] = 0.0  # as an older file holds it: RNA never clamped it
    return refused_f12(scene, "PROBE_GRID")


def main():
    scene = common.new_scene("cornell_box", SCALE)
    refusals, tried = range_refusals(scene)
    results = {"range_refusals": refusals, "limits_tried": tried,
               "f12": {"zero_scale_volume": zero_scale_volume(),
                       "no_diffuse_bounces": no_diffuse_bounces(),
                       "saved_visibility_blur": saved_visibility_blur()}}
    for case, message in results["f12"].items():
        print(f"{case:<24}{message.strip()}", flush=True)
    print(f"{tried} hard limits tried, refused: {refusals}")
    with open(results_path("shgi_engine_refusals.json"), "w") as out:
        json.dump(results, out, indent=1)
    print("ENGINE_REFUSALS_OK")


main()
