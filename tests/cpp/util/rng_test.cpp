// Pcg32: reproducibility, independent streams, advance, and the range of next_float.
#include "util/rng.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <vector>

namespace shgi {
namespace {

constexpr int kDraws = 100000;
// Pearson correlation of kDraws independent uniforms has standard deviation 1/sqrt(kDraws)
// ≈ 0.0032; five of those bound it for a fixed seed while catching correlated streams.
constexpr double kMaxCorrelation = 5.0 / 316.0;

double correlation(const std::vector<double>& a, const std::vector<double>& b) {
    double ma = 0.0, mb = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        ma += a[i];
        mb += b[i];
    }
    ma /= a.size();
    mb /= b.size();
    double cov = 0.0, va = 0.0, vb = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        cov += (a[i] - ma) * (b[i] - mb);
        va += (a[i] - ma) * (a[i] - ma);
        vb += (b[i] - mb) * (b[i] - mb);
    }
    return cov / std::sqrt(va * vb);
}

std::vector<double> draws(uint64_t seed, uint64_t stream, int count) {
    Pcg32 rng(seed, stream);
    std::vector<double> out(count);
    for (double& v : out) v = rng.next_float();
    return out;
}

TEST(Pcg32, SameSeedAndStreamReproduce) {
    Pcg32 a(42, 7), b(42, 7);
    for (int i = 0; i < 1000; ++i) ASSERT_EQ(a.next_u32(), b.next_u32());
}

TEST(Pcg32, DifferentStreamsAreDifferentAndUncorrelated) {
    for (uint64_t stream : {uint64_t{1}, uint64_t{2}, stream_id(1, 0), stream_id(0, 1ull << 39)}) {
        const std::vector<double> a = draws(42, 0, kDraws), b = draws(42, stream, kDraws);
        EXPECT_NE(a, b) << "stream " << stream;
        EXPECT_LT(std::abs(correlation(a, b)), kMaxCorrelation) << "stream " << stream;
        // Also no correlation at a lag of one (one stream a shifted copy of the other).
        const std::vector<double> a_shifted(a.begin() + 1, a.end());
        const std::vector<double> b_trimmed(b.begin(), b.end() - 1);
        EXPECT_LT(std::abs(correlation(a_shifted, b_trimmed)), kMaxCorrelation);
    }
    EXPECT_NE(draws(1, 0, 100), draws(2, 0, 100)) << "different seeds, same stream";
}

TEST(Pcg32, AdvanceEqualsDrawing) {
    for (uint64_t n : {0, 1, 17, 1000, 123457}) {
        Pcg32 drawn(9, 3), advanced(9, 3);
        for (uint64_t i = 0; i < n; ++i) drawn.next_u32();
        advanced.advance(n);
        for (int i = 0; i < 10; ++i) ASSERT_EQ(drawn.next_u32(), advanced.next_u32()) << "n=" << n;
    }
}

TEST(Pcg32, NextFloatIsInUnitIntervalWithMeanOneHalf) {
    Pcg32 rng(5, 5);
    double sum = 0.0;
    float lo = 1.0f, hi = 0.0f;
    for (int i = 0; i < kDraws; ++i) {
        const float u = rng.next_float();
        ASSERT_GE(u, 0.0f);
        ASSERT_LT(u, 1.0f);
        lo = std::min(lo, u);
        hi = std::max(hi, u);
        sum += u;
    }
    // Mean of kDraws uniforms: σ = sqrt(1/12 / kDraws) ≈ 9e-4; five σ.
    EXPECT_NEAR(sum / kDraws, 0.5, 5.0 * std::sqrt(1.0 / 12.0 / kDraws));
    EXPECT_LT(lo, 1e-3f);
    EXPECT_GT(hi, 1.0f - 1e-3f);
    // The largest possible output, (2^24 - 1) / 2^24, is still below 1.
    EXPECT_LT(static_cast<float>(0xffffffffu >> 8) * 0x1p-24f, 1.0f);
}

TEST(Pcg32, BoundedIntegersStayInRange) {
    Pcg32 rng(3, 0);
    std::vector<int> counts(7, 0);
    for (int i = 0; i < 7000; ++i) {
        const uint32_t v = rng.next_u32(7);
        ASSERT_LT(v, 7u);
        ++counts[v];
    }
    for (int c : counts) EXPECT_GT(c, 0);
}

TEST(Pcg32, StreamIdsDoNotCollide) {
    std::set<uint64_t> ids;
    for (uint64_t pass = 0; pass < 64; ++pass)
        for (uint64_t index : {uint64_t{0}, uint64_t{1}, uint64_t{1000}, (uint64_t{1} << 40) - 1})
            EXPECT_TRUE(ids.insert(stream_id(pass, index)).second)
                << "pass " << pass << " index " << index;
}

}  // namespace
}  // namespace shgi
