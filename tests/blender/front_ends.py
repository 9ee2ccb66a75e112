"""The same scene and settings give the same image through every front end, and a method
registered once reaches the add-on with no other edit.

1. F12 through the add-on, and a script that exports the same scene with the add-on's exporter,
   builds the solver with shgi.make_solver from the add-on's settings, renders with
   shgi.render_preview and denoises with shgi.frame_denoise, give the same float32 Combined,
   bit for bit: for the Photon Lattice, the
   Probe Grid and SINGLE_PROBE_TEST, the test-only method of tests/python/method_plugin.py.
2. That method, loaded through SHGI_METHOD_PLUGINS before the add-on imported shgi, is in the
   Render Method menu and in the bake's Indirect Light menu with its registry number, and a bake
   with it writes a lit lightmap.

Prints FRONT_ENDS_OK and writes what it measured to the results JSON.
"""

import json
import os
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
# Before the add-on imports shgi (engine_common enables it): the plugin registers its method the
# first time the registry is read.
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "python"))
os.environ["SHGI_METHOD_PLUGINS"] = "method_plugin"
sys.path.insert(0, HERE)
import engine_common as common  # noqa: E402

import blender_test_setup as setup  # noqa: E402
import bpy  # noqa: E402
import numpy as np  # noqa: E402

import method_plugin  # noqa: E402
import shgi  # noqa: E402
from shgi.frame_denoise import denoise_frame  # noqa: E402
from shgi_blender import settings  # noqa: E402
from shgi_blender.engine.field_solvers import solver_recipe  # noqa: E402
from shgi_blender.export import export_scene  # noqa: E402

SCALE = 0.25      # of the Cornell box's 128 x 128 pixels
SAMPLES = 4
METHODS = ("PHOTON_LATTICE", "PROBE_GRID", method_plugin.IDENTIFIER)


def script_render(scene):
    """What a script renders from the scene's export and the add-on's settings."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    export = export_scene(depsgraph, scene)
    native = export.scene
    native.commit()
    props = scene.shgi
    recipe = solver_recipe(props, shgi, export.probe_volumes)
    solver = shgi.make_solver(props.method, native, recipe.settings)
    for _ in range(recipe.passes):
        solver.refine()
    passes, _ = shgi.render_preview(native, solver.current_field(),
                                    settings.preview_settings(props, shgi))
    denoising = settings.denoising(props)
    passes = denoise_frame(passes, denoising.quality, denoising.prefilter, denoising.guides)
    return passes["Combined"]


def compare_front_ends(results):
    scene = common.new_scene("cornell_box", SCALE)
    scene.shgi.samples = SAMPLES
    scene.shgi.use_denoising = True  # F12's denoiser is the script's too
    scene.shgi.photon_lattice.photons = 20000
    scene.shgi.probe_grid.rays_per_probe = 32
    folder = tempfile.mkdtemp()
    for method in METHODS:
        scene.shgi.method = method
        f12 = common.render_f12(scene, "SHGI", os.path.join(folder, f"{method}.exr"))["Combined"]
        script = script_render(scene)
        f12 = f12.astype(np.float32)
        same = bool(np.array_equal(f12[..., :3], script[..., :3]))
        results[method] = {"identical": same, "mean": float(f12[..., :3].mean()),
                           "max_difference": float(np.abs(f12[..., :3] - script[..., :3]).max())}
        if not same:
            raise AssertionError(f"{method}: F12 and the script differ by up to "
                                 f"{results[method]['max_difference']}")
        if not results[method]["mean"] > 0.01:
            raise AssertionError(f"{method}: the F12 image is black")


def plugin_in_the_menus(results):
    scene = bpy.context.scene
    methods = {item.identifier: item.value
               for item in scene.shgi.bl_rna.properties["method"].enum_items}
    sources = {item.identifier: item.value
               for item in scene.shgi.bake.bl_rna.properties["source"].enum_items}
    results["render_methods"], results["bake_sources"] = methods, sources
    for menu, items in (("Render Method", methods), ("Indirect Light", sources)):
        if items.get(method_plugin.IDENTIFIER) != method_plugin.NUMBER:
            raise AssertionError(f"{menu}: {items} lacks {method_plugin.IDENTIFIER} "
                                 f"({method_plugin.NUMBER})")


def plugin_bakes(results):
    scene = bpy.context.scene
    floor = bpy.data.objects["floor"]
    bpy.ops.object.select_all(action="DESELECT")
    floor.select_set(True)
    bpy.context.view_layer.objects.active = floor
    folder = tempfile.mkdtemp()
    status = bpy.ops.shgi.bake_lightmaps(source=method_plugin.IDENTIFIER, resolution=16,
                                         samples=4, create_uv=True, output_folder=folder)
    written = sorted(name for name in os.listdir(folder) if name.endswith(".exr"))
    results["plugin_bake"] = {"status": sorted(status), "files": written}
    if status != {"FINISHED"} or not written:
        raise AssertionError(f"the bake with {method_plugin.IDENTIFIER}: {status}, {written}")
    lightmap = shgi.read_exr(os.path.join(folder, written[0]))["Lightmap"]
    results["plugin_bake"]["mean"] = float(lightmap[..., :3].mean())
    if not results["plugin_bake"]["mean"] > 0.0:
        raise AssertionError("the plugin method's lightmap is black")


def main():
    results = {}
    compare_front_ends(results)
    plugin_in_the_menus(results)
    plugin_bakes(results)
    with open(setup.results_path("front_ends.json"), "w") as out:
        json.dump(results, out, indent=1)
    print("FRONT_ENDS_OK")


main()
