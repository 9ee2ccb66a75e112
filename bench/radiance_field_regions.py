"""Where RADIANCE_FIELD's indirect light departs from the path tracer's, by region: the
DiffInd x DiffCol mean against the reference over the pixels of the floor, the ceiling, the
walls by facing (from the reference's Normal pass) and the sunlit pixels (DiffDir x DiffCol above
half its maximum), with the Combined PSNR and two ceilings: the preview with the reference's
indirect light (what the preview's direct light alone allows) and the reference with the
preview's indirect light (what the field alone costs). docs/methods.md, "Radiance field".

    PYTHONPATH=build/python /usr/bin/python3 bench/radiance_field_regions.py [scene] [settings]

from the repository root; scene one of sun_room (default), cornell_box, two_rooms; settings a
Python dict of RadianceFieldSettings fields, e.g. "{'use_mips': False}".
"""
import ast
import pathlib
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))
sys.path.insert(0, str(ROOT / "tests" / "python"))
import scenes  # noqa: E402
import shgi  # noqa: E402
from scene_support import path_traced_reference  # noqa: E402
from shgi.metrics import psnr  # noqa: E402

SCENES = {"sun_room": (0.25, 2048), "cornell_box": (0.25, 2048), "two_rooms": (0.5, 512)}


def rgb(passes, name):
    return np.asarray(passes[name])[..., :3]


def indirect(passes):
    return (rgb(passes, "DiffInd") * rgb(passes, "DiffCol"),
            rgb(passes, "GlossInd") * rgb(passes, "GlossCol"))


def with_indirect(base, other):
    """base's Combined with its indirect light replaced by other's."""
    combined = np.array(base["Combined"], dtype=np.float32)
    (bd, bg), (od, og) = indirect(base), indirect(other)
    combined[..., :3] += od - bd + og - bg
    return combined


def main():
    name = sys.argv[1] if len(sys.argv) > 1 else "sun_room"
    fields = ast.literal_eval(sys.argv[2]) if len(sys.argv) > 2 else {}
    scale, samples = SCENES[name]
    scene, ref = path_traced_reference(getattr(scenes, name), scale, samples)
    field = shgi.RadianceField(scene, shgi.RadianceFieldSettings(seed=5, **fields))
    field.refine()
    prev, _ = shgi.render_preview(scene, field, shgi.PreviewSettings(seed=5))
    quality = psnr(ref["Combined"], prev["Combined"])
    direct_cap = psnr(ref["Combined"], with_indirect(prev, ref))
    field_cap = psnr(ref["Combined"], with_indirect(ref, prev))
    a, b = indirect(prev)[0], indirect(ref)[0]
    n = rgb(ref, "Normal")
    regions = {"all": np.linalg.norm(n, axis=-1) >= 0.0, "floor": n[..., 2] > 0.9,
               "ceiling": n[..., 2] < -0.9}
    for label, axis, sign in (("+x", 0, 1), ("-x", 0, -1), ("+y", 1, 1), ("-y", 1, -1)):
        regions["wall " + label] = sign * n[..., axis] > 0.9
    direct = (rgb(ref, "DiffDir") * rgb(ref, "DiffCol")).mean(-1)
    regions["sunlit"] = direct > 0.5 * direct.max()
    print(f"{name} {fields or 'defaults'}: Combined PSNR {quality:.2f} dB (reference indirect: "
          f"{direct_cap:.2f} dB; reference direct: {field_cap:.2f} dB)")
    for label, mask in regions.items():
        if mask.any():
            print(f"  {label:8s} {int(mask.sum()):5d} px  DiffInd x DiffCol "
                  f"{100 * (a[mask].mean() / b[mask].mean() - 1):+.1f}%")


main()
