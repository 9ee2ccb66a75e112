#!/usr/bin/env python3
"""The photon lattice's glossy indirect light against the path tracer's, by view angle, read at
the first surface: a closed 3 x 3 x 2.5 m room of Principled plaster (Roughness 0.5, Specular
0.5: the two rooms' dim room alone) lit by a 100 W lamp, seen by an orthographic camera at
several angles from the floor's (or the back wall's) normal, so that every pixel of that surface
sees it at the same angle. Prints, per surface and angle, the mean GlossInd x GlossCol of the
surface's pixels, lattice over path tracer (and DiffInd x DiffCol likewise). A plain script
printing a table: benchmarks are not tests.

    PYTHONPATH=build/python python3 bench/lattice_glossy_angles.py [--photons 400000]
        [--resolution 32] [--reference-spp 1024] [--angles 0,30,50,65,80] [--roughness 0.5]
"""

import argparse
import pathlib
import sys

import numpy as np
import shgi

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)

SIZE = (3.0, 3.0, 2.5)
# (name, a point near the surface's middle, its normal into the room, the tilt axis' direction)
SURFACES = [("floor", (1.5, 1.5, 0.0), (0.0, 0.0, 1.0), (1.0, 0.0, 0.0)),
            ("back wall", (1.5, 3.0, 1.25), (0.0, -1.0, 0.0), (1.0, 0.0, 0.0))]


def room(roughness):
    plaster = shgi.Material(name="plaster", base_color=scenes.WHITE, roughness=roughness)
    builder = scenes.closed_room(SIZE, plaster, lamp_at=(1.5, 1.5, 2.0))
    builder.scene.commit()
    return builder.scene


def set_view(scene, target, normal, tilt, angle_deg, pixels):
    """An orthographic camera 0.9 m from target, angle_deg from the normal towards `tilt`."""
    angle = np.radians(angle_deg)
    direction = np.cos(angle) * np.asarray(normal) + np.sin(angle) * np.asarray(tilt)
    eye = np.asarray(target) + 0.9 * direction
    up = (0, 0, 1) if abs(normal[2]) < 0.5 else (0, 1, 0)
    camera = shgi.Camera(type=shgi.CameraType.ORTHOGRAPHIC, ortho_scale=0.8,
                         resolution_x=pixels, resolution_y=pixels, clip_start=0.01)
    camera.world_from_camera = scenes.look_at(eye, target, up)
    scene.set_camera(camera)
    scene.commit()


def surface_means(passes, normal):
    on = np.einsum("ijc,c->ij", passes["Normal"][..., :3], np.asarray(normal)) > 0.99
    glossy = (passes["GlossInd"] * passes["GlossCol"])[..., :3][on].mean()
    diffuse = (passes["DiffInd"] * passes["DiffCol"])[..., :3][on].mean()
    return glossy, diffuse, int(on.sum())


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photons", type=int, default=400_000)
    parser.add_argument("--resolution", type=int, default=32)
    parser.add_argument("--reference-spp", type=int, default=1024)
    parser.add_argument("--preview-spp", type=int, default=16)
    parser.add_argument("--pixels", type=int, default=24)
    parser.add_argument("--angles", default="0,30,50,65,80")
    parser.add_argument("--roughness", type=float, default=0.5)
    parser.add_argument("--method", choices=["lattice", "probe_grid"], default="lattice",
                        help="the field against the path tracer (the probe grid: 6 updates)")
    args = parser.parse_args()

    scene = room(args.roughness)
    if args.method == "lattice":
        lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(
            seed=5, photons=args.photons, resolution=args.resolution, max_bounces=4))
        lattice.solve()
    else:
        lattice = shgi.ProbeGrid(scene, shgi.ProbeGridSettings(seed=5))
        for _ in range(6):
            lattice.update()
    print(f"closed plaster room (Roughness {args.roughness}), 100 W lamp; {args.method}: "
          f"{args.photons} photons, {args.resolution} cells, direct lookup "
          f"({args.preview_spp} spp); path tracer {args.reference_spp} spp; orthographic views")
    print("surface   | angle | pixels | PT glossy | field/PT glossy | field/PT diffuse")
    totals = np.zeros(2)
    for name, target, normal, tilt in SURFACES:
        for angle in (float(a) for a in args.angles.split(",")):
            set_view(scene, target, normal, tilt, angle, args.pixels)
            reference = shgi.render_path_traced(scene, shgi.PathTracerSettings(
                samples=args.reference_spp, seed=11))
            preview, _ = shgi.render_preview(scene, lattice.current_field(), shgi.PreviewSettings(
                seed=5, samples=args.preview_spp))
            pt = surface_means(reference, normal)
            pl = surface_means(preview, normal)
            totals += (pl[0], pt[0])
            print(f"{name:9s} | {angle:5.0f} | {pt[2]:6d} | {pt[0]:9.5f} | {pl[0] / pt[0]:17.3f} | "
                  f"{pl[1] / pt[1]:.3f}", flush=True)
    print(f"all views: field/PT glossy {totals[0] / totals[1]:.3f}")


if __name__ == "__main__":
    main()
