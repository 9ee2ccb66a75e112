#include "probes/probe_visibility.h"

#include <algorithm>
#include <cmath>

#include "util/error.h"

namespace shgi {
namespace {

float sign_not_zero(float v) { return v >= 0.0f ? 1.0f : -1.0f; }

}  // namespace

vec2 octahedral_encode(const vec3& dir) {
    const float l1 = std::abs(dir.x) + std::abs(dir.y) + std::abs(dir.z);
    vec2 p(dir.x / l1, dir.y / l1);
    if (dir.z < 0.0f) {
        p = vec2((1.0f - std::abs(p.y)) * sign_not_zero(p.x),
                 (1.0f - std::abs(p.x)) * sign_not_zero(p.y));
    }
    return 0.5f * p + 0.5f;
}

vec3 octahedral_decode(const vec2& uv) {
    const vec2 p = 2.0f * uv - 1.0f;
    vec3 v(p.x, p.y, 1.0f - std::abs(p.x) - std::abs(p.y));
    if (v.z < 0.0f) {
        v.x = (1.0f - std::abs(p.y)) * sign_not_zero(p.x);
        v.y = (1.0f - std::abs(p.x)) * sign_not_zero(p.y);
    }
    return glm::normalize(v);
}

vec3 octahedral_texel_direction(int x, int y, int res) {
    return octahedral_decode(vec2((float(x) + 0.5f) / float(res), (float(y) + 0.5f) / float(res)));
}

vec2 sample_visibility(const vec2* moments, int res, const vec3& dir) {
    const vec2 t = octahedral_encode(dir) * float(res) - 0.5f;
    const float fx = std::floor(t.x), fy = std::floor(t.y);
    const vec2 f(t.x - fx, t.y - fy);
    const int x0 = std::clamp(int(fx), 0, res - 1), x1 = std::clamp(int(fx) + 1, 0, res - 1);
    const int y0 = std::clamp(int(fy), 0, res - 1), y1 = std::clamp(int(fy) + 1, 0, res - 1);
    const vec2 top = glm::mix(moments[y0 * res + x0], moments[y0 * res + x1], f.x);
    const vec2 bottom = glm::mix(moments[y1 * res + x0], moments[y1 * res + x1], f.x);
    return glm::mix(top, bottom, f.y);
}

float chebyshev_visibility(const vec2& moments, float distance, float bleed_bias) {
    const float mean = moments.x;
    if (distance <= mean) return 1.0f;
    const float variance = std::abs(moments.y - mean * mean);
    const float excess = distance - mean;
    float p = variance / (variance + excess * excess);
    if (bleed_bias > 0.0f) p = std::clamp((p - bleed_bias) / (1.0f - bleed_bias), 0.0f, 1.0f);
    return p;
}

VisibilityFilter::VisibilityFilter(int res, float blur) : res_(res) {
    if (res < 1) throw InvalidArgument(format_message("visibility resolution is ", res));
    if (!(blur > 0.0f))
        throw InvalidArgument(format_message("visibility_blur is ", blur, "; use a value > 0"));
    exponent_ = 1.0f / (blur * blur);
    // max(0, c)^k >= 1e-3  <=>  c >= 1e-3^(1/k)
    min_cos_ = std::pow(1e-3f, 1.0f / exponent_);
    directions_.reserve(size_t(res) * res);
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) directions_.push_back(octahedral_texel_direction(x, y, res));
    weight_.assign(directions_.size(), 0.0f);
    sum_.assign(directions_.size(), 0.0f);
    sum2_.assign(directions_.size(), 0.0f);
}

void VisibilityFilter::clear() {
    std::fill(weight_.begin(), weight_.end(), 0.0f);
    std::fill(sum_.begin(), sum_.end(), 0.0f);
    std::fill(sum2_.begin(), sum2_.end(), 0.0f);
}

void VisibilityFilter::add(const vec3& dir, float distance) {
    for (size_t i = 0; i < directions_.size(); ++i) {
        const float c = glm::dot(directions_[i], dir);
        if (c < min_cos_) continue;
        const float w = std::pow(c, exponent_);
        weight_[i] += w;
        sum_[i] += w * distance;
        sum2_[i] += w * distance * distance;
    }
}

void VisibilityFilter::moments(const vec2* fallback, vec2* out) const {
    for (size_t i = 0; i < directions_.size(); ++i)
        out[i] = weight_[i] > 0.0f ? vec2(sum_[i], sum2_[i]) / weight_[i] : fallback[i];
}

}  // namespace shgi
