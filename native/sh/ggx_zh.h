// Zonal-harmonic band factors of the GGX specular lobe, for split-sum specular lighting from SH
// probes (seed 002 §4.2.2 and Appendix A, "Fitted zonal harmonic coefficients function for GGX
// specular lobes").
//
// ggx_specular_zh(roughness) is the seed's fitted GLSL get_ggx_specular_zh, transcribed
// constant for constant. It returns per-band multipliers k_0..k_4 with k_0 = 1 (the seed returns
// only L1..L4 "since L0 is always 1"), i.e. the lobe is normalised to unit integral and
// k_l = √(4π/(2l+1)) z_l / (√(4π) z_0). Specular radiance toward the viewer is then
//     L_s(r) ≈ Σ_lm k_l L_lm Y_lm(r),   r = reflect(-wo, n),
// to be multiplied by the split-sum environment BRDF (Karis 2013) by the caller.
//
// `roughness` is the perceptual (glTF / Blender Principled) roughness in [0, 1]. The seed does
// not state which lobe it fitted; ggx_specular_zh_reference projects the candidate
// f(θ) = D_GGX(cos(θ/2); α = roughness²) · max(cos θ, 0) — Karis' prefiltering lobe with n = v = r,
// whose GGX pdf D (n·h)/(4 v·h) collapses to D/4, weighted by n·l — and the fit matches it to
// ~1e-4 over the whole range (tests/cpp/sh/ggx_zh_test.cpp), from an impulse (all 1) at
// roughness 0 to the normalised clamped cosine (1, 2/3, 1/4, 0, -1/24) at roughness 1.
//
// The fit (and the true lobe, for L4) has slightly negative bands, so the reconstruction can
// ring below zero: sh_specular_radiance clamps its result to >= 0, and every use site of the raw
// factors must clamp the final radiance likewise.
//
// sh_specular_radiance runs once per glossy shading point of every preview frame, where the fit's
// eight cosines and four square roots cost more than the SH evaluation itself; it reads the fit
// from a table over roughness instead (ggx_specular_zh_tabulated), whose interpolation error is
// that of evaluating the fit in float (~2e-5), a fifth of the fit's own error.
#pragma once

#include <cstring>

#include "sh/zonal_harmonics.h"

namespace shgi {

// Seed 002 Appendix A; throws InvalidArgument unless roughness is in [0, 1].
BandFactors ggx_specular_zh(float roughness);

// The same factors by numerical projection of the lobe described above (slow; for tests and
// for offline tables). Roughness 0 returns the impulse (all 1) exactly.
BandFactors ggx_specular_zh_reference(float roughness);

// Intervals of the roughness table behind ggx_specular_zh_tabulated. Linear interpolation over
// 256 equal intervals is within 2.2e-5 of the fit (measured over 200001 roughness values; worst
// in bands 3 and 4, whose terms have the largest curvature), and finer tables do not get closer:
// the fit evaluated in float scatters by ~1.6e-5 around its smooth curve.
inline constexpr int kGgxZhTableIntervals = 256;

// ggx_specular_zh interpolated linearly between its values at roughness i / kGgxZhTableIntervals
// (the table is built on first use); k_0 = 1 exactly, as the fit's. Throws InvalidArgument unless
// roughness is in [0, 1].
BandFactors ggx_specular_zh_tabulated(float roughness);

// max(0, Σ k_l(roughness) L_lm Y_lm(reflected)) per channel: pre-filtered specular radiance
// (W·m⁻²·sr⁻¹) in the unit direction `reflected`, with k_l from ggx_specular_zh_tabulated.
vec3 sh_specular_radiance(const ShRgb& radiance, const vec3& reflected, float roughness);
// The same with the factors given (ggx_specular_zh_tabulated's, e.g. from a GgxZhMemo).
vec3 sh_specular_radiance(const ShRgb& radiance, const vec3& reflected, const BandFactors& factors);

// ggx_specular_zh_tabulated of the last roughness asked for. The factors are a function of the
// roughness alone, and a preview frame asks for the few roughnesses of its materials over and
// over (once per glossy pixel, ~1% of a frame), so a caller that keeps one memo per thread gets
// the bits a new call would give without the call. Not thread-safe.
class GgxZhMemo {
  public:
    const BandFactors& factors(float roughness) {
        // Bits, not ==: a NaN must reach ggx_specular_zh_tabulated's check every time.
        if (!valid_ || std::memcmp(&roughness, &roughness_, sizeof(float)) != 0) {
            factors_ = ggx_specular_zh_tabulated(roughness);
            roughness_ = roughness;
            valid_ = true;
        }
        return factors_;
    }

  private:
    bool valid_ = false;
    float roughness_ = 0.0f;
    BandFactors factors_{};
};

// The band factors of `roughness` from `memo` when there is one, else ggx_specular_zh_tabulated's
// (the same values): what every glossy field read (FieldLookup::glossy, QuadGlossy) takes.
inline BandFactors ggx_specular_zh_factors(float roughness, GgxZhMemo* memo) {
    return memo != nullptr ? memo->factors(roughness) : ggx_specular_zh_tabulated(roughness);
}

}  // namespace shgi
