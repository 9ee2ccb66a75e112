#!/usr/bin/env python3
"""Scripting demo: build a Cornell box from numpy arrays, trace it with SHGI, write EXR + PNG.

The box is open towards the camera and lit by a uniform sky (Blender's world colour x strength).
For each pixel the camera ray's hit point receives direct sky light
    L = albedo / pi * integral(L_sky * V(w) * cos(theta) dw) = albedo * L_sky * <V>_cos
estimated with cosine-distributed occlusion rays (an unbiased Monte Carlo estimate of one bounce
of sky light; interreflections come with the solvers). Output layers, Blender-named:
Combined (RGBA), Normal (XYZ, world space) and Depth (Z, metres along the ray).

Usage: python3 examples/cornell_box.py [--out DIR] [--size N] [--sky-rays K] [--seed S]
"""

import argparse
import pathlib
import sys
import time

import numpy as np

import shgi

# Cornell box proportions (metres), Blender frame: Z up, camera looking down +Y.
BOX = 2.0
WHITE, RED, GREEN = (0.73, 0.73, 0.73), (0.65, 0.05, 0.05), (0.12, 0.45, 0.15)
SKY_RADIANCE = np.array([1.0, 1.0, 1.0], np.float32)  # W m^-2 sr^-1
SELF_HIT_OFFSET = 1e-4  # m: moves sky rays off the surface they start on


def quad(corner, edge_u, edge_v):
    """Two triangles spanning corner, corner+u, corner+u+v, corner+v (CCW seen from u x v)."""
    c, u, v = (np.asarray(x, np.float32) for x in (corner, edge_u, edge_v))
    return np.array([c, c + u, c + u + v, c + v], np.float32), np.array([[0, 1, 2], [0, 2, 3]])


def build_scene(size):
    scene = shgi.Scene()
    materials = {name: scene.add_material(shgi.Material(name=name, base_color=color))
                 for name, color in (("white", WHITE), ("red", RED), ("green", GREEN))}
    albedo = {}
    walls = [  # (name, material, corner, u, v): normals point into the box
        ("floor", "white", (-1, 0, 0), (0, BOX, 0), (BOX, 0, 0)),
        ("ceiling", "white", (-1, 0, BOX), (BOX, 0, 0), (0, BOX, 0)),
        ("back", "white", (-1, BOX, 0), (0, 0, BOX), (BOX, 0, 0)),
        ("left", "red", (-1, 0, 0), (0, 0, BOX), (0, BOX, 0)),
        ("right", "green", (1, 0, 0), (0, BOX, 0), (0, 0, BOX)),
    ]
    for name, material, corner, u, v in walls:
        positions, triangles = quad(corner, u, v)
        mesh_id = scene.add_mesh(positions=positions, triangles=triangles, name=name,
                                 material_indices=np.full(2, materials[material]))
        instance_id = scene.add_instance(mesh_id, np.eye(4), name)
        albedo[instance_id] = (WHITE, RED, GREEN)[materials[material]]
    # A short block on the floor, rotated 20 degrees about Z.
    block = shgi_box((0.35, 1.1, 0.0), 0.6, 0.6, 0.6, np.radians(20))
    mesh_id = scene.add_mesh(positions=block[0], triangles=block[1], name="block",
                             material_indices=np.zeros(len(block[1]), np.int32))
    albedo[scene.add_instance(mesh_id, np.eye(4), "block")] = WHITE

    camera = shgi.Camera()
    camera.world_from_camera = look_at_matrix(eye=(0, -3.2, 1.0), target=(0, 1.0, 1.0))
    camera.lens = 50.0
    camera.resolution_x = camera.resolution_y = size
    scene.set_camera(camera)
    world = shgi.World()
    world.color = SKY_RADIANCE
    world.strength = 1.0
    scene.set_world(world)
    return scene, albedo


def shgi_box(center, sx, sy, sz, angle):
    """A closed box mesh (12 triangles, outward CCW) resting on z = center.z."""
    x, y, z = sx / 2, sy / 2, sz
    corners = np.array([[-x, -y, 0], [x, -y, 0], [x, y, 0], [-x, y, 0],
                        [-x, -y, z], [x, -y, z], [x, y, z], [-x, y, z]], np.float32)
    c, s = np.cos(angle), np.sin(angle)
    corners = corners @ np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]], np.float32)
    corners += np.asarray(center, np.float32)
    faces = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    triangles = [[f[0], f[1], f[2]] for f in faces] + [[f[0], f[2], f[3]] for f in faces]
    return corners, np.array(triangles, np.int32)


