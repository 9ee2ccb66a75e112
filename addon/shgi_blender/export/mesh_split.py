"""Per-corner Blender mesh data → per-vertex SHGI mesh arrays, without bpy.

Blender stores normals and UVs per face corner ("loop"); an shgi mesh stores them per vertex.
A Blender vertex therefore becomes one SHGI vertex per distinct (position index, normal, UVs...)
combination among its corners: smooth surfaces keep shared vertices, flat-shaded edges and UV
seams split them. Splitting is exact (bitwise equal corner data shares a vertex), done in numpy
with ``np.unique`` over rows.
"""

from dataclasses import dataclass, field

import numpy as np


@dataclass
class SplitMesh:
    """Arrays ready for ``shgi.Scene.add_mesh``: one row per SHGI vertex."""

    positions: np.ndarray                        # (N, 3) float32, object space (m)
    triangles: np.ndarray                        # (T, 3) int32
    normals: np.ndarray | None = None            # (N, 3) float32 or None
    uvs: dict = field(default_factory=dict)      # {uv map name: (N, 2) float32}, in order


def require_finite_positions(positions, name):
    """ValueError naming the mesh and the first vertex with a NaN or infinite coordinate."""
    positions = np.asarray(positions)
    bad = np.flatnonzero(~np.isfinite(positions).all(axis=1))
    if bad.size:
        vertex = int(bad[0])
        raise ValueError(f"mesh {name!r}: vertex {vertex} is {tuple(positions[vertex].tolist())}; "
                         f"all coordinates must be finite ({bad.size} such vertices)")


def split_corners(positions, corner_vertices, corner_normals=None, corner_uvs=None,
                  name="mesh"):
    """Builds per-vertex arrays from per-corner data of a triangle list.

    positions: (V, 3) Blender vertex positions. corner_vertices: (3T,) vertex index of each
    triangle corner, three per triangle in winding order. corner_normals: (3T, 3) or None.
    corner_uvs: {uv map name: (3T, 2)} or None. Returns a SplitMesh whose vertices are the
    distinct corner rows (ordered by vertex index, then attributes).
    Raises ValueError naming the mesh for mismatched sizes, bad indices or non-finite data.
    """
    positions = np.asarray(positions, dtype=np.float32).reshape(-1, 3)
    corner_vertices = np.asarray(corner_vertices, dtype=np.int64).ravel()
    corner_uvs = dict(corner_uvs or {})
    corners = corner_vertices.size
    if corners % 3:
        raise ValueError(f"mesh {name!r}: {corners} corners is not a multiple of 3")
    if corners and (corner_vertices.min() < 0 or corner_vertices.max() >= len(positions)):
        raise ValueError(f"mesh {name!r}: corner vertex indices must lie in "
                         f"[0, {len(positions)})")
    require_finite_positions(positions, name)
    columns = [corner_vertices[:, None].astype(np.float64)]
    if corner_normals is not None:
        corner_normals = _corner_array(corner_normals, corners, 3, f"mesh {name!r}: normals")
        columns.append(corner_normals)
    for uv_name, uv in corner_uvs.items():
        corner_uvs[uv_name] = _corner_array(uv, corners, 2,
                                            f"mesh {name!r}: UV map {uv_name!r}")
        columns.append(corner_uvs[uv_name])
    keys = np.concatenate(columns, axis=1)
    _, first_corner, corner_to_vertex = np.unique(
        keys, axis=0, return_index=True, return_inverse=True)
    corner_to_vertex = np.asarray(corner_to_vertex).ravel()
    split = SplitMesh(positions=positions[corner_vertices[first_corner]],
                      triangles=corner_to_vertex.reshape(-1, 3).astype(np.int32))
    if corner_normals is not None:
        split.normals = corner_normals[first_corner].astype(np.float32)
    split.uvs = {uv_name: uv[first_corner].astype(np.float32) for uv_name, uv in corner_uvs.items()}
    return split


def _corner_array(values, corners, width, what):
    """(corners, width) float64 copy of per-corner data; ValueError for a wrong size or NaN."""
    array = np.asarray(values, dtype=np.float64)
    if array.size != corners * width:
        raise ValueError(f"{what}: {array.size} values for {corners} corners × {width}")
    array = array.reshape(corners, width)
    if not np.isfinite(array).all():
        bad = int(np.flatnonzero(~np.isfinite(array).all(axis=1))[0])
        raise ValueError(f"{what}: corner {bad} is {tuple(array[bad].tolist())}; "
                         "values must be finite")
    return array
