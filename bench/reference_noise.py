"""How far bench/equal_time.py's cached references are from the most converged one of the same
scene, size and renderer: PSNR (shgi.metrics.psnr, the bench's own score) of each reference
against the one of most samples. A render scored against a reference cannot show more than
roughly that figure (its own error and the reference's noise add), so a --quick table
(256-spp references) is only meaningful where this figure is well above its cells.

    PYTHONPATH=build/python python3 bench/reference_noise.py [--cache build/equal_time_cache]

Also prints MSE x samples (display-space variance per sample, up to the denoiser-free 1/N
law): its ratio between the two renderers at the same samples is how many more samples one
needs for the other's noise."""
import argparse
import collections
import os
import re

import numpy as np

from shgi import metrics


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cache", default=os.path.join("build", "equal_time_cache"))
    args = parser.parse_args()
    found = collections.defaultdict(dict)
    for file in os.listdir(args.cache):
        # <scene>_<W>x<H>_<renderer>[_clamp<c>][_fg<f>][_<filter><w>][_seed<s>]_<spp>spp.npy: by all
        # but the samples.
        match = re.fullmatch(r"(.+)_(cycles|shgi)((?:_[a-z]+[0-9.]+)*)_(\d+)spp\.npy", file)
        if match:
            found[match[1], match[2] + match[3]][int(match[4])] = os.path.join(args.cache, file)
    print(f"{'scene':24s} {'renderer':30s} {'spp':>5s} {'vs spp':>6s} {'PSNR dB':>8s} "
          f"{'MSE x spp':>10s} {'mean ratio':>10s}")
    for (scene, renderer), files in sorted(found.items()):
        best = max(files)
        reference = np.load(files[best])
        for spp in sorted(files):
            if spp == best:
                continue
            image = np.load(files[spp])
            exposure = metrics.auto_exposure(reference)
            mse = float(np.mean((metrics.display(reference, exposure)
                                 - metrics.display(image, exposure)) ** 2))
            mean_ratio = float((image[..., :3] @ metrics.LUMINANCE).mean()
                               / (reference[..., :3] @ metrics.LUMINANCE).mean())
            print(f"{scene:24s} {renderer:30s} {spp:5d} {best:6d} "
                  f"{metrics.psnr(reference, image):8.2f} {mse * spp:10.4f} {mean_ratio:10.4f}")


if __name__ == "__main__":
    main()
