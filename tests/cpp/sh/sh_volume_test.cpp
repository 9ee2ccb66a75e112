// ShVolume: constant fields sample to the constant (both samplers), a field linear in x is
// reproduced by trilinear sampling, the seed 001 §4.1 cubic weights, and bad inputs refused.
#include "sh/sh_volume.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "support/expect_error.h"
#include "util/rng.h"

namespace shgi {
namespace {

// Float rounding of a weighted sum of at most 27 terms of magnitude ~1, normalised.
constexpr float kSumTolerance = 1e-5f;

const vec3 kOrigin(-1.0f, 0.5f, 2.0f);
constexpr float kCellSize = 0.25f;
const ivec3 kCounts(5, 4, 3);

// A distinct, arbitrary value per coefficient and channel.
ShRgb constant_expansion(int order) {
    ShRgb sh(order);
    for (int i = 0; i < sh.num_coefficients(); ++i)
        sh[i] = vec3(0.3f + 0.1f * float(i), -0.2f * float(i), 1.5f - 0.05f * float(i));
    return sh;
}

void fill(ShVolume& volume, const std::function<ShRgb(const ivec3&)>& field) {
    ivec3 c;
    for (c.z = 0; c.z < volume.counts().z; ++c.z)
        for (c.y = 0; c.y < volume.counts().y; ++c.y)
            for (c.x = 0; c.x < volume.counts().x; ++c.x) volume.set_cell_coefficients(c, field(c));
}

void expect_near(const ShRgb& actual, const ShRgb& expected, float tolerance, const vec3& p) {
    ASSERT_EQ(actual.order, expected.order);
    for (int i = 0; i < expected.num_coefficients(); ++i)
        for (int ch = 0; ch < 3; ++ch)
            EXPECT_NEAR(actual[i][ch], expected[i][ch], tolerance)
                << "coefficient " << i << " channel " << ch << " at (" << p.x << ", " << p.y
                << ", " << p.z << ")";
}

// Points inside, on the faces of, and well outside the volume.
std::vector<vec3> sample_points(const ShVolume& volume) {
    std::vector<vec3> points;
    const vec3 extent = vec3(volume.counts()) * volume.cell_size();
    Pcg32 rng(5, 0);
    for (int k = 0; k < 200; ++k) {
        const vec3 u(rng.next_float(), rng.next_float(), rng.next_float());
        points.push_back(volume.origin() + (u * 1.4f - 0.2f) * extent);  // ~35% outside
    }
    points.push_back(volume.origin());
    points.push_back(volume.origin() + extent);
    points.push_back(volume.origin() - 100.0f);
    return points;
}

TEST(ShVolume, ConstantFieldSamplesToTheConstantEverywhere) {
    for (int order = 0; order <= kMaxShVolumeOrder; ++order) {
        for (const ivec3& counts : {kCounts, ivec3(1, 1, 1), ivec3(1, 3, 2)}) {
            ShVolume volume(kOrigin, kCellSize, counts, order);
            const ShRgb constant = constant_expansion(order);
            fill(volume, [&](const ivec3&) { return constant; });
            for (const vec3& p : sample_points(volume)) {
                expect_near(volume.sample_trilinear(p), constant, kSumTolerance, p);
                expect_near(volume.sample_cubic(p), constant, kSumTolerance, p);
            }
        }
    }
}

// Coefficient i of channel c at the centre of cell (x, ., .) is a_ic + b_ic x; trilinear
// interpolation between centres reproduces a_ic + b_ic (q.x − ½) for q.x in [½, n − ½]
// (q in cells) and the boundary value beyond.
TEST(ShVolume, TrilinearReproducesAFieldLinearInX) {
    constexpr int kOrder = 2;
    ShVolume volume(kOrigin, kCellSize, kCounts, kOrder);
    const auto linear = [&](float x) {
        ShRgb sh(kOrder);
        for (int i = 0; i < sh.num_coefficients(); ++i)
            sh[i] = vec3(1.0f + 0.5f * float(i), -2.0f, 0.1f * float(i)) +
                    x * vec3(0.25f, 1.0f - 0.1f * float(i), -0.75f);
        return sh;
    };
    fill(volume, [&](const ivec3& c) { return linear(float(c.x)); });
    Pcg32 rng(9, 0);
    for (int k = 0; k < 200; ++k) {
        // Anywhere in y and z (even outside: clamping keeps x's interpolation), x between the
        // first and last centres.
        const vec3 q(0.5f + rng.next_float() * float(kCounts.x - 1),
                     -1.0f + rng.next_float() * float(kCounts.y + 2),
                     -1.0f + rng.next_float() * float(kCounts.z + 2));
        const vec3 p = kOrigin + q * kCellSize;
        // The magnitude reaches ~6 here; float rounding of q and the sum stays below 1e-5 × that.
        expect_near(volume.sample_trilinear(p), linear(q.x - 0.5f), 6.0f * kSumTolerance, p);
    }
    // Beyond the last centre the field stays at the boundary value.
    const vec3 beyond = kOrigin + vec3(float(kCounts.x) + 3.0f, 1.0f, 1.0f) * kCellSize;
    expect_near(volume.sample_trilinear(beyond), linear(float(kCounts.x - 1)), kSumTolerance,
                beyond);
    // At a cell centre, exactly that cell's expansion.
    const ivec3 cell(2, 1, 1);
    const vec3 centre = volume.cell_centre(cell);
    expect_near(volume.sample_trilinear(centre), volume.cell_coefficients(cell), kSumTolerance,
                centre);
}

TEST(ShVolume, CubicFalloffIsOneAtZeroZeroAtRadiusAndSmooth) {
    constexpr float r = kCubicRadiusCells;
    EXPECT_EQ(cubic_falloff(0.0f), 1.0f);
    EXPECT_NEAR(cubic_falloff(r * (1.0f - 1e-7f)), 0.0f, 1e-6f);
    EXPECT_EQ(cubic_falloff(r), 0.0f);
    EXPECT_EQ(cubic_falloff(2.0f * r), 0.0f);
    EXPECT_NEAR(cubic_falloff(0.5f * r), 0.5f, 1e-6f);  // symmetric about the midpoint
    EXPECT_NEAR(cubic_falloff(1.0f, 2.0f), 0.5f, 1e-6f);
    // Against the formula, monotone decreasing, and slopes (central differences) zero at both
    // ends: w'(d) = 6d²/r³ − 6d/r², so |w'| peaks at 1.5/r at d = r/2.
    constexpr float h = 1e-3f;
    float previous = 2.0f;
    for (int k = 0; k <= 100; ++k) {
        const float d = r * float(k) / 100.0f;
        const float expected = 2.0f * d * d * d / (r * r * r) - 3.0f * d * d / (r * r) + 1.0f;
        EXPECT_NEAR(cubic_falloff(d), expected, 1e-6f) << "d = " << d;
        EXPECT_LE(cubic_falloff(d), previous) << "d = " << d;
        previous = cubic_falloff(d);
        if (k > 0 && k < 100) {
            const float slope = (cubic_falloff(d + h) - cubic_falloff(d - h)) / (2.0f * h);
            const float expected_slope = 6.0f * d * d / (r * r * r) - 6.0f * d / (r * r);
            EXPECT_NEAR(slope, expected_slope, 1e-2f) << "d = " << d;
        }
    }
    EXPECT_NEAR((cubic_falloff(h) - 1.0f) / h, 0.0f, 1e-2f);    // zero slope at d = 0
    EXPECT_NEAR(cubic_falloff(r - h) / h, 0.0f, 1e-2f);         // zero slope at d = r
}

// The cubic sampler is the normalised weighted sum over the 3×3×3 block: check one point by hand.
TEST(ShVolume, CubicIsTheNormalisedBlockSum) {
    ShVolume volume(vec3(0.0f), 1.0f, ivec3(4, 4, 4), 0);
    fill(volume, [](const ivec3& c) {
        ShRgb sh(0);
        sh[0] = vec3(float(c.x), float(c.y * c.y), float(c.x + 2 * c.z));
        return sh;
    });
    const vec3 q(1.3f, 2.6f, 0.2f);  // in cell (1, 2, 0): the block is x 0..2, y 1..3, z 0..1
    glm::dvec3 sum(0.0);
    double total = 0.0;
    for (int z = 0; z <= 1; ++z)
        for (int y = 1; y <= 3; ++y)
            for (int x = 0; x <= 2; ++x) {
                const float w = cubic_falloff(glm::length(q - (vec3(x, y, z) + 0.5f)));
                sum += double(w) * glm::dvec3(volume.cell_coefficients(ivec3(x, y, z))[0]);
                total += w;
            }
    ShRgb expected(0);
    expected[0] = vec3(sum / total);
    expect_near(volume.sample_cubic(q), expected, kSumTolerance * 10.0f, q);
}

TEST(ShVolume, NonFinitePointsSampleToZero) {
    ShVolume volume(kOrigin, kCellSize, kCounts, 1);
    fill(volume, [](const ivec3&) { return constant_expansion(1); });
    const vec3 nan_point(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f);
    expect_near(volume.sample_trilinear(nan_point), ShRgb(1), 0.0f, nan_point);
    expect_near(volume.sample_cubic(nan_point), ShRgb(1), 0.0f, nan_point);
}

TEST(ShVolume, RefusesBadInputsNamingTheField) {
    using testing::expect_invalid_argument;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    expect_invalid_argument([&] { ShVolume(vec3(nan, 0, 0), 1.0f, kCounts, 2); }, "origin");
    expect_invalid_argument([&] { ShVolume(vec3(0, inf, 0), 1.0f, kCounts, 2); }, "origin");
    expect_invalid_argument([&] { ShVolume(kOrigin, nan, kCounts, 2); }, "cell_size = nan");
    expect_invalid_argument([&] { ShVolume(kOrigin, inf, kCounts, 2); }, "cell_size");
    expect_invalid_argument([&] { ShVolume(kOrigin, 0.0f, kCounts, 2); }, "cell_size = 0");
    expect_invalid_argument([&] { ShVolume(kOrigin, -1.0f, kCounts, 2); }, "cell_size = -1");
    expect_invalid_argument([&] { ShVolume(kOrigin, 1.0f, ivec3(4, 0, 4), 2); },
                            "counts = (4, 0, 4)");
    expect_invalid_argument([&] { ShVolume(kOrigin, 1.0f, ivec3(-1, 4, 4), 2); }, "counts");
    expect_invalid_argument([&] { ShVolume(kOrigin, 1.0f, ivec3(1024, 1024, 129), 2); },
                            "counts = (1024, 1024, 129)");
    expect_invalid_argument([&] { ShVolume(kOrigin, 3e37f, ivec3(100, 1, 1), 2); },
                            "counts × cell_size");
    expect_invalid_argument([&] { ShVolume(kOrigin, 1.0f, kCounts, 3); }, "order = 3");
    expect_invalid_argument([&] { ShVolume(kOrigin, 1.0f, kCounts, -1); }, "order = -1");

    ShVolume volume(kOrigin, kCellSize, kCounts, 1);
    expect_invalid_argument([&] { volume.set_cell_coefficients(ivec3(0), ShRgb(2)); },
                            "of order 2");
    expect_invalid_argument([&] { volume.set_cell_coefficients(ivec3(5, 0, 0), ShRgb(1)); },
                            "cell = (5, 0, 0)");
    expect_invalid_argument([&] { volume.cell_coefficients(ivec3(0, -1, 0)); },
                            "cell = (0, -1, 0)");
}

}  // namespace
}  // namespace shgi
