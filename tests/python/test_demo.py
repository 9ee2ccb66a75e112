"""The main job (examples/demo.py) runs end to end at a tiny size and writes what it promises."""

import re
import sys

import numpy as np
import pytest

import shgi
from shgi.metrics import psnr

from blender_support import REPO_ROOT

sys.path.insert(0, str(REPO_ROOT / "examples"))
import demo  # noqa: E402  (examples/ is not a package)

PASSES = {"Combined", "DiffDir", "DiffInd", "DiffCol", "GlossDir", "GlossInd", "GlossCol",
          "TransDir", "TransInd", "TransCol", "Emit", "Env", "Normal", "Depth",
          "Denoising Albedo", "Denoising Normal"}


def test_demo_writes_every_pass_and_a_png_for_both_scenes(tmp_path, capsys):
    assert demo.main(["--out", str(tmp_path), "--samples", "2", "--scale", "0.125",
                      "--bake-resolution", "16", "--bake-samples", "4"]) == 0
    summary = capsys.readouterr().out
    for name, size in (("cornell_box", (32, 32)), ("sun_room", (24, 32))):
        layers = shgi.read_exr(str(tmp_path / f"{name}.exr"))
        assert set(layers) == PASSES
        combined = layers["Combined"]
        assert combined.shape == (*size, 4)
        assert np.isfinite(combined).all() and combined[..., :3].mean() > 0.0
        assert (tmp_path / f"{name}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert f"{name:12s} {size[1]}x{size[0]} px, 2 spp" in summary
        # Each solver's preview: the same passes, lit, and a line comparing it with the path
        # tracer whose figures are those of the written images.
        for solver in demo.SOLVERS:
            preview = shgi.read_exr(str(tmp_path / f"{name}_{solver}.exr"))
            assert set(preview) == PASSES
            assert preview["Combined"].shape == (*size, 4)
            assert np.isfinite(preview["Combined"]).all()
            assert (preview["DiffInd"][..., :3] * preview["DiffCol"][..., :3]).mean() > 0.0
            assert (tmp_path / f"{name}_{solver}.png").exists()
            line = next(line for line in summary.splitlines()
                        if line.startswith(f"{name:12s} {solver:14s} solve "))
            figures = re.search(r"indirect diffuse ([+-][0-9.]+)%, PSNR ([0-9.]+) dB \(path "
                                r"tracer, same time, ([0-9]+) spp: ([0-9.]+) dB\)", line)
            assert figures, line
            difference = demo.indirect_diffuse(preview) / demo.indirect_diffuse(layers) - 1
            assert float(figures[1]) == pytest.approx(100 * difference, abs=0.051), line
            quality = psnr(combined, preview["Combined"])
            assert float(figures[2]) == pytest.approx(quality, abs=0.051), line

    # The bake: a lightmap per baked object, lit (the sun room's floor sees the sun patch).
    assert "bake         sun room, 5 lightmaps of 16x16, 4 samples/texel" in summary
    floor = shgi.read_exr(str(tmp_path / "lightmaps" / "floor.exr"))
    assert set(floor) == {"Lightmap", "Variance", "Coverage"}
    assert floor["Lightmap"].shape == (16, 16, 3)
    assert np.isfinite(floor["Lightmap"]).all() and floor["Lightmap"].max() > 1.0
    assert (tmp_path / "lightmaps" / "floor.png").exists()
