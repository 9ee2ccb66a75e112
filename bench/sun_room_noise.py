"""Where the sun room's path-traced noise comes from: SHGI's path tracer on
examples/scenes.sun_room (half size, 128 x 96; Light Paths limits of bench/equal_time.py) with
the sun, the sky and the window's portal each left out in turn. Two renders of different seeds
at --samples give the variance per sample (MSE between them / 2 x samples), in the display
space of shgi.metrics.psnr (auto-exposure of the full scene, sRGB) and in linear radiance.
No timing: the figures are per sample, so they hold on a loaded machine.

    PYTHONPATH=build/python python3 bench/sun_room_noise.py [--samples 16]
"""
import argparse
import inspect
import os
import sys

import numpy as np

import shgi
from shgi import metrics

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples"))
import scenes  # noqa: E402

VARIANTS = [("sun + sky, portal", {}), ("sun only", dict(sky=False)),
            ("sky only, portal", dict(sun=False)), ("sky only, no portal", dict(sun=False, portal=False)),
            ("sun + sky, no portal", dict(portal=False))]


def build(sun=True, sky=True, portal=True):
    """scenes.sun_room at half size, with the sun, the sky or the portal left out."""
    source = inspect.getsource(scenes.sun_room)
    for keep, old, new in ((sun, "b.scene.add_light(sun)", "pass"),
                           (portal, "b.scene.add_light(portal)", "pass"),
                           (sky, "strength=0.0 if window_shut else 1.0", "strength=0.0")):
        if not keep:
            assert old in source, old
            source = source.replace(old, new)
    namespace = dict(vars(scenes))
    exec(source, namespace)
    scene = namespace["sun_room"](0.5).scene
    scene.commit()
    return scene


def render(scene, samples, seed):
    settings = shgi.PathTracerSettings(samples=samples, seed=seed, max_bounces=8,
                                       diffuse_bounces=4, glossy_bounces=4,
                                       transmission_bounces=8)
    return shgi.render_path_traced(scene, settings)["Combined"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=16)
    args = parser.parse_args()
    n = args.samples
    exposure = metrics.auto_exposure(render(build(), n, 1))
    print(f"{'variant':24s} {'display var/spp':>15s} {'linear var/spp':>14s} {'mean lum':>9s}")
    for name, variant in VARIANTS:
        scene = build(**variant)
        a, b = render(scene, n, 1), render(scene, n, 2)
        display = np.mean((metrics.display(a, exposure) - metrics.display(b, exposure)) ** 2)
        linear = np.mean((a[..., :3].astype(np.float64) - b[..., :3]) ** 2)
        mean = float((a[..., :3] @ metrics.LUMINANCE).mean())
        print(f"{name:24s} {display / 2 * n:15.4f} {linear / 2 * n:14.5f} {mean:9.4f}")


if __name__ == "__main__":
    main()
