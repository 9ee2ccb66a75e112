"""An evaluated Blender mesh → per-corner numpy arrays → a SplitMesh (bpy side).

Bulk data goes through ``foreach_get`` into numpy: vertex positions, the loop triangles' loops,
vertices and material indices, the corner ("split") normals and every UV map. Corner normals
come from ``Mesh.corner_normals`` on Blender 4.1+ and ``calc_normals_split()`` before.
UV maps are ordered with the active render UV map first: SHGI textures read the first UV set,
as Blender reads the render UV map when an Image Texture's Vector input is unlinked. Tangents,
when a material's normal map asks for them, are Blender's own MikkTSpace tangents of that UV map
(``Mesh.calc_tangents``), per corner with their bitangent sign, as Cycles reads them.
"""

import numpy as np

from .mesh_split import never_stop, require_finite_positions, split_corners


def read_mesh(mesh, name, check_stop=never_stop, tangent_uv_map=None, log=None):
    """(SplitMesh, (T,) int32 Blender material index per triangle) of a Blender mesh.

    tangent_uv_map: None, or the UV map whose tangents a normal map reads ('' = the render UV
    map); tangents that cannot be computed (no such UV map, n-gons) are left out with a
    warning to `log`. Raises ValueError naming the mesh for a non-finite vertex. check_stop is
    called between the reading stages and may raise to stop.
    """
    positions = _foreach(mesh.vertices, "co", np.float32, len(mesh.vertices) * 3).reshape(-1, 3)
    # Check before the normals are computed, which would spread the NaN around.
    require_finite_positions(positions, name)
    check_stop()
    mesh.calc_loop_triangles()
    check_stop()
    triangles = mesh.loop_triangles
    corner_loops = _foreach(triangles, "loops", np.int32, len(triangles) * 3)
    corner_vertices, material_indices = _triangle_vertices_and_materials(mesh, corner_loops)
    check_stop()
    corner_normals = _loop_normals(mesh)[corner_loops]
    check_stop()
    corner_uvs = {layer.name: _foreach(layer.data, "uv", np.float32,
                                       len(mesh.loops) * 2).reshape(-1, 2)[corner_loops]
                  for layer in _uv_layers_render_first(mesh)}
    corner_tangents = None
    if tangent_uv_map is not None:
        corner_tangents = _loop_tangents(mesh, tangent_uv_map, name, log)
        if corner_tangents is not None:
            corner_tangents = corner_tangents[corner_loops]
    check_stop()
    split = split_corners(positions, corner_vertices, corner_normals, corner_uvs, name=name,
                          check_stop=check_stop, corner_tangents=corner_tangents)
    return split, material_indices


def triangle_count(mesh):
    """Triangles of a Blender mesh without triangulating it: a polygon of n corners makes n - 2."""
    return len(mesh.loops) - 2 * len(mesh.polygons)


def _triangle_vertices_and_materials(mesh, corner_loops):
    """((3T,) int32 vertex of each triangle corner, (T,) int32 material index of each triangle).

    On Blender 4.x/5.x both come from arrays Blender stores (the corners' vertices, the
    triangles' polygons, the faces' material_index attribute), which foreach_get copies whole;
    the loop triangles' own "vertices" and "material_index" go through Blender's property
    accessors one triangle at a time, ~0.16 s of a 523k-triangle mesh's ~1 s F12. Blender 3.4
    (no loop_triangle_polygons) and any build without those arrays read them the slow way,
    with the same values (test_blender_export)."""
    triangles = mesh.loop_triangles
    corner_vert = mesh.attributes.get(".corner_vert")
    if (hasattr(mesh, "loop_triangle_polygons") and corner_vert is not None
            and corner_vert.domain == "CORNER" and corner_vert.data_type == "INT"):
        vertices = _foreach(corner_vert.data, "value", np.int32, len(mesh.loops))[corner_loops]
        polygons = _foreach(mesh.loop_triangle_polygons, "value", np.int32, len(triangles))
        materials = mesh.attributes.get("material_index")
        if materials is None:  # Blender leaves it out while every face uses slot 0
            return vertices, np.zeros(len(triangles), dtype=np.int32)
        faces = _foreach(materials.data, "value", np.int32, len(mesh.polygons))
        return vertices, faces[polygons]
    return (_foreach(triangles, "vertices", np.int32, len(triangles) * 3),
            _foreach(triangles, "material_index", np.int32, len(triangles)))


def _loop_normals(mesh):
    """(L, 3) float32 corner normals (flat, smooth, auto-smooth and custom as Blender shades)."""
    loops = len(mesh.loops)
    if hasattr(mesh, "corner_normals"):  # Blender 4.1+
        return _foreach(mesh.corner_normals, "vector", np.float32, loops * 3).reshape(-1, 3)
    mesh.calc_normals_split()
    return _foreach(mesh.loops, "normal", np.float32, loops * 3).reshape(-1, 3)


def _loop_tangents(mesh, uv_map, name, log):
    """(L, 4) float32 MikkTSpace tangents and bitangent signs of `uv_map` ('' = the render UV
    map), or None after a warning when Blender cannot compute them."""
    layers = _uv_layers_render_first(mesh)
    if uv_map == "" and layers:
        uv_map = layers[0].name
    if uv_map not in [layer.name for layer in layers]:
        if log is not None:
            log.warn(f"mesh {name!r}: a normal map reads UV map {uv_map!r}, which the mesh does "
                     "not have; it is shaded without its normal map")
        return None
    try:
        mesh.calc_tangents(uvmap=uv_map)
    except RuntimeError as error:  # e.g. n-gons: Blender computes tangents of tris and quads
        if log is not None:
            log.warn(f"mesh {name!r}: Blender cannot compute tangents of UV map {uv_map!r} "
                     f"({error}); it is shaded without its normal map (triangulate it)")
        return None
    loops = len(mesh.loops)
    tangents = np.empty((loops, 4), dtype=np.float32)
    tangents[:, :3] = _foreach(mesh.loops, "tangent", np.float32, loops * 3).reshape(-1, 3)
    tangents[:, 3] = _foreach(mesh.loops, "bitangent_sign", np.float32, loops)
    mesh.free_tangents()
    return tangents


def _uv_layers_render_first(mesh):
    """The mesh's UV maps with the active render one first, the others in Blender's order."""
    layers = list(mesh.uv_layers)
    return sorted(layers, key=lambda layer: not layer.active_render)


def _foreach(collection, attribute, dtype, size):
    """A flat numpy array of `attribute` over a bpy collection, read with foreach_get."""
    array = np.empty(size, dtype=dtype)
    if size:
        collection.foreach_get(attribute, array)
    return array
