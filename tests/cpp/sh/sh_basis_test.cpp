// The SH basis against ground truth: orthonormality by exact quadrature, the closed-form
// polynomials against the associated-Legendre reference, and the docs/architecture.md sign
// convention.
#include "sh/sh_basis.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "sh/sphere_quadrature.h"
#include "util/error.h"
#include "util/rng.h"
#include "util/sampling.h"

namespace shgi {
namespace {

// Orthonormality: the product rule below is exact for Y_i Y_j (degree <= 8), so the only error is
// float evaluation of sh_eval (~1e-7 relative, summed over ~500 nodes); 1e-4 is the brief's bound.
constexpr double kOrthonormalityTolerance = 1e-4;
constexpr int kQuadratureThetaNodes = 16;  // exact to degree 31 in cos θ
constexpr int kQuadraturePhiNodes = 32;    // exact to trigonometric degree 31
// Fast (float) vs reference (double): constants are rounded to float, polynomials of degree 4
// in |x|,|y|,|z| <= 1 with values up to ~1.5 lose a few ulp; 2e-6 absolute covers it.
constexpr double kFastVsReferenceTolerance = 2e-6;
constexpr int kRandomDirections = 2000;

TEST(ShBasis, CountsAndIndices) {
    EXPECT_EQ(sh_num_coefficients(0), 1);
    EXPECT_EQ(sh_num_coefficients(2), 9);
    EXPECT_EQ(sh_num_coefficients(4), 25);
    EXPECT_EQ(kMaxShCoefficients, 25);
    EXPECT_EQ(sh_index(1, -1), 1);
    EXPECT_EQ(sh_index(2, 0), 6);
    EXPECT_EQ(sh_index(4, 4), 24);
    for (int l = 0; l <= kMaxShOrder; ++l)
        for (int m = -l; m <= l; ++m) EXPECT_EQ(sh_band(sh_index(l, m)), l);
    for (int order = 0; order <= kMaxShOrder; ++order)
        EXPECT_EQ(sh_order_from_count(sh_num_coefficients(order), "n"), order);
    EXPECT_THROW(sh_order_from_count(5, "n"), InvalidArgument);
    EXPECT_THROW(sh_order_from_count(36, "n"), InvalidArgument);
}

TEST(ShBasis, RejectsUnsupportedOrders) {
    float out[kMaxShCoefficients];
    EXPECT_THROW(sh_eval(-1, vec3(0, 0, 1), out), InvalidArgument);
    EXPECT_THROW(sh_eval(kMaxShOrder + 1, vec3(0, 0, 1), out), InvalidArgument);
    EXPECT_THROW(sh_eval_reference(2, 3, glm::dvec3(0, 0, 1)), InvalidArgument);
}

TEST(ShBasis, OrthonormalByQuadrature) {
    const SphereQuadrature quadrature =
        sphere_quadrature(kQuadratureThetaNodes, kQuadraturePhiNodes);
    std::vector<double> gram(kMaxShCoefficients * kMaxShCoefficients, 0.0);
    float basis[kMaxShCoefficients];
    for (size_t k = 0; k < quadrature.directions.size(); ++k) {
        sh_eval(kMaxShOrder, vec3(quadrature.directions[k]), basis);
        for (int i = 0; i < kMaxShCoefficients; ++i)
            for (int j = 0; j < kMaxShCoefficients; ++j)
                gram[i * kMaxShCoefficients + j] += quadrature.weights[k] * basis[i] * basis[j];
    }
    for (int i = 0; i < kMaxShCoefficients; ++i)
        for (int j = 0; j < kMaxShCoefficients; ++j)
            EXPECT_NEAR(gram[i * kMaxShCoefficients + j], i == j ? 1.0 : 0.0,
                        kOrthonormalityTolerance)
                << "<Y" << i << ", Y" << j << ">";
}

TEST(ShBasis, ReferenceIsOrthonormalToo) {
    const SphereQuadrature quadrature =
        sphere_quadrature(kQuadratureThetaNodes, kQuadraturePhiNodes);
    for (int i = 0; i < kMaxShCoefficients; ++i) {
        const int li = sh_band(i), mi = i - sh_index(li, 0);
        for (int j = 0; j <= i; ++j) {
            const int lj = sh_band(j), mj = j - sh_index(lj, 0);
            double sum = 0.0;
            for (size_t k = 0; k < quadrature.directions.size(); ++k)
                sum += quadrature.weights[k] * sh_eval_reference(li, mi, quadrature.directions[k]) *
                       sh_eval_reference(lj, mj, quadrature.directions[k]);
            EXPECT_NEAR(sum, i == j ? 1.0 : 0.0, 1e-12) << "<Y" << i << ", Y" << j << ">";
        }
    }
}

TEST(ShBasis, FastMatchesReferenceOnRandomDirections) {
    Pcg32 rng(7, 1);
    float basis[kMaxShCoefficients];
    for (int k = 0; k < kRandomDirections; ++k) {
        const vec3 dir = sample_uniform_sphere(rng.next_vec2());
        sh_eval(kMaxShOrder, dir, basis);
        for (int l = 0; l <= kMaxShOrder; ++l)
            for (int m = -l; m <= l; ++m)
                ASSERT_NEAR(basis[sh_index(l, m)], sh_eval_reference(l, m, glm::dvec3(dir)),
                            kFastVsReferenceTolerance)
                    << "l=" << l << " m=" << m << " dir=(" << dir.x << "," << dir.y << ","
                    << dir.z << ")";
    }
}

TEST(ShBasis, LowerOrdersArePrefixesOfHigherOnes) {
    const vec3 dir = glm::normalize(vec3(0.3f, -0.5f, 0.8f));
    float full[kMaxShCoefficients];
    sh_eval(kMaxShOrder, dir, full);
    for (int order = 0; order < kMaxShOrder; ++order) {
        float part[kMaxShCoefficients];
        sh_eval(order, dir, part);
        for (int i = 0; i < sh_num_coefficients(order); ++i) EXPECT_EQ(part[i], full[i]);
    }
}

// docs/architecture.md: Y00 = 0.282095, Y1-1 = +0.488603 y, Y10 = +0.488603 z, Y11 = +0.488603 x,
// no Condon–Shortley phase (every Y_lm with m != 0 is positive where cos/sin(mφ) and the
// polynomial are positive).
TEST(ShBasis, SignConventionHasNoCondonShortleyPhase) {
    constexpr float kDesignPrecision = 1e-6f;  // docs/architecture.md quotes six digits
    float b[kMaxShCoefficients];
    sh_eval(kMaxShOrder, vec3(0, 1, 0), b);
    EXPECT_NEAR(b[0], 0.282095f, kDesignPrecision);
    EXPECT_NEAR(b[1], 0.488603f, kDesignPrecision);  // Y1-1 = +0.488603 y
    EXPECT_NEAR(b[2], 0.0f, kDesignPrecision);
    EXPECT_NEAR(b[3], 0.0f, kDesignPrecision);
    sh_eval(kMaxShOrder, vec3(0, 0, 1), b);
    EXPECT_NEAR(b[2], 0.488603f, kDesignPrecision);  // Y10 = +0.488603 z
    sh_eval(kMaxShOrder, vec3(1, 0, 0), b);
    EXPECT_NEAR(b[3], 0.488603f, kDesignPrecision);  // Y11 = +0.488603 x
    EXPECT_GT(b[sh_index(2, 2)], 0.0f);   // x² - y²
    EXPECT_GT(b[sh_index(3, 3)], 0.0f);   // x (x² - 3y²)
    EXPECT_GT(b[sh_index(4, 4)], 0.0f);   // x⁴ - 6x²y² + y⁴
    // In the first octant away from the axes every non-zonal function with positive
    // polynomial part is positive; check a few that would flip sign under the phase.
    const vec3 d = glm::normalize(vec3(0.5f, 0.3f, 0.8f));
    sh_eval(kMaxShOrder, d, b);
    for (int i : {sh_index(2, -2), sh_index(2, -1), sh_index(2, 1), sh_index(3, -2),
                  sh_index(3, 1), sh_index(3, -1), sh_index(4, 1), sh_index(4, -3)})
        EXPECT_GT(b[i], 0.0f) << "Y" << i;
}

}  // namespace
}  // namespace shgi
