#include "render/bump_irradiance.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "sh/sh_basis.h"
#include "sh/sphere_quadrature.h"

namespace shgi {
namespace {

// The table's tilts: kTiltSteps + 1 entries over [0, π] (steps of 1.4°; K changes smoothly with
// the tilt, and the interpolation error stays below 1e-4 of the cosine's coefficients:
// normal_map_test's BumpCosineShMatchesTheIntegral).
constexpr int kTiltSteps = 128;
// Its quadrature of the hemisphere about the bent normal: S has a kink along the interpolated
// normal's horizon, which crosses the product grid obliquely, so the rule is fine rather than
// of high degree (the integrals agree with a 4x finer rule to ~1e-5).
constexpr int kTableThetas = 64, kTablePhis = 128;

using Coefficients = std::array<float, kMaxShCoefficients>;

struct KernelTable {
    std::array<Coefficients, kTiltSteps + 1> tilts;
};

float shadowing(BumpShadowing model, const vec3& smooth, const vec3& bent, const vec3& wi) {
    return model == BumpShadowing::Microfacet ? bump_shadowing_microfacet(smooth, bent, wi)
                                              : bump_shadowing_term(smooth, bent, wi);
}

// K's coefficients up to L4 in the canonical frame (z the bent normal, the interpolated normal at
// tilt t in the xz-plane), for every tabulated tilt.
KernelTable build_table(BumpShadowing model) {
    const SphereQuadrature rule = sphere_quadrature(kTableThetas, kTablePhis, 0.0, 1.0);
    const vec3 bent(0.0f, 0.0f, 1.0f);
    std::vector<std::array<float, kMaxShCoefficients>> basis(rule.directions.size());
    for (size_t j = 0; j < rule.directions.size(); ++j)
        sh_eval(kMaxShOrder, vec3(rule.directions[j]), basis[j].data());
    KernelTable table;
    for (int k = 0; k <= kTiltSteps; ++k) {
        const double t = kPi * double(k) / kTiltSteps;
        const vec3 smooth(float(std::sin(t)), 0.0f, float(std::cos(t)));
        std::array<double, kMaxShCoefficients> sum{};
        for (size_t j = 0; j < rule.directions.size(); ++j) {
            const vec3 w(rule.directions[j]);
            const double kernel = rule.weights[j] * double(shadowing(model, smooth, bent, w)) *
                                  double(w.z);
            for (int i = 0; i < kMaxShCoefficients; ++i) sum[size_t(i)] += kernel * basis[j][size_t(i)];
        }
        for (int i = 0; i < kMaxShCoefficients; ++i)
            table.tilts[size_t(k)][size_t(i)] = float(sum[size_t(i)]);
    }
    return table;
}

const KernelTable& kernel_table(BumpShadowing model) {
    if (model == BumpShadowing::Microfacet) {
        static const KernelTable microfacet = build_table(BumpShadowing::Microfacet);
        return microfacet;
    }
    static const KernelTable chiang = build_table(BumpShadowing::Chiang);
    return chiang;
}

// The rotation's rule for an order: directions d_j (canonical frame), weights w_j and the basis
// at d_j; sphere_quadrature(order + 1, 2 order + 1) integrates degree 2 order exactly.
struct RotationRule {
    std::vector<vec3> directions;
    std::vector<float> weights;
    std::vector<Coefficients> basis;
};

const RotationRule& rotation_rule(int order) {
    static const std::array<RotationRule, kMaxShOrder + 1> rules = [] {
        std::array<RotationRule, kMaxShOrder + 1> out;
        for (int l = 0; l <= kMaxShOrder; ++l) {
            const SphereQuadrature q = sphere_quadrature(l + 1, 2 * l + 1);
            RotationRule& rule = out[size_t(l)];
            for (size_t j = 0; j < q.directions.size(); ++j) {
                rule.directions.push_back(vec3(q.directions[j]));
                rule.weights.push_back(float(q.weights[j]));
                Coefficients y{};
                sh_eval(l, rule.directions.back(), y.data());
                rule.basis.push_back(y);
            }
        }
        return out;
    }();
    return rules[size_t(order)];
}

}  // namespace

vec3 field_lookup_normal(const Shading& shading) {
    if (!shading.bsdf.has_smooth_normal()) return shading.frame.z;
    return glm::normalize(shading.frame.to_world(shading.bsdf.smooth_normal()));
}

float DiffuseBump::shadowing(const vec3& bent, const vec3& wi) const {
    return shgi::shadowing(model, smooth_normal, bent, wi);
}

bool diffuse_bump(const Shading& shading, DiffuseBump* out) {
    if (!shading.bsdf.has_smooth_normal()) return false;
    out->smooth_normal = field_lookup_normal(shading);
    out->model = shading.bsdf.microfacet_bump() ? BumpShadowing::Microfacet : BumpShadowing::Chiang;
    return true;
}

ShCoeffs bump_cosine_sh(int order, const vec3& bent, const DiffuseBump& bump) {
    check_sh_order(order, "bump_cosine_sh");
    const int count = sh_num_coefficients(order);
    // The canonical frame: x along the interpolated normal's part across the bent one (any
    // frame about the bent normal where the two are parallel: K is symmetric about it there).
    const float cos_tilt = glm::dot(bump.smooth_normal, bent);
    const vec3 across = bump.smooth_normal - cos_tilt * bent;
    const float sin_tilt = glm::length(across);
    Frame frame = Frame::from_z(bent);
    if (sin_tilt > 1e-6f) {
        frame.x = across / sin_tilt;
        frame.y = glm::cross(bent, frame.x);
        frame.z = bent;
    }
    const float u = std::atan2(sin_tilt, cos_tilt) * (float(kTiltSteps) * kInvPi);
    const int k = std::clamp(int(u), 0, kTiltSteps - 1);
    const float f = std::clamp(u - float(k), 0.0f, 1.0f);
    const Coefficients& lo = kernel_table(bump.model).tilts[size_t(k)];
    const Coefficients& hi = kernel_table(bump.model).tilts[size_t(k) + 1];
    float canonical[kMaxShCoefficients];
    for (int i = 0; i < count; ++i) canonical[i] = lo[size_t(i)] + f * (hi[size_t(i)] - lo[size_t(i)]);
    // K_i = Σ_j w_j K(d_j) Y_i(R d_j): exact, as Y_i K has degree <= 2 order.
    const RotationRule& rule = rotation_rule(order);
    ShCoeffs out(order);
    float y[kMaxShCoefficients];
    for (size_t j = 0; j < rule.directions.size(); ++j) {
        float kernel = 0.0f;
        for (int i = 0; i < count; ++i) kernel += canonical[i] * rule.basis[j][size_t(i)];
        if (kernel == 0.0f) continue;
        sh_eval(order, frame.to_world(rule.directions[j]), y);
        const float weight = rule.weights[j] * kernel;
        for (int i = 0; i < count; ++i) out.coeffs[size_t(i)] += weight * y[i];
    }
    return out;
}

vec3 sh_bump_irradiance(const ShRgb& radiance, const vec3& bent, const DiffuseBump& bump) {
    return sh_dot(radiance, bump_cosine_sh(radiance.order, bent, bump));
}

}  // namespace shgi
