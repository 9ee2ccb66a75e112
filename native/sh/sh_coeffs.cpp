#include "sh/sh_coeffs.h"

#include <algorithm>

#include "util/error.h"

namespace shgi {

ShCoeffs::ShCoeffs(int order_) : order(order_) { check_sh_order(order_, "ShCoeffs"); }

ShRgb::ShRgb(int order_) : order(order_) { check_sh_order(order_, "ShRgb"); }

float sh_evaluate(const ShCoeffs& sh, const vec3& dir) {
    float basis[kMaxShCoefficients];
    sh_eval(sh.order, dir, basis);
    float sum = 0.0f;
    for (int i = 0; i < sh.num_coefficients(); ++i) sum += sh.coeffs[i] * basis[i];
    return sum;
}

vec3 sh_evaluate(const ShRgb& sh, const vec3& dir) {
    float basis[kMaxShCoefficients];
    sh_eval(sh.order, dir, basis);
    vec3 sum(0.0f);
    for (int i = 0; i < sh.num_coefficients(); ++i) sum += sh.coeffs[i] * basis[i];
    return sum;
}

float sh_dot(const ShCoeffs& a, const ShCoeffs& b) {
    const int n = sh_num_coefficients(std::min(a.order, b.order));
    float sum = 0.0f;
    for (int i = 0; i < n; ++i) sum += a.coeffs[i] * b.coeffs[i];
    return sum;
}

vec3 sh_dot(const ShRgb& a, const ShCoeffs& b) {
    const int n = sh_num_coefficients(std::min(a.order, b.order));
    vec3 sum(0.0f);
    for (int i = 0; i < n; ++i) sum += a.coeffs[i] * b.coeffs[i];
    return sum;
}

void sh_add_scaled(ShRgb& a, const ShRgb& b, float scale) {
    if (a.order != b.order)
        throw InvalidArgument(format_message("sh_add_scaled: orders differ (", a.order, " and ",
                                             b.order, "); convert one first"));
    for (int i = 0; i < a.num_coefficients(); ++i) a.coeffs[i] += scale * b.coeffs[i];
}

ShCoeffs sh_channel(const ShRgb& sh, int channel) {
    if (channel < 0 || channel > 2)
        throw InvalidArgument(format_message("sh_channel: channel ", channel, " is not 0, 1 or 2"));
    ShCoeffs out(sh.order);
    for (int i = 0; i < sh.num_coefficients(); ++i) out.coeffs[i] = sh.coeffs[i][channel];
    return out;
}

}  // namespace shgi
