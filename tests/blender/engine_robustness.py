"""Scenes that are broken or odd render through F12 with warnings, never an error or a crash.

Each case edits the project's Cornell box (examples/blender_scenes.py, 32 x 32 px) and renders it
with every method: no lights (and a black world), an object without material, non-mesh objects
(text, a curve without bevel, an empty, a volume), a mesh with NaN vertices, a scene with no
geometry at all, emitters whose power overflows 32-bit floats (the world, a material, a light:
Blender allows 3.4e38), a NaN material colour and an image of NaN pixels. A case passes when the
render reports no error, every expected warning (naming the datablock at fault) is reported, and
Combined has the render's size with finite pixels. Prints ENGINE_ROBUSTNESS_OK.
"""

import math
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import engine_common as common  # noqa: E402
from blender_test_setup import set_principled_inputs  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from shgi_blender.engine import final_render  # noqa: E402

SCALE = 0.125  # 32 x 32 px
SAMPLES = 4
PHOTONS = 20000
METHODS = ("PATH_TRACE", "PHOTON_LATTICE")
# Near Blender's largest float (3.4e38): an emitted power of it overflows.
HUGE = 3e38


def remove_lights():
    for obj in [o for o in bpy.data.objects if o.type == "LIGHT"]:
        bpy.data.objects.remove(obj, do_unlink=True)


def add_object(name, data):
    obj = bpy.data.objects.new(name, data)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def add_mesh(name, vertices, faces):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(vertices, [], faces)
    return add_object(name, mesh)


def add_unmaterialed_cube():
    add_mesh("bare_cube", [(x, y, z) for z in (0.2, 0.6) for y in (0.2, 0.6) for x in (-0.6, -0.2)],
             [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)])


def add_non_mesh_objects():
    text = bpy.data.curves.new("label", "FONT")
    text.body = "SHGI"
    add_object("label", text).location = (-0.5, 1.5, 1.0)
    curve = bpy.data.curves.new("path", "CURVE")  # no bevel: edges only, nothing to render
    spline = curve.splines.new("POLY")
    spline.points.add(2)
    for point, co in zip(spline.points, ((0, 1, 0.1, 1), (0.5, 1, 0.5, 1), (0.8, 1.2, 0.2, 1))):
        point.co = co
    add_object("path", curve)
    add_object("marker", None)  # an empty
    add_object("fog", bpy.data.volumes.new("fog"))


def add_nan_mesh():
    add_mesh("broken", [(0, 0.5, 0.5), (0.3, 0.5, 0.5), (math.nan, 0.5, 0.8)], [(0, 1, 2)])


def overflow_emitters():
    """The world, the red walls' emission and a new point light at HUGE strength or power."""
    background = bpy.context.scene.world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    background.inputs["Strength"].default_value = HUGE
    red = bpy.data.materials["red"].node_tree.nodes["Principled BSDF"]
    set_principled_inputs(red, emission_color=(1.0, 1.0, 1.0), emission_strength=HUGE)
    lamp = bpy.data.lights.new("huge_lamp", "POINT")
    lamp.energy = HUGE
    add_object("huge_lamp", lamp).location = (0.0, 1.0, 1.5)


def nan_base_color():
    white = bpy.data.materials["white"].node_tree.nodes["Principled BSDF"]
    set_principled_inputs(white, base_color=(math.nan, 0.5, 0.5))


def nan_image():
    """A float image of NaN pixels as the white material's base colour texture."""
    image = bpy.data.images.new("nan_pixels", 2, 2, float_buffer=True)
    image.pixels = [math.nan] * 16
    tree = bpy.data.materials["white"].node_tree
    texture = tree.nodes.new("ShaderNodeTexImage")
    texture.image = image
    tree.links.new(texture.outputs["Color"], tree.nodes["Principled BSDF"].inputs["Base Color"])


def remove_geometry():
    for obj in [o for o in bpy.data.objects if o.type == "MESH"]:
        bpy.data.objects.remove(obj, do_unlink=True)


# case: (edit of the Cornell box, substrings that must appear in the reported warnings)
CASES = {
    "no_lights": (remove_lights, ["nothing in the scene emits light"]),
    "no_material": (add_unmaterialed_cube, ["'bare_cube' has no material"]),
    "non_mesh_objects": (add_non_mesh_objects, ["'fog': type VOLUME is not supported"]),
    "nan_vertices": (add_nan_mesh, ["'broken'", "nan"]),
    "no_geometry": (remove_geometry, ["no geometry SHGI can render"]),
    "overflowing_emitters": (overflow_emitters, [
        "world 'World", "Background Color × Strength is 3e+38 W/m²/sr", "default world",
        "material 'red':", "emission is turned off",
        "light 'huge_lamp': Power × Color is 3e+38 W", "would overflow"]),
    "nan_base_color": (nan_base_color, ["material 'white': Base Color (nan, 0.5, 0.5) is not a "
                                        "finite number", "fallback material"]),
    "nan_image": (nan_image, ["image 'nan_pixels': 16 of its 16 pixel values are NaN"]),
}


def run_case(name, tmpdir):
    edit, expected = CASES[name]
    rows = []
    for method in METHODS:
        scene = common.new_scene("cornell_box", SCALE)
        edit()
        scene.shgi.method = method
        scene.shgi.samples = SAMPLES
        scene.shgi.photon_lattice.photons = PHOTONS
        start = time.perf_counter()
        passes = common.render_f12(scene, "SHGI", os.path.join(tmpdir, f"{name}_{method}.exr"))
        record = final_render.last_render()
        warnings = " | ".join(record["warnings"])
        if record["errors"]:
            raise AssertionError(f"{name}, {method}: errors {record['errors']}")
        missing = [text for text in expected if text not in warnings]
        if missing:
            raise AssertionError(f"{name}, {method}: no warning with {missing} in: {warnings}")
        combined = passes["Combined"]
        size = (scene.render.resolution_y, scene.render.resolution_x)
        if combined.shape[:2] != size or not np.all(np.isfinite(combined)):
            raise AssertionError(f"{name}, {method}: Combined {combined.shape} is not {size} "
                                 "finite pixels")
        rows.append(f"{name:<22}{method:<16}{time.perf_counter() - start:6.2f} s  "
                    f"mean {common.mean_rgb(combined):8.4f}  warnings: {warnings}")
    return rows


def main():
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="shgi_robust_") as tmpdir:
        for name in CASES:
            for row in run_case(name, tmpdir):
                print(row, flush=True)
    print(f"ENGINE_ROBUSTNESS_OK {len(CASES)} cases in {time.perf_counter() - start:.1f} s")


main()
