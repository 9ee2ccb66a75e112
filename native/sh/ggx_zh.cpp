#include "sh/ggx_zh.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "sh/sphere_quadrature.h"
#include "util/error.h"

namespace shgi {

namespace {

// Seed 002 Appendix A, verbatim (vec4 lanes = bands L1..L4).
constexpr float kFitBase[4] = {0.27793123f, 0.59372022f, 0.2400839f, 0.000250700498f};
constexpr float kFitAmp1[4] = {0.905501229f, 10.57518269f, 21.6480923f, 5.53340572f};
constexpr float kFitFreq1[4] = {2.49220829f, 3.49132073f, 3.92510137f, 3.98902127f};
constexpr float kFitPhase1[4] = {2.88755638f, 0.56672964f, 0.50116945f, 0.705097221f};
constexpr float kFitAmp2[4] = {1.98743320f, 9.52855312f, 19.90690569f, 3.23348085f};
constexpr float kFitFreq2[4] = {1.79537159f, 3.58608449f, 4.01505002f, 4.63841986f};
constexpr float kFitPhase2[4] = {0.636261278f, 3.60689811f, 3.55551139f, 3.25144230f};
constexpr float kFitRsqOffset[4] = {0.329615862f, 0.29109984f, 0.25094573f, 0.211655471f};
constexpr float kFitRsqScale[4] = {1.54054310f, 4.35171889f, 7.58146856f, 9.84410536f};
constexpr float kFitRsqBias[4] = {-4.73179141e-04f, -3.58678416f, -6.47567145f, -8.76804538f};

// Reference quadrature: Gauss–Legendre panels in θ on [0, π/2], halving toward θ = 0 where the
// GGX peak (width ~ 2α) lives, so α down to kPanelCount halvings (~1e-6 rad) is resolved.
constexpr int kPanelCount = 24;
constexpr int kNodesPerPanel = 24;

void check_roughness(float roughness, const char* what) {
    if (!(roughness >= 0.0f && roughness <= 1.0f))
        throw InvalidArgument(format_message(what, ": roughness is ", roughness,
                                             "; it must be in [0, 1]"));
}

// GGX normal distribution D(cos θ_h) with α = roughness² (unnormalised constants cancel).
double ggx_d(double cos_h, double alpha) {
    const double a2 = alpha * alpha;
    const double t = cos_h * cos_h * (a2 - 1.0) + 1.0;
    return a2 / (kPiD * t * t);
}

}  // namespace

BandFactors ggx_specular_zh(float roughness) {
    check_roughness(roughness, "ggx_specular_zh");
    BandFactors factors{};
    factors[0] = 1.0f;
    for (int k = 0; k < 4; ++k) {
        float zh = kFitBase[k];
        zh += kFitAmp1[k] * std::cos(std::fma(roughness, kFitFreq1[k], kFitPhase1[k]));
        zh += kFitAmp2[k] * std::cos(std::fma(roughness, kFitFreq2[k], kFitPhase2[k]));
        zh += roughness * std::fma(1.0f / std::sqrt(kFitRsqOffset[k] + roughness * roughness),
                                   kFitRsqScale[k], kFitRsqBias[k]);
        factors[k + 1] = zh;
    }
    return factors;
}

BandFactors ggx_specular_zh_reference(float roughness) {
    check_roughness(roughness, "ggx_specular_zh_reference");
    BandFactors factors{};
    factors.fill(1.0f);
    if (roughness == 0.0f) return factors;  // a delta lobe: the impulse response
    const double alpha = static_cast<double>(roughness) * roughness;
    double moments[kMaxShOrder + 1] = {};   // ∫ f P_l sin θ dθ
    double hi = kPiD / 2.0;
    for (int panel = 0; panel < kPanelCount; ++panel) {
        const double lo = panel + 1 == kPanelCount ? 0.0 : hi / 2.0;
        const QuadratureRule rule = gauss_legendre(kNodesPerPanel, lo, hi);
        for (int i = 0; i < kNodesPerPanel; ++i) {
            const double theta = rule.nodes[i];
            const double x = std::cos(theta);
            const double f = ggx_d(std::cos(theta / 2.0), alpha) * x * std::sin(theta);
            // Legendre P_l(x) by recurrence; P_l = Y_l0 / Y_l0(pole).
            double p_prev = 1.0, p = x;
            moments[0] += rule.weights[i] * f;
            moments[1] += rule.weights[i] * f * x;
            for (int l = 2; l <= kMaxShOrder; ++l) {
                const double p_next = ((2.0 * l - 1.0) * x * p - (l - 1.0) * p_prev) / l;
                p_prev = p;
                p = p_next;
                moments[l] += rule.weights[i] * f * p;
            }
        }
        hi = lo;
    }
    for (int l = 1; l <= kMaxShOrder; ++l)
        factors[l] = static_cast<float>(moments[l] / moments[0]);
    return factors;
}

BandFactors ggx_specular_zh_tabulated(float roughness) {
    check_roughness(roughness, "ggx_specular_zh_tabulated");
    using Table = std::array<BandFactors, kGgxZhTableIntervals + 1>;
    static const Table table = [] {
        Table nodes{};
        for (int i = 0; i <= kGgxZhTableIntervals; ++i)
            nodes[i] = ggx_specular_zh(float(i) / float(kGgxZhTableIntervals));
        return nodes;
    }();
    const float x = roughness * float(kGgxZhTableIntervals);
    const int i = std::min(int(x), kGgxZhTableIntervals - 1);  // roughness 1: the last interval
    const float t = x - float(i);
    const BandFactors& lo = table[i];
    const BandFactors& hi = table[i + 1];
    BandFactors factors{};
    for (int l = 0; l <= kMaxShOrder; ++l) factors[l] = lo[l] + t * (hi[l] - lo[l]);
    return factors;
}

vec3 sh_specular_radiance(const ShRgb& radiance, const vec3& reflected, float roughness) {
    return sh_specular_radiance(radiance, reflected, ggx_specular_zh_tabulated(roughness));
}

vec3 sh_specular_radiance(const ShRgb& radiance, const vec3& reflected,
                          const BandFactors& factors) {
    // Ringing (negative k_4, fitted overshoot) can push the sum below zero: clamp at use.
    return glm::max(sh_evaluate_scaled(radiance, factors, reflected), vec3(0.0f));
}

}  // namespace shgi
