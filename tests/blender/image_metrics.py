"""The image comparison behind the acceptance figures: PSNR of sRGB display values.

Issues 4 and 5 compare a render with a reference as a viewer sees them: both are scaled by the
reference's auto-exposure (its mean Rec. 709 luminance mapped to middle grey, 0.18), encoded
with shgi's sRGB curve and clipped to [0, 1]; the PSNR of those display values is the figure.
tests/python/test_photon_lattice.py (system Python) and the Blender scripts (engine_common.py,
Blender's Python) both use this file, so it imports neither bpy nor mathutils. Every step has
a fixed dtype (exposure applied in float64, float32 into shgi's native sRGB curve, float64 after
it, Python floats for the scalars): the same pixel values give the same figure whether they come
as float32 passes or float64 EXR reads, and whichever numpy promotion rules the caller's numpy
follows.
"""

import math

import numpy as np
import shgi

# Rec. 709 / sRGB primaries: relative luminance of linear RGB.
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
# Auto-exposure of the comparisons: the reference's mean luminance is mapped to middle grey.
MIDDLE_GREY = 0.18


def display(image, exposure):
    """sRGB-encoded [0, 1] float64 RGB of linear `image` (H, W, >= 3) scaled by `exposure`."""
    linear = np.clip(np.asarray(image[..., :3], np.float64) * exposure, 0.0, None)
    linear = linear.astype(np.float32)
    return np.clip(np.asarray(shgi.srgb_from_linear(linear), np.float64), 0.0, 1.0)


def psnr(reference, image):
    """PSNR (dB) of the sRGB images after the reference's auto-exposure; inf when equal."""
    exposure = MIDDLE_GREY / float((np.asarray(reference[..., :3], np.float64) @ LUMINANCE).mean())
    mse = float(np.mean((display(reference, exposure) - display(image, exposure)) ** 2))
    return math.inf if mse == 0.0 else 10.0 * math.log10(1.0 / mse)
