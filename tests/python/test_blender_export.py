"""Blender scene export, run inside each Blender (scripts in tests/blender/), and the export's
checks of the values artists type, outside Blender.

Each script builds its scenes with bpy from scratch, checks the exported shgi.Scene and prints a
success marker; a failed check raises, so Blender exits with 1 (--python-exit-code 1).
"""

import math
import os
import sys

import numpy as np
import pytest

from blender_support import ADDON_DIR, BLENDER_SCRIPTS, REPO_ROOT, run_blender

sys.path.insert(0, str(REPO_ROOT / "addon"))

from shgi_blender.export import conversions  # noqa: E402

# Blender's largest float: what a typo in a Strength or Power field can reach.
BLENDER_FLOAT_MAX = 3.4028234663852886e38

SCRIPTS = {
    "addon_register.py": "ADDON_REGISTER_OK",
    "export_scene_checks.py": "EXPORT_SCENE_OK",
    "export_camera_checks.py": "EXPORT_CAMERA_OK",
    "export_memory_checks.py": "EXPORT_MEMORY_OK",
}


@pytest.mark.parametrize("script", sorted(SCRIPTS))
def test_blender_script(script, blender, build_python_dir):
    result = run_blender(BLENDER_SCRIPTS / script, build_python_dir, ADDON_DIR, blender=blender,
                         timeout=300)
    output = result.stdout[-4000:] + result.stderr[-4000:]
    assert result.returncode == 0, output
    assert SCRIPTS[script] in result.stdout, output


# --- values no renderer can use (no Blender) ---------------------------------------------------

def test_emitters_brighter_than_float32_sums_are_refused_by_name():
    """An emitter's colour x strength above MAX_EMISSION would overflow the native power sums:
    lights and the world raise ValueError naming what the artist set; the limit itself passes."""
    with pytest.raises(ValueError, match=r"^Power × Color is 3\.4e\+38 W, above the 1e\+20 W "
                                         r"SHGI renders \(its emitted power would overflow\)"):
        conversions.light_fields("POINT", BLENDER_FLOAT_MAX, (1.0, 1.0, 1.0), np.eye(4))
    with pytest.raises(ValueError, match=r"^Strength × 2\^Exposure × Color is 8e\+20 W/m²"):
        conversions.light_fields("SUN", 1e20, (1.0, 0.5, 0.5), np.eye(4), exposure=3.0)
    with pytest.raises(ValueError, match=r"^Background Color × Strength is 1\.5e\+37 W/m²/sr"):
        conversions.world_fields((0.05, 0.05, 0.05), 3e38)  # a new world's grey
    with pytest.raises(ValueError, match=r"Power × Color is \(nan, 1\.0, 1\.0\) × 10\.0, not "
                                         r"finite numbers"):
        conversions.light_fields("AREA", 10.0, (math.nan, 1.0, 1.0), np.eye(4))
    limit = conversions.MAX_EMISSION
    assert conversions.light_fields("POINT", limit, (1.0, 1.0, 1.0), np.eye(4))["power"] == limit
    assert conversions.world_fields((1.0, 1.0, 1.0), limit)["strength"] == limit
    assert conversions.emission_problem((0.0, 0.0, 0.0), BLENDER_FLOAT_MAX, "E", "W") is None


def test_material_inputs_that_are_not_numbers_are_named():
    fields = conversions.material_fields_from_principled(
        {"Base Color": (math.nan, 0.5, 0.5, 1.0), "Metallic": 0.0, "Roughness": math.inf,
         "IOR": 1.45, "Specular": 0.5, "Transmission": 0.0, "Emission": (0.0, 0.0, 0.0, 1.0),
         "Emission Strength": 1.0}, (3, 4, 1))
    assert conversions.non_finite_fields(fields) == ["base_color", "roughness"]
    names = conversions.input_names(conversions.PRINCIPLED_NODE, (4, 2, 0))
    assert (names["base_color"], names["emission_color"]) == ("Base Color", "Emission Color")
    assert conversions.input_names(conversions.EMISSION_NODE, (3, 4, 1)) == {
        "emission_color": "Color", "emission_strength": "Strength"}


# --- the export's memory check (no Blender) ----------------------------------------------------

def test_a_mesh_needing_more_than_the_available_memory_is_refused_with_the_fix():
    from shgi_blender.export import memory
    per_triangle = (memory.EXPORT_BYTES_PER_TRIANGLE
                    + 2 * memory.EXPORT_BYTES_PER_TRIANGLE_PER_UV_MAP)
    assert memory.export_bytes(18_000_000, 2) == 18_000_000 * per_triangle
    fits = int(memory.export_bytes(1000, 2) / memory.EXPORT_SHARE_OF_AVAILABLE) + 1
    assert memory.export_memory_problem(1000, 2, available=fits) is None
    problem = memory.export_memory_problem(18_000_000, 2, available=4 * 2**30)
    assert problem.startswith(f"its 18,000,000 triangles need about "
                              f"{18_000_000 * per_triangle / 2**30:.1f} GiB of memory to export "
                              "but 4.0 GiB is available; lower the Render levels of its Subdivision "
                              "Surface or Multiresolution modifier (Properties > Modifiers)")
    available = memory.available_memory_bytes()  # Linux's MemAvailable
    assert available is not None and 0 < available <= os.sysconf("SC_PHYS_PAGES") * os.sysconf(
        "SC_PAGE_SIZE")
