// Owen-scrambled Sobol' points: the (0, m, 2)-net property of every power-of-two prefix and of
// aligned blocks, 1D stratification, the (1, m, 3)-nets of the 3-D points, and uniformity of
// each point over seeds.
#include "util/owen_sobol.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace shgi {
namespace {

// Each of the 2^m elementary boxes of shape 2^-a x 2^-(m-a) holds exactly one point.
void expect_net(uint32_t first, uint32_t m, uint32_t seed) {
    const uint32_t count = 1u << m;
    for (uint32_t a = 0; a <= m; ++a) {
        std::vector<int> boxes(count, 0);
        for (uint32_t i = first; i < first + count; ++i) {
            const vec2 p = owen_sobol_2d(i, seed);
            const uint32_t x = uint32_t(p.x * float(1u << a));
            const uint32_t y = uint32_t(p.y * float(1u << (m - a)));
            ++boxes[(x << (m - a)) | y];
        }
        for (uint32_t box = 0; box < count; ++box)
            ASSERT_EQ(boxes[box], 1) << "m " << m << " a " << a << " seed " << seed
                                     << " first " << first << " box " << box;
    }
}

TEST(OwenSobol, EveryPowerOfTwoPrefixIsANet) {
    for (uint32_t seed : {0u, 1u, 12345u, hash_seed(7, 3)})
        for (uint32_t m = 0; m <= 10; ++m) expect_net(0, m, seed);
}

TEST(OwenSobol, AlignedBlocksAreNetsToo) {
    for (uint32_t seed : {5u, 99u}) {
        expect_net(16, 4, seed);
        expect_net(256, 6, seed);
        expect_net(1024, 8, seed);
    }
}

TEST(OwenSobol, OneDimensionalPrefixesAreStratified) {
    for (uint32_t seed : {3u, 77u})
        for (uint32_t m = 0; m <= 12; ++m) {
            std::vector<int> bins(1u << m, 0);
            for (uint32_t i = 0; i < (1u << m); ++i)
                ++bins[uint32_t(owen_sobol_1d(i, seed) * float(1u << m))];
            for (int count : bins) ASSERT_EQ(count, 1) << "m " << m;
        }
}

// Over seeds, a fixed point is uniform on [0,1)^2: chi-square over 8 x 8 bins.
TEST(OwenSobol, EachPointIsUniformOverSeeds) {
    for (uint32_t index : {0u, 1u, 5u, 1000u}) {
        const int bins = 8, samples = 64000;
        std::vector<int> counts(bins * bins, 0);
        for (int s = 0; s < samples; ++s) {
            const vec2 p = owen_sobol_2d(index, hash_seed(uint64_t(s), 17));
            ASSERT_TRUE(p.x >= 0.0f && p.x < 1.0f && p.y >= 0.0f && p.y < 1.0f);
            ++counts[int(p.x * bins) * bins + int(p.y * bins)];
        }
        const double expected = double(samples) / (bins * bins);
        double chi2 = 0.0;
        for (int c : counts) chi2 += (c - expected) * (c - expected) / expected;
        // 63 degrees of freedom: P(chi2 > 120) ~ 2e-5.
        EXPECT_LT(chi2, 120.0) << "index " << index;
    }
}

// The third dimension, unscrambled, is Joe and Kuo's Sobol' dimension 3 (x^2 + x + 1, m = 1, 3):
// its first points in index order.
TEST(OwenSobol, SobolDimensionTwoMatchesJoeKuo) {
    const double expected[8] = {0.0, 0.5, 0.75, 0.25, 0.375, 0.875, 0.625, 0.125};
    for (uint32_t i = 0; i < 8; ++i)
        EXPECT_EQ(double(owen_sobol_detail::sobol_dimension2(i)) * 0x1p-32, expected[i])
            << "index " << i;
}

// The second dimension's reversal without tables is the tables' bit for bit: every single-bit
// index (each direction number alone), 0, all ones, and a million indices of an LCG (all 32 bits
// vary, as the scrambled indices renderers pass). Its first eight values reversed are Sobol's
// second dimension's 0, 1/2, 3/4, 1/4, 5/8, 1/8, 3/8, 7/8 as well.
TEST(OwenSobol, ReversedSobolDimensionOneIsTheTablesReversed) {
    using owen_sobol_detail::reverse_bits;
    using owen_sobol_detail::reversed_sobol_dimension1;
    using owen_sobol_detail::sobol_dimension1;
    std::vector<uint32_t> indices = {0u, 0xFFFFFFFFu};
    for (int bit = 0; bit < 32; ++bit) indices.push_back(1u << bit);
    uint32_t x = 1u;
    for (int i = 0; i < 1000000; ++i) indices.push_back(x = x * 1664525u + 1013904223u);
    for (const uint32_t index : indices)
        ASSERT_EQ(reversed_sobol_dimension1(index), reverse_bits(sobol_dimension1(index)))
            << "index " << index;
    const double expected[8] = {0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875};
    for (uint32_t i = 0; i < 8; ++i)
        EXPECT_EQ(double(reverse_bits(reversed_sobol_dimension1(i))) * 0x1p-32, expected[i])
            << "index " << i;
}

// Each elementary box of volume 2^(1-m) (shape 2^-a x 2^-b x 2^-c, a + b + c = m - 1) holds
// exactly two of the 2^m points from `first`: the (1, m, 3)-net property, which makes the points
// a range of z selects stratified in (x, y).
void expect_three_dimensional_net(uint32_t first, uint32_t m, uint32_t seed) {
    const uint32_t count = 1u << m;
    for (uint32_t a = 0; a < m; ++a)
        for (uint32_t b = 0; a + b < m; ++b) {
            const uint32_t c = m - 1 - a - b;
            std::vector<int> boxes(count / 2, 0);
            for (uint32_t i = first; i < first + count; ++i) {
                const vec3 p = owen_sobol_3d(i, seed);
                const uint32_t x = uint32_t(p.x * float(1u << a));
                const uint32_t y = uint32_t(p.y * float(1u << b));
                const uint32_t z = uint32_t(p.z * float(1u << c));
                ++boxes[(((x << b) | y) << c) | z];
            }
            for (uint32_t box = 0; box < count / 2; ++box)
                ASSERT_EQ(boxes[box], 2) << "m " << m << " a " << a << " b " << b << " seed "
                                         << seed << " first " << first << " box " << box;
        }
}

TEST(OwenSobol, ThreeDimensionalPrefixesAndBlocksAreNets) {
    for (uint32_t seed : {0u, 1u, 12345u, hash_seed(7, 4)})
        for (uint32_t m = 1; m <= 10; ++m) expect_three_dimensional_net(0, m, seed);
    expect_three_dimensional_net(256, 6, 42u);
}

// x and y are owen_sobol_2d's, bit for bit: a 2-D user of the sequence is unchanged.
TEST(OwenSobol, ThreeDimensionalPointExtendsTheTwoDimensionalOne) {
    for (uint32_t i : {0u, 3u, 100u, 65535u}) {
        const vec3 p = owen_sobol_3d(i, 9u);
        const vec2 q = owen_sobol_2d(i, 9u);
        EXPECT_EQ(p.x, q.x);
        EXPECT_EQ(p.y, q.y);
    }
}

// Over seeds, the third coordinate of a fixed point is uniform: chi-square over 16 bins.
TEST(OwenSobol, ThirdCoordinateIsUniformOverSeeds) {
    for (uint32_t index : {1u, 6u, 777u}) {
        const int bins = 16, samples = 32000;
        std::vector<int> counts(bins, 0);
        for (int s = 0; s < samples; ++s) {
            const float z = owen_sobol_3d(index, hash_seed(uint64_t(s), 23)).z;
            ASSERT_TRUE(z >= 0.0f && z < 1.0f);
            ++counts[int(z * bins)];
        }
        const double expected = double(samples) / bins;
        double chi2 = 0.0;
        for (int c : counts) chi2 += (c - expected) * (c - expected) / expected;
        // 15 degrees of freedom: P(chi2 > 45) ~ 7e-5.
        EXPECT_LT(chi2, 45.0) << "index " << index;
    }
}

TEST(OwenSobol, SeedsGiveDifferentSequences) {
    EXPECT_NE(owen_sobol_2d(3, 1).x, owen_sobol_2d(3, 2).x);
    EXPECT_NE(hash_seed(1, 2), hash_seed(2, 1));
}

}  // namespace
}  // namespace shgi
