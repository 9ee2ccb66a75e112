"""shgi imports and works inside each Blender (Debian's 3.4.1 and the bpy module)."""

from blender_support import run_blender

SCRIPT = """
import sys
sys.path.insert(0, {path!r})
import numpy as np
import shgi
scene = shgi.Scene()
scene.add_material(shgi.Material())
mesh_id = scene.add_mesh(positions=np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32),
                         triangles=np.array([[0, 1, 2]], np.int32))
scene.add_instance(mesh_id, np.eye(4))
scene.commit()
hits = scene.intersect(np.array([[0.2, 0.2, 1.0]], np.float32), np.array([[0, 0, -1.0]], np.float32))
assert abs(float(hits["t"][0]) - 1.0) < 1e-6, hits
print("SHGI_IN_BLENDER", shgi.__version__, shgi.__file__)
"""


def test_shgi_imports_and_traces_inside_blender(blender, build_python_dir, tmp_path):
    script = tmp_path / "import_shgi.py"
    script.write_text(SCRIPT.format(path=str(build_python_dir)))
    result = run_blender(script, blender=blender, timeout=300)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    assert "SHGI_IN_BLENDER" in result.stdout
