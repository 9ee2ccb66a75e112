#include "render/indirect_field.h"

#include <algorithm>
#include <cmath>

#include "render/bump_irradiance.h"
#include "sh/ggx_zh.h"
#include "sh/sh_irradiance.h"
#include "util/rng.h"
#include "util/sampling.h"

namespace shgi {
namespace {

// Roughness below this gathers the Phong lobe of this roughness (a mirror's lobe would need an
// infinite exponent).
constexpr float kMinGatherRoughness = 0.01f;

// The mean of `radiance` over `rays` directions sampled around `axis` by `sample` (a local
// direction around +Z from a uniform point of the square), stratified in the first dimension.
// Each direction w's radiance is weighed by weight(w) (world space; 1 by default, an exact
// product).
template <typename Sample, typename Weight = float (*)(const vec3&)>
vec3 gathered_mean(const ShRgb& radiance, const vec3& axis, uint32_t rays, uint64_t key,
                   uint64_t stream, Sample&& sample,
                   Weight&& weight = [](const vec3&) { return 1.0f; }) {
    Pcg32 rng(key, stream);
    const Frame frame = Frame::from_z(axis);
    vec3 sum(0.0f);
    for (uint32_t i = 0; i < rays; ++i) {
        const vec2 u((float(i) + rng.next_float()) / float(rays), rng.next_float());
        const vec3 w = frame.to_world(sample(u));
        sum += sh_evaluate(radiance, w) * weight(w);
    }
    return sum / float(rays);
}

// What the lobe of band factors k_l reads, in the direction at cosine `cosine` from n, of the SH
// of the upper hemisphere about n (1 where w.n > 0, 0 below) truncated at `order`: the
// hemisphere's zonal coefficients are sqrt(pi), sqrt(3 pi)/2, 0, -(pi/2) sqrt(7/(16 pi)), 0 (every
// even band above 0 vanishes), so the sum is 1/2 + (3/4) k_1 c - (7/32) k_3 (5c^3 - 3c). At least
// 1/2 for c >= 0 (the reflected direction of a view above the surface).
float upper_hemisphere_read(int order, const BandFactors& factors, float cosine) {
    const float c = std::max(cosine, 0.0f);
    float read = 0.5f + 0.75f * factors[1] * c;
    if (order >= 3) read -= (7.0f / 32.0f) * factors[3] * (5.0f * c * c * c - 3.0f * c);
    return read;
}

}  // namespace

float FieldLookup::gather_phong_exponent(float roughness) {
    const float r = std::max(roughness, kMinGatherRoughness);
    const float alpha = r * r;
    // Blinn-Phong's half-vector exponent 2/α² − 2 (Walter et al. 2007), a quarter of it about
    // the reflected direction.
    return std::max(0.0f, 0.5f / (alpha * alpha) - 0.5f);
}

vec3 FieldLookup::irradiance(const vec3& n) const {
    if (diffuse_rays > 0) {
        const vec3 mean = gathered_mean(radiance, n, diffuse_rays, gather_key, 0,
                                         [](const vec2& u) { return sample_cosine_hemisphere(u); });
        return glm::max(kPi * mean, vec3(0.0f)) + extra_irradiance;
    }
    return glm::max(sh_irradiance(radiance, n), vec3(0.0f)) + extra_irradiance;
}

vec3 FieldLookup::irradiance(const vec3& n, const DiffuseBump& bump) const {
    if (diffuse_rays > 0) {
        const vec3 mean = gathered_mean(
            radiance, n, diffuse_rays, gather_key, 0,
            [](const vec2& u) { return sample_cosine_hemisphere(u); },
            [&](const vec3& w) { return bump.shadowing(n, w); });
        return glm::max(kPi * mean, vec3(0.0f)) + extra_irradiance;
    }
    return glm::max(sh_bump_irradiance(radiance, n, bump), vec3(0.0f)) + extra_irradiance;
}

vec3 FieldLookup::glossy(const vec3& n, const vec3& wo, float roughness, GgxZhMemo* zh) const {
    const vec3 reflected = 2.0f * glm::dot(wo, n) * n - wo;
    if (glossy_rays > 0) {
        const float exponent = gather_phong_exponent(roughness);
        const vec3 mean =
            gathered_mean(radiance, glm::normalize(reflected), glossy_rays, gather_key, 1,
                          [exponent](const vec2& u) { return sample_power_cosine(u, exponent); });
        return glm::max(mean, vec3(0.0f));
    }
    const BandFactors factors = ggx_specular_zh_factors(roughness, zh);
    if (!horizon || radiance.order < 1)
        return sh_specular_radiance(radiance, reflected, factors);
    // Read about the clipped lobe's dominant direction, the zonal lobe about r no longer reads
    // mostly the rounded step at the horizon (docs/methods.md: 80 degrees from a floor's normal
    // read 0.84 of the path tracer's about r, 0.91 about the dominant direction).
    const vec3 dominant = glossy_dominant_direction(n, reflected, roughness);
    return sh_specular_radiance(radiance, dominant, factors) /
           upper_hemisphere_read(radiance.order, factors, glm::dot(n, dominant));
}

FieldLookup IndirectField::lookup(const vec3& p, const vec3& n) const {
    return FieldLookup{radiance_sh(p, n), vec3(0.0f)};
}

}  // namespace shgi
