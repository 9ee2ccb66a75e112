"""The lattice overlay's spheres: one per lattice cell holding surface. No bpy.

Cells: the global lattice's grid as lattice/sh_lattice.h lays it, cubes of side (longest side of
the scene's bounds) / resolution, centred on the bounds, each axis a whole number of cells.
(The native grid also adds a 1e-4 margin; at overlay scale that is invisible.) A cell holds
surface when a point sampled on a triangle falls inside it: triangles are sampled on a
barycentric grid at half a cell's spacing, so large triangles mark every cell they cross.
field_spheres.py shades a sphere at each such cell's centre by the lattice's irradiance.

Everything runs on the viewport's worker thread; the main thread only uploads the arrays.
"""

import numpy as np

from .field_spheres import field_spheres

SAMPLE_SPACING_CELLS = 0.5   # barycentric sampling step on triangles
MAX_TRIANGLE_STEPS = 256     # caps the samples of one (huge) triangle per edge


def lattice_grid(bounds_min, bounds_max, resolution):
    """(origin (3,), cell size, dims (3,) int) of the global lattice over the bounds."""
    lower, upper = np.asarray(bounds_min, np.float64), np.asarray(bounds_max, np.float64)
    extent = upper - lower
    cell = float(extent.max()) / resolution
    dims = np.maximum(1, np.ceil(extent / cell - 1e-3)).astype(np.int64)
    origin = (lower + upper) / 2.0 - dims * cell / 2.0
    return origin, cell, dims


def triangle_samples(vertices, triangles, spacing):
    """Points on triangles: a barycentric grid with steps of at most `spacing` along edges."""
    corners = vertices[triangles]                                    # (T, 3, 3)
    edges = np.stack([corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 1],
                      corners[:, 0] - corners[:, 2]], axis=1)
    longest = np.linalg.norm(edges, axis=2).max(axis=1)
    steps = np.clip(np.ceil(longest / spacing), 1, MAX_TRIANGLE_STEPS).astype(np.int64)
    points = []
    for n in np.unique(steps):
        weights = _barycentric_grid(int(n))                          # (m, 3)
        points.append(np.einsum("mk,tkd->tmd", weights, corners[steps == n]).reshape(-1, 3))
    return np.concatenate(points) if points else np.zeros((0, 3))


def surface_cell_centres(snapshot, bounds, resolution):
    """(centres (K, 3), cell size) of the lattice cells that hold a surface of the snapshot."""
    origin, cell, dims = lattice_grid(bounds[0], bounds[1], resolution)
    object_samples = {}
    occupied = set()
    meshes = snapshot.meshes  # a shgi.Scene copies every mesh on each read of .meshes
    for record in snapshot.instances:
        mesh_id = record.mesh_id
        if mesh_id not in object_samples:
            mesh = meshes[mesh_id]
            object_samples[mesh_id] = (mesh.positions.astype(np.float64),
                                       mesh.triangles.astype(np.int64))
        positions, triangles = object_samples[mesh_id]
        matrix = np.asarray(record.world_from_object, np.float64)
        world = positions @ matrix[:3, :3].T + matrix[:3, 3]
        points = triangle_samples(world, triangles, SAMPLE_SPACING_CELLS * cell)
        cells = np.floor((points - origin) / cell).astype(np.int64)
        cells = cells[np.all((cells >= 0) & (cells < dims), axis=1)]
        occupied.update(map(tuple, np.unique(cells, axis=0)))
    if not occupied:
        return np.zeros((0, 3), np.float32), cell
    cells = np.array(sorted(occupied), np.float64)
    return ((origin + (cells + 0.5) * cell).astype(np.float32)), cell


def lattice_overlay(field, snapshot, scene, resolution):
    """The FieldSpheres of a solved lattice over a committed scene built from `snapshot`, or
    None when no cell holds surface."""
    if scene.empty:
        return None
    centres, cell = surface_cell_centres(snapshot, scene.bounds(), resolution)
    if len(centres) == 0:
        return None
    return field_spheres(field, centres, cell)


def _barycentric_grid(n):
    """(m, 3) barycentric weights of the points i/n, j/n (i + j <= n) of a triangle."""
    if n == 1:
        return np.full((1, 3), 1.0 / 3.0)
    rows = [(i / n, j / n, 1.0 - (i + j) / n) for i in range(n + 1) for j in range(n + 1 - i)]
    return np.array(rows)
