"""Time and peak memory of exporting one big evaluated mesh (shgi_blender.export). Prints figures.

    blender -b --factory-startup --python bench/export_memory_bench.py -- \
        [build python dir (build/python)] [addon dir (addon)] [grid | flat-sphere] [UV maps (1)]

(Debian's Blender needs pyenv's folders off PATH, see tests/python/blender_support.py.)

grid: a 100 x 100 grid under a level-4 Subdivision Surface, smooth (5.12M triangles; most
corners of a vertex agree). flat-sphere: a 100 x 50 UV sphere under a level-4 Subdivision
Surface, flat-shaded (2.53M triangles; every corner of a vertex has its own normal, the
split's worst case). Printed: the export's wall time, the growth of the process's peak resident
memory per triangle (run in a fresh process: the peak before is Blender's start-up),
export/memory.py's bound for the mesh, and the longest stretch between two polls of the
export's should_stop (how late Esc during F12 can stop it).
"""

import os
import resource
import sys
import time

import bpy

REPO_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
sys.path[:0] = [ARGS[1] if len(ARGS) > 1 else os.path.join(REPO_ROOT, "addon"),
                ARGS[0] if len(ARGS) > 0 else os.path.join(REPO_ROOT, "build", "python")]
SHAPE = ARGS[2] if len(ARGS) > 2 else "grid"
UV_MAPS = int(ARGS[3]) if len(ARGS) > 3 else 1

from shgi_blender.export import export_scene, memory  # noqa: E402
from shgi_blender.export.mesh import triangle_count  # noqa: E402


def resident_bytes():
    with open("/proc/self/statm", encoding="ascii") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def peak_resident_bytes():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux: KiB


def build(shape, uv_maps):
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    if shape == "grid":
        bpy.ops.mesh.primitive_grid_add(x_subdivisions=100, y_subdivisions=100)
    else:
        bpy.ops.mesh.primitive_uv_sphere_add(segments=100, ring_count=50)
    obj = bpy.context.active_object
    modifier = obj.modifiers.new("Subdivision", "SUBSURF")
    modifier.levels = modifier.render_levels = 4
    if shape == "grid":
        bpy.ops.object.shade_smooth()
    else:
        bpy.ops.object.shade_flat()
    layers = obj.data.uv_layers
    while len(layers) > uv_maps:
        layers.remove(layers[-1])
    while len(layers) < uv_maps:
        layers.new(name=f"UVMap.{len(layers):03d}")
    return obj


def main():
    obj = build(SHAPE, UV_MAPS)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    mesh = obj.evaluated_get(depsgraph).data
    triangles = triangle_count(mesh)
    before = max(resident_bytes(), peak_resident_bytes())
    polls = []

    def should_stop():
        polls.append(time.perf_counter())
        return False

    start = time.perf_counter()
    result = export_scene(depsgraph, with_camera=False, should_stop=should_stop)
    seconds = time.perf_counter() - start
    stamps = [start, *polls, start + seconds]
    longest = max(b - a for a, b in zip(stamps, stamps[1:]))
    growth = peak_resident_bytes() - before
    assert result.stats.triangles == triangles, result.warnings
    print(f"{SHAPE}, {UV_MAPS} UV map(s), {triangles} triangles, Blender {bpy.app.version_string}:"
          f" export {seconds:.2f} s, peak +{growth / triangles:.0f} B per triangle (bound "
          f"{memory.export_bytes(triangles, UV_MAPS) / triangles:.0f}), should_stop polled "
          f"{len(polls)} times, at most {longest:.2f} s apart")


main()
