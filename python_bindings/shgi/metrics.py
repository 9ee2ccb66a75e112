"""Comparing a render with a reference as a viewer sees them: PSNR of sRGB display values.

This is the figure behind SHGI's acceptance tests (a preview against Cycles or the path tracer,
"Combined PSNR >= 30 dB"): both images are scaled by the reference's auto-exposure (its mean
Rec. 709 luminance mapped to middle grey, 0.18), encoded with shgi's sRGB curve
(``shgi.srgb_from_linear``) and clipped to [0, 1]; the PSNR of those display values, with a
peak of 1, is the figure. Scripts that compare their own renders use the same function, so
their numbers read like those of docs/methods.md and docs/benchmarks.md.

Every step has a fixed dtype (exposure applied in float64, float32 into the native sRGB curve,
float64 after it, Python floats for the scalars): the same pixel values give the same figure
whether they come as float32 passes or float64 EXR reads, and whichever numpy promotion rules
the caller's numpy follows (1.x in Debian's Blender, 2.x under pip).
"""

import math

import numpy as np

from . import _shgi

# Rec. 709 / sRGB primaries: relative luminance of linear RGB.
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
# Auto-exposure of the comparisons: the reference's mean luminance is mapped to middle grey.
MIDDLE_GREY = 0.18


def auto_exposure(reference):
    """The scale that maps the mean Rec. 709 luminance of linear `reference` (..., >= 3) to
    MIDDLE_GREY; ValueError when that mean is not a positive finite number (a black or
    non-finite reference has no exposure)."""
    mean = float((np.asarray(reference[..., :3], np.float64) @ LUMINANCE).mean())
    if not (math.isfinite(mean) and mean > 0.0):
        raise ValueError(f"auto_exposure: the reference's mean luminance is {mean}; it must be "
                         "positive and finite (is the reference image black or non-finite?)")
    return MIDDLE_GREY / mean


def display(image, exposure):
    """sRGB-encoded [0, 1] float64 RGB of linear `image` (..., >= 3) scaled by `exposure`."""
    linear = np.clip(np.asarray(image[..., :3], np.float64) * exposure, 0.0, None)
    linear = linear.astype(np.float32)
    return np.clip(np.asarray(_shgi.srgb_from_linear(linear), np.float64), 0.0, 1.0)


def psnr(reference, image):
    """PSNR (dB) of linear `image` against linear `reference` as displayed after the reference's
    auto-exposure; inf when the display values are equal. Both are (H, W, >= 3) images or
    (N, >= 3) lists of pixels (e.g. a lightmap's covered texels), the same size; alpha and other
    channels past RGB are ignored. ValueError for anything else."""
    reference = np.asarray(reference)
    image = np.asarray(image)
    if (reference.ndim < 2 or image.ndim < 2 or reference.shape[:-1] != image.shape[:-1]
            or min(reference.shape[-1], image.shape[-1]) < 3):
        raise ValueError(f"psnr: reference {reference.shape} and image {image.shape} must be "
                         "(H, W, >= 3) images, or (N, >= 3) pixel lists, of the same size")
    exposure = auto_exposure(reference)
    mse = float(np.mean((display(reference, exposure) - display(image, exposure)) ** 2))
    return math.inf if mse == 0.0 else 10.0 * math.log10(1.0 / mse)
