#include "sh/zonal_harmonics.h"

#include <cmath>
#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

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
// With SSE2 the three channels of a coefficient go through one 4-wide multiply-multiply-add
// (the fourth lane carries the next coefficient's red and is dropped): each channel takes the
// same IEEE operations in the same order as the scalar form, so the sums are bit-identical,
// in a third of the instructions (two of these a preview pixel, ~3% of its frame before).
template <int kOrder>
vec3 evaluate_scaled(const ShRgb& sh, const BandFactors& factors, const float* basis) {
#if defined(__SSE2__)
    const float* coeffs = sh.data();
    __m128 sum = _mm_setzero_ps();
    for (int l = 0; l <= kOrder; ++l) {
        const __m128 factor = _mm_set1_ps(factors[l]);
        for (int m = -l; m <= l; ++m) {
            const int i = sh_index(l, m);
            // Four floats from coefficient i, unless that reads past the array (i = 24).
            const __m128 c = 3 * i + 4 <= 3 * kMaxShCoefficients
                                 ? _mm_loadu_ps(coeffs + 3 * i)
                                 : _mm_setr_ps(coeffs[3 * i], coeffs[3 * i + 1],
                                               coeffs[3 * i + 2], 0.0f);
            sum = _mm_add_ps(sum, _mm_mul_ps(_mm_mul_ps(c, factor), _mm_set1_ps(basis[i])));
        }
    }
    alignas(16) float out[4];
    _mm_store_ps(out, sum);
    return vec3(out[0], out[1], out[2]);
#else
    vec3 sum(0.0f);
    for (int l = 0; l <= kOrder; ++l)
        for (int m = -l; m <= l; ++m) {
            const int i = sh_index(l, m);
            sum += (sh.coeffs[i] * factors[l]) * basis[i];
        }
    return sum;
#endif
}

// evaluate_scaled with the basis of a low order (the fields' 2 and below) computed in place:
// the nine values stay in registers instead of going through sh_eval's array.
template <int kOrder>
vec3 evaluate_scaled_low(const ShRgb& sh, const BandFactors& factors, const vec3& dir) {
    float basis[sh_num_coefficients(kOrder)];
    sh_eval_low_bands<kOrder>(dir, basis);
    return evaluate_scaled<kOrder>(sh, factors, basis);
}

}  // namespace

vec3 sh_evaluate_scaled(const ShRgb& sh, const BandFactors& factors, const vec3& dir) {
    switch (sh.order) {
        case 0: return evaluate_scaled_low<0>(sh, factors, dir);
        case 1: return evaluate_scaled_low<1>(sh, factors, dir);
        case 2: return evaluate_scaled_low<2>(sh, factors, dir);
        default: break;
    }
    float basis[kMaxShCoefficients];
    sh_eval(sh.order, dir, basis);  // checks the order
    return sh.order == 3 ? evaluate_scaled<3>(sh, factors, basis)
                         : evaluate_scaled<4>(sh, factors, basis);
}

}  // namespace shgi
