"""The export's memory bound (shgi_blender.export.memory) holds, and a mesh over it is left out
by name before it is read.

1. Peak: exporting a flat-shaded UV sphere under a Subdivision Surface (633,600 triangles, one
   UV map; every corner of a vertex has its own normal, the split's worst case) raises the
   process's peak resident memory by no more than memory.export_bytes() says. Runs first, in a
   fresh process, so that the peak it reads is the export's own.
2. Refusal: with the available memory reported as 16 MiB, a cube under a level-6 Subdivision
   Surface (49,152 triangles, 25.3 MiB by the bound) is skipped with a warning naming it, its
   triangle count and the fix, while a plane beside it is exported.
Prints EXPORT_MEMORY_OK.
"""

import os
import resource
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()

import bpy  # noqa: E402
from shgi_blender.export import export_scene, memory  # noqa: E402
from shgi_blender.export.mesh import triangle_count  # noqa: E402


def resident_bytes():
    with open("/proc/self/statm", encoding="ascii") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def peak_resident_bytes():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux: KiB


def subdivided(obj, levels):
    modifier = obj.modifiers.new("Subdivision", "SUBSURF")
    modifier.levels = modifier.render_levels = levels
    return obj


def check_peak_within_bound():
    setup.clear_scene()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=100, ring_count=50)
    sphere = subdivided(bpy.context.active_object, 3)
    bpy.ops.object.shade_flat()
    depsgraph = bpy.context.evaluated_depsgraph_get()
    mesh = sphere.evaluated_get(depsgraph).data
    triangles = triangle_count(mesh)
    uv_maps = len(mesh.uv_layers)
    bound = memory.export_bytes(triangles, uv_maps)
    before = max(resident_bytes(), peak_resident_bytes())
    result = export_scene(depsgraph, with_camera=False)
    growth = peak_resident_bytes() - before
    if result.stats.triangles != triangles or uv_maps != 1:
        raise AssertionError(f"exported {result.stats.triangles} of {triangles} triangles, "
                             f"{uv_maps} UV maps")
    print(f"export peak: {growth / triangles:.0f} B per triangle over {triangles} triangles; "
          f"bound {bound / triangles:.0f}")
    if growth > bound:
        raise AssertionError(f"the export's peak grew by {growth} bytes, above the bound "
                             f"{bound} of memory.export_bytes({triangles}, {uv_maps})")


def check_refusal():
    setup.clear_scene()
    bpy.ops.mesh.primitive_cube_add()
    bpy.context.active_object.name = "HeavyCube"
    subdivided(bpy.context.active_object, 6)
    bpy.ops.mesh.primitive_plane_add(location=(0.0, 0.0, -2.0))
    bpy.context.active_object.name = "Floor"
    real = memory.available_memory_bytes
    memory.available_memory_bytes = lambda: 16 * 2**20
    try:
        result = export_scene(bpy.context.evaluated_depsgraph_get(), with_camera=False)
    finally:
        memory.available_memory_bytes = real
    problem = result.skipped.get("HeavyCube", "")
    for part in ("49,152 triangles", "25.3 MiB of memory", "16.0 MiB is available",
                 "Render levels", "Properties > Modifiers"):
        if part not in problem:
            raise AssertionError(f"HeavyCube's problem lacks {part!r}: {problem!r}")
    if not any("object 'HeavyCube': its 49,152 triangles" in w for w in result.warnings):
        raise AssertionError(f"no warning names HeavyCube: {result.warnings}")
    if result.stats.triangles != 2 or result.stats.instances != 1:
        raise AssertionError(f"expected only Floor's 2 triangles: {result.stats}")


def main():
    check_peak_within_bound()
    check_refusal()
    print("EXPORT_MEMORY_OK")


main()
