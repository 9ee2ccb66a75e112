// χ² goodness-of-fit test shared by the sampler tests (util/sampling, the light tree): observed
// counts per bin against expected counts from the claimed pdf. Bins are merged in order until
// each group expects kMinExpectedCount samples (the validity rule of the χ² approximation); the
// statistic is compared with the χ² quantile at significance kSignificance by the
// Wilson–Hilferty approximation. A bin with zero expected count but observed samples fails.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "util/error.h"

namespace shgi::testing {

inline constexpr double kSignificance = 1e-3;
inline constexpr double kMinExpectedCount = 5.0;

// Upper quantile of the standard normal: z with P(Z > z) = alpha, by bisection on erfc.
inline double normal_upper_quantile(double alpha) {
    double lo = 0.0, hi = 40.0;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (0.5 * std::erfc(mid / std::sqrt(2.0)) > alpha ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

// Wilson & Hilferty 1931: χ²_k ≈ k (1 - 2/(9k) + z sqrt(2/(9k)))³, accurate to <1% for k >= 3.
inline double chi2_critical_value(int dof, double alpha) {
    const double k = dof, z = normal_upper_quantile(alpha);
    const double t = 1.0 - 2.0 / (9.0 * k) + z * std::sqrt(2.0 / (9.0 * k));
    return k * t * t * t;
}

// Merges bins (in order) until each group's expected count reaches kMinExpectedCount, then runs
// the test. Returns an empty string on success, else a description of the failure.
inline std::string chi2_test(const std::vector<double>& observed, const std::vector<double>& expected) {
    for (size_t i = 0; i < observed.size(); ++i)
        if (expected[i] == 0.0 && observed[i] > 0.0)
            return format_message("bin ", i, " has ", observed[i], " samples but the pdf is 0");
    std::vector<double> obs, exp;
    double o = 0.0, e = 0.0;
    for (size_t i = 0; i < observed.size(); ++i) {
        o += observed[i];
        e += expected[i];
        if (e >= kMinExpectedCount) {
            obs.push_back(o);
            exp.push_back(e);
            o = e = 0.0;
        }
    }
    if (e > 0.0 || o > 0.0) {  // a small remainder joins the last group
        if (exp.empty()) return "all bins together expect fewer than kMinExpectedCount samples";
        obs.back() += o;
        exp.back() += e;
    }
    double chi2 = 0.0;
    for (size_t i = 0; i < obs.size(); ++i) chi2 += (obs[i] - exp[i]) * (obs[i] - exp[i]) / exp[i];
    const int dof = static_cast<int>(obs.size()) - 1;
    if (dof < 1) return "fewer than two bins after merging";
    const double critical = chi2_critical_value(dof, kSignificance);
    if (chi2 > critical)
        return format_message("chi2 = ", chi2, " > critical ", critical, " (", dof, " dof)");
    return "";
}

}  // namespace shgi::testing
