"""Shared code of the render engine scripts (tests/blender/engine_*.py).

Scenes are the project's Cornell box and sun room built with bpy (examples/blender_scenes.py)
in a file reset as the Cycles calibration resets it (calibration_common.reset_scene: CPU, no
denoising for either engine, 1 px box filter, Standard view, calibration bounce limits, every
light pass, EXR output). Renders go through F12 (``bpy.ops.render.render``) and are read back from the Render
Result, saved as a multilayer EXR (background Blender gives Python no pixels of it otherwise).

Scripts run as ``blender -b --factory-startup --python-exit-code 1 --python <script> --
<build python dir> <addon dir> <results json>``.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()
sys.path.insert(0, str(setup.REPO_ROOT / "examples"))

# Enabled before anything imports shgi_blender's modules: addon_utils would otherwise find the
# package imported as a plain module and reload it.
setup.enable_addon()

import blender_scenes  # noqa: E402
import bpy  # noqa: E402
import calibration_common as calibration  # noqa: E402


def new_scene(name, scale, lightmap=False):
    """A fresh file holding project scene `name` at `scale`, ready for Cycles and SHGI; with
    `lightmap`, its walls face inwards and carry LightmapUV (blender_scenes.SceneBuilder)."""
    calibration.reset_scene()
    setup.enable_addon()
    scene = blender_scenes.SCENES[name](scale, lightmap)
    for field, value in calibration.BOUNCES.items():  # the same limits for both engines
        setattr(scene.shgi, field, value)
    scene.shgi.clamp_indirect = scene.cycles.sample_clamp_indirect  # and the same clamp (0)
    scene.shgi.filter_glossy = scene.cycles.blur_glossy  # and the same Filter Glossy (0)
    # and the same pixel filter (Cycles' Box of width 1, reset_scene)
    scene.shgi.pixel_filter = scene.cycles.pixel_filter_type
    scene.shgi.filter_width = scene.cycles.filter_width
    # Compared with Cycles undenoised (reset_scene), as references are: the denoiser has its
    # own tests (engine_denoise_checks.py).
    scene.shgi.use_denoising = scene.shgi.use_viewport_denoising = False
    return scene


def render_f12(scene, engine, path):
    """F12 with `engine`; {pass name: float64 (H, W, C)} read back from the Render Result."""
    scene.render.engine = engine
    bpy.ops.render.render(write_still=False)
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    return setup.read_render_exr(path)


def mean_rgb(image):
    return float(image[..., :3].mean())
