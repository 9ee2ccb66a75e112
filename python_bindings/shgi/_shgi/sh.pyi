"""
Real spherical harmonics, orders 0..4: orthonormal, index i = l(l+1)+m, no Condon-Shortley phase (Y00 = 0.282095, Y1-1 = +0.488603 y, Y10 = +0.488603 z, Y11 = +0.488603 x). RGB coefficients are float32 arrays of shape (n, 3), n = (order+1)^2; directions are unit vectors in Blender's frame (Z up).
"""
from __future__ import annotations
import numpy
import numpy.typing
import typing
__all__ = ['MAX_ORDER', 'convolve_cosine', 'convolve_zonal', 'cosine_lobe_zh', 'eval', 'evaluate', 'ggx_specular_zh', 'irradiance', 'lambert_zh', 'num_coefficients', 'phong_zh', 'project', 'rotate_zonal', 'scale_bands', 'specular_radiance', 'window', 'window_factors']
def convolve_cosine(coeffs: typing.Any) -> numpy.typing.NDArray[numpy.float32]:
    """
    Radiance coefficients (n, 3) -> irradiance coefficients (n, 3): each band l times A_l.
    """
def convolve_zonal(coeffs: typing.Any, zh: typing.Any) -> numpy.typing.NDArray[numpy.float32]:
    """
    Convolution with the zonal kernel `zh` (ZH coefficients z_l, Funk-Hecke): band l times sqrt(4pi/(2l+1)) z_l. Returns float32 (n, 3).
    """
def cosine_lobe_zh(order: typing.SupportsIndex = 4) -> numpy.typing.NDArray[numpy.float32]:
    """
    ZH coefficients z_0..z_order of the clamped cosine max(cos theta, 0): sqrt(pi)/2, sqrt(pi/3), sqrt(5pi)/8, 0, -sqrt(pi)/16.
    """
def eval(directions: typing.Any, order: typing.SupportsIndex = 2) -> numpy.typing.NDArray[numpy.float32]:
    """
    Basis functions Y_i at unit `directions` (N, 3): float32 (N, (order+1)^2), index i = l(l+1)+m, no Condon-Shortley phase (Y1-1 = +0.488603 y).
    """
def evaluate(coeffs: typing.Any, directions: typing.Any) -> numpy.typing.NDArray[numpy.float32]:
    """
    Reconstructs RGB coefficients (n, 3) at unit `directions` (N, 3): float32 (N, 3).
    """
def ggx_specular_zh(roughness: typing.SupportsFloat | typing.SupportsIndex) -> numpy.typing.NDArray[numpy.float32]:
    """
    Per-band factors (5,) of the fitted GGX specular lobe (seed 002 Appendix A), factor 0 = 1. Use with scale_bands; clamp the reconstructed radiance at 0.
    """
def irradiance(coeffs: typing.Any, normals: typing.Any) -> numpy.typing.NDArray[numpy.float32]:
    """
    Irradiance E(n) = sum A_l L_lm Y_lm(n) (W/m^2, unclamped) of radiance coefficients (n, 3) at unit normals (N, 3): float32 (N, 3). A_l = pi, 2pi/3, pi/4, 0, -pi/24.
    """
def lambert_zh(order: typing.SupportsIndex = 4, albedo: typing.SupportsFloat | typing.SupportsIndex = 1.0) -> numpy.typing.NDArray[numpy.float32]:
    """
    ZH coefficients of the Lambertian BRDF times cosine, (albedo/pi) max(cos theta, 0) (seed 004 3.3.1, corrected even-l formula).
    """
def num_coefficients(order: typing.SupportsIndex) -> int:
    """
    Number of SH coefficients of an order-`order` expansion: (order+1)^2.
    """
def phong_zh(exponent: typing.SupportsFloat | typing.SupportsIndex, order: typing.SupportsIndex = 4, specular: typing.SupportsFloat | typing.SupportsIndex = 1.0) -> numpy.typing.NDArray[numpy.float32]:
    """
    ZH coefficients of the normalised Phong lobe specular*(n+1)/(2pi) cos^n theta (seed 004 3.3.2).
    """
def project(directions: typing.Any, values: typing.Any, weights: typing.Any = None, order: typing.SupportsIndex = 2) -> numpy.typing.NDArray[numpy.float32]:
    """
    Projects samples: returns sum_k weights[k] * values[k] * Y(directions[k]) as float32 (n, 3). directions (N, 3) unit, values (N, 3) RGB, weights (N,) or None (all 1). For a Monte Carlo estimate of the integral use weights = 1 / (N * pdf).
    """
def rotate_zonal(zh: typing.Any, axis: typing.Any) -> numpy.typing.NDArray[numpy.float32]:
    """
    SH coefficients (bands^2,) of the axially symmetric lobe with ZH coefficients `zh` (around +Z) turned to the unit `axis`: c_lm = sqrt(4pi/(2l+1)) z_l Y_lm(axis).
    """
def scale_bands(coeffs: typing.Any, factors: typing.Any) -> numpy.typing.NDArray[numpy.float32]:
    """
    Multiplies every coefficient of band l by factors[l] (e.g. ggx_specular_zh or window_factors); coeffs (n, 3), factors (>= order+1,). Returns float32 (n, 3).
    """
def specular_radiance(coeffs: typing.Any, reflected: typing.Any, roughness: typing.SupportsFloat | typing.SupportsIndex) -> numpy.typing.NDArray[numpy.float32]:
    """
    Pre-filtered GGX specular radiance (N, 3), clamped at 0, of radiance coefficients (n, 3) in unit reflected directions (N, 3).
    """
def window(coeffs: typing.Any, kind: str = 'hanning', width: typing.SupportsFloat | typing.SupportsIndex = 0.0) -> numpy.typing.NDArray[numpy.float32]:
    """
    Returns the coefficients (n, 3) with a window applied per band (see window_factors).
    """
def window_factors(kind: str, order: typing.SupportsIndex, width: typing.SupportsFloat | typing.SupportsIndex = 0.0) -> numpy.typing.NDArray[numpy.float32]:
    """
    Windowing factors (order+1,) against ringing: kind 'none', 'hanning' or 'lanczos'; width in bands, <= 0 means order+1 (Sloan 2008).
    """
MAX_ORDER: int = 4
