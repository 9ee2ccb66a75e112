#include "sh/lobe_zh.h"

#include <cmath>

#include "util/error.h"

namespace shgi {

namespace {

// √((2l+1)/(4π)): the normalisation of Y_l0 at the pole.
double y_l0_norm(int l) { return std::sqrt((2.0 * l + 1.0) / (4.0 * kPiD)); }

// ∫_0^1 x^n P_l(x) dx · (n+1): the Phong products of seed 004 §3.3.2.
double phong_band_integral(int l, double n) {
    double numerator = 1.0, denominator = 1.0;
    if (l % 2 == 1) {
        numerator = n + 1.0;
        for (int j = 1; j <= (l - 1) / 2; ++j) numerator *= n + 1.0 - 2.0 * j;  // (n-1)…(n-l+2)
        for (int j = 0; j <= (l - 1) / 2; ++j) denominator *= n + l + 1.0 - 2.0 * j;  // …(n+2)
    } else {
        for (int j = 0; j < l / 2; ++j) numerator *= n - 2.0 * j;               // n…(n-l+2)
        for (int j = 0; j < l / 2; ++j) denominator *= n + l + 1.0 - 2.0 * j;   // …(n+3)
    }
    return numerator / denominator;
}

}  // namespace

double cosine_lobe_zh_band(int l) {
    if (l < 0)
        throw InvalidArgument(format_message("cosine_lobe_zh_band: band ", l, " is negative"));
    if (l == 0) return std::sqrt(kPiD) / 2.0;
    if (l == 1) return std::sqrt(kPiD / 3.0);
    if (l % 2 == 1) return 0.0;
    // Ramamoorthi & Hanrahan 2001 eq. 8 (Â_l) divided by √(4π/(2l+1)).
    double factorial_l = 1.0, factorial_half = 1.0;
    for (int k = 2; k <= l; ++k) factorial_l *= k;
    for (int k = 2; k <= l / 2; ++k) factorial_half *= k;
    const double sign = (l / 2 - 1) % 2 == 0 ? 1.0 : -1.0;
    return 2.0 * kPiD * y_l0_norm(l) * sign * factorial_l /
           ((l + 2.0) * (l - 1.0) * std::ldexp(1.0, l) * factorial_half * factorial_half);
}

ZhCoeffs cosine_lobe_zh() {
    ZhCoeffs zh{};
    for (int l = 0; l <= kMaxShOrder; ++l) zh[l] = static_cast<float>(cosine_lobe_zh_band(l));
    return zh;
}

ZhCoeffs lambert_zh(float albedo) {
    if (!std::isfinite(albedo))
        throw InvalidArgument(format_message("lambert_zh: albedo is ", albedo, "; need finite"));
    ZhCoeffs zh{};
    for (int l = 0; l <= kMaxShOrder; ++l)
        zh[l] = static_cast<float>(albedo / kPiD * cosine_lobe_zh_band(l));
    return zh;
}

ZhCoeffs phong_zh(float exponent, float specular) {
    if (!std::isfinite(exponent) || exponent < 0.0f)
        throw InvalidArgument(format_message("phong_zh: exponent is ", exponent,
                                             "; the Phong exponent must be finite and >= 0"));
    if (!std::isfinite(specular))
        throw InvalidArgument(format_message("phong_zh: specular is ", specular, "; need finite"));
    ZhCoeffs zh{};
    for (int l = 0; l <= kMaxShOrder; ++l)
        zh[l] = static_cast<float>(specular * y_l0_norm(l) * phong_band_integral(l, exponent));
    return zh;
}

}  // namespace shgi
