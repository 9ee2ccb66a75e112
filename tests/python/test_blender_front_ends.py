"""Every front end gives the same image for the same scene and settings, and a GI method
registered once (tests/python/method_plugin.py, through SHGI_METHOD_PLUGINS) reaches the add-on
with no other edit: tests/blender/front_ends.py in each Blender (F12 against a script's render,
the Bake Lightmaps operator against shgi.bake.bake_scene). The CLI and shgi.bake are compared
byte for byte in test_methods.py."""

from blender_support import run_script_once

# tests/python/method_plugin.py's method and file number (not imported here: it would register
# the method in this process too).
PLUGIN, PLUGIN_NUMBER = "SINGLE_PROBE_TEST", 90
METHODS = ("PHOTON_LATTICE", "PROBE_GRID", PLUGIN)
# The objects front_ends.py bakes (BAKED_OBJECTS).
BAKED_OBJECTS = ("back", "floor", "left", "short_block")


def _results(blender, build_python_dir, tmp_path_factory):
    return run_script_once("front_ends.py", "FRONT_ENDS_OK", build_python_dir, tmp_path_factory,
                           blender=blender)


def test_f12_equals_a_script_and_a_plugin_method_reaches_the_addon(blender, build_python_dir,
                                                                      tmp_path_factory):
    results = _results(blender, build_python_dir, tmp_path_factory)
    for method in METHODS:
        assert results[method]["identical"], results[method]
        assert results[method]["mean"] > 0.01, results[method]
    assert results["render_methods"][PLUGIN] == PLUGIN_NUMBER
    assert results["bake_sources"][PLUGIN] == PLUGIN_NUMBER
    assert results["bake_sources"]["PATH_TRACE"] == 0  # the old PATH_TRACER's number
    assert results["plugin_bake"]["status"] == ["FINISHED"]
    assert results["plugin_bake"]["mean"] > 0.0


def test_bake_operator_equals_shgi_bake_texel_for_texel(blender, build_python_dir,
                                                       tmp_path_factory):
    """The operator's float images and bake_scene's Lightmap.color: array_equal, lit."""
    results = _results(blender, build_python_dir, tmp_path_factory)
    for method in METHODS:
        rows = results[f"bake_{method}"]
        assert sorted(rows) == sorted(BAKED_OBJECTS), rows
        for name, row in rows.items():
            assert row["identical"], (method, name, row)
            assert row["mean"] > 0.0, (method, name, row)
