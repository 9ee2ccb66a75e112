"""Shared start of the Blender test scripts: their arguments, paths to shgi and the add-on,
enabling the add-on, a scene reset, and the settings whose API differs between Blender 3.4 and
Blender 4.x / 5.x (Principled BSDF inputs, multilayer EXR output).

Scripts run as ``blender -b --factory-startup --python-exit-code 1 --python <script> --
<build python dir> <addon dir> [<results json> ...]``; the two folders may also come from the
environment variables SHGI_BUILD_PYTHON and SHGI_ADDON_DIR. A failed check raises, which makes
Blender exit with 1.
"""

import json
import os
import pathlib
import sys
import tempfile
import traceback

import addon_utils
import bpy
import numpy as np

REPO_ROOT = pathlib.Path(__file__).resolve().parents[2]
ADDON = "shgi_blender"
# Principled BSDF colour inputs (RGBA sockets), by shgi.Material field name.
PRINCIPLED_COLOR_FIELDS = ("base_color", "emission_color")


def script_args():
    """The script's own arguments: what follows '--' on Blender's command line."""
    return sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []


def results_path(default_name):
    """The results JSON path given after '--' (third argument), or one in the temp folder."""
    args = script_args()
    return args[2] if len(args) > 2 else os.path.join(tempfile.gettempdir(), default_name)


def add_import_paths():
    """Puts the shgi build folder and the add-on folder at the front of sys.path."""
    args = script_args()
    build = args[0] if len(args) > 0 else os.environ.get(
        "SHGI_BUILD_PYTHON", str(REPO_ROOT / "build" / "python"))
    addon = args[1] if len(args) > 1 else os.environ.get(
        "SHGI_ADDON_DIR", str(REPO_ROOT / "addon"))
    for path in (addon, build):
        sys.path.insert(0, path)


def enable_addon():
    """Enables the add-on (a factory reset disables every add-on the factory set lacks)."""
    if ADDON not in bpy.context.preferences.addons:
        if addon_utils.enable(ADDON, default_set=True, handle_error=None) is None:
            raise AssertionError("the shgi_blender add-on did not enable")


def clear_scene():
    """Removes every object of the factory scene (keeps its world and render settings)."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)


def set_principled_inputs(node, **fields):
    """Sets a Principled BSDF node's inputs from shgi.Material field names, in Blender 3.4's
    units, on any Blender version.

    The add-on's own table (conversions.principled_socket_names) names the sockets. `specular`
    is Blender 3.4's "Specular" (F0 = 0.08 · specular); from Blender 4 it becomes the "Specular
    IOR Level" giving that F0 at the node's IOR (`ior` of the same call, else the node's).
    Colours may be RGB (alpha 1 is added).
    """
    from shgi_blender.export import conversions  # after add_import_paths

    names = conversions.principled_socket_names(bpy.app.version)
    values = dict(fields)
    if "specular" in values and bpy.app.version >= conversions.PRINCIPLED_V2_VERSION:
        ior = values.get("ior", node.inputs[names["ior"]].default_value)
        values["specular"] = conversions.ior_level_from_specular(values["specular"], ior)
    for field, value in values.items():
        if field in PRINCIPLED_COLOR_FIELDS:
            value = (*value[:3], 1.0)
        node.inputs[names[field]].default_value = value


def native_area_power(power):
    """An area light's "Power" in this Blender's units (W) as SHGI's light takes it: Blender 4
    changed the area light's radiance (conversions.light_fields converts)."""
    from shgi_blender.export import conversions  # after add_import_paths

    return conversions.light_fields("AREA", power, (1.0, 1.0, 1.0), np.eye(4),
                                    blender_version=bpy.app.version)["power"]


def add_irradiance_volume(scene, name, resolution):
    """An Irradiance Volume light probe object with `resolution` probes along x, y, z (its type
    and property names depend on the Blender version: shgi_blender.export.light_probe)."""
    from shgi_blender.export import light_probe  # after add_import_paths

    types = bpy.types.LightProbe.bl_rna.properties["type"].enum_items.keys()
    data = bpy.data.lightprobes.new(
        name, next(t for t in light_probe.IRRADIANCE_VOLUME_TYPES if t in types))
    for prop, count in zip(light_probe.resolution_properties(data), resolution):
        setattr(data, prop, count)
    obj = bpy.data.objects.new(name, data)
    scene.collection.objects.link(obj)
    return obj


def use_multilayer_exr(image_settings):
    """Render output as 32-bit float, ZIP-compressed multilayer OpenEXR (every pass a layer).

    Blender 5.0 made "multilayer" a media type (its file format then reads OPEN_EXR_MULTILAYER,
    the file format itself in Blender 3.4) and writes one EXR part per pass unless told to
    interleave them as Blender 3.4 does. Its default, multi-part, is kept: shgi.read_exr reads
    every part under the layer names of the single-part file.
    """
    if hasattr(image_settings, "media_type"):
        image_settings.media_type = "MULTI_LAYER_IMAGE"
    image_settings.file_format = "OPEN_EXR_MULTILAYER"
    image_settings.color_depth = "32"
    image_settings.exr_codec = "ZIP"


def read_render_exr(path):
    """{pass: float64 (H, W, C)} of a multilayer EXR written as use_multilayer_exr sets, keyed
    by the renderers' pass names ("DiffDir", also where Blender 5 says "Diffuse Direct")."""
    import shgi
    from shgi_blender.engine import passes  # after add_import_paths

    names = passes.names_from_blender_names(bpy.app.version)
    result = {}
    for layer, pixels in shgi.read_exr(path).items():
        blender_name = layer.split(".")[-1]  # multilayer EXR layers are "<view layer>.<pass>"
        result[names.get(blender_name, blender_name)] = np.asarray(pixels, np.float64)
    return result


def check_close(what, actual, expected, tolerance):
    """Raises AssertionError naming `what` and both values when they differ by more."""
    actual_values = list(actual) if hasattr(actual, "__len__") else [actual]
    expected_values = list(expected) if hasattr(expected, "__len__") else [expected]
    if len(actual_values) != len(expected_values) or any(
            abs(float(a) - float(e)) > tolerance for a, e in zip(actual_values, expected_values)):
        raise AssertionError(f"{what}: {actual} != expected {expected} (tolerance {tolerance})")


def run_steps_in_window(steps, results, path, ok_marker, echo_results=False):
    """Drives the generator `steps` from a Blender timer, each of its yields the seconds until
    the next step (a windowed test lets Blender redraw between steps). When it ends, writes
    `results` to `path` as JSON (and prints them with `echo_results`), prints `ok_marker` and
    exits with 0; an exception puts its traceback in results["error"] and exits with 1."""
    def finish(code):
        with open(path, "w") as handle:
            json.dump(results, handle, indent=1)
        if echo_results:
            print(json.dumps(results, indent=1))
        if code == 0:
            print(ok_marker)
        sys.stdout.flush()
        os._exit(code)

    def drive():
        try:
            return next(steps)
        except StopIteration:
            finish(0)
        except Exception:
            results["error"] = traceback.format_exc()
            print(results["error"])
            finish(1)
        return None

    bpy.app.timers.register(drive, first_interval=1.0)
