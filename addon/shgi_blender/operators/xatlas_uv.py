"""Create UV Map with xatlas (bpy): a lightmap UV map laid out by shgi.uv_atlas (xatlas), the
alternative to Blender's Lightmap Pack.

xatlas sees the mesh's triangles (Blender's loop triangles) in world space, so the charts keep
their relative sizes on a scaled object, and packs them into the square of the object's
lightmap size (the bake's Resolution, or the size its Texel Density gives) with
shgi.bake.BakeOptions' uv_padding empty texels around each chart. Its vertices are split at
chart seams; Blender keeps UVs per face corner (loop), so each triangle corner's UV goes to its
loop. A polygon whose triangles fell into different charts would need two UVs at one corner:
xatlas cuts charts along sharp creases, so that happens only on strongly non-planar polygons,
and the corners that disagree are counted (the caller warns).
"""

import numpy as np


def loop_triangles(obj):
    """(world positions (N, 3) float64, triangles (T, 3) int64, loops (T, 3) int64) of the
    object's mesh: Blender's triangulation, vertices moved by matrix_world."""
    mesh = obj.data
    mesh.calc_loop_triangles()
    count = len(mesh.loop_triangles)
    vertices = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", vertices)
    triangles = np.empty(count * 3, np.int32)
    mesh.loop_triangles.foreach_get("vertices", triangles)
    loops = np.empty(count * 3, np.int32)
    mesh.loop_triangles.foreach_get("loops", loops)
    matrix = np.array(obj.matrix_world, np.float64)
    positions = vertices.reshape(-1, 3).astype(np.float64) @ matrix[:3, :3].T + matrix[:3, 3]
    return positions, triangles.reshape(-1, 3).astype(np.int64), loops.reshape(-1, 3)


def lay_out(obj, layer, resolution, texel_density, size_limits):
    """Fills UV layer `layer` of the object's mesh with an xatlas layout; (report, disagreeing
    corners). `resolution` > 0 is the lightmap's size; else the size follows from
    `texel_density` (texels per metre) as the bake sizes it (shgi.bake.resolution_for_area
    between `size_limits`). ValueError when the mesh has no faces."""
    from shgi import bake as shgi_bake
    from shgi import uv_atlas

    positions, triangles, loops = loop_triangles(obj)
    if len(triangles) == 0:
        raise ValueError(f"object {obj.name!r} has no faces to lay out")
    if resolution <= 0:
        resolution = shgi_bake.resolution_for_area(shgi_bake.surface_area(positions, triangles),
                                                   texel_density, *size_limits)
    layout = uv_atlas.lightmap_uvs(positions, triangles, resolution=resolution,
                                   padding=shgi_bake.BakeOptions().uv_padding)
    corner_uvs = layout.uvs[layout.triangles.reshape(-1)].astype(np.float64)
    loop_uvs = np.zeros((len(obj.data.loops), 2), np.float64)
    loop_uvs[loops.reshape(-1)] = corner_uvs  # the last triangle of a shared corner wins
    disagreeing = int(np.count_nonzero(
        np.abs(loop_uvs[loops.reshape(-1)] - corner_uvs).max(axis=1) > 1e-6))
    layer.data.foreach_set("uv", loop_uvs.astype(np.float32).reshape(-1))
    return layout.report, disagreeing
