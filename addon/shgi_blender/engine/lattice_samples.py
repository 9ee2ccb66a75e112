"""The lattice overlay's geometry: a small shaded sphere per lattice cell holding surface. No bpy.

Cells: the global lattice's grid as lattice/sh_lattice.h lays it, cubes of side (longest side of
the scene's bounds) / resolution, centred on the bounds, each axis a whole number of cells.
(The native grid also adds a 1e-4 margin; at overlay scale that is invisible.) A cell holds
surface when a point sampled on a triangle falls inside it: triangles are sampled on a
barycentric grid at half a cell's spacing, so large triangles mark every cell they cross.

Shading: each sphere shows the lattice's indirect irradiance as seen by a surface facing each
way: E(p, ±x), E(p, ±y), E(p, ±z) from IndirectField.irradiance at the cell centre, blended over
the sphere's normals with the weights n_x², n_y², n_z² of the positive or negative side (an
"ambient cube": exact for a field whose SH is at most linear, smooth for L2). The colour is the
radiance of a white diffuse surface, E / π, scaled so that the cells' mean luminance is middle
grey and sRGB-encoded: draw handlers draw after Blender's colour management.

Everything runs on the viewport's worker thread; the main thread only uploads the arrays.
"""

import math
from dataclasses import dataclass

import numpy as np
import shgi

SPHERE_RADIUS_CELLS = 0.18   # sphere radius in cells: small enough to see between them
SPHERE_SUBDIVISIONS = 1      # icosphere levels: 42 vertices, 80 triangles per sphere
SAMPLE_SPACING_CELLS = 0.5   # barycentric sampling step on triangles
MAX_TRIANGLE_STEPS = 256     # caps the samples of one (huge) triangle per edge
MIDDLE_GREY = 0.18
LUMINANCE = np.array([0.2126, 0.7152, 0.0722], np.float32)
# The six normals of the ambient cube, in the order of ambient_cube_weights' columns.
AXES = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]],
                np.float32)


@dataclass
class LatticeOverlay:
    """Sphere triangles for one GPU batch: positions (V, 3), sRGB colours (V, 4) float32,
    triangle indices (T, 3) int32; the cell centres and their six irradiances (K, 6, 3) W/m²."""

    positions: np.ndarray
    colors: np.ndarray
    indices: np.ndarray
    centres: np.ndarray
    irradiance: np.ndarray
    cell_size: float


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


def ambient_cube_weights(normals):
    """(V, 6) weights of AXES for unit normals: n_x² on the side n points to, summing to 1."""
    n = np.asarray(normals, np.float32)
    positive, negative = np.maximum(n, 0.0) ** 2, np.maximum(-n, 0.0) ** 2
    return np.stack([positive[:, 0], negative[:, 0], positive[:, 1], negative[:, 1],
                     positive[:, 2], negative[:, 2]], axis=1)


def icosphere(subdivisions):
    """(unit vertices (V, 3) float32, triangles (T, 3) int32) of an icosphere."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    vertices = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
                (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    vertices = [np.array(v, np.float64) / np.linalg.norm(v) for v in vertices]
    for _ in range(subdivisions):
        midpoints, refined = {}, []
        for a, b, c in faces:
            ab, bc, ca = (_midpoint(vertices, midpoints, i, j) for i, j in ((a, b), (b, c), (c, a)))
            refined += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = refined
    return np.array(vertices, np.float32), np.array(faces, np.int32)


def sphere_arrays(centres, radius, cube_radiance):
    """Positions, sRGB colours and indices of one sphere per centre.

    cube_radiance: (K, 6, 3) linear colour of each sphere towards AXES.
    """
    unit, faces = icosphere(SPHERE_SUBDIVISIONS)
    count = len(centres)
    positions = (centres[:, None, :] + radius * unit[None, :, :]).reshape(-1, 3)
    linear = np.einsum("vs,ksc->kvc", ambient_cube_weights(unit), cube_radiance)
    colors = np.ones((count * len(unit), 4), np.float32)
    colors[:, :3] = shgi.srgb_from_linear(np.ascontiguousarray(linear.reshape(-1, 3)))
    indices = (faces[None, :, :] + (np.arange(count) * len(unit))[:, None, None]).reshape(-1, 3)
    return positions.astype(np.float32), colors, indices.astype(np.int32)


def lattice_overlay(field, snapshot, scene, resolution):
    """The LatticeOverlay of a solved field over a committed scene built from `snapshot`."""
    if scene.empty:
        return None
    centres, cell = surface_cell_centres(snapshot, scene.bounds(), resolution)
    if len(centres) == 0:
        return None
    points = np.repeat(centres, len(AXES), axis=0)
    normals = np.tile(AXES, (len(centres), 1))
    irradiance = np.asarray(field.irradiance(points, normals), np.float32).reshape(-1, 6, 3)
    radiance = irradiance / np.float32(math.pi)
    mean_luminance = float((radiance @ LUMINANCE).mean())
    scale = MIDDLE_GREY / mean_luminance if mean_luminance > 0.0 else 1.0
    positions, colors, indices = sphere_arrays(centres, SPHERE_RADIUS_CELLS * cell,
                                               radiance * np.float32(scale))
    return LatticeOverlay(positions, colors, indices, centres, irradiance, cell)


def _barycentric_grid(n):
    """(m, 3) barycentric weights of the points i/n, j/n (i + j <= n) of a triangle."""
    if n == 1:
        return np.full((1, 3), 1.0 / 3.0)
    rows = [(i / n, j / n, 1.0 - (i + j) / n) for i in range(n + 1) for j in range(n + 1 - i)]
    return np.array(rows)


def _midpoint(vertices, cache, i, j):
    key = (min(i, j), max(i, j))
    if key not in cache:
        middle = vertices[i] + vertices[j]
        vertices.append(middle / np.linalg.norm(middle))
        cache[key] = len(vertices) - 1
    return cache[key]