def look_at_matrix(eye, target, up=(0, 0, 1)):
    """Blender-style camera matrix_world: the camera looks down its local -Z, +Y up."""
    eye, target, up = (np.asarray(v, np.float64) for v in (eye, target, up))
    forward = target - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    matrix = np.eye(4)
    matrix[:3, 0], matrix[:3, 1], matrix[:3, 2], matrix[:3, 3] = right, true_up, -forward, eye
    return matrix


def cosine_directions(normals, rng, count):
    """`count` cosine-distributed unit directions around each normal: shape (N, count, 3)."""
    n = normals[:, None, :]
    u1, u2 = rng.random((2, len(normals), count))
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0, 1 - u1))], -1)
    # Orthonormal frame per normal (Duff et al. 2017).
    sign = np.where(n[..., 2] >= 0, 1.0, -1.0)
    a = -1.0 / (sign + n[..., 2])
    b = n[..., 0] * n[..., 1] * a
    tx = np.stack([1 + sign * n[..., 0] ** 2 * a, sign * b, -sign * n[..., 0]], -1)
    ty = np.stack([b, sign + n[..., 1] ** 2 * a, -n[..., 1]], -1)
    return local[..., :1] * tx + local[..., 1:2] * ty + local[..., 2:] * n


def render(scene, albedo, sky_rays, seed, progress):
    camera = scene.camera
    width, height = camera.resolution_x, camera.resolution_y
    js, is_ = np.mgrid[0:height, 0:width]
    film = np.stack([is_.ravel() + 0.5, js.ravel() + 0.5], -1).astype(np.float32)
    origins, directions = camera.generate_rays(film)
    hits = scene.intersect(origins, directions, progress=progress)
    hit = hits["instance_id"] != np.iinfo(np.uint32).max
    t = np.where(hit, hits["t"], np.inf)

    normals = hits["normal"].astype(np.float64)
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-20)
    facing = np.where((normals * directions).sum(1, keepdims=True) > 0, -normals, normals)

    idx = np.nonzero(hit)[0]
    points = origins[idx] + directions[idx] * t[idx, None] + SELF_HIT_OFFSET * facing[idx]
    rng = np.random.default_rng(seed)
    sky_dirs = cosine_directions(facing[idx], rng, sky_rays).reshape(-1, 3).astype(np.float32)
    sky_origins = np.repeat(points, sky_rays, axis=0).astype(np.float32)
    blocked = scene.occluded(sky_origins, sky_dirs, progress=progress).reshape(-1, sky_rays)
    visibility = 1.0 - blocked.mean(axis=1)

    combined = np.zeros((width * height, 4), np.float32)
    combined[:, :3] = SKY_RADIANCE  # rays that miss see the sky
    combined[:, 3] = 1.0
    hit_albedo = np.array([albedo[i] for i in hits["instance_id"][idx]], np.float32)
    combined[idx, :3] = hit_albedo * SKY_RADIANCE * visibility[:, None]
    depth = np.where(hit, t, 0.0).astype(np.float32)
    normal_pass = np.where(hit[:, None], facing, 0.0).astype(np.float32)
    shape = (height, width)
    return {"Combined": combined.reshape(*shape, 4), "Normal": normal_pass.reshape(*shape, 3),
            "Depth": depth.reshape(shape)}, len(origins) + len(sky_origins)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("demo_output"))
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--sky-rays", type=int, default=64)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)

    start = time.perf_counter()
    scene, albedo = build_scene(args.size)
    scene.commit()
    progress = shgi.Progress()
    layers, rays = render(scene, albedo, args.sky_rays, args.seed, progress)
    seconds = time.perf_counter() - start

    args.out.mkdir(parents=True, exist_ok=True)
    shgi.write_exr(str(args.out / "cornell_box.exr"), layers)
    shgi.write_png(str(args.out / "cornell_box.png"), layers["Combined"])
    stats = scene.stats()
    print(f"cornell box: {args.size}x{args.size} px, {args.sky_rays} sky rays per pixel, "
          f"{stats['instanced_triangles']} triangles")
    print(f"traced {rays / 1e6:.2f} M rays in {seconds:.2f} s "
          f"({rays / seconds / 1e6:.2f} M rays/s including Python), threads: {shgi.max_threads()}")
    print(f"wrote {args.out / 'cornell_box.exr'} (Combined, Normal, Depth) and "
          f"{args.out / 'cornell_box.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
