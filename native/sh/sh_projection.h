// Projection of sampled functions onto the SH basis: c_i = Σ_k w_k f(ω_k) Y_i(ω_k).
//
// This is the Monte Carlo estimator of c_i = ∫ f(ω) Y_i(ω) dω used by probes and lattices
// (seed 004 §3.2: "replacing Equation 1 by the estimator Y_l^m(ω) L(ω) / p(ω)"; seed 002 §4.1.1):
// for N samples drawn with pdf p (sr⁻¹), pass weight w_k = 1 / (N p(ω_k)). For a quadrature
// rule (sh/sphere_quadrature.h) the weights are the rule's solid-angle weights. Directions are
// unit vectors in world space; the unit of the coefficients is that of f (e.g. W·m⁻²·sr⁻¹).
//
// sh_add_sample is the streaming form (one sample into a running sum, float); sh_project is the
// batch form, summed in double in sample order so the result does not depend on batching.
#pragma once

#include <cstddef>

#include "sh/sh_coeffs.h"

namespace shgi {

// sh += weighted_value · Y(dir). `dir` must be unit length.
void sh_add_sample(ShCoeffs& sh, const vec3& dir, float weighted_value);
void sh_add_sample(ShRgb& sh, const vec3& dir, const vec3& weighted_radiance);

// Σ_k weights[k] · values[k] · Y(directions[k]) for k < count; `weights` may be nullptr (all
// ones). Throws InvalidArgument naming the sample if a direction is not unit length (within
// kUnitLengthTolerance) or a value or weight is not finite.
ShCoeffs sh_project(int order, const vec3* directions, const float* values, const float* weights,
                    size_t count);
ShRgb sh_project(int order, const vec3* directions, const vec3* radiance, const float* weights,
                 size_t count);

// How far |ω| may stray from 1 before sh_project rejects a direction: float normalisation
// leaves ~1e-7; 1e-3 admits directions stored at half precision but catches unnormalised input.
inline constexpr float kUnitLengthTolerance = 1e-3f;

// Throws InvalidArgument "<what>[index] ..." unless `dir` is finite and unit length.
void check_unit_direction(const vec3& dir, const char* what, size_t index);

}  // namespace shgi
