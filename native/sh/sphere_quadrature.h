// Deterministic quadrature on an interval and on the unit sphere, for projecting analytic
// functions (BRDF lobes, test fields) onto SH without Monte Carlo noise.
//
// gauss_legendre(n, a, b): the n-point Gauss–Legendre rule on [a, b], exact for polynomials of
// degree <= 2n-1 (Golub & Welsch 1969; nodes by Newton iteration on P_n, as in Numerical
// Recipes 3rd ed. §4.6.1). sphere_quadrature(n_theta, n_phi): the product of Gauss–Legendre in
// cos θ with n_phi uniform azimuths; it integrates every spherical polynomial of degree
// <= min(2 n_theta - 1, n_phi - 1) exactly, e.g. Y_i Y_j up to L4 (degree 8) with (16, 32).
// Weights are solid angles (sr) and sum to 4π. All in double precision.
#pragma once

#include <functional>
#include <vector>

#include "sh/zonal_harmonics.h"

namespace shgi {

struct QuadratureRule {
    std::vector<double> nodes;
    std::vector<double> weights;
};

// Throws InvalidArgument unless n >= 1 and a < b are finite.
QuadratureRule gauss_legendre(int n, double a, double b);

struct SphereQuadrature {
    std::vector<glm::dvec3> directions;  // unit vectors, Blender frame
    std::vector<double> weights;         // sr, Σ = 4π
};

// The band of directions with cos θ in [cos_lo, cos_hi] (default: the whole sphere); use
// [0, 1] to integrate a function with a kink at the horizon exactly.
SphereQuadrature sphere_quadrature(int n_theta, int n_phi, double cos_lo = -1.0,
                                   double cos_hi = 1.0);

// z_l = 2π ∫_{cos_lo}^{cos_hi} f(x) Y_l0(x) dx for l = 0..kMaxShOrder, with an n-point rule in
// x = cos θ. Exact when f is a polynomial of degree <= 2n - 1 - kMaxShOrder on the interval.
ZhCoeffs project_zonal(const std::function<double(double cos_theta)>& f, double cos_lo,
                       double cos_hi, int n);

}  // namespace shgi
