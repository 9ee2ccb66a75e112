// SH coefficient vectors: ShCoeffs (one channel) and ShRgb (linear Rec.709 RGB).
//
// Both have a run-time order 0..kMaxShOrder and a fixed capacity of 25 coefficients, so they
// are plain values (no heap) that lattices and probe grids can store in arrays. ShRgb keeps the
// docs/architecture.md storage layout: coefficient-major [coeff][rgb] float32, i.e. `coeffs` is 25
// vec3 with three contiguous floats each. Coefficients beyond `num_coefficients()` are zero.
//
// Units are those of the projected function: a probe of incident radiance stores W·m⁻²·sr⁻¹
// coefficients; sh_evaluate then returns radiance in that unit. Basis: sh/sh_basis.h.
#pragma once

#include <array>

#include "sh/sh_basis.h"
#include "util/math.h"

namespace shgi {

struct ShCoeffs {
    int order = 2;
    std::array<float, kMaxShCoefficients> coeffs{};

    ShCoeffs() = default;
    // All-zero expansion of the given order; throws InvalidArgument for an order outside 0..4.
    explicit ShCoeffs(int order_);

    int num_coefficients() const { return sh_num_coefficients(order); }
    float& operator[](int i) { return coeffs[i]; }
    float operator[](int i) const { return coeffs[i]; }
};

struct ShRgb {
    int order = 2;
    std::array<vec3, kMaxShCoefficients> coeffs{};

    ShRgb() = default;
    explicit ShRgb(int order_);

    int num_coefficients() const { return sh_num_coefficients(order); }
    vec3& operator[](int i) { return coeffs[i]; }
    const vec3& operator[](int i) const { return coeffs[i]; }
    // Coefficient-major float view: data()[3 * i + c] is coefficient i of channel c.
    float* data() { return &coeffs[0].x; }
    const float* data() const { return &coeffs[0].x; }
};

// The reconstructed function at unit direction `dir`: Σ_i c_i Y_i(dir).
float sh_evaluate(const ShCoeffs& sh, const vec3& dir);
vec3 sh_evaluate(const ShRgb& sh, const vec3& dir);

// ∫ f g dω of two expansions (orthonormality makes it the dot product of the coefficients);
// the shorter order wins, as the missing bands are zero.
float sh_dot(const ShCoeffs& a, const ShCoeffs& b);
// Per channel: Σ_i a_i b_i with scalar b (e.g. radiance against a projected BRDF lobe).
vec3 sh_dot(const ShRgb& a, const ShCoeffs& b);

// a += scale * b, channel-wise; orders must match (InvalidArgument otherwise).
void sh_add_scaled(ShRgb& a, const ShRgb& b, float scale);

// One channel of an RGB expansion (0 = R, 1 = G, 2 = B).
ShCoeffs sh_channel(const ShRgb& sh, int channel);

}  // namespace shgi
