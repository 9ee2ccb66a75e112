// The bump-shadowed cosine kernel against direct integration: for random bent normals, tilts
// and SH radiance, Σ L_i K_i equals ∫ L(w) S(w) max(w . n_b, 0) dw by a fine quadrature (the
// identity is exact for a radiance of the kernel's order, so only the table's interpolation and
// quadrature remain); without a tilt it is the plain cosine convolution; a field lookup through
// a bumped lobe uses it, and a Monte Carlo gather weighs its directions by S.
#include <cmath>

#include <gtest/gtest.h>

#include "render/bump_irradiance.h"
#include "render/indirect_field.h"
#include "sh/sh_basis.h"
#include "sh/sh_irradiance.h"
#include "sh/sphere_quadrature.h"
#include "util/rng.h"

namespace shgi {
namespace {

// The kernel's error against direct integration, relative to the integral of |L| cos (the
// scale of the irradiance): measured below 1e-4 (the table's steps of 1.4° and its quadrature).
constexpr float kKernelTolerance = 2e-4f;
// Float sums of a few dozen terms.
constexpr float kSumTolerance = 1e-5f;

vec3 random_unit(Pcg32& rng) {
    const float z = 2.0f * rng.next_float() - 1.0f;
    const float phi = 2.0f * kPi * rng.next_float();
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return vec3(r * std::cos(phi), r * std::sin(phi), z);
}

ShRgb random_radiance(int order, Pcg32& rng) {
    ShRgb sh(order);
    for (int i = 0; i < sh.num_coefficients(); ++i)
        sh.coeffs[size_t(i)] =
            vec3(rng.next_float(), rng.next_float(), rng.next_float()) * (i == 0 ? 2.0f : 0.6f) -
            vec3(i == 0 ? 0.0f : 0.3f);
    return sh;
}

// A bent normal and an interpolated one `tilt` radians from it.
DiffuseBump tilted(const vec3& bent, float tilt, Pcg32& rng, BumpShadowing model) {
    const Frame frame = Frame::from_z(bent);
    const float phi = 2.0f * kPi * rng.next_float();
    DiffuseBump bump;
    bump.smooth_normal = frame.to_world(
        vec3(std::sin(tilt) * std::cos(phi), std::sin(tilt) * std::sin(phi), std::cos(tilt)));
    bump.model = model;
    return bump;
}

// ∫ L S max(cos, 0) over a fine product rule of the bent normal's hemisphere, and ∫ |L| cos.
std::pair<vec3, float> integrate(const ShRgb& radiance, const vec3& bent, const DiffuseBump& bump) {
    static const SphereQuadrature rule = sphere_quadrature(256, 512, 0.0, 1.0);
    const Frame frame = Frame::from_z(bent);
    glm::dvec3 sum(0.0);
    double scale = 0.0;
    for (size_t j = 0; j < rule.directions.size(); ++j) {
        const vec3 local(rule.directions[j]);
        const vec3 w = frame.to_world(local);
        const vec3 l = sh_evaluate(radiance, w);
        sum += glm::dvec3(l) * (rule.weights[j] * local.z * bump.shadowing(bent, w));
        scale += rule.weights[j] * local.z * glm::length(glm::dvec3(l));
    }
    return {vec3(sum), float(scale)};
}

TEST(BumpIrradiance, KernelMatchesTheIntegral) {
    Pcg32 rng(7, 3);
    for (const BumpShadowing model : {BumpShadowing::Chiang, BumpShadowing::Microfacet})
        for (const int order : {2, 4})
            for (const float tilt : {0.05f, 0.3f, 0.61f, 1.0f, 1.4f}) {
                const vec3 bent = random_unit(rng);
                const DiffuseBump bump = tilted(bent, tilt, rng, model);
                const ShRgb radiance = random_radiance(order, rng);
                const auto [expected, scale] = integrate(radiance, bent, bump);
                const vec3 e = sh_bump_irradiance(radiance, bent, bump);
                for (int c = 0; c < 3; ++c)
                    EXPECT_NEAR(e[c], expected[c], kKernelTolerance * scale)
                        << "model " << int(model) << " order " << order << " tilt " << tilt;
            }
}

// The shadowing darkens: light from beyond the interpolated horizon is faded, so a uniform
// radiance reaches a tilted lobe with less than π L.
TEST(BumpIrradiance, ShadowingOnlyTakesLightAway) {
    Pcg32 rng(2, 9);
    ShRgb uniform(2);
    uniform.coeffs[0] = vec3(1.0f / 0.282095f);  // L = 1
    const vec3 bent = random_unit(rng);
    float previous = kPi * (1.0f + kSumTolerance);
    for (const float tilt : {0.1f, 0.4f, 0.8f}) {
        const float e = sh_bump_irradiance(uniform, bent, tilted(bent, tilt, rng,
                                                                 BumpShadowing::Chiang)).x;
        EXPECT_LT(e, previous) << tilt;
        previous = e;
    }
}

// Without a tilt S = 1: the kernel is the clamped cosine, E the cosine convolution.
TEST(BumpIrradiance, NoTiltIsTheCosineConvolution) {
    Pcg32 rng(5, 1);
    for (const BumpShadowing model : {BumpShadowing::Chiang, BumpShadowing::Microfacet}) {
        const vec3 bent = random_unit(rng);
        const ShRgb radiance = random_radiance(2, rng);
        DiffuseBump bump;
        bump.smooth_normal = bent;
        bump.model = model;
        const vec3 e = sh_bump_irradiance(radiance, bent, bump);
        const vec3 expected = sh_irradiance(radiance, bent);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(e[c], expected[c], 1e-4f);
    }
}

// FieldLookup::irradiance through a bumped lobe: the kernel's value (closed form), and with
// diffuse_rays the mean over cosine-distributed directions weighed by S, which converges to it.
TEST(BumpIrradiance, FieldLookupAppliesTheShadowing) {
    Pcg32 rng(11, 4);
    const vec3 bent = random_unit(rng);
    const DiffuseBump bump = tilted(bent, 0.6f, rng, BumpShadowing::Chiang);
    FieldLookup lookup{random_radiance(2, rng), vec3(0.0f)};
    const vec3 closed = lookup.irradiance(bent, bump);
    const vec3 kernel = glm::max(sh_bump_irradiance(lookup.radiance, bent, bump), vec3(0.0f));
    EXPECT_EQ(closed, kernel);
    EXPECT_LT(closed.x, lookup.irradiance(bent).x);
    lookup.diffuse_rays = 1 << 16;
    const vec3 gathered = lookup.irradiance(bent, bump);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(gathered[c], closed[c], 0.01f * closed[c]);
}

}  // namespace
}  // namespace shgi
