// Windowing of SH expansions against ringing: per-band factors σ_l multiplied into the
// coefficients (a convolution with a smooth ZH kernel, so the result stays rotation invariant).
//
// Sloan 2008, "Stupid Spherical Harmonics (SH) Tricks", §"Windowing":
//   Hanning: σ_l = (1 + cos(π l / w)) / 2 for l < w, 0 beyond;
//   Lanczos: σ_l = sin(π l / w) / (π l / w) (σ_0 = 1), 0 for l >= w.
// w is the window width in bands; Sloan's suggestion w = number of bands = order + 1 is
// the default (width <= 0 selects it). Both keep σ_0 = 1, so the mean (and hence the
// irradiance of a constant field) is unchanged. Seed 002 §4.2.2 deliberately uses no window;
// SHGI offers it as an option, off by default wherever a setting exposes it.
#pragma once

#include <string>

#include "sh/zonal_harmonics.h"

namespace shgi {

enum class ShWindow { None, Hanning, Lanczos };

// "none", "hanning", "lanczos" -> ShWindow; InvalidArgument naming the accepted names otherwise.
ShWindow parse_sh_window(const std::string& name);
const char* sh_window_name(ShWindow window);

// σ_0..σ_4 for an expansion of `order` (bands above order get 0). width <= 0: order + 1.
BandFactors sh_window_factors(ShWindow window, int order, float width = 0.0f);

// Multiplies the window into `sh` (its own order picks the default width).
void sh_apply_window(ShRgb& sh, ShWindow window, float width = 0.0f);

}  // namespace shgi
