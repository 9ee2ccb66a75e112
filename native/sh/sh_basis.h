// The real spherical-harmonics basis Y_i(ω) up to order L4, evaluated fast and by a slow reference.
//
// Convention (docs/architecture.md, "SH"): real, orthonormal over the unit sphere (∫ Y_i Y_j dω =
// δ_ij), index i = l(l+1) + m, WITHOUT the Condon–Shortley phase, as in Ramamoorthi & Hanrahan 2001
// ("An efficient representation for irradiance environment maps", eq. 3) and three.js:
//     Y00 = 0.282095, Y1-1 = +0.488603 y, Y10 = +0.488603 z, Y11 = +0.488603 x.
// For m > 0, Y_lm = √2 K_lm P_l^m(cos θ) cos(mφ); for m < 0, √2 K_l|m| P_l^|m|(cos θ) sin(|m|φ);
// K_lm = √((2l+1)/(4π) (l-|m|)!/(l+|m|)!), P_l^m without the (-1)^m factor. θ is measured from
// +Z and φ from +X towards +Y (Blender's frame, util/math.h). Orders 0..4 (1..25 coefficients).
//
// sh_eval is the closed-form polynomial form (Sloan 2013, "Efficient Spherical Harmonic
// Evaluation", with the phase removed) used in every hot loop; sh_eval_reference uses the
// associated-Legendre recurrence in double precision and exists to check it.
#pragma once

#include "util/math.h"

namespace shgi {

inline constexpr int kMaxShOrder = 4;
inline constexpr int kMaxShCoefficients = (kMaxShOrder + 1) * (kMaxShOrder + 1);

// Number of coefficients of an order-`order` expansion: (order + 1)^2.
constexpr int sh_num_coefficients(int order) { return (order + 1) * (order + 1); }

// Flat index of (l, m), -l <= m <= l.
constexpr int sh_index(int l, int m) { return l * (l + 1) + m; }

// Band l of flat index i (the inverse of sh_index for the l part).
int sh_band(int index);

// Throws InvalidArgument naming `what` for an order outside 0..kMaxShOrder.
[[noreturn]] void throw_bad_sh_order(int order, const char* what);

// Throws InvalidArgument naming `what` unless 0 <= order <= kMaxShOrder. Inline, so that the
// compiler sees that a bad constant order never reaches the loops after the check (with
// link-time optimisation it otherwise warns that those loops would overrun their arrays).
inline void check_sh_order(int order, const char* what) {
    if (order < 0 || order > kMaxShOrder) throw_bad_sh_order(order, what);
}

// Order of an expansion with `num_coefficients` coefficients; throws InvalidArgument naming
// `what` unless the count is a perfect square (order + 1)^2 with order <= kMaxShOrder.
int sh_order_from_count(int num_coefficients, const char* what);

// Normalisation constants of bands 0..2's polynomial forms, K_lm times the factors that turn
// P_l^m(z) cos/sin(mφ) into a polynomial in x, y, z (e.g. sin(2φ) sin²θ = 2xy). Computed in
// double from K_lm and checked against sh_eval_reference in sh_basis_test.cpp.
inline constexpr float kShY00 = 0.28209479177387814f;  // 1 / (2√π)
inline constexpr float kShY1 = 0.48860251190291992f;   // √3 / (2√π)
inline constexpr float kShY2xy = 1.0925484305920792f;  // Y2-2 = k xy,  Y2-1 = k yz, Y21 = k xz
inline constexpr float kShY20 = 0.31539156525252005f;  // Y20 = k (3z² - 1)
inline constexpr float kShY22 = 0.54627421529603959f;  // Y22 = k (x² - y²)

// sh_eval's bands 0..kOrder for kOrder <= 2, inline: the same expressions (so the same bits),
// for callers that evaluate a low-order expansion once per shading point and keep the basis in
// registers (sh_evaluate_scaled) rather than pass it through memory.
template <int kOrder>
inline void sh_eval_low_bands(const vec3& dir, float* out) {
    static_assert(kOrder >= 0 && kOrder <= 2, "bands 3 and 4 are sh_eval's");
    const float x = dir.x, y = dir.y, z = dir.z;
    out[0] = kShY00;
    if constexpr (kOrder >= 1) {
        out[1] = kShY1 * y;
        out[2] = kShY1 * z;
        out[3] = kShY1 * x;
    }
    if constexpr (kOrder >= 2) {
        out[4] = kShY2xy * x * y;
        out[5] = kShY2xy * y * z;
        out[6] = kShY20 * (3.0f * z * z - 1.0f);
        out[7] = kShY2xy * x * z;
        out[8] = kShY22 * (x * x - y * y);
    }
}

// Writes Y_0 .. Y_{n-1}, n = sh_num_coefficients(order), at the unit direction `dir` into
// `out`. `dir` must be normalised (not checked: this is the inner loop of every projection).
// Throws InvalidArgument for an order outside 0..kMaxShOrder.
void sh_eval(int order, const vec3& dir, float* out);

// Slow reference for tests: the same basis from the associated-Legendre recurrence in double
// precision, valid for any l, m (not limited to kMaxShOrder). `dir` must be normalised.
double sh_eval_reference(int l, int m, const glm::dvec3& dir);

}  // namespace shgi
