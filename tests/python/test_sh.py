"""shgi.sh: the SH bindings against closed-form identities, and their input checks.

Run with Debian's Python from the build tree:
    PYTHONPATH=<build>/python /usr/bin/python3 -m pytest tests/python/test_sh.py
"""

import math
import sys
import threading
import time

import numpy as np
import pytest

import shgi
from shgi import sh

# float32 evaluation summed over a few hundred quadrature nodes: ~1e-6 relative.
FLOAT_TOLERANCE = 1e-5


def sphere_quadrature(n_theta=16, n_phi=32):
    """Gauss-Legendre in cos(theta) x uniform phi: exact for Y_i Y_j up to L4 (degree 8)."""
    z, wz = np.polynomial.legendre.leggauss(n_theta)
    phi = (np.arange(n_phi) + 0.5) * 2.0 * math.pi / n_phi
    zz, pp = np.meshgrid(z, phi, indexing="ij")
    r = np.sqrt(1.0 - zz**2)
    directions = np.stack([r * np.cos(pp), r * np.sin(pp), zz], axis=-1).reshape(-1, 3)
    weights = (wz[:, None] * np.full(n_phi, 2.0 * math.pi / n_phi)[None, :]).reshape(-1)
    return directions, weights


def random_directions(count, seed=0):
    v = np.random.default_rng(seed).normal(size=(count, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def test_num_coefficients_and_max_order():
    assert [sh.num_coefficients(order) for order in range(5)] == [1, 4, 9, 16, 25]
    assert sh.MAX_ORDER == 4


def test_basis_is_orthonormal_by_quadrature():
    directions, weights = sphere_quadrature()
    y = sh.eval(directions, order=4)
    assert y.shape == (len(directions), 25) and y.dtype == np.float32
    gram = (y.astype(np.float64) * weights[:, None]).T @ y.astype(np.float64)
    np.testing.assert_allclose(gram, np.eye(25), atol=1e-4)


def test_sign_convention_without_condon_shortley_phase():
    y = sh.eval(np.eye(3), order=1)
    # Rows: +X, +Y, +Z. Y1-1 = +0.488603 y, Y10 = +0.488603 z, Y11 = +0.488603 x.
    np.testing.assert_allclose(y[:, 0], 0.282095, atol=1e-6)
    np.testing.assert_allclose(y[:, 1:], np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]]) * 0.488603,
                               atol=1e-6)


def test_project_then_evaluate_round_trips_band_limited_field():
    rng = np.random.default_rng(1)
    truth = rng.uniform(-1, 1, size=(9, 3)).astype(np.float32)
    directions, weights = sphere_quadrature(8, 16)
    radiance = sh.evaluate(truth, directions)
    coeffs = sh.project(directions, radiance, weights, order=2)
    assert coeffs.shape == (9, 3) and coeffs.dtype == np.float32
    np.testing.assert_allclose(coeffs, truth, atol=FLOAT_TOLERANCE)


def test_irradiance_of_constant_field_is_pi_times_radiance():
    radiance = np.array([0.5, 1.0, 2.0])
    coeffs = np.zeros((9, 3), np.float32)
    coeffs[0] = radiance * math.sqrt(4.0 * math.pi)  # L * sqrt(4 pi) on Y00
    normals = random_directions(100)
    e = sh.irradiance(coeffs, normals)
    assert e.shape == (100, 3)
    np.testing.assert_allclose(e, np.broadcast_to(math.pi * radiance, e.shape), rtol=1e-5)


def test_irradiance_matches_brute_force_hemisphere_integral():
    rng = np.random.default_rng(2)
    coeffs = rng.uniform(-1, 1, size=(25, 3)).astype(np.float32)
    directions, weights = sphere_quadrature(64, 128)
    radiance = sh.evaluate(coeffs, directions).astype(np.float64)
    for normal in random_directions(5, seed=3):
        cosine = np.maximum(directions @ normal, 0.0)
        # The kink at the horizon makes the sphere rule inexact: 64x128 nodes give ~1e-3.
        brute = (weights * cosine) @ radiance
        np.testing.assert_allclose(sh.irradiance(coeffs, normal[None])[0], brute, atol=5e-3)


def test_convolve_cosine_band_factors():
    coeffs = np.ones((25, 3), np.float32)
    out = sh.convolve_cosine(coeffs)
    a = [math.pi, 2 * math.pi / 3, math.pi / 4, 0.0, -math.pi / 24]
    for index in range(25):
        band = int(math.isqrt(index))
        np.testing.assert_allclose(out[index], a[band], atol=1e-6)


