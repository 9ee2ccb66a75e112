// Test helpers for Monte Carlo estimates checked against closed forms: an estimate passes when it
// lies within kSigmas standard errors of the exact value, plus an absolute floor each caller
// states (float accumulation, a documented bias). Standard errors come either from the spread of
// independent batches (BatchStats) or from the samples of one estimate (standard_error_of_sum).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "util/math.h"

namespace shgi::testing {

// Five standard errors: a false failure has probability ~6e-7 per comparison.
constexpr double kSigmas = 5.0;

// Mean and standard error of the mean of independent batch results, per value.
struct BatchStats {
    std::vector<double> sum, sum2;
    int batches = 0;

    void add(const std::vector<float>& values) {
        sum.resize(values.size(), 0.0);
        sum2.resize(values.size(), 0.0);
        for (size_t i = 0; i < values.size(); ++i) {
            sum[i] += values[i];
            sum2[i] += double(values[i]) * values[i];
        }
        ++batches;
    }
    void add(const vec3& value) { add(std::vector<float>{value.x, value.y, value.z}); }
    double mean(size_t i) const { return sum[i] / batches; }
    double standard_error(size_t i) const {
        const double m = mean(i);
        return std::sqrt(std::max(0.0, sum2[i] / batches - m * m) / (batches - 1));
    }
};

// Standard error of a sum of n independent samples, from the sums of the samples and of their
// squares.
inline double standard_error_of_sum(double sum, double sum_squares, uint64_t n) {
    return std::sqrt(std::max(0.0, sum_squares - sum * sum / double(n)));
}

// `value` (standard error `error`) within kSigmas standard errors plus `absolute_floor` of
// `expected`.
inline void expect_within_noise(double value, double error, double expected,
                                double absolute_floor, const std::string& what) {
    EXPECT_NEAR(value, expected, kSigmas * error + absolute_floor)
        << what << ": standard error " << error;
}

}  // namespace shgi::testing
