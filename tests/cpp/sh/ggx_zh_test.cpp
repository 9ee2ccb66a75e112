// The fitted GGX lobe of seed 002 Appendix A: its limits, its smoothness, and its agreement
// with a numerical projection of the GGX prefiltering lobe (see sh/ggx_zh.h for the lobe).
#include "sh/ggx_zh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "sh/lobe_zh.h"
#include "sh/sh_irradiance.h"
#include "util/error.h"

namespace shgi {
namespace {

// The seed's fit evaluated in float differs from the projected lobe by at most 2.2e-4 over 1001
// roughness values (the worst is roughness 0, where the fit gives 1.0002 for L4); 1e-3 leaves
// margin for float rounding of the fit's cancelling cosine terms (amplitudes up to 21).
constexpr float kFitVsProjectionTolerance = 1e-3f;
constexpr int kRoughnessSteps = 100;
// Neighbouring roughness values 0.01 apart: the fit's derivative is below ~2.5 per unit
// roughness (L4 at mid roughness), so a step changes a factor by < 0.03.
constexpr float kMaxStepChange = 0.03f;

TEST(GgxZh, RoughnessZeroIsTheImpulse) {
    const BandFactors k = ggx_specular_zh(0.0f);
    for (int l = 0; l <= kMaxShOrder; ++l) EXPECT_NEAR(k[l], 1.0f, kFitVsProjectionTolerance);
    const BandFactors reference = ggx_specular_zh_reference(0.0f);
    for (int l = 0; l <= kMaxShOrder; ++l) EXPECT_EQ(reference[l], 1.0f);
}

// Seed 002 §4.2.2: the curve "fades from a lobe representing impulse response to a lobe
// representing a clamped cosine lobe": at roughness 1, Â_l / Â_0 = 1, 2/3, 1/4, 0, -1/24.
TEST(GgxZh, RoughnessOneIsTheNormalisedCosineLobe) {
    const BandFactors k = ggx_specular_zh(1.0f);
    const BandFactors reference = ggx_specular_zh_reference(1.0f);
    const BandFactors cosine = cosine_lobe_band_factors();
    for (int l = 0; l <= kMaxShOrder; ++l) {
        EXPECT_NEAR(k[l], cosine[l] / cosine[0], kFitVsProjectionTolerance) << "band " << l;
        EXPECT_NEAR(reference[l], cosine[l] / cosine[0], 1e-6f) << "band " << l;
    }
}

TEST(GgxZh, FitMatchesNumericallyProjectedLobe) {
    for (int step = 0; step <= kRoughnessSteps; ++step) {
        const float roughness = static_cast<float>(step) / kRoughnessSteps;
        const BandFactors fit = ggx_specular_zh(roughness);
        const BandFactors reference = ggx_specular_zh_reference(roughness);
        EXPECT_EQ(fit[0], 1.0f);
        for (int l = 1; l <= kMaxShOrder; ++l)
            EXPECT_NEAR(fit[l], reference[l], kFitVsProjectionTolerance)
                << "roughness " << roughness << " band " << l;
    }
}

TEST(GgxZh, FitIsContinuousAndInRange) {
    BandFactors previous = ggx_specular_zh(0.0f);
    for (int step = 1; step <= kRoughnessSteps; ++step) {
        const BandFactors k = ggx_specular_zh(static_cast<float>(step) / kRoughnessSteps);
        for (int l = 1; l <= kMaxShOrder; ++l) {
            EXPECT_LT(std::abs(k[l] - previous[l]), kMaxStepChange) << "step " << step;
            // A unit-integral non-negative lobe has |k_l| <= k_0 = 1 (|P_l| <= 1); the fit may
            // overshoot by its error.
            EXPECT_LE(std::abs(k[l]), 1.0f + kFitVsProjectionTolerance);
            // Sharper lobes keep more of every band: k_l is non-increasing in l for l <= 3.
            if (l <= 3) {
                EXPECT_LE(k[l], k[l - 1] + kFitVsProjectionTolerance);
            }
        }
        previous = k;
    }
}

TEST(GgxZh, SpecularRadianceIsClampedAtZero) {
    // A field that is strongly negative along -Z after reconstruction (ringing of a bright
    // spot along +Z with a negative constant term).
    ShRgb radiance(4);
    radiance.coeffs[0] = vec3(-1.0f);
    radiance.coeffs[sh_index(1, 0)] = vec3(0.5f);
    EXPECT_EQ(sh_specular_radiance(radiance, vec3(0, 0, -1), 0.3f), vec3(0.0f));
    // A constant field L·√(4π) on Y00 gives L back for every roughness (k_0 = 1).
    ShRgb constant(2);
    constant.coeffs[0] = vec3(1.0f, 2.0f, 3.0f) * std::sqrt(kFourPi);
    const vec3 l = sh_specular_radiance(constant, glm::normalize(vec3(1, 1, 0)), 0.6f);
    EXPECT_NEAR(l.x, 1.0f, 1e-5f);
    EXPECT_NEAR(l.z, 3.0f, 1e-5f);
}

// The table's interpolation error (measured: 2.2e-5 at most, in bands 3 and 4) with margin for
// a different compiler's rounding of the fit; a fifth of the fit's distance to the true lobe.
constexpr float kTabulatedVsFitTolerance = 5e-5f;
constexpr int kTabulatedSteps = 20000;  // ~78 samples per table interval

TEST(GgxZh, TabulatedMatchesFitEverywhere) {
    for (int step = 0; step <= kTabulatedSteps; ++step) {
        const float roughness = static_cast<float>(step) / kTabulatedSteps;
        const BandFactors fit = ggx_specular_zh(roughness);
        const BandFactors tabulated = ggx_specular_zh_tabulated(roughness);
        EXPECT_EQ(tabulated[0], 1.0f);
        for (int l = 1; l <= kMaxShOrder; ++l)
            ASSERT_NEAR(tabulated[l], fit[l], kTabulatedVsFitTolerance)
                << "roughness " << roughness << " band " << l;
    }
}

TEST(GgxZh, TabulatedIsTheFitAtTableNodes) {
    for (int i = 0; i <= kGgxZhTableIntervals; ++i) {
        const float roughness = static_cast<float>(i) / kGgxZhTableIntervals;
        const BandFactors fit = ggx_specular_zh(roughness);
        const BandFactors tabulated = ggx_specular_zh_tabulated(roughness);
        for (int l = 0; l <= kMaxShOrder; ++l)
            EXPECT_EQ(tabulated[l], fit[l]) << "roughness " << roughness << " band " << l;
    }
}

// sh_specular_radiance is the tabulated factors applied to the field, evaluated at `reflected`.
TEST(GgxZh, SpecularRadianceIsTheFilteredFieldInTheReflectedDirection) {
    ShRgb radiance(2);
    for (int i = 0; i < radiance.num_coefficients(); ++i)
        radiance.coeffs[i] = vec3(1.0f + 0.1f * float(i), 0.5f, 0.25f * float(i % 3));
    const vec3 reflected = glm::normalize(vec3(0.3f, -0.2f, 0.9f));
    for (float roughness : {0.0f, 0.25f, 0.8f, 1.0f}) {
        ShRgb filtered = radiance;
        sh_scale_bands(filtered, ggx_specular_zh_tabulated(roughness));
        const vec3 expected = glm::max(sh_evaluate(filtered, reflected), vec3(0.0f));
        EXPECT_EQ(sh_specular_radiance(radiance, reflected, roughness), expected)
            << "roughness " << roughness;
    }
}

// The memo gives ggx_specular_zh_tabulated's bits for any sequence of roughnesses (repeated,
// alternating, -0 after +0) and checks every roughness it has not just seen, NaN included.
TEST(GgxZh, MemoIsTheTabulatedFactorsBitForBit) {
    GgxZhMemo memo;
    for (float roughness : {0.5f, 0.5f, 0.25f, 0.5f, 0.0f, -0.0f, 1.0f, 1.0f, 0.123f, 0.25f}) {
        const BandFactors expected = ggx_specular_zh_tabulated(roughness);
        const BandFactors& memoised = memo.factors(roughness);
        EXPECT_EQ(std::memcmp(memoised.data(), expected.data(), sizeof(BandFactors)), 0)
            << "roughness " << roughness;
    }
    EXPECT_THROW(memo.factors(NAN), InvalidArgument);
    EXPECT_THROW(memo.factors(NAN), InvalidArgument);
    EXPECT_THROW(memo.factors(1.5f), InvalidArgument);
    const BandFactors expected = ggx_specular_zh_tabulated(0.25f);
    EXPECT_EQ(std::memcmp(memo.factors(0.25f).data(), expected.data(), sizeof(BandFactors)), 0);
}

TEST(GgxZh, RejectsRoughnessOutsideUnitInterval) {
    EXPECT_THROW(ggx_specular_zh(-0.1f), InvalidArgument);
    EXPECT_THROW(ggx_specular_zh(1.5f), InvalidArgument);
    EXPECT_THROW(ggx_specular_zh(NAN), InvalidArgument);
    EXPECT_THROW(ggx_specular_zh_reference(2.0f), InvalidArgument);
    EXPECT_THROW(ggx_specular_zh_tabulated(-0.1f), InvalidArgument);
    EXPECT_THROW(ggx_specular_zh_tabulated(NAN), InvalidArgument);
}

}  // namespace
}  // namespace shgi
