#include "render/normal_map.h"

#include <cmath>

#include "render/shading.h"

namespace shgi {
namespace {

// Light this close to the interpolated horizon is fully shadowed (Cycles' 1e-6).
constexpr float kMinBumpCosine = 1e-6f;

}  // namespace

vec3 ensure_valid_reflection(const vec3& ng, const vec3& wo, const vec3& n) {
    const float cos_ng_wo = glm::dot(ng, wo);
    const float threshold = std::min(kReflectionCosineShare * cos_ng_wo, kMinReflectionCosine);
    const vec3 reflected = 2.0f * glm::dot(n, wo) * n - wo;
    if (glm::dot(ng, reflected) >= threshold) return n;

    // Work in the plane of ng and n: x is n's direction along the surface, and a candidate normal
    // is sin(theta) x + cos(theta) ng. Only wo's components in that plane enter the reflection's
    // elevation, which is 2 (n'.wo) cos(theta) - wo_z = a cos(2 theta - phi) with
    // (wo_x, wo_z) = a (sin phi, cos phi). Solving a cos(2 theta - phi) = threshold gives two
    // angles; the answer is the larger one not beyond n's own angle: the least tilt back
    // towards ng (theta = 0, whose reflection has elevation wo_z > threshold, is always valid).
    const vec3 along = n - glm::dot(n, ng) * ng;
    const float along_length = glm::length(along);
    if (!(along_length > 0.0f)) return ng;
    const vec3 x = along / along_length;
    const float wo_x = glm::dot(wo, x), wo_z = cos_ng_wo;
    const float a = std::sqrt(wo_x * wo_x + wo_z * wo_z);
    if (!(a > 0.0f) || std::fabs(threshold) > a) return ng;
    const float phi = std::atan2(wo_x, wo_z);
    const float spread = std::acos(threshold / a);
    const float theta_n = std::atan2(glm::dot(n, x), glm::dot(n, ng));
    float theta = -1.0f;
    for (const float candidate : {0.5f * (phi - spread), 0.5f * (phi + spread)})
        if (candidate >= 0.0f && candidate <= theta_n) theta = std::max(theta, candidate);
    if (theta < 0.0f) return ng;
    return std::sin(theta) * x + std::cos(theta) * ng;
}

float bump_shadowing_term(const vec3& smooth, const vec3& bent, const vec3& wi) {
    const float cos_bent_wi = glm::dot(bent, wi);
    const vec3 reference = cos_bent_wi < 0.0f ? -smooth : smooth;
    const float denominator = cos_bent_wi * glm::dot(reference, bent);
    const float g = denominator != 0.0f ? glm::dot(reference, wi) / denominator : 0.0f;
    if (g >= 1.0f) return 1.0f;
    if (!(g >= 0.0f)) return 0.0f;
    // Smooth step to 1 at g = 1 with zero slope there, so no crease at the terminator.
    const float g2 = g * g;
    return -g2 * g + g2 + g;
}

float bump_shadowing_microfacet(const vec3& smooth, const vec3& bent, const vec3& wi) {
    const float cos_smooth_wi = glm::dot(smooth, wi);
    const float cos_bend = glm::dot(smooth, bent);
    if (cos_smooth_wi * cos_bend * glm::dot(bent, wi) < 0.0f) return 0.0f;  // behind the surface
    const float cos_i = std::fabs(cos_smooth_wi), cos_d = std::fabs(cos_bend);
    if (cos_d >= 1.0f || cos_i >= 1.0f) return 1.0f;
    if (cos_i < kMinBumpCosine) return 0.0f;
    // The bend as a GGX roughness: the wider the bend, the rougher the implied microsurface.
    const float alpha2 = std::min(1.0f, (1.0f / (cos_d * cos_d) - 1.0f) / 8.0f);
    const float tan2_i = (1.0f - cos_i * cos_i) / (cos_i * cos_i);
    return 2.0f / (1.0f + std::sqrt(1.0f + alpha2 * tan2_i));
}

vec3 mapped_normal(const Material& material, const Texture& texture, const SurfacePoint& sp,
                   const vec3& smooth, bool back_face, const mat3& normal_from_object) {
    const vec3 texel = decode_normal_texel(texture_bilinear(texture, sp.normal_uv));
    vec3 n(0.0f);
    switch (material.normal_space) {
        case NormalMapSpace::Tangent:
            n = texel.x * sp.tangent + texel.y * sp.bitangent + texel.z * sp.shading_normal;
            break;
        case NormalMapSpace::Object: n = normal_from_object * texel; break;
        case NormalMapSpace::World: n = texel; break;
        case NormalMapSpace::BlenderObject:
            n = normal_from_object * vec3(texel.x, -texel.y, -texel.z);
            break;
        case NormalMapSpace::BlenderWorld: n = vec3(texel.x, -texel.y, -texel.z); break;
    }
    if (material.normal_space == NormalMapSpace::Tangent && sp.tangent == vec3(0.0f))
        return smooth;  // no tangent frame at this hit (no tangents or UVs, a dropped tangent)
    const float length = glm::length(n);
    if (!(length > 0.0f) || !std::isfinite(length)) return smooth;
    n /= length;
    if (back_face) n = -n;
    if (material.normal_strength != 1.0f) {
        n = smooth + material.normal_strength * (n - smooth);
        const float blended = glm::length(n);
        if (!(blended > 0.0f)) return smooth;
        n /= blended;
    }
    return n;
}

namespace {

// A texel's height as the Bump node reads a colour: its luminance (Rec. 709, Blender's default
// colour management).
float texel_height(const Texture& texture, const vec2& uv) {
    return luminance(texture_bilinear(texture, uv));
}

}  // namespace

vec3 bumped_normal(const Material& material, const Texture& texture, const SurfacePoint& sp,
                   const vec3& normal_in) {
    if (sp.dpdu == vec3(0.0f) && sp.dpdv == vec3(0.0f)) return normal_in;  // no UVs here
    // The height's UV derivatives by central differences half a texel either side (the
    // bilinear texture's slope around the point, as a pixel footprint sees it).
    const float du = 0.5f / float(std::max(texture.width, 1u));
    const float dv = 0.5f / float(std::max(texture.height, 1u));
    const vec2& uv = sp.bump_uv;
    const float dh_du = (texel_height(texture, uv + vec2(du, 0.0f)) -
                         texel_height(texture, uv - vec2(du, 0.0f))) / (2.0f * du);
    const float dh_dv = (texel_height(texture, uv + vec2(0.0f, dv)) -
                         texel_height(texture, uv - vec2(0.0f, dv))) / (2.0f * dv);
    // Cycles' svm_node_set_bump with the surface derivatives along u and v in place of the
    // pixel's: R_u, R_v span the plane normal to normal_in, and surfgrad / det is the height's
    // gradient in that plane.
    const vec3 r_u = glm::cross(sp.dpdv, normal_in);
    const vec3 r_v = glm::cross(normal_in, sp.dpdu);
    const float det = glm::dot(sp.dpdu, r_u);
    const vec3 surfgrad = dh_du * r_u + dh_dv * r_v;
    vec3 n = std::fabs(det) * normal_in -
             material.bump_distance * (det < 0.0f ? -1.0f : 1.0f) * surfgrad;
    const float length = glm::length(n);
    if (!(length > 0.0f) || !std::isfinite(length)) return normal_in;
    n /= length;
    if (material.bump_strength != 1.0f) {
        n = material.bump_strength * n + (1.0f - material.bump_strength) * normal_in;
        const float blended = glm::length(n);
        if (!(blended > 0.0f)) return normal_in;
        n /= blended;
    }
    return n;
}

}  // namespace shgi
