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
# Irradiance at random points of the dim room's surfaces (x > 0.05), from the field's radiance SH
# unclamped and clamped at zero: how much the lookup's clamp adds.
Ahat = np.array([np.pi] + [2 * np.pi / 3] * 3 + [np.pi / 4] * 5)
def sh9(n):
    x, y, z = n
    return np.array([0.282095, 0.488603 * y, 0.488603 * z, 0.488603 * x, 1.092548 * x * y, 1.092548 * y * z,
                     0.315392 * (3 * z * z - 1), 1.092548 * x * z, 0.546274 * (x * x - y * y)])
sc = scenes.two_rooms(0.5, bright_power=0.0).scene; sc.commit()
rng = np.random.default_rng(3)
tris = []
for inst in sc.instances:
    m = sc.meshes[inst.mesh_id]; M = np.asarray(inst.world_from_object)
    P = np.asarray(m.positions) @ M[:3, :3].T + M[:3, 3]
    for t in np.asarray(m.triangles): tris.append(P[t])
tris = np.array(tris)
area = 0.5 * np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
pts, nrm = [], []
while len(pts) < 3000:
    t = tris[rng.choice(len(tris), p=area / area.sum())]
    u, v = rng.random(2)
    if u + v > 1: u, v = 1 - u, 1 - v
    p = t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0])
    n = np.cross(t[1] - t[0], t[2] - t[0]); n /= np.linalg.norm(n)
    if p[0] < 0.06: continue
    # face into the dim room: flip towards the room's centre
    if np.dot(n, np.array([1.5, 1.5, 1.25]) - p) < 0: n = -n
    pts.append(p); nrm.append(n)
C = dict(occlude_first_step=True, drop_outward_vpls=True, travel_reinjection=True, damping=True, steps=24)
for name, cfg in (("unclamped", dict(C, unclamped_transfer=True)), ("rescaled", C)):
    for order in (1, 2):
        v = shgi.PropagationVolume(sc, shgi.PropagationSettings(seed=5, order=order, **cfg)); v.refine(); f = v.current_field()
        raw = []
        for p, n in zip(pts, nrm):
            L = np.asarray(f.radiance_sh(tuple(p), tuple(n)))  # (9 or 4, 3)
            k = L.shape[0]
            raw.append(((Ahat[:k] * sh9(n)[:k])[:, None] * L).sum(0).mean())
        raw = np.array(raw)
        print(f"{name} order {order}: mean E unclamped {raw.mean():.4f}, clamped {np.maximum(raw, 0).mean():.4f} "
              f"(+{np.maximum(raw, 0).mean() / raw.mean() - 1:.1%}), share < 0 {float((raw < 0).mean()):.3f}", flush=True)
