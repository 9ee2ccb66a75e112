#include "util/sampling.h"

#include <algorithm>

#include <glm/gtc/quaternion.hpp>

#include "util/error.h"

namespace shgi {

vec3 sample_uniform_sphere(const vec2& u) {
    const float z = 1.0f - 2.0f * u.x;
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return spherical_direction(r, z, kTwoPi * u.y);
}
float sample_uniform_sphere_pdf() { return kInvFourPi; }

vec3 sample_uniform_hemisphere(const vec2& u) {
    const float z = u.x;
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return spherical_direction(r, z, kTwoPi * u.y);
}
float sample_uniform_hemisphere_pdf() { return kInvTwoPi; }

vec3 sample_cosine_hemisphere(const vec2& u) {
    const vec2 d = sample_uniform_disk(u);
    const float z = std::sqrt(std::max(0.0f, 1.0f - d.x * d.x - d.y * d.y));
    return vec3(d.x, d.y, z);
}
float sample_cosine_hemisphere_pdf(float cos_theta) { return std::max(cos_theta, 0.0f) * kInvPi; }

vec3 sample_uniform_cone(const vec2& u, float cos_theta_max) {
    const float cos_theta = (1.0f - u.x) + u.x * cos_theta_max;
    const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
    return spherical_direction(sin_theta, cos_theta, kTwoPi * u.y);
}
float sample_uniform_cone_pdf(float cos_theta_max) {
    return 1.0f / (kTwoPi * (1.0f - cos_theta_max));
}

vec3 sample_power_cosine(const vec2& u, float exponent) {
    // Inverting the cdf of cos^n over the hemisphere: cos(theta) = u^(1/(n+1)).
    const float cos_theta = std::pow(u.x, 1.0f / (exponent + 1.0f));
    const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
    return spherical_direction(sin_theta, cos_theta, kTwoPi * u.y);
}
float sample_power_cosine_pdf(float exponent, float cos_theta) {
    if (cos_theta <= 0.0f) return 0.0f;
    return (exponent + 1.0f) * kInvTwoPi * std::pow(cos_theta, exponent);
}

namespace {

// (cos x, sin x) for |x| <= pi/4 from their Taylor series to x^10 and x^11 (truncation below
// 1e-9, so within about an ulp of float): the concentric disk map only needs this quarter turn,
// and libm's general sincosf (range reduction, a call) was ~2.3% of the photon trace's time
// (perf), which samples a cosine-weighted direction at every diffuse bounce.
vec2 cos_sin_quarter_turn(float x) {
    const float x2 = x * x;
    const float c = 1.0f + x2 * (-1.0f / 2.0f + x2 * (1.0f / 24.0f + x2 * (-1.0f / 720.0f +
                    x2 * (1.0f / 40320.0f + x2 * (-1.0f / 3628800.0f)))));
    const float s = x * (1.0f + x2 * (-1.0f / 6.0f + x2 * (1.0f / 120.0f + x2 * (-1.0f / 5040.0f +
                    x2 * (1.0f / 362880.0f + x2 * (-1.0f / 39916800.0f))))));
    return vec2(c, s);
}

}  // namespace

vec2 sample_uniform_disk(const vec2& u) {
    // Shirley & Chiu 1997: maps concentric squares to concentric circles. The angle is
    // (pi/4) (y/x) in the wedges around the x axis and pi/2 - (pi/4) (x/y) around the y axis,
    // whose cosine and sine are the sine and cosine of (pi/4) (x/y): one quarter-turn sincos.
    const vec2 offset = 2.0f * u - vec2(1.0f);
    if (offset.x == 0.0f && offset.y == 0.0f) return vec2(0.0f);
    if (std::abs(offset.x) > std::abs(offset.y))
        return offset.x * cos_sin_quarter_turn(0.25f * kPi * (offset.y / offset.x));
    const vec2 cs = cos_sin_quarter_turn(0.25f * kPi * (offset.x / offset.y));
    return offset.y * vec2(cs.y, cs.x);
}
float sample_uniform_disk_pdf() { return kInvPi; }

vec3 sample_uniform_triangle(const vec2& u) {
    // Heitz 2019, "A Low-Distortion Map Between Triangle and Square".
    float b0, b1;
    if (u.x < u.y) {
        b0 = u.x / 2.0f;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0f;
        b0 = u.x - b1;
    }
    return vec3(b0, b1, 1.0f - b0 - b1);
}

DiscreteDistribution::DiscreteDistribution(const std::vector<float>& weights) {
    double sum = 0.0;
    for (size_t i = 0; i < weights.size(); ++i) {
        if (!std::isfinite(weights[i]) || weights[i] < 0.0f)
            throw InvalidArgument(format_message("DiscreteDistribution: weight[", i, "] is ",
                                                 weights[i], "; weights must be finite and >= 0"));
        sum += weights[i];
    }
    total_ = sum;
    pdf_.resize(weights.size(), 0.0f);
    cdf_.resize(weights.size() + 1, 0.0);
    if (sum <= 0.0) return;
    for (size_t i = 0; i < weights.size(); ++i) {
        pdf_[i] = static_cast<float>(weights[i] / sum);
        cdf_[i + 1] = cdf_[i] + weights[i] / sum;
    }
    cdf_.back() = 1.0;
}

uint32_t DiscreteDistribution::sample(float u, float* u_remapped) const {
    if (empty()) throw InvalidArgument("DiscreteDistribution::sample: all weights are zero");
    // First bin whose upper cdf bound exceeds u; zero-weight bins have zero width and are skipped.
    const auto it = std::upper_bound(cdf_.begin() + 1, cdf_.end(), static_cast<double>(u));
    uint32_t index = static_cast<uint32_t>(std::min<ptrdiff_t>(it - cdf_.begin() - 1,
                                                                 static_cast<ptrdiff_t>(size() - 1)));
    while (pdf_[index] == 0.0f && index > 0) --index;  // u == 1 - eps landing past the last bin
    if (u_remapped) {
        const double width = cdf_[index + 1] - cdf_[index];
        const double t = width > 0.0 ? (u - cdf_[index]) / width : 0.0;
        *u_remapped = std::min(static_cast<float>(t), kOneMinusEpsilon);
    }
    return index;
}

vec3 fibonacci_sphere(uint32_t i, uint32_t n) {
    constexpr double kInvGoldenRatio = 0.6180339887498949;  // 1 / phi = phi - 1
    const float z = 1.0f - (2.0f * float(i) + 1.0f) / float(n);
    const double turns = double(i) * kInvGoldenRatio;
    const float phi = float(kTwoPi * (turns - std::floor(turns)));
    return spherical_direction(std::sqrt(std::max(0.0f, 1.0f - z * z)), z, phi);
}

mat3 sample_uniform_rotation(const vec3& u) {
    // A uniform unit quaternion (x, y, z, w), then its matrix.
    const float r1 = std::sqrt(1.0f - u.x), r2 = std::sqrt(u.x);
    const float t1 = kTwoPi * u.y, t2 = kTwoPi * u.z;
    const glm::quat q(r2 * std::cos(t2), r1 * std::sin(t1), r1 * std::cos(t1), r2 * std::sin(t2));
    return glm::mat3_cast(q);
}

}  // namespace shgi
