// ZH constants of the analytic lobes against numerical projection (seed 003 eq. 3.1, seed 004
// §3.3.1–3.3.2).
#include "sh/lobe_zh.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sh/sphere_quadrature.h"
#include "util/error.h"

namespace shgi {
namespace {

// project_zonal with 32 nodes is exact for polynomials of degree <= 59 - 4 on [0, 1]; the
// lobes below are polynomials there, so the comparison is at float rounding of the result.
constexpr int kZonalNodes = 32;
constexpr float kZhTolerance = 1e-6f;
// Non-integer Phong exponents make cos^n non-polynomial (x^n with fractional n has unbounded
// derivatives at 0); 400 Gauss nodes still converge to ~1e-7 for n >= 0.5.
constexpr int kZonalNodesNonPolynomial = 400;
constexpr float kZhToleranceNonPolynomial = 1e-5f;

void expect_zh_near(const ZhCoeffs& actual, const ZhCoeffs& expected, float tolerance) {
    for (int l = 0; l <= kMaxShOrder; ++l)
        EXPECT_NEAR(actual[l], expected[l], tolerance) << "band " << l;
}

TEST(LobeZh, CosineLobeConstantsOfSeed003) {
    const ZhCoeffs zh = cosine_lobe_zh();
    EXPECT_NEAR(zh[0], std::sqrt(kPi) / 2.0f, kZhTolerance);
    EXPECT_NEAR(zh[1], std::sqrt(kPi / 3.0f), kZhTolerance);
    EXPECT_NEAR(zh[2], std::sqrt(5.0f * kPi) / 8.0f, kZhTolerance);
    EXPECT_NEAR(zh[3], 0.0f, kZhTolerance);
    EXPECT_NEAR(zh[4], -std::sqrt(kPi) / 16.0f, kZhTolerance);
}

TEST(LobeZh, CosineLobeByQuadrature) {
    expect_zh_near(cosine_lobe_zh(), project_zonal([](double c) { return c; }, 0.0, 1.0,
                                                   kZonalNodes),
                   kZhTolerance);
    // Higher bands of the closed form too (odd ones vanish, even ones alternate in sign).
    const QuadratureRule rule = gauss_legendre(kZonalNodes, 0.0, 1.0);
    for (int l = 0; l <= 10; ++l) {
        double integral = 0.0;
        for (size_t i = 0; i < rule.nodes.size(); ++i) {
            const double x = rule.nodes[i];
            const glm::dvec3 dir(std::sqrt(1.0 - x * x), 0.0, x);
            integral += rule.weights[i] * x * sh_eval_reference(l, 0, dir);
        }
        EXPECT_NEAR(cosine_lobe_zh_band(l), 2.0 * kPiD * integral, 1e-12) << "band " << l;
    }
}

TEST(LobeZh, LambertIsAlbedoOverPiTimesCosineLobe) {
    constexpr double kAlbedo = 0.8;
    const ZhCoeffs projected = project_zonal(
        [](double c) { return kAlbedo / kPiD * c; }, 0.0, 1.0, kZonalNodes);
    expect_zh_near(lambert_zh(static_cast<float>(kAlbedo)), projected, kZhTolerance);
    // The seed's own l = 0, 1 values: (k_d/π)·√π/2 and (k_d/π)·√(π/3).
    EXPECT_NEAR(lambert_zh(1.0f)[0], std::sqrt(kPi) / 2.0f / kPi, kZhTolerance);
    EXPECT_NEAR(lambert_zh(1.0f)[1], std::sqrt(kPi / 3.0f) / kPi, kZhTolerance);
}

// The misprinted even-l formula of seed 004 §3.3.1 ((-1)^((l-1)/2), "2! (l/2)!") would give
// |ρ_4| = 2π·√(9/4π)·24/(6·3·2·2) / π ≈ 0.56, against the true 0.0353: this test pins the
// corrected value.
TEST(LobeZh, LambertBand4IsTheCorrectedValue) {
    EXPECT_NEAR(lambert_zh(1.0f)[4], -std::sqrt(kPi) / 16.0f / kPi, kZhTolerance);
    EXPECT_NEAR(lambert_zh(1.0f)[2], std::sqrt(5.0f * kPi) / 8.0f / kPi, kZhTolerance);
}

TEST(LobeZh, PhongByQuadratureForIntegerExponents) {
    for (int n : {0, 1, 2, 5, 10, 32}) {
        const ZhCoeffs projected = project_zonal(
            [n](double c) { return (n + 1.0) / (2.0 * kPiD) * std::pow(c, n); }, 0.0, 1.0,
            kZonalNodes);
        SCOPED_TRACE(::testing::Message() << "exponent " << n);
        expect_zh_near(phong_zh(static_cast<float>(n)), projected, kZhTolerance);
    }
}

TEST(LobeZh, PhongByQuadratureForFractionalExponents) {
    for (double n : {0.5, 2.5, 7.3}) {
        const ZhCoeffs projected = project_zonal(
            [n](double c) { return (n + 1.0) / (2.0 * kPiD) * std::pow(c, n); }, 0.0, 1.0,
            kZonalNodesNonPolynomial);
        SCOPED_TRACE(::testing::Message() << "exponent " << n);
        expect_zh_near(phong_zh(static_cast<float>(n)), projected, kZhToleranceNonPolynomial);
    }
}

// A unit-integral lobe has z_0 = 1/√(4π) whatever the exponent, and sharpens toward the impulse
// (k_l = √(4π/(2l+1)) z_l / (√(4π) z_0) -> 1) as n grows.
TEST(LobeZh, PhongIsNormalisedAndTendsToImpulse) {
    for (float n : {0.0f, 1.0f, 100.0f})
        EXPECT_NEAR(phong_zh(n)[0], 1.0f / std::sqrt(kFourPi), 1e-7f);
    const BandFactors k = zonal_band_factors(phong_zh(1e5f));
    for (int l = 0; l <= kMaxShOrder; ++l) EXPECT_NEAR(k[l] / k[0], 1.0f, 1e-3f);
    EXPECT_FLOAT_EQ(phong_zh(4.0f, 0.5f)[2], 0.5f * phong_zh(4.0f)[2]);
}

TEST(LobeZh, RejectsBadParameters) {
    EXPECT_THROW(phong_zh(-1.0f), InvalidArgument);
    EXPECT_THROW(phong_zh(NAN), InvalidArgument);
    EXPECT_THROW(lambert_zh(INFINITY), InvalidArgument);
    EXPECT_THROW(cosine_lobe_zh_band(-1), InvalidArgument);
}

}  // namespace
}  // namespace shgi
