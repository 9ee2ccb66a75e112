// Irradiance by cosine convolution against brute-force integration E(n) = ∫ L(ω) max(0, n·ω) dω.
//
// The brute force integrates over the hemisphere around n with Gauss–Legendre in cos θ: there
// the integrand L(ω) (n·ω) is a polynomial of degree <= 5, so the product rule is exact and the
// comparison checks the Â_l of Ramamoorthi & Hanrahan 2001 to float precision — for L2 fields
// and for L4 fields alike (a band-limited field is convolved exactly by its first Â_l).
#include "sh/sh_irradiance.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sh/sphere_quadrature.h"
#include "util/rng.h"
#include "util/sampling.h"
#include "support/sh_fields.h"

namespace shgi {
namespace {

// Float evaluation against a double quadrature: with coefficients in [-1, 1], |E| stays below
// ~30 W/m², and float rounding over 25 terms (~1e-6 relative) stays well below 1e-4 absolute.
constexpr float kIrradianceTolerance = 1e-4f;
constexpr int kRandomNormals = 50;

// ∫ L(ω) max(0, n·ω) dω over the hemisphere around n, exact for band-limited L.
glm::dvec3 brute_force_irradiance(const ShRgb& radiance, const vec3& normal) {
    const SphereQuadrature local = sphere_quadrature(8, 16, 0.0, 1.0);
    const Frame frame = Frame::from_z(normal);
    glm::dvec3 sum(0.0);
    for (size_t k = 0; k < local.directions.size(); ++k) {
        const vec3 wi = glm::normalize(frame.to_world(vec3(local.directions[k])));
        sum += local.weights[k] * local.directions[k].z * glm::dvec3(sh_evaluate(radiance, wi));
    }
    return sum;
}

TEST(ShIrradiance, CosineBandFactorsAreRamamoorthiHanrahan) {
    const BandFactors a = cosine_lobe_band_factors();
    constexpr float kExact = 1e-6f;
    EXPECT_NEAR(a[0], kPi, kExact);
    EXPECT_NEAR(a[1], 2.0f * kPi / 3.0f, kExact);
    EXPECT_NEAR(a[2], kPi / 4.0f, kExact);
    EXPECT_NEAR(a[3], 0.0f, kExact);
    EXPECT_NEAR(a[4], -kPi / 24.0f, kExact);
}

TEST(ShIrradiance, MatchesBruteForceForL2AndL4Fields) {
    Pcg32 rng(3, 4);
    for (int order : {2, 4}) {
        for (uint64_t seed = 0; seed < 4; ++seed) {
            const ShRgb radiance = testing::random_sh_field(order, 100 * order + seed);
            for (int k = 0; k < kRandomNormals; ++k) {
                const vec3 n = sample_uniform_sphere(rng.next_vec2());
                const vec3 fast = sh_irradiance(radiance, n);
                const glm::dvec3 truth = brute_force_irradiance(radiance, n);
                for (int c = 0; c < 3; ++c)
                    ASSERT_NEAR(fast[c], truth[c], kIrradianceTolerance)
                        << "order " << order << " seed " << seed << " channel " << c;
            }
        }
    }
}

// Â_3 = 0: the odd band l = 3 of an L3/L4 radiance field carries no irradiance at all; the
// brute force agrees (the l = 3 part integrates to zero against every clamped cosine).
TEST(ShIrradiance, Band3OfRadianceDoesNotReachIrradiance) {
    Pcg32 rng(8, 1);
    ShRgb radiance(4);
    for (int m = -3; m <= 3; ++m)
        radiance.coeffs[sh_index(3, m)] = vec3(rng.next_float(), 1.0f, -rng.next_float());
    for (int k = 0; k < kRandomNormals; ++k) {
        const vec3 n = sample_uniform_sphere(rng.next_vec2());
        const glm::dvec3 truth = brute_force_irradiance(radiance, n);
        const vec3 fast = sh_irradiance(radiance, n);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(truth[c], 0.0, kIrradianceTolerance);
            EXPECT_NEAR(fast[c], 0.0f, kIrradianceTolerance);
        }
    }
}

// A constant radiance field L has coefficient L·√(4π) on Y00, and E = π L for every normal.
TEST(ShIrradiance, ConstantFieldGivesPiTimesRadiance) {
    const vec3 radiance_value(0.5f, 1.0f, 2.0f);
    ShRgb radiance(2);
    radiance.coeffs[0] = radiance_value * std::sqrt(kFourPi);
    for (const vec3& n : {vec3(0, 0, 1), vec3(0, 0, -1), glm::normalize(vec3(1, 2, 3))}) {
        const vec3 e = sh_irradiance(radiance, n);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(e[c], kPi * radiance_value[c], 1e-5f);
    }
}

TEST(ShIrradiance, ConvolveCosineThenEvaluateEqualsIrradiance) {
    ShRgb sh = testing::random_sh_field(3, 42);
    const vec3 n = glm::normalize(vec3(-0.2f, 0.7f, 0.1f));
    const vec3 direct = sh_irradiance(sh, n);
    sh_convolve_cosine(sh);
    const vec3 via_coefficients = sh_evaluate(sh, n);
    for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(direct[c], via_coefficients[c]);
}

}  // namespace
}  // namespace shgi