def test_rotate_zonal_cosine_lobe_to_plus_z_and_lobe_constants():
    zh = sh.cosine_lobe_zh()
    np.testing.assert_allclose(
        zh, [math.sqrt(math.pi) / 2, math.sqrt(math.pi / 3), math.sqrt(5 * math.pi) / 8, 0.0,
             -math.sqrt(math.pi) / 16], atol=1e-6)
    c = sh.rotate_zonal(zh[:3], [0.0, 0.0, 1.0])
    assert c.shape == (9,)
    expected = np.zeros(9)
    expected[[0, 2, 6]] = zh[:3]
    np.testing.assert_allclose(c, expected, atol=1e-6)
    np.testing.assert_allclose(sh.lambert_zh(order=2, albedo=0.5), 0.5 / math.pi * zh[:3],
                               rtol=1e-6)
    phong = sh.phong_zh(10.0, order=2)
    np.testing.assert_allclose(phong[0], 1 / math.sqrt(4 * math.pi), rtol=1e-6)


def test_ggx_specular_zh_limits_and_clamped_specular_radiance():
    np.testing.assert_allclose(sh.ggx_specular_zh(0.0), np.ones(5), atol=1e-3)
    np.testing.assert_allclose(sh.ggx_specular_zh(1.0), [1, 2 / 3, 1 / 4, 0, -1 / 24], atol=1e-3)
    coeffs = np.zeros((4, 3), np.float32)
    coeffs[0] = -1.0
    out = sh.specular_radiance(coeffs, np.array([[0.0, 0.0, 1.0]]), 0.5)
    np.testing.assert_array_equal(out, np.zeros((1, 3)))
    scaled = sh.scale_bands(np.ones((9, 3), np.float32), sh.ggx_specular_zh(1.0))
    np.testing.assert_allclose(scaled[4:], 0.25, atol=1e-3)


def test_window_keeps_the_mean_and_damps_high_bands():
    np.testing.assert_allclose(sh.window_factors("hanning", 2), [1.0, 0.75, 0.25], atol=1e-6)
    out = sh.window(np.ones((9, 3), np.float32), "lanczos")
    assert out[0, 0] == pytest.approx(1.0) and 0 < out[8, 0] < out[1, 0] < 1


@pytest.mark.parametrize(
    "call, argument",
    [
        (lambda: sh.eval(np.zeros((4, 2)), 2), "directions"),                      # shape
        (lambda: sh.eval(np.zeros((4, 3), np.int32), 2), "directions"),            # dtype
        (lambda: sh.eval(np.array([[0.0, 0.0, np.nan]]), 2), "directions"),        # NaN
        (lambda: sh.eval(np.array([[0.0, 0.0, 2.0]]), 2), "directions"),           # not unit
        (lambda: sh.eval(np.array([[0.0, 0.0, 1.0]]), 5), "order"),
        (lambda: sh.irradiance(np.zeros((5, 3)), np.eye(3)), "coeffs"),            # n not square
        (lambda: sh.irradiance(np.zeros((9, 3)), np.full((1, 3), np.inf)), "normals"),
        (lambda: sh.project(np.eye(3), np.ones((2, 3)), None, 2), "values"),
        (lambda: sh.project(np.eye(3), np.ones((3, 3)), np.ones(4), 2), "weights"),
        (lambda: sh.project(np.eye(3), np.ones((3, 3)), np.full(3, np.nan), 2), "weights"),
        (lambda: sh.rotate_zonal(np.ones(6), [0, 0, 1]), "zh"),
        (lambda: sh.rotate_zonal(np.ones(3), [0, 0, 3]), "axis"),
        (lambda: sh.ggx_specular_zh(1.5), "roughness"),
        (lambda: sh.phong_zh(-1.0), "exponent"),
        (lambda: sh.scale_bands(np.ones((9, 3)), np.ones(2)), "factors"),
        (lambda: sh.window(np.ones((9, 3)), "hamming"), "hamming"),
    ],
)
def test_bad_input_raises_value_error_naming_the_argument(call, argument):
    with pytest.raises(ValueError, match=argument):
        call()


def test_native_loop_releases_the_gil():
    """The main thread keeps running Python while a worker is inside sh.eval."""
    directions = random_directions(1_000_000)
    span = {}
    results = []

    def work():
        span["start"] = time.perf_counter()
        results.append(sh.eval(directions, 4))
        span["end"] = time.perf_counter()

    ticks = []  # main-thread timestamps, at most one per millisecond
    worker = threading.Thread(target=work)
    worker.start()
    while worker.is_alive():
        now = time.perf_counter()
        if not ticks or now - ticks[-1] > 1e-3:
            ticks.append(now)
    worker.join()
    assert results[0].shape == (1_000_000, 25)
    # Python switches threads every sys.getswitchinterval() (5 ms) only between bytecodes, so
    # with the GIL held the main thread could not run more than one interval into the call.
    margin = 4 * sys.getswitchinterval()
    if span["end"] - span["start"] < 3 * margin:
        pytest.skip("sh.eval finished too quickly to observe concurrency")
    assert any(span["start"] + margin < t < span["end"] - margin for t in ticks)


def test_every_function_has_a_docstring():
    for name in dir(sh):
        value = getattr(sh, name)
        if callable(value):
            assert value.__doc__ and len(value.__doc__) > 20, name
    assert shgi.sh is sh
