// Normal maps: the shading normal a material's normal texture gives at a hit, and Cycles' two
// guards that keep a bent normal from changing the light units (Blender's Normal Map node as
// Cycles' svm_node_normal_map evaluates it; glTF 2.0's normalTexture).
//
// Decoding: a texel c (non-colour data) holds n = 2c - 1. Tangent space: n is along the mesh's
// interpolated tangent T, bitangent B = sign x cross(N, T) and interpolated normal N, all
// unnormalised and in object space, then mapped to world by the instance's normal transform
// (SurfacePoint carries T, B and N already mapped, scale shared, so the result is the same).
// Object space: n mapped by the normal transform; world space: n as it is; Blender's object and
// world spaces: the same with n's Y and Z negated (Cycles' node_normal_map). The result is flipped
// with the surface on a back-face hit, then Strength blends it with the interpolated normal:
// normalize(N + strength (n - N)). A zero result (a grey (0.5, 0.5, 0.5) texel) falls back to N.
//
// Below-surface correction (ensure_valid_reflection): a bent normal can make the mirror
// direction of the view ray point into the geometric surface, where no light arrives; Cycles
// tilts the normal back towards the geometric normal, in the plane of the two, just enough that
// the reflected view ray leaves the surface at a small elevation. The tilt is solved in closed
// form in that plane (ensure_valid_reflection below). Cycles 3.x corrects the normal of every
// closure; Cycles 4+ only that of its specular closures (render/shading.cpp picks accordingly,
// from the material's PrincipledModel).
//
// Bump shadowing: a diffuse lobe whose normal was bent is scaled by a smooth factor G(wi) in
// [0, 1] that fades light arriving from beyond the interpolated normal's horizon, as Cycles
// applies to diffuse closures: Chiang, Li and Burley 2019, "Taming the Shadow Terminator" in
// Cycles 3.x, a microfacet shadowing term (Conty Estevez et al. 2021) in Cycles 4+.
#pragma once

#include "scene/material.h"
#include "scene/scene.h"
#include "util/math.h"

namespace shgi {

// n = 2c - 1 per component (not normalised).
inline vec3 decode_normal_texel(const vec3& texel) { return 2.0f * texel - vec3(1.0f); }

// The elevation (cosine to the geometric normal) the reflected view ray keeps at least: Cycles'
// min(0.9 cos(Ng, I), 0.01).
inline constexpr float kMinReflectionCosine = 0.01f;
inline constexpr float kReflectionCosineShare = 0.9f;

// n tilted towards ng, in their common plane, until the mirror image of `wo` (unit, towards the
// viewer, on ng's side) about it leaves the surface at cosine
// min(kReflectionCosineShare cos(ng, wo), kMinReflectionCosine); n unchanged when its reflection
// already does. All vectors unit, world space; the result is unit.
vec3 ensure_valid_reflection(const vec3& ng, const vec3& wo, const vec3& n);

// Chiang et al.'s shadowing factor for light from `wi` on a lobe whose normal `bent` was bent away
// from the interpolated normal `smooth`: 1 while wi is well above the interpolated horizon, a
// smooth cubic falling to 0 at it.
float bump_shadowing_term(const vec3& smooth, const vec3& bent, const vec3& wi);

// Cycles 4+'s replacement (Conty Estevez, Lecocq and Stein 2021, "A Microfacet-Based Shadowing
// Function to Solve the Bump Terminator Problem"): 0 for light below the interpolated horizon,
// else GGX's Smith G1 for the light's angle to the interpolated normal, with alpha^2 =
// min(1, tan^2(bend) / 8) from the bend between the two normals.
float bump_shadowing_microfacet(const vec3& smooth, const vec3& bent, const vec3& wi);

// Which of the two a Material's diffuse lobe gets (PrincipledModel V1: Cycles 3.x's Chiang et
// al.; V2: Cycles 4+'s microfacet term).
enum class BumpShadowing : uint8_t { Chiang, Microfacet };

// The world-space shading normal of `material`'s normal map at `sp`, on the side of `smooth`
// (sp.shading_normal flipped to the viewer's side: back_face says whether it was), before the
// below-surface correction; `smooth` when the map cannot apply (tangent space without a tangent
// frame at the hit, a texel decoding to zero). normal_from_object: the instance's normal
// transform (Scene::normal_from_object), used by object-space maps.
vec3 mapped_normal(const Material& material, const Texture& texture, const SurfacePoint& sp,
                   const vec3& smooth, bool back_face, const mat3& normal_from_object);

// The Bump node (Cycles' svm_node_set_bump) with an Image Texture as its Height: the height h
// is the texel's luminance (Cycles' colour-to-float conversion), and the normal
//   normalize(normal_in - bump_distance * grad h),
// grad h the height's gradient along the surface in the plane normal to normal_in, blended with
// normal_in by bump_strength. normal_in is the normal on the viewer's side (the normal map's
// result where the material has one: the Bump node's Normal input). normal_in when the hit has
// no UV derivatives (SurfacePoint::dpdu, dpdv zero) or the result collapses.
vec3 bumped_normal(const Material& material, const Texture& texture, const SurfacePoint& sp,
                   const vec3& normal_in);

}  // namespace shgi
