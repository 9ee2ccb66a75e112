#include "sh/sphere_quadrature.h"

#include <algorithm>
#include <cmath>

#include "sh/sh_basis.h"
#include "util/error.h"

namespace shgi {

namespace {

// Newton stops once a step is below this: nodes are then correct to double precision.
constexpr double kNewtonTolerance = 1e-15;
constexpr int kNewtonMaxIterations = 100;

// P_n(x) and its derivative by the three-term recurrence.
void legendre_and_derivative(int n, double x, double& p, double& dp) {
    double p0 = 1.0, p1 = x;
    if (n == 0) {
        p = 1.0;
        dp = 0.0;
        return;
    }
    for (int k = 2; k <= n; ++k) {
        const double pk = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = pk;
    }
    p = p1;
    dp = n * (x * p1 - p0) / (x * x - 1.0);
}

}  // namespace

QuadratureRule gauss_legendre(int n, double a, double b) {
    if (n < 1 || !std::isfinite(a) || !std::isfinite(b) || !(a < b))
        throw InvalidArgument(format_message("gauss_legendre: n = ", n, " on [", a, ", ", b,
                                             "]; need n >= 1 and a finite interval a < b"));
    QuadratureRule rule;
    rule.nodes.resize(n);
    rule.weights.resize(n);
    const double half = 0.5 * (b - a), mid = 0.5 * (a + b);
    // Roots are symmetric: find the upper half, starting from Tricomi's estimate.
    for (int i = 0; i < (n + 1) / 2; ++i) {
        double x = std::cos(kPiD * (i + 0.75) / (n + 0.5));
        double p = 0.0, dp = 1.0;
        for (int iteration = 0; iteration < kNewtonMaxIterations; ++iteration) {
            legendre_and_derivative(n, x, p, dp);
            const double step = p / dp;
            x -= step;
            if (std::abs(step) < kNewtonTolerance) break;
        }
        legendre_and_derivative(n, x, p, dp);
        const double weight = 2.0 / ((1.0 - x * x) * dp * dp);
        rule.nodes[i] = mid + half * x;
        rule.nodes[n - 1 - i] = mid - half * x;
        rule.weights[i] = rule.weights[n - 1 - i] = half * weight;
    }
    return rule;
}

SphereQuadrature sphere_quadrature(int n_theta, int n_phi, double cos_lo, double cos_hi) {
    if (n_phi < 1)
        throw InvalidArgument(format_message("sphere_quadrature: n_phi = ", n_phi, "; need >= 1"));
    if (cos_lo < -1.0 || cos_hi > 1.0)
        throw InvalidArgument(format_message("sphere_quadrature: cos range [", cos_lo, ", ",
                                             cos_hi, "] is not inside [-1, 1]"));
    const QuadratureRule rule = gauss_legendre(n_theta, cos_lo, cos_hi);
    SphereQuadrature quadrature;
    const double phi_weight = 2.0 * kPiD / n_phi;
    for (int i = 0; i < n_theta; ++i) {
        const double cos_theta = rule.nodes[i];
        const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
        for (int j = 0; j < n_phi; ++j) {
            // Offset by half a step so no node sits exactly on the ±X axis seams.
            const double phi = phi_weight * (j + 0.5);
            quadrature.directions.emplace_back(sin_theta * std::cos(phi),
                                               sin_theta * std::sin(phi), cos_theta);
            quadrature.weights.push_back(rule.weights[i] * phi_weight);
        }
    }
    return quadrature;
}

ZhCoeffs project_zonal(const std::function<double(double cos_theta)>& f, double cos_lo,
                       double cos_hi, int n) {
    const QuadratureRule rule = gauss_legendre(n, cos_lo, cos_hi);
    double sum[kMaxShOrder + 1] = {};
    for (int i = 0; i < n; ++i) {
        const double x = rule.nodes[i];
        const glm::dvec3 dir(std::sqrt(std::max(0.0, 1.0 - x * x)), 0.0, x);
        const double fx = f(x) * rule.weights[i];
        for (int l = 0; l <= kMaxShOrder; ++l) sum[l] += fx * sh_eval_reference(l, 0, dir);
    }
    ZhCoeffs zh{};
    for (int l = 0; l <= kMaxShOrder; ++l) zh[l] = static_cast<float>(2.0 * kPiD * sum[l]);
    return zh;
}

}  // namespace shgi
