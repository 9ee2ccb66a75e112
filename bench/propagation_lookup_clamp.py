#!/usr/bin/env python3
"""Does the lookup's clamp at zero raise the unclamped volume's light? At 3000 random points of
the two rooms' dim room (its lamp alone on), the irradiance from the field's radiance SH
(radiance_sh, convolved with the clamped cosine) unclamped and clamped at zero, for the
unclamped and the rescaled transfer (travel re-injection, damping, both corrections, 24 steps).

    PYTHONPATH=build/python python3 bench/propagation_lookup_clamp.py
"""
import pathlib
import sys

import numpy as np

import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)
# The defaults before settings layout 6, which this bench's figures in docs/methods.md were
# measured with.
from propagation_lpv_sweep import SEED  # noqa: E402
# Â_l, the clamped cosine's band factors, per coefficient of bands 0..2.
COSINE_BANDS = np.array([np.pi] + [2 * np.pi / 3] * 3 + [np.pi / 4] * 5)
SETTINGS = dict(occlude_first_step=True, drop_outward_vpls=True, travel_reinjection=True,
                damping=True, steps=24)


def sh9(n):
    """Real SH basis of bands 0..2 at unit n (SHGI's order: y, z, x in band 1)."""
    x, y, z = n
    return np.array([0.282095, 0.488603 * y, 0.488603 * z, 0.488603 * x, 1.092548 * x * y,
                     1.092548 * y * z, 0.315392 * (3 * z * z - 1), 1.092548 * x * z,
                     0.546274 * (x * x - y * y)])


def dim_room_points(scene, count, rng):
    """Area-uniform random points of the dim room's surfaces (x > 0.06), normals into it."""
    triangles = []
    for instance in scene.instances:
        mesh = scene.meshes[instance.mesh_id]
        matrix = np.asarray(instance.world_from_object)
        positions = np.asarray(mesh.positions) @ matrix[:3, :3].T + matrix[:3, 3]
        triangles += [positions[t] for t in np.asarray(mesh.triangles)]
    triangles = np.array(triangles)
    edges = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    area = 0.5 * np.linalg.norm(edges, axis=1)
    points, normals = [], []
    while len(points) < count:
        t = triangles[rng.choice(len(triangles), p=area / area.sum())]
        u, v = rng.random(2)
        if u + v > 1:
            u, v = 1 - u, 1 - v
        p = t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0])
        if p[0] < 0.06:
            continue
        n = np.cross(t[1] - t[0], t[2] - t[0])
        n /= np.linalg.norm(n)
        if np.dot(n, np.array([1.5, 1.5, 1.25]) - p) < 0:  # face the room's middle
            n = -n
        points.append(p)
        normals.append(n)
    return points, normals


def main():
    scene = scenes.two_rooms(0.5, bright_power=0.0).scene
    scene.commit()
    points, normals = dim_room_points(scene, 3000, np.random.default_rng(3))
    for name, settings in (("unclamped", dict(SETTINGS, unclamped_transfer=True)),
                           ("rescaled", SETTINGS)):
        for order in (1, 2):
            volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
                seed=5, order=order, **dict(SEED, **settings)))
            volume.refine()
            field = volume.current_field()
            raw = []
            for p, n in zip(points, normals):
                radiance = np.asarray(field.radiance_sh(tuple(p), tuple(n)))
                k = radiance.shape[0]
                raw.append(((COSINE_BANDS[:k] * sh9(n)[:k])[:, None] * radiance).sum(0).mean())
            raw = np.array(raw)
            clamped = np.maximum(raw, 0.0).mean()
            print(f"{name} order {order}: mean irradiance {raw.mean():.4f}, clamped at zero "
                  f"{clamped:.4f} ({clamped / raw.mean() - 1:+.1%}), below zero at "
                  f"{float((raw < 0).mean()):.3f} of the points", flush=True)


if __name__ == "__main__":
    main()
