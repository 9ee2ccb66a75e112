#include "scene/validation.h"

#include <cmath>

#include "util/error.h"

namespace shgi::scene_detail {

std::string label(const char* kind, const std::string& name) {
    return name.empty() ? format_message(kind, " (unnamed)")
                        : format_message(kind, " '", name, "'");
}

std::string to_string(const vec2& v) { return format_message("(", v.x, ", ", v.y, ")"); }

std::string to_string(const vec3& v) {
    return format_message("(", v.x, ", ", v.y, ", ", v.z, ")");
}

void require_finite(const std::string& item, const char* field, float value) {
    if (!std::isfinite(value))
        throw InvalidArgument(format_message(item, ": ", field, " = ", value, " is not finite"));
}

void require_finite(const std::string& item, const char* field, const vec3& value) {
    if (!is_finite(value))
        throw InvalidArgument(
            format_message(item, ": ", field, " = ", to_string(value), " is not finite"));
}

void require_non_negative(const std::string& item, const char* field, float value) {
    require_finite(item, field, value);
    if (value < 0.0f)
        throw InvalidArgument(format_message(item, ": ", field, " = ", value, " must be >= 0"));
}

void require_non_negative(const std::string& item, const char* field, const vec3& value) {
    require_finite(item, field, value);
    if (value.x < 0.0f || value.y < 0.0f || value.z < 0.0f)
        throw InvalidArgument(format_message(item, ": ", field, " = ", to_string(value),
                                             " must have every component >= 0"));
}

void require_positive(const std::string& item, const char* field, float value) {
    require_finite(item, field, value);
    if (!(value > 0.0f))
        throw InvalidArgument(format_message(item, ": ", field, " = ", value, " must be > 0"));
}

void require_in_range(const std::string& item, const char* field, float value, float lo,
                      float hi) {
    require_finite(item, field, value);
    if (value < lo || value > hi)
        throw InvalidArgument(format_message(item, ": ", field, " = ", value, " is outside [",
                                             lo, ", ", hi, "]"));
}

bool is_singular(const mat4& m) {
    // In double: float determinants of tiny-but-valid scales would underflow the comparison.
    double columns[3][3];
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) columns[c][r] = m[c][r];
    const auto length = [](const double* v) {
        return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    };
    const double* a = columns[0];
    const double* b = columns[1];
    const double* c = columns[2];
    const double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - b[0] * (a[1] * c[2] - a[2] * c[1]) +
                       c[0] * (a[1] * b[2] - a[2] * b[1]);
    const double scale = length(a) * length(b) * length(c);
    return !(std::abs(det) > kMinRelativeDeterminant * scale);
}

void require_transform(const std::string& item, const char* field, const mat4& m) {
    if (!is_finite(m))
        throw InvalidArgument(format_message(item, ": ", field,
                                             " has a non-finite (NaN or Inf) entry"));
    if (is_singular(m))
        throw InvalidArgument(format_message(
            item, ": ", field,
            " is singular (a scale of 0 flattens it); give every axis a non-zero scale"));
    // A bottom row other than (0, 0, 0, 1) is a projective map, which no Blender object has; its
    // inverse would divide positions by w.
    if (m[0][3] != 0.0f || m[1][3] != 0.0f || m[2][3] != 0.0f || m[3][3] != 1.0f)
        throw InvalidArgument(format_message(item, ": ", field, " has the bottom row (",
                                             m[0][3], ", ", m[1][3], ", ", m[2][3], ", ", m[3][3],
                                             "); an object transform's is (0, 0, 0, 1)"));
    const vec3 translation(m[3]);
    if (glm::any(glm::greaterThan(glm::abs(translation), vec3(kMaxCoordinate))))
        throw InvalidArgument(format_message(item, ": ", field, " translation ",
                                             to_string(translation), " exceeds ",
                                             kMaxCoordinate, " m"));
}

double max_axis_scale(const mat4& m) {
    // In double: a float length of a column scaled by 1e20 overflows its squares.
    double longest = 0.0;
    for (int c = 0; c < 3; ++c) {
        const glm::dvec3 column(m[c]);
        longest = std::max(longest, glm::length(column));
    }
    return longest;
}

}  // namespace shgi::scene_detail
