#include "sh/sh_irradiance.h"

#include "sh/lobe_zh.h"

namespace shgi {

BandFactors cosine_lobe_band_factors() {
    // Constants (pi, 2 pi / 3, pi / 4, ...) that every irradiance lookup needs: computed once.
    static const BandFactors factors = zonal_band_factors(cosine_lobe_zh());
    return factors;
}

void sh_convolve_cosine(ShRgb& sh) { sh_scale_bands(sh, cosine_lobe_band_factors()); }

vec3 sh_irradiance(const ShRgb& radiance, const vec3& normal) {
    return sh_evaluate_scaled(radiance, cosine_lobe_band_factors(), normal);
}

}  // namespace shgi
