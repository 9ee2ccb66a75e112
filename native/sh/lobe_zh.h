// Zonal-harmonic coefficients of the analytic lobes SHGI projects: the clamped cosine, the
// Lambertian BRDF and the normalised Phong lobe.
//
// All lobes are axially symmetric about +Z and given as ZhCoeffs z_0..z_4 with
// z_l = ∫ f(ω) Y_l0(ω) dω = 2π ∫ f(θ) Y_l0(θ) sin θ dθ (seed 003 eq. 3.1; seed 004 §3.3, the
// ρ̂_l integral). Rotate them to a normal / reflection direction with sh_rotate_zonal, or
// turn them into convolution factors with zonal_band_factors (sh/zonal_harmonics.h).
//
//  * cosine_lobe_zh: f = max(cos θ, 0). z_0 = √π/2, z_1 = √(π/3), z_2 = √(5π)/8, z_3 = 0,
//    z_4 = -√π/16 (seed 003 §3.2.1; Ramamoorthi & Hanrahan 2001, eq. 8 gives the general l).
//  * lambert_zh: seed 004 §3.3.1, f = (k_d/π) max(cos θ, 0), i.e. k_d/π times the cosine lobe.
//    The seed's closed form for even l >= 2 is misprinted: it shows (-1)^((l-1)/2) (imaginary
//    for even l) and "2! (l/2)!" in the denominator. The correct value, which reproduces the
//    seed's own l = 0, 1 cases and Ramamoorthi & Hanrahan's Â_l, is
//        z_l = 2π √((2l+1)/(4π)) (-1)^(l/2-1) l! / ((l+2)(l-1) 2^l ((l/2)!)²),
//    implemented here and checked by quadrature in tests/cpp/sh/lobe_zh_test.cpp.
//  * phong_zh: seed 004 §3.3.2, f = k_s (n+1)/(2π) cos^n θ on the hemisphere cos θ > 0 around
//    the reflection vector (a unit-integral lobe for k_s = 1). The seed's closed form is right:
//        odd l:  z_l = k_s √((2l+1)/(4π)) (n+1)(n-1)(n-3)…(n-l+2) / ((n+l+1)(n+l-1)…(n+2))
//        even l: z_l = k_s √((2l+1)/(4π)) n(n-2)…(n-l+2) / ((n+l+1)(n+l-1)…(n+3))
//    (products step by 2; an empty product is 1). It holds for any real exponent n >= 0.
#pragma once

#include "sh/zonal_harmonics.h"

namespace shgi {

// z_l of the clamped cosine max(cos θ, 0) for any band l >= 0 (double precision).
double cosine_lobe_zh_band(int l);

ZhCoeffs cosine_lobe_zh();

// Lambertian BRDF times the cosine, (albedo/π) max(cos θ, 0); albedo is k_d in [0, 1].
ZhCoeffs lambert_zh(float albedo = 1.0f);

// Normalised Phong lobe k_s (n+1)/(2π) cos^n θ around the reflection vector. Throws
// InvalidArgument unless exponent is finite and >= 0.
ZhCoeffs phong_zh(float exponent, float specular = 1.0f);

}  // namespace shgi
