"""Small spheres shaded by an IndirectField's irradiance: the overlays' geometry. No bpy.

The lattice overlay (lattice_samples.py: one sphere per lattice cell holding surface) and the
probe overlay (one sphere per active probe of a probe grid) both draw a FieldSpheres batch.

Shading: each sphere shows the field's indirect irradiance as seen by a surface facing each
way: E(p, ±x), E(p, ±y), E(p, ±z) from IndirectField.irradiance at the sphere's centre,
blended over the sphere's normals with the weights n_x², n_y², n_z² of the positive or negative
side (an "ambient cube": exact for a field whose SH is at most linear, smooth for L2). The
colour is the radiance of a white diffuse surface, E / π, scaled so that the spheres' mean
luminance is middle grey, lifted by a dim grey (AMBIENT_LIFT) so that a side no indirect light
reaches reads as dark rather than as a black hole, and sRGB-encoded: draw handlers draw after
Blender's colour management. The spheres' radius is a share of the cell or probe spacing the
artist sets (``resized``: only the positions change).

Everything runs on worker threads; the main thread only uploads the arrays.
"""

import math
from dataclasses import dataclass

import numpy as np
import shgi
from shgi.metrics import LUMINANCE, MIDDLE_GREY

SPHERE_RADIUS_SPACINGS = 0.12  # sphere radius in cells or probe spacings: room to see between
# Linear grey added to every sphere colour, as a share of middle grey (after the exposure).
AMBIENT_LIFT = 0.15
SPHERE_SUBDIVISIONS = 1        # icosphere levels: 42 vertices, 80 triangles per sphere
# The six normals of the ambient cube, in the order of ambient_cube_weights' columns.
AXES = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]],
                np.float32)


@dataclass
class FieldSpheres:
    """Sphere triangles for one GPU batch: positions (V, 3), sRGB colours (V, 4) float32,
    triangle indices (T, 3) int32; the sphere centres (K, 3) and their six irradiances
    (K, 6, 3) W/m²; the spacing (m) the radius was chosen from."""

    positions: np.ndarray
    colors: np.ndarray
    indices: np.ndarray
    centres: np.ndarray
    irradiance: np.ndarray
    spacing: float
    radius_spacings: float = SPHERE_RADIUS_SPACINGS

    def resized(self, radius_spacings):
        """The same spheres with a radius of `radius_spacings` spacings (self when equal)."""
        if radius_spacings == self.radius_spacings:
            return self
        positions = sphere_positions(self.centres, radius_spacings * self.spacing)
        return FieldSpheres(positions, self.colors, self.indices, self.centres, self.irradiance,
                            self.spacing, radius_spacings)


def field_spheres(field, centres, spacing):
    """The FieldSpheres of `field` (an IndirectField) at centres (K >= 1, 3), `spacing` apart."""
    centres = np.asarray(centres, np.float32)
    points = np.repeat(centres, len(AXES), axis=0)
    normals = np.tile(AXES, (len(centres), 1))
    irradiance = np.asarray(field.irradiance(points, normals), np.float32).reshape(-1, 6, 3)
    radiance = irradiance / np.float32(math.pi)
    mean_luminance = float((radiance @ LUMINANCE).mean())
    scale = MIDDLE_GREY / mean_luminance if mean_luminance > 0.0 else 1.0
    lifted = radiance * np.float32(scale) + np.float32(AMBIENT_LIFT * MIDDLE_GREY)
    positions, colors, indices = sphere_arrays(centres, SPHERE_RADIUS_SPACINGS * spacing, lifted)
    return FieldSpheres(positions, colors, indices, centres, irradiance, spacing)


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
    positions = sphere_positions(centres, radius)
    linear = np.einsum("vs,ksc->kvc", ambient_cube_weights(unit), cube_radiance)
    colors = np.ones((count * len(unit), 4), np.float32)
    colors[:, :3] = shgi.srgb_from_linear(np.ascontiguousarray(linear.reshape(-1, 3)))
    indices = (faces[None, :, :] + (np.arange(count) * len(unit))[:, None, None]).reshape(-1, 3)
    return positions, colors, indices.astype(np.int32)


def sphere_positions(centres, radius):
    """(K * V, 3) float32 vertices of one icosphere of `radius` per centre."""
    unit, _ = icosphere(SPHERE_SUBDIVISIONS)
    centres = np.asarray(centres, np.float32)
    return (centres[:, None, :] + np.float32(radius) * unit[None, :, :]).reshape(-1, 3).astype(
        np.float32)


def _midpoint(vertices, cache, i, j):
    key = (min(i, j), max(i, j))
    if key not in cache:
        middle = vertices[i] + vertices[j]
        vertices.append(middle / np.linalg.norm(middle))
        cache[key] = len(vertices) - 1
    return cache[key]

