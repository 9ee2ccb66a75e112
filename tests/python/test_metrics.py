"""shgi.metrics: the display PSNR the acceptance tests and the demo report, against answers
worked out by hand from the sRGB curve (IEC 61966-2-1) and the Rec. 709 luminance weights."""

import math

import numpy as np
import pytest

from shgi.metrics import LUMINANCE, MIDDLE_GREY, auto_exposure, display, psnr


def srgb(x):
    """The sRGB encoding written out, independently of shgi's native curve."""
    return 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1.0 / 2.4) - 0.055


def grey(value, shape=(4, 6)):
    return np.full(shape + (3,), value, np.float32)


def test_auto_exposure_maps_the_mean_luminance_to_middle_grey():
    assert LUMINANCE.sum() == pytest.approx(1.0)
    assert auto_exposure(grey(0.5)) == pytest.approx(MIDDLE_GREY / 0.5)
    # Pure green: its luminance is the green weight alone.
    green = np.zeros((2, 2, 4), np.float32)
    green[..., 1] = 1.0
    green[..., 3] = 123.0  # alpha is ignored
    assert auto_exposure(green) == pytest.approx(MIDDLE_GREY / 0.7152)


def test_psnr_of_a_black_image_against_grey_is_the_encoded_middle_grey():
    # After exposure the grey reference shows middle grey, the black image 0: MSE = srgb(0.18)^2.
    expected = -20.0 * math.log10(srgb(MIDDLE_GREY))
    assert psnr(grey(0.5), grey(0.0)) == pytest.approx(expected, abs=1e-4)
    assert expected == pytest.approx(6.719, abs=1e-3)


def test_psnr_of_a_uniform_offset_follows_the_encoded_difference():
    reference = grey(0.2)
    image = grey(0.3)  # 1.5x the reference: middle grey x 1.5 on screen
    expected = -20.0 * math.log10(srgb(1.5 * MIDDLE_GREY) - srgb(MIDDLE_GREY))
    assert psnr(reference, image) == pytest.approx(expected, abs=1e-4)
    # The reference's exposure scales both, so scaling both leaves the figure alone.
    assert psnr(4.0 * reference, 4.0 * image) == pytest.approx(expected, abs=1e-4)


def test_psnr_is_infinite_for_equal_display_values_and_clips_above_white():
    reference = grey(0.5)
    assert psnr(reference, reference) == math.inf
    # One pixel of 30 puts the mean luminance at (23 x 0.5 + 30) / 24 and the exposure at 0.104:
    # 30 and 300 both show past white, so they are equal on screen.
    bright = grey(0.5)
    bright[0, 0] = 30.0
    brighter = bright.copy()
    brighter[0, 0] = 300.0
    exposure = auto_exposure(bright)
    assert exposure == pytest.approx(MIDDLE_GREY * 24.0 / (23 * 0.5 + 30.0))
    assert display(bright, exposure)[0, 0, 0] == 1.0
    assert psnr(bright, brighter) == math.inf


def test_psnr_of_a_pixel_list_is_the_psnr_of_its_image():
    """Bakes compare the covered texels only, as (N, 3) lists."""
    rng = np.random.default_rng(5)
    reference = rng.random((6, 4, 3))
    image = reference * rng.uniform(0.8, 1.2, (6, 4, 3))
    assert psnr(reference.reshape(-1, 3), image.reshape(-1, 3)) == psnr(reference, image)


def test_psnr_is_the_same_for_float32_and_float64_pixels():
    rng = np.random.default_rng(3)
    reference = rng.random((8, 8, 3)).astype(np.float32)
    image = (reference + 0.05 * rng.standard_normal((8, 8, 3))).astype(np.float32)
    assert psnr(reference, image) == psnr(reference.astype(np.float64), image.astype(np.float64))


@pytest.mark.parametrize("reference, image, match", [
    (grey(0.5), grey(0.5, (4, 5)), "of the same size"),
    (np.zeros((4, 6, 2)), np.zeros((4, 6, 2)), "of the same size"),
    (np.ones(6), np.ones(6), "of the same size"),  # no channel axis
    (np.ones((24, 3)), grey(0.5), "of the same size"),  # a pixel list against an image
    (grey(0.0), grey(0.5), "mean luminance is 0.0"),
    (grey(math.nan), grey(0.5), "mean luminance is nan"),
])
def test_bad_images_raise_value_error_naming_the_problem(reference, image, match):
    with pytest.raises(ValueError, match=match):
        psnr(reference, image)
