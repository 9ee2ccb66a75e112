#include "sh/sh_basis.h"

#include <algorithm>
#include <cmath>

#include "util/error.h"

namespace shgi {

namespace {

// Normalisation constants of bands 3 and 4's polynomial forms (bands 0..2's are in sh_basis.h),
// computed and checked as those.
constexpr float kY33 = 0.59004358992664363f;          // Y3±3
constexpr float kY3xyz = 2.8906114426405547f;         // Y3-2 = k xyz
constexpr float kY31 = 0.45704579946446577f;          // Y3±1 = k {y, x} (5z² - 1)
constexpr float kY30 = 0.3731763325901154f;           // Y30 = k z (5z² - 3)
constexpr float kY32 = 1.4453057213202773f;           // Y32 = k z (x² - y²)
constexpr float kY4m4 = 2.503342941796705f;           // Y4-4 = k xy (x² - y²)
constexpr float kY43 = 1.7701307697799307f;           // Y4±3
constexpr float kY4m2 = 0.94617469575755997f;         // Y4-2 = k xy (7z² - 1)
constexpr float kY41 = 0.66904654355728921f;          // Y4±1 = k {y, x} z (7z² - 3)
constexpr float kY40 = 0.10578554691520431f;          // Y40 = k (35z⁴ - 30z² + 3)
constexpr float kY42 = 0.47308734787877998f;          // Y42 = k (x² - y²)(7z² - 1)
constexpr float kY44 = 0.62583573544917626f;          // Y44 = k (x⁴ - 6x²y² + y⁴)

// Bands 3 and 4 of the polynomial evaluation; `out` points at the full array.
void eval_band3(float x, float y, float z, float* out) {
    const float x2 = x * x, y2 = y * y, z2 = z * z;
    out[9] = kY33 * y * (3.0f * x2 - y2);
    out[10] = kY3xyz * x * y * z;
    out[11] = kY31 * y * (5.0f * z2 - 1.0f);
    out[12] = kY30 * z * (5.0f * z2 - 3.0f);
    out[13] = kY31 * x * (5.0f * z2 - 1.0f);
    out[14] = kY32 * z * (x2 - y2);
    out[15] = kY33 * x * (x2 - 3.0f * y2);
}

void eval_band4(float x, float y, float z, float* out) {
    const float x2 = x * x, y2 = y * y, z2 = z * z;
    out[16] = kY4m4 * x * y * (x2 - y2);
    out[17] = kY43 * y * z * (3.0f * x2 - y2);
    out[18] = kY4m2 * x * y * (7.0f * z2 - 1.0f);
    out[19] = kY41 * y * z * (7.0f * z2 - 3.0f);
    out[20] = kY40 * (35.0f * z2 * z2 - 30.0f * z2 + 3.0f);
    out[21] = kY41 * x * z * (7.0f * z2 - 3.0f);
    out[22] = kY42 * (x2 - y2) * (7.0f * z2 - 1.0f);
    out[23] = kY43 * x * z * (x2 - 3.0f * y2);
    out[24] = kY44 * (x2 * x2 - 6.0f * x2 * y2 + y2 * y2);
}

// P_l^m(x) for m >= 0 WITHOUT the Condon–Shortley phase, by the standard stable recurrence
// (Press et al., Numerical Recipes 3rd ed. §6.7): P_m^m = (2m-1)!! (1-x²)^{m/2},
// P_{m+1}^m = x (2m+1) P_m^m, (l-m) P_l^m = x (2l-1) P_{l-1}^m - (l+m-1) P_{l-2}^m.
double legendre_no_phase(int l, int m, double x) {
    const double sin_theta = std::sqrt(std::max(0.0, 1.0 - x * x));
    double pmm = 1.0;
    for (int k = 1; k <= m; ++k) pmm *= (2.0 * k - 1.0) * sin_theta;
    if (l == m) return pmm;
    double pm1 = x * (2.0 * m + 1.0) * pmm;
    for (int ll = m + 2; ll <= l; ++ll) {
        const double pll = (x * (2.0 * ll - 1.0) * pm1 - (ll + m - 1.0) * pmm) / (ll - m);
        pmm = pm1;
        pm1 = pll;
    }
    return pm1;
}

}  // namespace

int sh_band(int index) {
    int l = 0;
    while ((l + 1) * (l + 1) <= index) ++l;
    return l;
}

void throw_bad_sh_order(int order, const char* what) {
    throw InvalidArgument(format_message(what, ": SH order ", order, " is not supported; use 0..",
                                         kMaxShOrder));
}

int sh_order_from_count(int num_coefficients, const char* what) {
    for (int order = 0; order <= kMaxShOrder; ++order)
        if (sh_num_coefficients(order) == num_coefficients) return order;
    throw InvalidArgument(format_message(what, ": ", num_coefficients,
                                         " SH coefficients is not (order+1)^2 for an order in 0..",
                                         kMaxShOrder, " (expected 1, 4, 9, 16 or 25)"));
}

void sh_eval(int order, const vec3& dir, float* out) {
    check_sh_order(order, "sh_eval");
    const float x = dir.x, y = dir.y, z = dir.z;
    if (order < 1) return sh_eval_low_bands<0>(dir, out);
    if (order < 2) return sh_eval_low_bands<1>(dir, out);
    sh_eval_low_bands<2>(dir, out);
    if (order < 3) return;
    eval_band3(x, y, z, out);
    if (order < 4) return;
    eval_band4(x, y, z, out);
}

double sh_eval_reference(int l, int m, const glm::dvec3& dir) {
    if (l < 0 || m < -l || m > l)
        throw InvalidArgument(format_message("sh_eval_reference: (l, m) = (", l, ", ", m,
                                             ") is not a valid SH index; need |m| <= l"));
    const int am = std::abs(m);
    // K_lm = sqrt((2l+1)/(4π) (l-|m|)!/(l+|m|)!), the factorial ratio as a running product.
    double ratio = 1.0;
    for (int k = l - am + 1; k <= l + am; ++k) ratio /= k;
    const double k_lm = std::sqrt((2.0 * l + 1.0) / (4.0 * kPiD) * ratio);
    const double p = legendre_no_phase(l, am, std::clamp(dir.z, -1.0, 1.0));
    if (m == 0) return k_lm * p;
    const double phi = std::atan2(dir.y, dir.x);
    const double azimuth = m > 0 ? std::cos(m * phi) : std::sin(am * phi);
    return std::sqrt(2.0) * k_lm * p * azimuth;
}

}  // namespace shgi
