"""Blender scene export, run inside each Blender (scripts in tests/blender/).

Each script builds its scenes with bpy from scratch, checks the exported shgi.Scene and prints a
success marker; a failed check raises, so Blender exits with 1 (--python-exit-code 1).
"""

import pytest

from blender_support import ADDON_DIR, BLENDER_SCRIPTS, run_blender

SCRIPTS = {
    "addon_register.py": "ADDON_REGISTER_OK",
    "export_scene_checks.py": "EXPORT_SCENE_OK",
    "export_camera_checks.py": "EXPORT_CAMERA_OK",
}


@pytest.mark.parametrize("script", sorted(SCRIPTS))
def test_blender_script(script, blender, build_python_dir):
    result = run_blender(BLENDER_SCRIPTS / script, build_python_dir, ADDON_DIR, blender=blender,
                         timeout=300)
    output = result.stdout[-4000:] + result.stderr[-4000:]
    assert result.returncode == 0, output
    assert SCRIPTS[script] in result.stdout, output
