"""Installs a `make dist` package into a clean Blender profile and renders with it.

Run by tests/python/test_dist.py with BLENDER_USER_SCRIPTS (and, for 4.2+, BLENDER_USER_
EXTENSIONS and BLENDER_USER_CONFIG) pointing at empty folders, as
``blender -b --factory-startup --python-exit-code 1 --python dist_install_checks.py --
<package zip> <results json>``: the add-on zip on Blender 3.4 to 4.1 (Preferences > Add-ons >
Install), the extension zip on 4.2+ (Install from Disk). Neither the build tree nor the
repository's add-on folder is put on sys.path: `shgi` must come from the package.

Then F12 of the project's Cornell box (64 x 64, no specular layer) with the SHGI engine's path
tracer and with Cycles at the same samples; the results JSON holds where shgi and the add-on were loaded from
and both Combined means. Prints DIST_INSTALL_OK.
"""

import importlib
import json
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402  (not add_import_paths: no build tree here)

sys.path.insert(0, str(setup.REPO_ROOT / "examples"))

import addon_utils  # noqa: E402
import blender_scenes  # noqa: E402
import bpy  # noqa: E402
import numpy as np  # noqa: E402

SCALE = 0.25          # 256 x 256 -> 64 x 64 pixels
SAMPLES = 64
# Blender 4.2 turned add-ons with a blender_manifest.toml into extensions.
EXTENSIONS_VERSION = (4, 2, 0)


def install(package):
    """Installs and enables the package; the add-on's module name."""
    if bpy.app.version >= EXTENSIONS_VERSION:
        result = bpy.ops.extensions.package_install_files(
            filepath=package, repo="user_default", enable_on_install=True)
        module = "bl_ext.user_default.shgi_blender"
    else:
        result = bpy.ops.preferences.addon_install(filepath=package)
        module = "shgi_blender"
        if addon_utils.enable(module, default_set=True, handle_error=None) is None:
            raise AssertionError(f"{module} did not enable after installing {package}")
    if result != {"FINISHED"}:
        raise AssertionError(f"installing {package} returned {result}")
    if module not in bpy.context.preferences.addons:
        raise AssertionError(f"{module} is not among the enabled add-ons: "
                             f"{sorted(bpy.context.preferences.addons.keys())}")
    return module


def render_mean(scene, engine, folder):
    """F12 with `engine`; the mean of Combined's RGB, read back from the Render Result."""
    scene.render.engine = engine
    bpy.ops.render.render(write_still=False)
    path = os.path.join(folder, f"{engine}.exr")
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    shgi = sys.modules["shgi"]  # the packaged module (checked in main)
    layers = {name.split(".")[-1]: pixels for name, pixels in shgi.read_exr(path).items()}
    combined = np.asarray(layers["Combined"], np.float64)[..., :3]
    if not np.isfinite(combined).all():
        raise AssertionError(f"{engine}: Combined has non-finite pixels")
    return float(combined.mean())


def main():
    package, results_path = setup.script_args()[:2]
    profile = os.environ["BLENDER_USER_SCRIPTS"]
    module = install(package)
    addon = sys.modules[module]
    shgi = importlib.import_module(f"{module}.native").module()  # as the add-on imports it
    if shgi is None:
        raise AssertionError(importlib.import_module(f"{module}.native").error())
    where = {"shgi": os.path.realpath(shgi.__file__), "addon": os.path.realpath(addon.__file__)}
    # Extensions live beside the scripts folder of the clean profile (BLENDER_USER_EXTENSIONS).
    roots = [os.path.realpath(p)
             for p in (profile, os.environ.get("BLENDER_USER_EXTENSIONS", profile))]
    for name, path in where.items():
        if not any(path.startswith(root + os.sep) for root in roots):
            raise AssertionError(f"{name} was loaded from {path}, not from the clean profile")

    scene = blender_scenes.cornell_box(SCALE)
    # Without the Principled BSDF's specular layer: SHGI's material is Blender 3.4's Principled,
    # and Cycles 4+ dims the diffuse under the specular (docs/addon.md, "Blender versions"), which is
    # not what this test is about.
    for material in bpy.data.materials:
        for node in material.node_tree.nodes if material.node_tree else ():
            for name in ("Specular", "Specular IOR Level"):
                if node.bl_idname == "ShaderNodeBsdfPrincipled" and name in node.inputs:
                    node.inputs[name].default_value = 0.0
    setup.use_multilayer_exr(scene.render.image_settings)
    scene.cycles.device = "CPU"
    scene.cycles.samples = SAMPLES
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.pixel_filter_type = "BOX"  # SHGI's default pixel filter
    scene.cycles.filter_width = 1.0
    for limit in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces"):
        setattr(scene.cycles, limit, getattr(scene.shgi, limit))
    scene.shgi.method = "PATH_TRACE"
    scene.shgi.samples = SAMPLES
    with tempfile.TemporaryDirectory() as folder:
        means = {engine: render_mean(scene, engine, folder) for engine in ("SHGI", "CYCLES")}
    results = {"blender": bpy.app.version_string, "module": module, "where": where,
               "shgi_version": shgi.__version__, "means": means}
    with open(results_path, "w") as f:
        json.dump(results, f, indent=1)
    print(f"shgi {shgi.__version__} from {where['shgi']}; Combined mean SHGI "
          f"{means['SHGI']:.5f}, Cycles {means['CYCLES']:.5f}")
    print("DIST_INSTALL_OK")


main()
