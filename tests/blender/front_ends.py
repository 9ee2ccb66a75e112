"""The same scene and settings give the same image through every front end, and a method
registered once reaches the add-on with no other edit.

1. F12 through the add-on, and a script that exports the same scene with the add-on's exporter,
   builds the solver with shgi.make_solver from the add-on's settings, renders with
   shgi.render_preview and denoises with shgi.frame_denoise, give the same float32 Combined,
   bit for bit: for the Photon Lattice, the
   Probe Grid and SINGLE_PROBE_TEST, the test-only method of tests/python/method_plugin.py.
2. The Bake Lightmaps operator (its settings taken from the Bake panel's scene.shgi.bake), and a
   script that exports the same scene as the operator does, takes its shgi.bake.BakeOptions from
   the add-on's own mapping (bake_settings.bake_options), its jobs from shgi.bake.jobs_for_scene,
   solves the field with shgi.bake.solve_field (the registry's final_passes) and bakes with
   shgi.bake.bake_scene, give the same float32 lightmap texels, bit for bit: the images the
   operator made against bake_scene's Lightmap.color, before any file encoding, for the same
   three methods, on four objects (one of them given its UV map by the operator's Create UV Map).
3. That method, loaded through SHGI_METHOD_PLUGINS before the add-on imported shgi, is in the
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
from shgi import bake as shgi_bake  # noqa: E402
from shgi.frame_denoise import denoise_frame  # noqa: E402
from shgi_blender import bake_settings, settings  # noqa: E402
from shgi_blender.engine.field_solvers import solver_recipe  # noqa: E402
from shgi_blender.export import export_scene  # noqa: E402
from shgi_blender.operators.lightmap_images import image_name  # noqa: E402

SCALE = 0.25      # of the Cornell box's 128 x 128 pixels
SAMPLES = 4
METHODS = ("PHOTON_LATTICE", "PROBE_GRID", method_plugin.IDENTIFIER)
# The bake: the Cornell box's floor, back and left walls (LightmapUV of their own) and the short
# block (Lightmap Pack lays out its UV map), at a texel density giving 16-24 texels a side.
BAKED_OBJECTS = ("back", "floor", "left", "short_block")
BAKE_TEXELS_PER_METRE = 8.0
BAKE_SAMPLES = 4
# Not the default seed: a front end that dropped it would still agree at 0.
BAKE_SEED = 5


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
    preview = settings.preview_settings(props, shgi)
    passes, _ = shgi.render_preview(native, solver.current_field(), preview)
    denoising = settings.denoising(props)
    passes = denoise_frame(passes, denoising.quality, denoising.prefilter, denoising.guides,
                           samples=preview.samples, pixel_filter=denoising.pixel_filter,
                           filter_width=denoising.filter_width)
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


def operator_bake(scene, folder):
    """{object name: float32 (H, W, 3)} of the images the Bake Lightmaps operator made, run as
    the panel's button runs it (no property set: all of them from scene.shgi.bake)."""
    bake = scene.shgi.bake
    bake.output_folder = folder
    bpy.ops.object.select_all(action="DESELECT")
    for name in BAKED_OBJECTS:
        bpy.data.objects[name].select_set(True)
    bpy.context.view_layer.objects.active = bpy.data.objects[BAKED_OBJECTS[0]]
    status = bpy.ops.shgi.bake_lightmaps()
    if status != {"FINISHED"}:
        raise AssertionError(f"the bake with {bake.source}: {status}")
    images = {}
    for name in BAKED_OBJECTS:
        image = bpy.data.images[image_name(name)]
        width, height = image.size
        rgba = np.empty(width * height * 4, np.float32)
        image.pixels.foreach_get(rgba)
        images[name] = rgba.reshape(height, width, 4)[..., :3]
    return images


def script_bake(scene, folder):
    """{object name: float32 (H, W, 3)} of shgi.bake.bake_scene on the scene exported as the
    operator exports it (every object facing the scene: nothing turned around), with the
    add-on's own BakeOptions and field settings."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    export = export_scene(depsgraph, scene, for_render=True, with_camera=False)
    native = export.scene
    native.commit()
    props, bake = scene.shgi, scene.shgi.bake
    options = bake_settings.bake_options(bake, props, shgi)
    jobs = shgi_bake.jobs_for_scene(native, bake.uv_map, texels_per_metre=bake.texel_density,
                                    names=BAKED_OBJECTS)
    recipe = solver_recipe(props, shgi, export.probe_volumes, gather=False)  # read at texels
    field = shgi_bake.solve_field(native, bake.source, settings=recipe.settings)
    lightmaps = shgi_bake.bake_scene(native, jobs, options, folder, field)
    return {lightmap.name: lightmap.color for lightmap in lightmaps}


def compare_bakes(results):
    scene = common.new_scene("cornell_box", SCALE, lightmap=True)
    scene.shgi.photon_lattice.photons = 20000
    scene.shgi.probe_grid.rays_per_probe = 32
    scene.shgi.seed = BAKE_SEED
    bake = scene.shgi.bake
    bake.samples, bake.texel_density = BAKE_SAMPLES, BAKE_TEXELS_PER_METRE
    bake.create_uv = bake.filter = True  # Lightmap Pack for the block; SHGI's filter
    for method in METHODS:
        # The operator solves the bake's source; the script's solver_recipe reads the method.
        scene.shgi.method = bake.source = method
        operator = operator_bake(scene, tempfile.mkdtemp())
        script = script_bake(scene, tempfile.mkdtemp())
        rows = results[f"bake_{method}"] = {}
        for name in BAKED_OBJECTS:
            ours, theirs = operator[name], script[name]
            same = ours.shape == theirs.shape and bool(np.array_equal(ours, theirs))
            rows[name] = {"identical": same, "shape": list(ours.shape),
                          "mean": float(ours.mean()),
                          "max_difference": (float(np.abs(ours - theirs).max())
                                             if ours.shape == theirs.shape else None)}
            if not same:
                raise AssertionError(f"{method}, {name}: the bake operator and shgi.bake differ: "
                                     f"{rows[name]}, script shape {list(theirs.shape)}")
            if not rows[name]["mean"] > 0.0:
                raise AssertionError(f"{method}, {name}: the lightmap is black")


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
    compare_bakes(results)
    plugin_in_the_menus(results)
    plugin_bakes(results)
    with open(setup.results_path("front_ends.json"), "w") as out:
        json.dump(results, out, indent=1)
    print("FRONT_ENDS_OK")


main()
