"""Per-corner Blender mesh data → per-vertex SHGI mesh arrays, without bpy.

Blender stores normals and UVs per face corner ("loop"); an shgi mesh stores them per vertex.
A Blender vertex therefore becomes one SHGI vertex per distinct (position index, normal, UVs...)
combination among its corners: smooth surfaces keep shared vertices, flat-shaded edges and UV
seams split them. Splitting is exact (bitwise equal corner data shares a vertex), done in numpy
with ``np.unique`` over rows.
"""

from dataclasses import dataclass, field

import numpy as np
import shgi


@dataclass
class SplitMesh:
    """Arrays ready for ``shgi.Scene.add_mesh``: one row per SHGI vertex."""

    positions: np.ndarray                        # (N, 3) float32, object space (m)
    triangles: np.ndarray                        # (T, 3) int32
    normals: np.ndarray | None = None            # (N, 3) float32 or None
    uvs: dict = field(default_factory=dict)      # {uv map name: (N, 2) float32}, in order
    tangents: np.ndarray | None = None           # (N, 4) float32 (xyz, bitangent sign) or None


def never_stop():
    """The default cancel point of the export steps: never stops."""


def require_finite_positions(positions, name):
    """ValueError naming the mesh, the first vertex with a coordinate SHGI cannot place (NaN,
    infinite, or beyond shgi.MAX_COORDINATE), that coordinate and the fix.

    Blender keeps an "inf" typed into a vertex field as its largest float, 3.4e+38: finite to
    numpy, but the normals computed from it are NaN, so it is reported as the inf it was.
    """
    positions = np.asarray(positions)
    placeable = np.abs(positions) <= shgi.MAX_COORDINATE  # False for NaN too
    bad = np.flatnonzero(~placeable.all(axis=1))
    if bad.size:
        vertex = int(bad[0])
        axis = int(np.flatnonzero(~placeable[vertex])[0])
        value = float(positions[vertex, axis])
        more = f" (and {bad.size - 1} more vertices)" if bad.size > 1 else ""
        raise ValueError(
            f"mesh {name!r}: vertex {vertex} has {'xyz'[axis]} = {_coordinate_text(value)}{more}; "
            f"SHGI places coordinates within "
            f"±{shgi.MAX_COORDINATE:g} m: move the vertex back (Edit Mode, Sidebar > Item > "
            "Vertex) or fix the modifier or geometry nodes that put it there")


def _coordinate_text(value):
    """A coordinate as the artist knows it: nan, ±inf (Blender's largest float included), or
    the number in metres."""
    if np.isnan(value):
        return "nan"
    if abs(value) >= np.finfo(np.float32).max:
        return "inf" if value > 0 else "-inf"
    return f"{value:g} m"


def split_corners(positions, corner_vertices, corner_normals=None, corner_uvs=None,
                  name="mesh", check_stop=never_stop, corner_tangents=None):
    """Builds per-vertex arrays from per-corner data of a triangle list.

    positions: (V, 3) Blender vertex positions. corner_vertices: (3T,) vertex index of each
    triangle corner, three per triangle in winding order. corner_normals: (3T, 3) or None.
    corner_uvs: {uv map name: (3T, 2)} or None. corner_tangents: (3T, 4) (tangent, bitangent
    sign) or None; NaN tangents are kept (shgi drops them with a warning). Attributes are compared as the float32 values
    the SplitMesh stores (so 0.0 and -0.0 share a vertex). Returns a SplitMesh whose vertices
    are ordered by Blender vertex index, then by the first corner that uses them.
    Raises ValueError naming the mesh for mismatched sizes, bad indices or non-finite data.
    check_stop is called between the steps (a cancel point: it may raise).

    Memory: each corner is compared with the first corner of its Blender vertex, and only the
    corners that differ from it (creases, UV seams) are sorted by their data, so that meshes of
    tens of millions of triangles (a Subdivision Surface at render levels) split without running
    the machine out of memory: about 28 bytes per corner beyond the inputs and the result on a
    smooth grid, where few corners differ; more where most do (flat shading).
    """
    positions = np.asarray(positions, dtype=np.float32).reshape(-1, 3)
    corner_vertices = np.asarray(corner_vertices).ravel()
    corners = corner_vertices.size
    if corners % 3:
        raise ValueError(f"mesh {name!r}: {corners} corners is not a multiple of 3")
    if corners and (corner_vertices.min() < 0 or corner_vertices.max() >= len(positions)):
        raise ValueError(f"mesh {name!r}: corner vertex indices must lie in "
                         f"[0, {len(positions)})")
    require_finite_positions(positions, name)
    attributes = []  # (corners, width) float32 arrays: the normals, then each UV map
    if corner_normals is not None:
        corner_normals = _corner_array(corner_normals, corners, 3, f"mesh {name!r}: normals")
        attributes.append(corner_normals)
    corner_uvs = {uv_name: _corner_array(uv, corners, 2, f"mesh {name!r}: UV map {uv_name!r}")
                  for uv_name, uv in (corner_uvs or {}).items()}
    attributes.extend(corner_uvs.values())
    if corner_tangents is not None:
        corner_tangents = np.asarray(corner_tangents, dtype=np.float32)
        if corner_tangents.size != corners * 4:
            raise ValueError(f"mesh {name!r}: tangents: {corner_tangents.size} values for "
                             f"{corners} corners × 4")
        corner_tangents = corner_tangents.reshape(corners, 4)
        # Compared as finite values (NaN != NaN would split every such corner): zero them,
        # which shgi reads as "no tangent" as it would the NaN.
        corner_tangents = np.where(np.isfinite(corner_tangents), corner_tangents,
                                   np.float32(0.0))
        attributes.append(corner_tangents)
    check_stop()

    # Group the corners by Blender vertex; each group's first corner is its representative.
    order = np.argsort(corner_vertices, kind="stable")
    sorted_vertices = corner_vertices[order]
    group_start = np.flatnonzero(np.diff(sorted_vertices, prepend=-1))
    groups = group_start.size
    representative = order[group_start]  # the first corner of each used vertex
    group = np.empty(corners, dtype=_index_type(groups))
    group[order] = np.repeat(np.arange(groups, dtype=group.dtype),
                             np.diff(group_start, append=corners))
    del order, sorted_vertices, group_start
    check_stop()

    # Corners whose data differ from their representative's become extra vertices: one per
    # distinct (vertex, data) among them, numbered in the order of their first corner.
    same = np.ones(corners, dtype=bool)
    for attribute in attributes:
        for column in range(attribute.shape[1]):
            values = attribute[:, column]
            same &= values == values[representative][group]
    differing = np.flatnonzero(~same)
    del same
    check_stop()
    corner_to_vertex = group.astype(np.int64)
    first_corners = representative
    if differing.size:
        columns = [group[differing]]
        for attribute in attributes:
            values = attribute[differing] + np.float32(0.0)  # -0.0 becomes 0.0
            columns += [values[:, column].view(np.uint32) for column in range(values.shape[1])]
        check_stop()
        first, inverse = distinct_rows(columns, check_stop=check_stop)
        corner_to_vertex[differing] = groups + inverse
        first_corners = np.concatenate([representative, differing[first]])
        check_stop()
    del group

    # Renumber: by Blender vertex, then by first corner (representatives come first).
    # One key per vertex, (Blender vertex, first corner), all distinct: one unstable sort.
    vertex_order = np.argsort(corner_vertices[first_corners].astype(np.int64) * corners
                              + first_corners)
    new_index = np.empty(vertex_order.size, dtype=np.int64)
    new_index[vertex_order] = np.arange(vertex_order.size)
    first_corners = first_corners[vertex_order]
    split = SplitMesh(positions=positions[corner_vertices[first_corners]],
                      triangles=new_index[corner_to_vertex].astype(np.int32).reshape(-1, 3))
    if corner_normals is not None:
        split.normals = corner_normals[first_corners]
    split.uvs = {uv_name: uv[first_corners] for uv_name, uv in corner_uvs.items()}
    if corner_tangents is not None:
        split.tangents = corner_tangents[first_corners]
    return split


