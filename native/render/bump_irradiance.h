// Irradiance from SH radiance through a bump-shadowed diffuse lobe.
//
// Where a normal map bends a diffuse lobe's normal, Cycles scales the lobe by a shadowing factor
// S(wi) toward each light (render/normal_map.h: Chiang et al.'s term in Cycles 3.x, the
// microfacet term in Cycles 4+), a function of the light's direction. A field's diffuse light,
// the clamped-cosine convolution of its SH radiance about the shading normal
// (sh/sh_irradiance.h), leaves it out: on a normal-mapped floor a field read ~10% brighter than
// the path tracer, which applies S at every light sample. The kernel
//     K(w) = S(w) max(w . n_b, 0)        (n_b the bent normal)
// projected onto SH up to the radiance's order takes it in: E = ∫ L K dw = Σ_i L_i K_i, exact for
// a radiance of that order, as the cosine convolution is (Ramamoorthi & Hanrahan 2001 eq. 7 is
// its S = 1 case). For a sum of deltas (VPLs) each delta reads K's projection, as with the cosine.
//
// K depends on the directions only through the tilt t between the interpolated normal n_s and
// n_b: its coefficients are tabulated once per model over t in [0, π] in a canonical frame (z =
// n_b, n_s in the xz-plane on the +x side), by a product quadrature of the hemisphere about n_b,
// and interpolated linearly in t. They are turned to the world frame by a quadrature rule exact
// for the products Y_i K of the kernel's order (degree 2 order; sh/sphere_quadrature.h):
// K_i = Σ_j w_j K(d_j) Y_i(R d_j), R the canonical frame's rotation to the world.
//
// Units: K in sr⁻¹·sr (a cosine-weighted solid angle), so radiance in W m⁻² sr⁻¹ gives
// irradiance in W m⁻², as sh_irradiance.
#pragma once

#include "render/normal_map.h"
#include "render/shading.h"
#include "sh/sh_coeffs.h"
#include "util/math.h"

namespace shgi {

// A diffuse lobe's bump shadowing at a hit, in world space: the interpolated normal its bent
// normal departs from (unit) and which term (render/normal_map.h).
struct DiffuseBump {
    vec3 smooth_normal{0.0f};
    BumpShadowing model = BumpShadowing::Chiang;

    // S toward unit world direction wi for the lobe's unit bent normal `bent`.
    float shadowing(const vec3& bent, const vec3& wi) const;
};

// The diffuse lobe's bump shadowing at `shading` (its BSDF's set_smooth_normal) into `out`;
// false where its normal was not bent (S = 1: the plain cosine convolution, bit for bit as
// before, is the caller's).
bool diffuse_bump(const Shading& shading, DiffuseBump* out);

// The normal a field places its lookup by at `shading` (a light propagation volume moves it
// normal_offset cells along it and damps by the light behind it, a probe grid biases it): the
// interpolated normal where a normal map bent the shading normal, whose tilt would move the
// lookup sideways and towards the surface (diffuse_bump's smooth_normal); the shading normal
// elsewhere. The lobes are then evaluated about the bent normal.
vec3 field_lookup_normal(const Shading& shading);

// K's SH coefficients (order 0..4) in the world frame, for the unit bent normal `bent`.
// Throws InvalidArgument for an order outside 0..4.
ShCoeffs bump_cosine_sh(int order, const vec3& bent, const DiffuseBump& bump);

// E = Σ_i L_i K_i (not clamped: ringing can make it slightly negative, as sh_irradiance).
vec3 sh_bump_irradiance(const ShRgb& radiance, const vec3& bent, const DiffuseBump& bump);

}  // namespace shgi
