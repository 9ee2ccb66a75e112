// Zonal-harmonic rotation and convolution against direct quadrature (Sloan 2008; seed 003
// eq. 3.2; seed 004 §3.3).
#include "sh/zonal_harmonics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "sh/lobe_zh.h"
#include "sh/sphere_quadrature.h"
#include "util/error.h"
#include "util/rng.h"
#include "util/sampling.h"

namespace shgi {
namespace {

// Both sides are exact for the polynomial lobes used (cosine, Phong n = 6 on the hemisphere):
// what is left is float rounding of coefficients of size <= ~1.
constexpr float kRotationTolerance = 2e-5f;
// Convolved values of a random L4 field reach ~10: float rounding stays below 1e-4 absolute.
constexpr float kConvolutionTolerance = 1e-4f;
constexpr int kRandomAxes = 20;

// Projects the lobe f(axis·ω) (zero where axis·ω < 0) onto SH by a hemisphere quadrature around
// `axis`; exact when f is a polynomial of degree <= 2·n_theta - 1 - 4.
ShCoeffs project_rotated_lobe(int order, const std::function<double(double)>& lobe,
                              const vec3& axis) {
    const SphereQuadrature local = sphere_quadrature(16, 32, 0.0, 1.0);
    const Frame frame = Frame::from_z(axis);
    ShCoeffs out(order);
    float basis[kMaxShCoefficients];
    for (size_t k = 0; k < local.directions.size(); ++k) {
        const vec3 w = glm::normalize(frame.to_world(vec3(local.directions[k])));
        sh_eval(order, w, basis);
        const double f = local.weights[k] * lobe(local.directions[k].z);
        for (int i = 0; i < out.num_coefficients(); ++i)
            out.coeffs[i] += static_cast<float>(f * basis[i]);
    }
    return out;
}

void expect_rotation_matches_projection(const ZhCoeffs& zh,
                                        const std::function<double(double)>& lobe) {
    Pcg32 rng(17, 5);
    for (int k = 0; k < kRandomAxes; ++k) {
        const vec3 axis = sample_uniform_sphere(rng.next_vec2());
        const ShCoeffs rotated = sh_rotate_zonal(kMaxShOrder, zh, axis);
        const ShCoeffs projected = project_rotated_lobe(kMaxShOrder, lobe, axis);
        for (int i = 0; i < kMaxShCoefficients; ++i)
            ASSERT_NEAR(rotated.coeffs[i], projected.coeffs[i], kRotationTolerance)
                << "coefficient " << i << " axis (" << axis.x << ", " << axis.y << ", " << axis.z
                << ")";
    }
}

TEST(ZonalHarmonics, RotatedCosineLobeMatchesDirectProjection) {
    expect_rotation_matches_projection(cosine_lobe_zh(), [](double c) { return c; });
}

TEST(ZonalHarmonics, RotatedPhongLobeMatchesDirectProjection) {
    constexpr double kExponent = 6.0;
    expect_rotation_matches_projection(phong_zh(static_cast<float>(kExponent)), [](double c) {
        return (kExponent + 1.0) / (2.0 * kPiD) * std::pow(c, kExponent);
    });
}

TEST(ZonalHarmonics, RotationToPlusZKeepsOnlyZonalCoefficients) {
    const ZhCoeffs zh = cosine_lobe_zh();
    const ShCoeffs sh = sh_rotate_zonal(kMaxShOrder, zh, vec3(0, 0, 1));
    for (int l = 0; l <= kMaxShOrder; ++l)
        for (int m = -l; m <= l; ++m)
            EXPECT_NEAR(sh.coeffs[sh_index(l, m)], m == 0 ? zh[l] : 0.0f, 1e-6f);
}

// Funk–Hecke: ∫ L(ω) h(d·ω) dω = Σ k_l L_lm Y_lm(d), k_l = √(4π/(2l+1)) h_l. Checked for the
// Phong lobe on a random L4 field by brute force around d.
TEST(ZonalHarmonics, ConvolutionByBandFactorsMatchesBruteForce) {
    constexpr double kExponent = 3.0;
    const auto lobe = [](double c) {
        return (kExponent + 1.0) / (2.0 * kPiD) * std::pow(c, kExponent);
    };
    Pcg32 rng(23, 0);
    ShCoeffs field(4);
    for (int i = 0; i < 25; ++i) field.coeffs[i] = 2.0f * rng.next_float() - 1.0f;
    ShCoeffs convolved = field;
    sh_scale_bands(convolved, zonal_band_factors(phong_zh(static_cast<float>(kExponent))));
    const SphereQuadrature local = sphere_quadrature(16, 32, 0.0, 1.0);
    for (int k = 0; k < kRandomAxes; ++k) {
        const vec3 d = sample_uniform_sphere(rng.next_vec2());
        const Frame frame = Frame::from_z(d);
        double brute = 0.0;
        for (size_t q = 0; q < local.directions.size(); ++q)
            brute += local.weights[q] * lobe(local.directions[q].z) *
                     sh_evaluate(field, glm::normalize(frame.to_world(vec3(local.directions[q]))));
        EXPECT_NEAR(sh_evaluate(convolved, d), brute, kConvolutionTolerance);
    }
}

// The fused form is the same float arithmetic as scaling a copy and evaluating it: equal bits.
TEST(ZonalHarmonics, EvaluateScaledIsScaleThenEvaluate) {
    Pcg32 rng(29, 0);
    const BandFactors factors = zonal_band_factors(phong_zh(5.0f));
    for (int order = 0; order <= kMaxShOrder; ++order) {
        ShRgb field(order);
        for (int i = 0; i < field.num_coefficients(); ++i)
            field.coeffs[i] = 2.0f * vec3(rng.next_float(), rng.next_float(), rng.next_float()) -
                              1.0f;
        ShRgb scaled = field;
        sh_scale_bands(scaled, factors);
        for (int k = 0; k < kRandomAxes; ++k) {
            const vec3 d = sample_uniform_sphere(rng.next_vec2());
            EXPECT_EQ(sh_evaluate_scaled(field, factors, d), sh_evaluate(scaled, d))
                << "order " << order;
        }
    }
}

TEST(ZonalHarmonics, RejectsBadInput) {
    EXPECT_THROW(sh_rotate_zonal(2, cosine_lobe_zh(), vec3(0, 0, 2)), InvalidArgument);
    EXPECT_THROW(sh_rotate_zonal(5, cosine_lobe_zh(), vec3(0, 0, 1)), InvalidArgument);
}

}  // namespace
}  // namespace shgi