def distinct_rows(columns, row_hash=None, check_stop=never_stop):
    """The distinct rows of a table given as equal-length integer columns: (first, inverse),
    where first[k] is the index of the first row of the k-th distinct row (ascending) and
    inverse[i] the distinct row of row i.

    Rows are sorted by a 64-bit hash (one sort, where sorting the rows themselves takes one per
    column), then every row is compared with the first row of its hash: exact. Should two
    different rows share a hash, the rows are sorted themselves instead. row_hash: the hash
    function (columns → (n,) uint64), for tests. check_stop: called between the steps.
    """
    hashes = (row_hash or _row_hash)(columns)
    check_stop()
    order = np.argsort(hashes)
    sorted_hashes = hashes[order]
    del hashes
    run_start = np.flatnonzero(np.diff(sorted_hashes, prepend=~sorted_hashes[:1]))
    del sorted_hashes
    first = np.minimum.reduceat(order, run_start)  # each run's first row (the sort is unstable)
    inverse = np.empty(order.size, dtype=np.int64)
    inverse[order] = np.repeat(np.arange(run_start.size), np.diff(run_start, append=order.size))
    del order, run_start
    check_stop()
    representative = first[inverse]
    if not all(np.array_equal(column, column[representative]) for column in columns):
        # Two different rows share a hash.
        _, first, inverse = np.unique(np.stack(columns, axis=1), axis=0, return_index=True,
                                      return_inverse=True)
        inverse = np.asarray(inverse).ravel()
    del representative
    check_stop()
    by_first = np.argsort(first)  # the values are distinct: no need for a stable sort
    rank = np.empty_like(by_first)
    rank[by_first] = np.arange(by_first.size)
    return first[by_first], rank[inverse]


def _row_hash(columns):
    """A 64-bit hash of each row (FNV-1a over the columns' words, then a final mix)."""
    hashes = np.full(columns[0].size, 0xCBF29CE484222325, dtype=np.uint64)
    for column in columns:
        hashes ^= column.astype(np.uint64)
        hashes *= np.uint64(0x100000001B3)
        hashes ^= hashes >> np.uint64(29)
    return hashes


def _index_type(count):
    """The smallest of int32 and int64 that holds indices below `count`."""
    return np.int32 if count < 2**31 else np.int64


def _corner_array(values, corners, width, what):
    """(corners, width) float32 per-corner data; ValueError for a wrong size or NaN."""
    array = np.asarray(values, dtype=np.float32)
    if array.size != corners * width:
        raise ValueError(f"{what}: {array.size} values for {corners} corners × {width}")
    array = array.reshape(corners, width)
    if not np.isfinite(array).all():
        bad = int(np.flatnonzero(~np.isfinite(array).all(axis=1))[0])
        raise ValueError(f"{what}: corner {bad} is {tuple(array[bad].tolist())}; "
                         "values must be finite")
    return array
