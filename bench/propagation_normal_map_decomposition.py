"""Why Light Propagation gains more from a normal map than the other field methods: its floor
DiffInd on test_instant_gi.py's normal-mapped floor taken apart per pixel.

The floor's indirect light is the wall's (the floor cannot see itself; the world is black), and
the wall is Lambert: the exact incident radiance at a floor point is the wall's radiance, read
from a path-traced orthographic image of the wall, along every direction that meets it, 0
elsewhere. For every floor pixel of one normal (the bumped scene's Normal pass, averaged over the
pixel's samples, of length > 0.995: inside one stripe), brute-force gathers over a
(n, 2n) product quadrature, through the diffuse lobe about the pixel's bent normal with Chiang's
bump shadowing (render/normal_map.h):
  - of that exact radiance (checks the reference against the path tracer's DiffInd),
  - of its projection on L2 (what an exact L2 field would give),
  - of the field's SH looked up for the bent normal and for the interpolated one (the preview's
    lookup, render/path_integrator.cpp's field_lookup_normal; checks the gather against the
    preview).

    PYTHONPATH=build/python python3 bench/propagation_normal_map_decomposition.py
        [--quadrature 64] [--samples 256] [--config defaults|lpv|fix|lpv_fix]
"""

import argparse
import math
import sys
from pathlib import Path

import numpy as np

import shgi

sys.path.insert(0, str(Path(__file__).resolve().parent))
import normal_map_particle_flux as flux  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "python"))
import test_instant_gi as floor_test  # noqa: E402

FIX = dict(furnace_scale=True, distance=96.0, settle_fraction=0.01, glossy_vpls=True,
           glossy_bounces=4, extend_to_bounds=True)  # propagation_lpv_sweep.py's "fix"
CONFIGS = {"defaults": {}, "lpv": dict(order=1), "fix": FIX, "lpv_fix": dict(order=1, **FIX)}


def chiang(smooth, bent, w):
    """render/normal_map.cpp's bump_shadowing_term for directions w (N, 3)."""
    cos_bent = w @ bent
    reference = np.where(cos_bent[:, None] < 0, -smooth, smooth)
    denominator = cos_bent * (reference @ bent)
    safe = np.where(denominator != 0, denominator, 1.0)
    g = np.where(denominator != 0, (reference * w).sum(-1) / safe, 0.0)
    return np.where(g >= 1, 1.0, np.where(g >= 0, -g**3 + g**2 + g, 0.0))


class Sphere:
    def __init__(self, n):
        theta = (np.arange(n) + 0.5) * math.pi / n
        phi = (np.arange(2 * n) + 0.5) * math.pi / n
        t, p = np.meshgrid(theta, phi, indexing="ij")
        self.weights = (np.sin(t) * (math.pi / n) ** 2).ravel()
        self.directions = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)],
                                   -1).reshape(-1, 3)
        self.basis = shgi.sh.eval(self.directions.astype(np.float32), 2).astype(np.float64)

    def radiance(self, coefficients):
        return self.basis[:, :len(coefficients)] @ coefficients

    def project(self, radiance):
        return (self.weights * radiance) @ self.basis

    def gather(self, radiance, bent, bumped):
        """The diffuse lobe's irradiance / pi (DiffInd), floored at 0 as the renderer's."""
        kernel = np.maximum(self.directions @ bent, 0.0)
        if bumped:
            kernel = kernel * chiang(np.array([0.0, 0.0, 1.0]), bent, self.directions)
        return max(float((self.weights * radiance * kernel).sum()), 0.0) / math.pi


def wall_radiance(scene, samples):
    camera = shgi.Camera(resolution_x=128, resolution_y=128)
    camera.type = shgi.CameraType.ORTHOGRAPHIC
    camera.ortho_scale = 2.0
    camera.world_from_camera = floor_test.look_at((0.0, 0.0, 1.0), (1.0, 0.0, 1.0))
    scene.set_camera(camera)
    scene.commit()
    image = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=samples, seed=3))
    return image["Combined"][..., :3].mean(-1).astype(np.float64)


