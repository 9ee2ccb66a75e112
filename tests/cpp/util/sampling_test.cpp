// χ² goodness-of-fit tests for every sampler of util/sampling.h (the Mitsuba habit: each
// sampler is checked against its own pdf), plus normalisation of every pdf.
//
// Method: draw kSamples samples with a fixed seed, histogram them, integrate the pdf over each
// bin numerically (Gauss–Legendre) for the expected counts, merge bins whose expected count is
// below kMinExpectedCount (the usual validity rule of the χ² approximation), and compare the
// statistic with the χ² quantile at significance kSignificance, computed by the Wilson–Hilferty
// approximation. A bin with zero expected count but observed samples fails outright.
#include "util/sampling.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "support/chi2.h"
#include "util/error.h"
#include "util/rng.h"

namespace shgi {
namespace {

using testing::chi2_critical_value;
using testing::chi2_test;
using testing::kMinExpectedCount;
using testing::normal_upper_quantile;

constexpr int kSamples = 400000;
constexpr int kZBins = 20;    // bins in cos θ (directions) or r² (disk)
constexpr int kPhiBins = 16;  // bins in azimuth
constexpr int kPdfNodes = 8;  // Gauss–Legendre nodes per bin when integrating a pdf
// Normalisation: the pdfs are smooth within each bin, so 8 nodes per bin integrate them to
// ~1e-10; the bound is float evaluation of the pdf (~1e-6 relative).
constexpr double kPdfIntegralTolerance = 1e-5;
// Sampled directions are normalised in float: |w| = 1 within a few ulp.
constexpr float kUnitLengthTolerance = 1e-5f;

// Gauss–Legendre nodes/weights on [-1, 1] (Newton on P_n).
void gauss_legendre(int n, std::vector<double>& nodes, std::vector<double>& weights) {
    nodes.assign(n, 0.0);
    weights.assign(n, 0.0);
    for (int i = 0; i < n; ++i) {
        double x = std::cos(kPiD * (i + 0.75) / (n + 0.5)), dp = 1.0;
        for (int iteration = 0; iteration < 100; ++iteration) {
            double p0 = 1.0, p1 = x;
            for (int k = 2; k <= n; ++k) {
                const double pk = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = pk;
            }
            dp = n * (x * p1 - p0) / (x * x - 1.0);
            const double step = p1 / dp;
            x -= step;
            if (std::abs(step) < 1e-15) break;
        }
        nodes[i] = x;
        weights[i] = 2.0 / ((1.0 - x * x) * dp * dp);
    }
}

// ∫_a^b f(t) dt with an n-node rule.
double integrate(const std::function<double(double)>& f, double a, double b, int n = kPdfNodes) {
    std::vector<double> nodes, weights;
    gauss_legendre(n, nodes, weights);
    double sum = 0.0;
    for (int i = 0; i < n; ++i) sum += weights[i] * f(0.5 * (a + b) + 0.5 * (b - a) * nodes[i]);
    return 0.5 * (b - a) * sum;
}

// Directions sampled by `sample`, binned in (cos θ in [z_lo, z_hi], φ); pdf(cos θ) is the
// claimed solid-angle density (all samplers here are symmetric about +Z).
struct DirectionSampler {
    std::function<vec3(const vec2&)> sample;
    std::function<float(float cos_theta)> pdf;
    double z_lo = -1.0, z_hi = 1.0;
};

// Returns the χ² failure message ("" on success); `pdf_total` receives ∫ pdf dω.
std::string direction_sampler_chi2(const DirectionSampler& s, uint64_t stream, double& pdf_total) {
    Pcg32 rng(1234, stream);
    std::vector<double> observed(kZBins * kPhiBins, 0.0), expected(kZBins * kPhiBins, 0.0);
    const double dz = (s.z_hi - s.z_lo) / kZBins;
    for (int k = 0; k < kSamples; ++k) {
        const vec3 w = s.sample(rng.next_vec2());
        if (std::abs(glm::length(w) - 1.0f) > kUnitLengthTolerance)
            return format_message("sample ", k, " has length ", glm::length(w));
        if (w.z < s.z_lo - kUnitLengthTolerance || w.z > s.z_hi + kUnitLengthTolerance)
            return format_message("sample ", k, " has cos theta ", w.z, " outside the support");
        const int iz = std::clamp(static_cast<int>((w.z - s.z_lo) / dz), 0, kZBins - 1);
        double phi = std::atan2(w.y, w.x);
        if (phi < 0.0) phi += 2.0 * kPiD;
        const int iphi = std::clamp(static_cast<int>(phi / (2.0 * kPiD) * kPhiBins), 0,
                                    kPhiBins - 1);
        observed[iz * kPhiBins + iphi] += 1.0;
    }
    // dω = dz dφ: a bin's probability is Δφ ∫ pdf(z) dz.
    double total = 0.0;
    for (int iz = 0; iz < kZBins; ++iz) {
        const double z0 = s.z_lo + iz * dz;
        const double p = integrate([&](double z) { return s.pdf(static_cast<float>(z)); }, z0,
                                   z0 + dz) * (2.0 * kPiD / kPhiBins);
        total += p * kPhiBins;
        for (int iphi = 0; iphi < kPhiBins; ++iphi) expected[iz * kPhiBins + iphi] = p * kSamples;
    }
    pdf_total = total;
    return chi2_test(observed, expected);
}

void expect_direction_sampler_fits(const DirectionSampler& s, uint64_t stream) {
    double pdf_total = 0.0;
    const std::string failure = direction_sampler_chi2(s, stream, pdf_total);
    EXPECT_TRUE(failure.empty()) << failure;
    EXPECT_NEAR(pdf_total, 1.0, kPdfIntegralTolerance) << "pdf does not integrate to 1";
}

TEST(SamplingChi2, ChiSquareCriticalValueIsRight) {
    // Tabulated χ² quantiles at α = 1e-3 (Abramowitz & Stegun, Table 26.8): 10 dof 29.588,
    // 100 dof 149.449. Wilson–Hilferty errs by 0.6% at 10 dof in this far tail and by less as
    // the dof grow (the tests here have ~100-300 dof), always on the conservative side.
    constexpr double kWilsonHilfertyError = 0.01;
    EXPECT_NEAR(chi2_critical_value(10, 1e-3), 29.588, kWilsonHilfertyError * 29.588);
    EXPECT_NEAR(chi2_critical_value(100, 1e-3), 149.449, kWilsonHilfertyError * 149.449);
    EXPECT_NEAR(normal_upper_quantile(1e-3), 3.0902323, 1e-6);
}

// Negative controls: the test must have the power to reject near-miss pdfs.
TEST(SamplingChi2, RejectsAWrongPdf) {
    double pdf_total = 0.0;
    EXPECT_FALSE(direction_sampler_chi2({sample_cosine_hemisphere,
                                         [](float) { return sample_uniform_hemisphere_pdf(); },
                                         0.0, 1.0},
                                        9, pdf_total)
                     .empty());
    // Exponent 5 samples against the exponent-5.5 pdf: a 10% change of the lobe's shape.
    EXPECT_FALSE(direction_sampler_chi2(
                     {[](const vec2& u) { return sample_power_cosine(u, 5.0f); },
                      [](float z) { return sample_power_cosine_pdf(5.5f, z); }, 0.0, 1.0},
                     9, pdf_total)
                     .empty());
}

TEST(SamplingChi2, UniformSphere) {
    expect_direction_sampler_fits(
        {sample_uniform_sphere, [](float) { return sample_uniform_sphere_pdf(); }}, 1);
}

TEST(SamplingChi2, UniformHemisphere) {
    expect_direction_sampler_fits({sample_uniform_hemisphere,
                                   [](float z) { return z >= 0 ? sample_uniform_hemisphere_pdf()
                                                               : 0.0f; },
                                   0.0, 1.0},
                                  2);
}

TEST(SamplingChi2, CosineHemisphere) {
    expect_direction_sampler_fits({sample_cosine_hemisphere, sample_cosine_hemisphere_pdf, 0.0,
                                   1.0},
                                  3);
}

TEST(SamplingChi2, UniformCone) {
    for (float cos_max : {0.9f, 0.0f, -0.5f}) {
        SCOPED_TRACE(::testing::Message() << "cos_theta_max " << cos_max);
        expect_direction_sampler_fits(
            {[cos_max](const vec2& u) { return sample_uniform_cone(u, cos_max); },
             [cos_max](float) { return sample_uniform_cone_pdf(cos_max); }, cos_max, 1.0},
            4);
    }
}

TEST(SamplingChi2, PowerCosine) {
    for (float exponent : {0.0f, 1.0f, 5.5f, 40.0f}) {
        SCOPED_TRACE(::testing::Message() << "exponent " << exponent);
        expect_direction_sampler_fits(
            {[exponent](const vec2& u) { return sample_power_cosine(u, exponent); },
             [exponent](float z) { return sample_power_cosine_pdf(exponent, z); }, 0.0, 1.0},
            5);
    }
}

// Disk: polar bins (r², angle) have area π Δ(r²) Δangle / (2π), so expected = pdf · area.
TEST(SamplingChi2, UniformDisk) {
    Pcg32 rng(1234, 6);
    std::vector<double> observed(kZBins * kPhiBins, 0.0), expected(kZBins * kPhiBins, 0.0);
    for (int k = 0; k < kSamples; ++k) {
        const vec2 p = sample_uniform_disk(rng.next_vec2());
        const double r2 = static_cast<double>(p.x) * p.x + static_cast<double>(p.y) * p.y;
        ASSERT_LE(r2, 1.0 + 1e-6);
        double angle = std::atan2(p.y, p.x);
        if (angle < 0.0) angle += 2.0 * kPiD;
        const int ir = std::clamp(static_cast<int>(r2 * kZBins), 0, kZBins - 1);
        const int ia = std::clamp(static_cast<int>(angle / (2.0 * kPiD) * kPhiBins), 0,
                                  kPhiBins - 1);
        observed[ir * kPhiBins + ia] += 1.0;
    }
    const double bin_area = kPiD / (kZBins * kPhiBins);
    for (double& e : expected) e = sample_uniform_disk_pdf() * bin_area * kSamples;
    EXPECT_NEAR(sample_uniform_disk_pdf() * kPiD, 1.0, kPdfIntegralTolerance);
    const std::string failure = chi2_test(observed, expected);
    EXPECT_TRUE(failure.empty()) << failure;
}

// The disk map is Shirley and Chiu's, whose angle's sine and cosine come from a short series
// rather than libm: every point lies within a few float ulps of the map computed in double with
// std::cos and std::sin, across both kinds of wedge and up to the unit circle.
TEST(Sampling, UniformDiskMatchesTheConcentricMapInDouble) {
    Pcg32 rng(99, 1);
    double worst = 0.0;
    for (int k = 0; k < 200000; ++k) {
        // Every 8th point on the square's border (the unit circle), and as many on a diagonal,
        // where the two kinds of wedge meet and the angle reaches +-pi/4.
        vec2 u = rng.next_vec2();
        if (k % 8 == 0) u[k / 8 % 2] = float(k / 16 % 2);
        if (k % 8 == 4) u.y = k / 8 % 2 ? u.x : 1.0f - u.x;
        const double x = 2.0 * u.x - 1.0, y = 2.0 * u.y - 1.0;
        double ex = 0.0, ey = 0.0;
        if (std::abs(x) > std::abs(y)) {
            ex = x * std::cos(0.25 * kPiD * y / x);
            ey = x * std::sin(0.25 * kPiD * y / x);
        } else if (y != 0.0) {
            ex = y * std::sin(0.25 * kPiD * x / y);
            ey = y * std::cos(0.25 * kPiD * x / y);
        }
        const vec2 p = sample_uniform_disk(u);
        worst = std::max({worst, std::abs(double(p.x) - ex), std::abs(double(p.y) - ey)});
    }
    EXPECT_LT(worst, 3.0 * 0x1p-24);  // a few ulps of 1 (libm on the old angle: ~4)
}

// Triangle: the unit triangle split into n² congruent sub-triangles of equal area.
TEST(SamplingChi2, UniformTriangle) {
    constexpr int kSplits = 16;
    Pcg32 rng(1234, 7);
    std::vector<double> observed(kSplits * kSplits * 2, 0.0), expected(observed.size(), 0.0);
    for (int k = 0; k < kSamples; ++k) {
        const vec3 b = sample_uniform_triangle(rng.next_vec2());
        ASSERT_NEAR(b.x + b.y + b.z, 1.0f, 1e-6f);
        ASSERT_GE(b.x, 0.0f);
        ASSERT_GE(b.y, 0.0f);
        ASSERT_GE(b.z, -1e-6f);
        const double u = b.x * kSplits, v = b.y * kSplits;
        const int i = std::min(static_cast<int>(u), kSplits - 1);
        const int j = std::min(static_cast<int>(v), kSplits - 1);
        const int upper = (u - i) + (v - j) > 1.0 ? 1 : 0;
        observed[(i * kSplits + j) * 2 + upper] += 1.0;
    }
    // Lower sub-triangles exist for i + j <= n - 1, upper ones for i + j <= n - 2.
    for (int i = 0; i < kSplits; ++i)
        for (int j = 0; j < kSplits; ++j) {
            const double count = static_cast<double>(kSamples) / (kSplits * kSplits);
            if (i + j <= kSplits - 1) expected[(i * kSplits + j) * 2] = count;
            if (i + j <= kSplits - 2) expected[(i * kSplits + j) * 2 + 1] = count;
        }
    const std::string failure = chi2_test(observed, expected);
    EXPECT_TRUE(failure.empty()) << failure;
}

TEST(SamplingChi2, DiscreteDistribution) {
    const std::vector<float> weights = {1.0f, 0.0f, 3.0f, 0.5f, 0.0f, 10.0f, 2.0f, 0.25f};
    const DiscreteDistribution distribution(weights);
    double weight_sum = 0.0;
    for (float w : weights) weight_sum += w;
    EXPECT_NEAR(distribution.total(), weight_sum, 1e-6);
    double pdf_sum = 0.0;
    for (uint32_t i = 0; i < distribution.size(); ++i) {
        EXPECT_NEAR(distribution.pdf(i), weights[i] / weight_sum, 1e-7);
        pdf_sum += distribution.pdf(i);
    }
    EXPECT_NEAR(pdf_sum, 1.0, kPdfIntegralTolerance);

    Pcg32 rng(1234, 8);
    std::vector<double> observed(weights.size(), 0.0), expected(weights.size(), 0.0);
    std::vector<double> remapped_observed(kZBins, 0.0);
    for (int k = 0; k < kSamples; ++k) {
        float remapped = -1.0f;
        const uint32_t index = distribution.sample(rng.next_float(), &remapped);
        ASSERT_LT(index, weights.size());
        ASSERT_GE(remapped, 0.0f);
        ASSERT_LT(remapped, 1.0f);
        observed[index] += 1.0;
        remapped_observed[std::min(static_cast<int>(remapped * kZBins), kZBins - 1)] += 1.0;
    }
    for (size_t i = 0; i < weights.size(); ++i) expected[i] = distribution.pdf(i) * kSamples;
    std::string failure = chi2_test(observed, expected);
    EXPECT_TRUE(failure.empty()) << "indices: " << failure;
    // The reused random number must again be uniform on [0, 1).
    const double per_bin = static_cast<double>(kSamples) / kZBins;
    failure = chi2_test(remapped_observed, std::vector<double>(kZBins, per_bin));
    EXPECT_TRUE(failure.empty()) << "remapped u: " << failure;
}

TEST(SamplingChi2, DiscreteDistributionEdgeCases) {
    EXPECT_THROW(DiscreteDistribution({1.0f, -1.0f}), InvalidArgument);
    EXPECT_THROW(DiscreteDistribution({NAN}), InvalidArgument);
    const DiscreteDistribution zero({0.0f, 0.0f});
    EXPECT_TRUE(zero.empty());
    EXPECT_THROW(zero.sample(0.5f), InvalidArgument);
    // u just below 1 lands in the last non-zero bin, never in a trailing zero-weight bin.
    const DiscreteDistribution trailing_zero({1.0f, 1.0f, 0.0f});
    EXPECT_EQ(trailing_zero.sample(0x1.fffffep-1f), 1u);
    EXPECT_EQ(trailing_zero.sample(0.0f), 0u);
    const DiscreteDistribution leading_zero({0.0f, 1.0f});
    EXPECT_EQ(leading_zero.sample(0.0f), 1u);
}

}  // namespace
}  // namespace shgi
