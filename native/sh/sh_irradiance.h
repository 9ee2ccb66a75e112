// Irradiance from an SH radiance expansion: convolution with the clamped cosine.
//
// Ramamoorthi & Hanrahan 2001, "An efficient representation for irradiance environment maps",
// eqs. 7–9: E(n) = ∫ L(ω) max(n·ω, 0) dω = Σ_lm Â_l L_lm Y_lm(n) with
//     Â_0 = π, Â_1 = 2π/3, Â_2 = π/4, Â_3 = 0, Â_4 = -π/24
// (Â_l = √(4π/(2l+1)) z_l of the cosine lobe, sh/lobe_zh.h). The identity is exact for a
// band-limited L: bands of L above its order contribute nothing, and because Â_3 = 0 the l = 3
// part of an L3/L4 radiance field never reaches irradiance. Seed 002 §4.2.2 uses this for diffuse
// probe lighting; docs/architecture.md fixes it as SHGI's irradiance.
//
// Units: radiance coefficients in W·m⁻²·sr⁻¹ give irradiance in W·m⁻². The result is not
// clamped: ringing can make E slightly negative, and callers that shade clamp at use.
#pragma once

#include "sh/zonal_harmonics.h"

namespace shgi {

// Â_0..Â_4.
BandFactors cosine_lobe_band_factors();

// radiance coefficients -> irradiance coefficients (E_lm = Â_l L_lm), in place.
void sh_convolve_cosine(ShRgb& sh);

// E(normal) for a unit normal.
vec3 sh_irradiance(const ShRgb& radiance, const vec3& normal);

}  // namespace shgi
