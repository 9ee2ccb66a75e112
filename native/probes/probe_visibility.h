// Probe visibility: what each probe sees around it as distances, stored per direction so that a
// shading point can tell whether a probe has a line of sight to it (the leak prevention of
// DDGI — Majercik et al. 2019, "Dynamic Diffuse Global Illumination with Ray-Traced Irradiance
// Fields" — which seed 002 §5.1.2 and §7 ask for: "store visibility information along with the
// probes"). Seed 002 §7 suggests SH of depth; an SH of order ≤ 4 smears a wall's distance over
// ~60°, so the moments are kept instead in a small octahedral map per probe, as DDGI and EEVEE's
// irradiance volumes do (EEVEE's Bias / Bleed Bias / Blur map onto normal_bias, bleed_bias and
// visibility_blur of probes/probe_field.h).
//
// Map: the octahedral parametrisation (Cigolle et al. 2014, "A Survey of Efficient
// Representations for Independent Unit Vectors", §3.6) of the sphere onto a res x res square;
// each texel holds (mean distance, mean squared distance) in metres of the rays leaving the probe
// near the texel's direction d, weighted by max(0, d·ω)^k with k = 1 / visibility_blur²
// (visibility_blur is roughly the filter's angular radius in radians).
//
// Test: Chebyshev's one-sided inequality bounds the fraction of the probe's surroundings in a
// direction that lies beyond a distance r > mean: P(x ≥ r) ≤ σ² / (σ² + (r - mean)²). Shading
// uses it as the probe's visibility weight towards a point at distance r; bleed_bias > 0 cuts the
// tail (weights below it become 0, the rest are rescaled to [0, 1]) as variance shadow maps'
// light-bleeding reduction does.
#pragma once

#include <cstdint>
#include <vector>

#include "util/math.h"

namespace shgi {

// Unit direction -> [0,1]^2 and back (the octahedron's upper half maps to the inner diamond).
vec2 octahedral_encode(const vec3& dir);
vec3 octahedral_decode(const vec2& uv);

// Direction of the centre of texel (x, y) of a res x res octahedral map.
vec3 octahedral_texel_direction(int x, int y, int res);

// Bilinear lookup of one probe's map (res*res moments, row-major) in direction `dir`; texels
// are clamped at the square's edge.
vec2 sample_visibility(const vec2* moments, int res, const vec3& dir);

// The Chebyshev visibility weight in [0, 1] of a point at `distance` from the probe, given the
// probe's moments towards it (see the header comment).
float chebyshev_visibility(const vec2& moments, float distance, float bleed_bias);

// Filters one pass of a probe's rays into a visibility map: add() each ray, then moments().
// Texel directions are shared by all probes of a grid (one filter per resolution and blur).
class VisibilityFilter {
  public:
    VisibilityFilter(int res, float blur);

    int resolution() const { return res_; }
    // Clears the sums for a new probe.
    void clear();
    // One ray leaving the probe along unit `dir` that met something at `distance` (m).
    void add(const vec3& dir, float distance);
    // The pass's map: texels no ray reached keep `fallback` (e.g. the previous pass's value).
    void moments(const vec2* fallback, vec2* out) const;

  private:
    int res_;
    float exponent_;
    float min_cos_;                 // weights below 1e-3 are skipped
    std::vector<vec3> directions_;  // texel centres
    std::vector<float> weight_, sum_, sum2_;
};

}  // namespace shgi
