// Zonal harmonics (ZH): rotation of axially symmetric lobes and convolution with them.
//
// A function symmetric about +Z projects onto the m = 0 basis functions only; its ZH
// coefficients are z_l = ∫ f(ω) Y_l0(ω) dω (seed 003 eq. 3.1, seed 004 §3.3 "ρ̂_l"). Two
// identities make ZH cheap (Sloan 2008, "Stupid Spherical Harmonics (SH) Tricks", §"Zonal
// Harmonics"; seed 003 §3.2.1 and §4.1.1; seed 004 §3.3):
//  * rotation: the lobe turned so that +Z maps to the unit axis d has SH coefficients
//        c_lm = √(4π/(2l+1)) z_l Y_lm(d)                                (seed 003 eq. 3.2)
//  * convolution (Funk–Hecke): ∫ f(ω) h(d·ω) dω has coefficients k_l f_lm in d, with the
//    per-band factor k_l = √(4π/(2l+1)) h_l.
// BandFactors holds such per-band multipliers k_0..k_4; they also express windowing
// (sh/sh_window.h), irradiance (sh/sh_irradiance.h) and the fitted GGX lobe (sh/ggx_zh.h).
#pragma once

#include <array>

#include "sh/sh_coeffs.h"

namespace shgi {

// z_0..z_4: ZH coefficients of a lobe around +Z (bands above the order in use are ignored).
using ZhCoeffs = std::array<float, kMaxShOrder + 1>;

// k_0..k_4: per-band multipliers applied to every coefficient of band l.
using BandFactors = std::array<float, kMaxShOrder + 1>;

// √(4π/(2l+1)): turns a ZH coefficient into a rotation/convolution factor.
float zonal_rotation_scale(int l);

// k_l = √(4π/(2l+1)) z_l for every band.
BandFactors zonal_band_factors(const ZhCoeffs& zh);

// SH coefficients of the lobe `zh` (defined around +Z) rotated to the unit axis `axis`.
// Throws InvalidArgument for a bad order or a non-unit axis.
ShCoeffs sh_rotate_zonal(int order, const ZhCoeffs& zh, const vec3& axis);

// c_lm *= factors[l] for every coefficient: convolution with a ZH kernel given its band factors
// (zonal_band_factors), or a windowing.
void sh_scale_bands(ShCoeffs& sh, const BandFactors& factors);
void sh_scale_bands(ShRgb& sh, const BandFactors& factors);

// Σ_lm factors[l] c_lm Y_lm(dir) per channel at the unit direction `dir`: sh_evaluate of the
// band-scaled expansion without forming it (irradiance and glossy lookups run once per shading
// point). The float operations and their order are those of sh_scale_bands followed by
// sh_evaluate, so the result is bit-identical to that pair.
vec3 sh_evaluate_scaled(const ShRgb& sh, const BandFactors& factors, const vec3& dir);

}  // namespace shgi
