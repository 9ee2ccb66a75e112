#include "sh/zonal_harmonics.h"

#include <cmath>

#include "sh/sh_projection.h"

namespace shgi {

float zonal_rotation_scale(int l) {
    return static_cast<float>(std::sqrt(4.0 * kPiD / (2.0 * l + 1.0)));
}

BandFactors zonal_band_factors(const ZhCoeffs& zh) {
    BandFactors factors{};
    for (int l = 0; l <= kMaxShOrder; ++l) factors[l] = zonal_rotation_scale(l) * zh[l];
    return factors;
}

ShCoeffs sh_rotate_zonal(int order, const ZhCoeffs& zh, const vec3& axis) {
    check_sh_order(order, "sh_rotate_zonal");
    check_unit_direction(axis, "sh_rotate_zonal: axis", 0);
    ShCoeffs out(order);
    sh_eval(order, axis, out.coeffs.data());
    sh_scale_bands(out, zonal_band_factors(zh));
    return out;
}

void sh_scale_bands(ShCoeffs& sh, const BandFactors& factors) {
    for (int l = 0; l <= sh.order; ++l)
        for (int m = -l; m <= l; ++m) sh.coeffs[sh_index(l, m)] *= factors[l];
}

void sh_scale_bands(ShRgb& sh, const BandFactors& factors) {
    for (int l = 0; l <= sh.order; ++l)
        for (int m = -l; m <= l; ++m) sh.coeffs[sh_index(l, m)] *= factors[l];
}

namespace {

// sh_evaluate_scaled for a compile-time order: the loops unroll into straight-line code.
template <int kOrder>
vec3 evaluate_scaled(const ShRgb& sh, const BandFactors& factors, const float* basis) {
    vec3 sum(0.0f);
    for (int l = 0; l <= kOrder; ++l)
        for (int m = -l; m <= l; ++m) {
            const int i = sh_index(l, m);
            sum += (sh.coeffs[i] * factors[l]) * basis[i];
        }
    return sum;
}

}  // namespace

vec3 sh_evaluate_scaled(const ShRgb& sh, const BandFactors& factors, const vec3& dir) {
    float basis[kMaxShCoefficients];
    sh_eval(sh.order, dir, basis);  // checks the order
    switch (sh.order) {
        case 0: return evaluate_scaled<0>(sh, factors, basis);
        case 1: return evaluate_scaled<1>(sh, factors, basis);
        case 2: return evaluate_scaled<2>(sh, factors, basis);
        case 3: return evaluate_scaled<3>(sh, factors, basis);
        default: return evaluate_scaled<4>(sh, factors, basis);
    }
}

}  // namespace shgi
