"""Whether the machine has the memory to export a mesh, asked before reading it (bpy-free).

An export copies each evaluated mesh out of Blender (corner arrays, the per-vertex split, the
shgi.Mesh) inside Blender's own process: a mesh too large for the free memory would get Blender
killed by the system with the artist's unsaved work. Such a mesh is left out with a warning
that says what it needs and how to lower it, before any of it is read.
"""

import os

# Peak bytes per triangle that reading one evaluated mesh adds to Blender's process, and the
# extra per UV map: upper bounds of the peaks measured on Blender 3.4.1 and the bpy 5.0.1
# module on a flat-shaded subdivided UV sphere (2.5M triangles; every corner of a vertex has
# its own normal, the worst case of the split): 371 and 431 B with no UV map, 467 and 431
# with one, 617 and 576 with three (3.4.1 and 5.0.1), plus a margin for the allocator's
# variation between runs. Smooth meshes peak near two thirds of this. Measured with
# bench/export_memory_bench.py (flat-sphere, 0, 1 and 3 UV maps);
# tests/blender/export_memory_checks.py checks the bound on every test run.
EXPORT_BYTES_PER_TRIANGLE = 480
EXPORT_BYTES_PER_TRIANGLE_PER_UV_MAP = 60
# The share of the available memory one mesh's export may take: the rest is left to Blender
# and to the scene's BVH, which commit() budgets on its own.
EXPORT_SHARE_OF_AVAILABLE = 0.8


def export_bytes(triangles, uv_maps):
    """Upper bound of the memory (bytes) reading a mesh of this size adds at its peak."""
    return triangles * (EXPORT_BYTES_PER_TRIANGLE + uv_maps * EXPORT_BYTES_PER_TRIANGLE_PER_UV_MAP)


def available_memory_bytes():
    """Memory the system can give without swapping (Linux MemAvailable), else the free
    physical pages; None when the system does not say."""
    try:
        with open("/proc/meminfo", encoding="ascii") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):
        return None


def export_memory_problem(triangles, uv_maps, available=None):
    """Why a mesh of `triangles` triangles with `uv_maps` UV maps cannot be exported with the
    memory available (bytes; default: available_memory_bytes()), or None when it can."""
    if available is None:
        available = available_memory_bytes()
    needed = export_bytes(triangles, uv_maps)
    if available is None or needed <= EXPORT_SHARE_OF_AVAILABLE * available:
        return None
    return (f"its {triangles:,} triangles need about {_size(needed)} of memory to export but "
            f"{_size(available)} is available; lower the Render levels of its Subdivision "
            "Surface or Multiresolution modifier (Properties > Modifiers), or free memory")


def _size(count):
    """Bytes in GiB, or in MiB below one GiB."""
    return f"{count / 2**30:.1f} GiB" if count >= 2**30 else f"{count / 2**20:.1f} MiB"