def incident(sphere, wall, p):
    """The wall's radiance along each direction from p that meets it (row 0: z = 2)."""
    d = sphere.directions
    with np.errstate(divide="ignore", invalid="ignore"):
        hit = p + ((1.0 - p[0]) / d[:, 0])[:, None] * d
    meets = (d[:, 0] > 0) & (np.abs(hit[:, 1]) < 1) & (hit[:, 2] > 0) & (hit[:, 2] < 2)
    n = wall.shape[0]
    row = np.clip(((2 - hit[:, 2]) / 2 * n).astype(int), 0, n - 1)
    col = np.clip(((1 - hit[:, 1]) / 2 * n).astype(int), 0, n - 1)
    return np.where(meets, wall[row, col], 0.0)


def floor_points():
    """Where each pixel's central camera ray meets z = 0."""
    camera = flux.floor_scene(False).camera
    m = np.asarray(camera.world_from_camera, np.float64)
    w, h = camera.resolution_x, camera.resolution_y
    half = 0.5 * camera.sensor_width / camera.lens
    x, y = np.meshgrid(((np.arange(w) + 0.5) / w * 2 - 1) * half,
                       -((np.arange(h) + 0.5) / h * 2 - 1) * half * h / w)
    d = np.stack([x, y, -np.ones_like(x)], -1) @ m[:3, :3].T
    return m[:3, 3] + (-m[2, 3] / d[..., 2])[..., None] * d


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quadrature", type=int, default=64)
    parser.add_argument("--samples", type=int, default=256)
    parser.add_argument("--config", default="defaults", choices=sorted(CONFIGS))
    args = parser.parse_args()
    sphere = Sphere(args.quadrature)
    settings = shgi.method("PROPAGATION").settings_type
    run = {}
    for normal_map in (False, True):
        scene = flux.floor_scene(normal_map)
        path = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=args.samples,
                                                                      seed=11))
        solver = shgi.make_solver("PROPAGATION", scene,
                                  settings(seed=5, **CONFIGS[args.config]))
        for _ in range(4):
            solver.refine()
        field = solver.current_field()
        run[normal_map] = dict(path=path, field=field,
                               preview=floor_test.preview(scene, field, samples=4),
                               wall=wall_radiance(flux.floor_scene(normal_map), args.samples))
    normals = run[True]["path"]["Normal"][..., :3]
    one = ((run[False]["path"]["Normal"][..., 2] > 0.9) &
           (np.linalg.norm(normals, axis=-1) > 0.995) & (np.abs(normals[..., 0]) > 0.05))
    points = floor_points()
    up = np.array([0.0, 0.0, 1.0])
    rows, bands = [], {}
    for r, c in zip(*np.nonzero(one)):
        p, bent = points[r, c], normals[r, c] / np.linalg.norm(normals[r, c])
        exact = {nm: incident(sphere, run[nm]["wall"], p) for nm in (False, True)}
        sh = {key: np.asarray(run[nm]["field"].radiance_sh(p.astype(np.float32),
                                                           n.astype(np.float32)),
                              np.float64).mean(-1)
              for key, nm, n in (("flat", False, up), ("bent", True, bent),
                                 ("smooth", True, up))}
        # Radiance integrated over the lower hemisphere and over the upper one's halves
        # towards the wall (+x) and away from it, exact and the field's (interpolated normal).
        d, w = sphere.directions, sphere.weights
        for name, radiance in (("exact", exact[True]), ("field", sphere.radiance(sh["smooth"]))):
            for part, mask in (("below", d[:, 2] < 0), ("towards", (d[:, 2] >= 0) & (d[:, 0] > 0)),
                               ("away", (d[:, 2] >= 0) & (d[:, 0] <= 0))):
                bands[name, part] = bands.get((name, part), 0.0) + float((w * radiance)[mask].sum())
        for name, coefficients in (("exact", sphere.project(exact[True])), ("field", sh["smooth"])):
            bands[name, "c10"] = bands.get((name, "c10"), 0.0) + coefficients[2]
            bands[name, "c00"] = bands.get((name, "c00"), 0.0) + coefficients[0]
        rows.append(dict(
            towards=bent[0] > 0,
            path_flat=run[False]["path"]["DiffInd"][r, c, :3].mean(),
            path_map=run[True]["path"]["DiffInd"][r, c, :3].mean(),
            preview_flat=run[False]["preview"]["DiffInd"][r, c, :3].mean(),
            preview_map=run[True]["preview"]["DiffInd"][r, c, :3].mean(),
            exact_flat=sphere.gather(exact[False], up, False),
            exact_map=sphere.gather(exact[True], bent, True),
            l2_flat=sphere.gather(sphere.radiance(sphere.project(exact[False])), up, False),
            l2_map=sphere.gather(sphere.radiance(sphere.project(exact[True])), bent, True),
            field_flat=sphere.gather(sphere.radiance(sh["flat"]), up, False),
            field_bent=sphere.gather(sphere.radiance(sh["bent"]), bent, True),
            field_smooth=sphere.gather(sphere.radiance(sh["smooth"]), bent, True)))
    mean = {k: np.mean([row[k] for row in rows]) for k in rows[0] if k != "towards"}
    print(f"{args.config}: {len(rows)} floor pixels of one normal; quadrature "
          f"{args.quadrature} x {2 * args.quadrature}")
    print(f"  exact incident light's gather / path tracer: flat "
          f"{mean['exact_flat'] / mean['path_flat']:.4f}, normal map "
          f"{mean['exact_map'] / mean['path_map']:.4f}")
    print(f"  field's gather (interpolated-normal lookup) / preview: flat "
          f"{mean['field_flat'] / mean['preview_flat']:.4f}, normal map "
          f"{mean['field_smooth'] / mean['preview_map']:.4f}")
    flat = mean["field_flat"] / mean["exact_flat"]
    print(f"  over the exact gather, flat / normal map / change: L2 projection "
          f"{mean['l2_flat'] / mean['exact_flat']:.4f} / {mean['l2_map'] / mean['exact_map']:.4f}"
          f" / {mean['l2_map'] / mean['exact_map'] / (mean['l2_flat'] / mean['exact_flat']):.4f}")
    for key, name in (("field_smooth", "field, interpolated-normal lookup"),
                      ("field_bent", "field, bent-normal lookup")):
        bumped = mean[key] / mean["exact_map"]
        print(f"    {name}: {flat:.4f} / {bumped:.4f} / {bumped / flat:.4f}")
    for towards, name in ((True, "stripes leaning towards the wall"),
                          (False, "stripes leaning away from it")):
        sel = [row for row in rows if row["towards"] == towards]
        exact = sum(row["exact_map"] for row in sel)
        print(f"  {name} ({len(sel)} px, {exact / sum(r['exact_map'] for r in rows):.3f} of the "
              f"exact light): over the exact gather, L2 projection "
              f"{sum(row['l2_map'] for row in sel) / exact:.4f}, field "
              f"{sum(row['field_smooth'] for row in sel) / exact:.4f} (bent-normal lookup "
              f"{sum(row['field_bent'] for row in sel) / exact:.4f})")

    total = bands["exact", "towards"] + bands["exact", "away"]
    print("  incident radiance over directions (the normal map's scene, / the exact light's "
          "upper hemisphere): below the horizon / upper half towards the wall / away from it: "
          + "; ".join(f"{name} {bands[name, 'below'] / total:.3f} / "
                      f"{bands[name, 'towards'] / total:.3f} / {bands[name, 'away'] / total:.3f}"
                      for name in ("exact", "field"))
          + "; L1 z term over L0: "
          + ", ".join(f"{name} {bands[name, 'c10'] / bands[name, 'c00']:+.3f}"
                      for name in ("exact", "field")))


if __name__ == "__main__":
    main()
