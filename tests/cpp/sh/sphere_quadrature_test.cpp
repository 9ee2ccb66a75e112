// The quadrature rules the SH tests rely on, against closed-form integrals.
#include "sh/sphere_quadrature.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "util/error.h"

namespace shgi {
namespace {

constexpr double kDoubleExact = 1e-13;

TEST(SphereQuadrature, GaussLegendreIsExactToDegree2nMinus1) {
    for (int n : {1, 2, 5, 16}) {
        const QuadratureRule rule = gauss_legendre(n, -0.5, 2.0);
        for (int degree = 0; degree <= 2 * n - 1; ++degree) {
            double sum = 0.0;
            for (int i = 0; i < n; ++i) sum += rule.weights[i] * std::pow(rule.nodes[i], degree);
            const double exact =
                (std::pow(2.0, degree + 1) - std::pow(-0.5, degree + 1)) / (degree + 1);
            EXPECT_NEAR(sum, exact, kDoubleExact * std::max(1.0, std::abs(exact)))
                << "n=" << n << " degree=" << degree;
        }
    }
}

TEST(SphereQuadrature, WeightsSumToSolidAngle) {
    const SphereQuadrature full = sphere_quadrature(8, 16);
    EXPECT_NEAR(std::accumulate(full.weights.begin(), full.weights.end(), 0.0), 4.0 * kPiD,
                kDoubleExact);
    const SphereQuadrature upper = sphere_quadrature(8, 16, 0.0, 1.0);
    EXPECT_NEAR(std::accumulate(upper.weights.begin(), upper.weights.end(), 0.0), 2.0 * kPiD,
                kDoubleExact);
    for (const glm::dvec3& d : full.directions) EXPECT_NEAR(glm::length(d), 1.0, kDoubleExact);
}

TEST(SphereQuadrature, IntegratesSphericalMonomials) {
    // ∫ x² z² dω = 4π/15, ∫ x⁴ dω = 4π/5 over the unit sphere.
    const SphereQuadrature q = sphere_quadrature(6, 12);
    double x2z2 = 0.0, x4 = 0.0;
    for (size_t k = 0; k < q.directions.size(); ++k) {
        const glm::dvec3& d = q.directions[k];
        x2z2 += q.weights[k] * d.x * d.x * d.z * d.z;
        x4 += q.weights[k] * d.x * d.x * d.x * d.x;
    }
    EXPECT_NEAR(x2z2, 4.0 * kPiD / 15.0, kDoubleExact);
    EXPECT_NEAR(x4, 4.0 * kPiD / 5.0, kDoubleExact);
}

TEST(SphereQuadrature, RejectsBadRules) {
    EXPECT_THROW(gauss_legendre(0, 0.0, 1.0), InvalidArgument);
    EXPECT_THROW(gauss_legendre(4, 1.0, 0.0), InvalidArgument);
    EXPECT_THROW(sphere_quadrature(4, 0), InvalidArgument);
    EXPECT_THROW(sphere_quadrature(4, 8, -2.0, 1.0), InvalidArgument);
}

}  // namespace
}  // namespace shgi
