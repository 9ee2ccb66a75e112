"""Shared code of the render engine scripts (tests/blender/engine_*.py).

Scenes are the project's Cornell box and sun room built with bpy (examples/blender_scenes.py)
in a file reset as the Cycles calibration resets it (calibration_common.reset_scene: CPU, no
denoising, 1 px box filter, Standard view, calibration bounce limits, every light pass, EXR
output). Renders go through F12 (``bpy.ops.render.render``) and are read back from the Render
Result, saved as a multilayer EXR (background Blender gives Python no pixels of it otherwise).

Scripts run as ``blender -b --factory-startup --python-exit-code 1 --python <script> --
<build python dir> <addon dir> <results json>``.
"""

import math
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()
sys.path.insert(0, str(setup.REPO_ROOT / "examples"))

import addon_utils  # noqa: E402
import bpy  # noqa: E402

ADDON = "shgi_blender"


def enable_addon():
    """Enables the add-on (a factory reset disables every add-on the factory set lacks)."""
    if ADDON not in bpy.context.preferences.addons:
        if addon_utils.enable(ADDON, default_set=True, handle_error=None) is None:
            raise AssertionError("the shgi_blender add-on did not enable")


# Enabled before anything imports shgi_blender's modules: addon_utils would otherwise find the
# package imported as a plain module and reload it.
enable_addon()

import blender_scenes  # noqa: E402
import calibration_common as calibration  # noqa: E402
import numpy as np  # noqa: E402
import shgi  # noqa: E402
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
# Auto-exposure of the comparisons: the reference's mean luminance is mapped to middle grey.
MIDDLE_GREY = 0.18


def results_path(default_name):
    """The results JSON path given after '--' (third argument), or one in the temp folder."""
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    return args[2] if len(args) > 2 else os.path.join(tempfile.gettempdir(),
                                                      default_name)


def new_scene(name, scale):
    """A fresh file holding project scene `name` at `scale`, ready for Cycles and SHGI."""
    calibration.reset_scene()
    enable_addon()
    scene = blender_scenes.SCENES[name](scale)
    for field, value in calibration.BOUNCES.items():  # the same limits for both engines
        setattr(scene.shgi, field, value)
    return scene


def render_f12(scene, engine, path):
    """F12 with `engine`; {pass name: float64 (H, W, C)} read back from the Render Result."""
    scene.render.engine = engine
    bpy.ops.render.render(write_still=False)
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    # Multilayer EXR layers are "<view layer>.<pass>".
    return {name.split(".")[-1]: np.asarray(pixels, np.float64)
            for name, pixels in shgi.read_exr(path).items()}


def display(image, exposure):
    """sRGB-encoded [0, 1] RGB of linear `image` scaled by `exposure`."""
    linear = np.clip(image[..., :3] * exposure, 0.0, None).astype(np.float32)
    return np.clip(np.asarray(shgi.srgb_from_linear(linear), np.float64), 0.0, 1.0)


def psnr(reference, image):
    """PSNR (dB) of the sRGB images after the reference's auto-exposure."""
    exposure = MIDDLE_GREY / float((reference[..., :3] @ LUMINANCE).mean())
    mse = float(np.mean((display(reference, exposure) - display(image, exposure)) ** 2))
    return math.inf if mse == 0.0 else 10.0 * math.log10(1.0 / mse)


def mean_rgb(image):
    return float(image[..., :3].mean())
