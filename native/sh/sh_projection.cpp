#include "sh/sh_projection.h"

#include <cmath>

#include "util/error.h"

namespace shgi {

void sh_add_sample(ShCoeffs& sh, const vec3& dir, float weighted_value) {
    float basis[kMaxShCoefficients];
    sh_eval(sh.order, dir, basis);
    for (int i = 0; i < sh.num_coefficients(); ++i) sh.coeffs[i] += weighted_value * basis[i];
}

void sh_add_sample(ShRgb& sh, const vec3& dir, const vec3& weighted_radiance) {
    float basis[kMaxShCoefficients];
    sh_eval(sh.order, dir, basis);
    for (int i = 0; i < sh.num_coefficients(); ++i) sh.coeffs[i] += weighted_radiance * basis[i];
}

void check_unit_direction(const vec3& dir, const char* what, size_t index) {
    const float length = glm::length(dir);
    if (!is_finite(dir) || !(std::abs(length - 1.0f) <= kUnitLengthTolerance))
        throw InvalidArgument(format_message(what, "[", index, "] = (", dir.x, ", ", dir.y, ", ",
                                             dir.z, ") has length ", length,
                                             "; directions must be normalised"));
}

namespace {

float sample_weight(const float* weights, size_t k) {
    if (!weights) return 1.0f;
    if (!std::isfinite(weights[k]))
        throw InvalidArgument(format_message("sh_project: weights[", k, "] is ", weights[k],
                                             "; weights must be finite"));
    return weights[k];
}

}  // namespace

ShCoeffs sh_project(int order, const vec3* directions, const float* values, const float* weights,
                    size_t count) {
    check_sh_order(order, "sh_project");
    ShCoeffs out(order);
    const int n = out.num_coefficients();
    double sum[kMaxShCoefficients] = {};
    float basis[kMaxShCoefficients];
    for (size_t k = 0; k < count; ++k) {
        check_unit_direction(directions[k], "sh_project: directions", k);
        if (!std::isfinite(values[k]))
            throw InvalidArgument(format_message("sh_project: values[", k, "] is ", values[k],
                                                 "; values must be finite"));
        const double weighted = static_cast<double>(sample_weight(weights, k)) * values[k];
        sh_eval(order, directions[k], basis);
        for (int i = 0; i < n; ++i) sum[i] += weighted * basis[i];
    }
    for (int i = 0; i < n; ++i) out.coeffs[i] = static_cast<float>(sum[i]);
    return out;
}

ShRgb sh_project(int order, const vec3* directions, const vec3* radiance, const float* weights,
                 size_t count) {
    check_sh_order(order, "sh_project");
    ShRgb out(order);
    const int n = out.num_coefficients();
    glm::dvec3 sum[kMaxShCoefficients] = {};
    float basis[kMaxShCoefficients];
    for (size_t k = 0; k < count; ++k) {
        check_unit_direction(directions[k], "sh_project: directions", k);
        if (!is_finite(radiance[k]))
            throw InvalidArgument(format_message("sh_project: radiance[", k, "] is (",
                                                 radiance[k].x, ", ", radiance[k].y, ", ",
                                                 radiance[k].z, "); values must be finite"));
        const glm::dvec3 weighted =
            static_cast<double>(sample_weight(weights, k)) * glm::dvec3(radiance[k]);
        sh_eval(order, directions[k], basis);
        for (int i = 0; i < n; ++i) sum[i] += weighted * static_cast<double>(basis[i]);
    }
    for (int i = 0; i < n; ++i) out.coeffs[i] = vec3(sum[i]);
    return out;
}

}  // namespace shgi
