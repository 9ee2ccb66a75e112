// Math types and constants shared by all of SHGI.
//
// Vectors and matrices are GLM's (column-major, column vectors: p_world = world_from_object * p).
// Frame and units are Blender's: right-handed, Z up, metres. Colours are linear Rec.709 RGB.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_inverse.hpp>

namespace shgi {

using glm::mat3;
using glm::mat4;
using glm::ivec3;
using glm::uvec3;
using glm::vec2;
using glm::vec3;
using glm::vec4;

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kTwoPi = 2.0f * kPi;
inline constexpr float kFourPi = 4.0f * kPi;
inline constexpr float kInvPi = 1.0f / kPi;
inline constexpr float kInvTwoPi = 1.0f / kTwoPi;
inline constexpr float kInvFourPi = 1.0f / kFourPi;
inline constexpr double kPiD = 3.14159265358979323846;

// Rec.709 / sRGB-primaries luminance weights (ITU-R BT.709), used for Russian roulette and
// light selection by power.
inline float luminance(const vec3& rgb) {
    return 0.2126f * rgb.x + 0.7152f * rgb.y + 0.0722f * rgb.z;
}

inline float max_component(const vec3& v) { return std::max(v.x, std::max(v.y, v.z)); }
// max(|x|, |y|, |z|) without branches. glm::abs is x >= 0 ? x : -x, which GCC must compile to a
// compare and a jump (it keeps -0.0): a mispredicted jump per component wherever signs are random
// (photon directions, positions around the origin) cost ~10% of a photon bounce.
inline float max_abs_component(const vec3& v) {
    return std::max(std::fabs(v.x), std::max(std::fabs(v.y), std::fabs(v.z)));
}

inline bool is_finite(float v) { return std::isfinite(v); }
inline bool is_finite(const vec2& v) { return std::isfinite(v.x) && std::isfinite(v.y); }
inline bool is_finite(const vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
bool is_finite(const mat4& m);

// Orthonormal frame around a unit normal z; Duff et al. 2017, "Building an Orthonormal Basis,
// Revisited" (branchless, no singularity at the poles).
struct Frame {
    vec3 x, y, z;

    static Frame from_z(const vec3& n);
    vec3 to_world(const vec3& local) const { return local.x * x + local.y * y + local.z * z; }
    vec3 to_local(const vec3& world) const {
        return vec3(glm::dot(world, x), glm::dot(world, y), glm::dot(world, z));
    }
};

// Spherical direction from polar angle theta (from +Z) and azimuth phi (from +X towards +Y).
inline vec3 spherical_direction(float sin_theta, float cos_theta, float phi) {
    return vec3(sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta);
}

}  // namespace shgi
