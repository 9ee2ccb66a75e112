// Sampling routines, each paired with its pdf (the yocto-gl `sample_x` / `sample_x_pdf` habit).
//
// Inputs are uniform numbers u in [0,1)^k. Directions are unit vectors in the local frame of
// the routine (+Z is the lobe axis); pdfs are with respect to solid angle (sr^-1) for
// directions and to area for points. Every routine has a chi-square test in
// tests/cpp/util/sampling_test.cpp.
#pragma once

#include <cstdint>
#include <vector>

#include "util/math.h"

namespace shgi {

// Largest float below 1: a remapped or stratified u must stay in [0, 1) after rounding.
inline constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;

// Uniform over the unit sphere; pdf = 1/(4 pi).
vec3 sample_uniform_sphere(const vec2& u);
float sample_uniform_sphere_pdf();

// Uniform over the +Z hemisphere; pdf = 1/(2 pi).
vec3 sample_uniform_hemisphere(const vec2& u);
float sample_uniform_hemisphere_pdf();

// Cosine-weighted over the +Z hemisphere (Malley's method); pdf = cos(theta)/pi.
vec3 sample_cosine_hemisphere(const vec2& u);
float sample_cosine_hemisphere_pdf(float cos_theta);

// Uniform inside the cone of directions with cos(theta) >= cos_theta_max around +Z;
// pdf = 1 / (2 pi (1 - cos_theta_max)). Used for sun lights with an angular diameter.
vec3 sample_uniform_cone(const vec2& u, float cos_theta_max);
float sample_uniform_cone_pdf(float cos_theta_max);

// Phong power-cosine lobe around +Z: pdf = (n+1)/(2 pi) cos^n(theta). Seed 004 §3.3.2.
vec3 sample_power_cosine(const vec2& u, float exponent);
float sample_power_cosine_pdf(float exponent, float cos_theta);

// Uniform on the unit disk (Shirley-Chiu concentric map); pdf = 1/pi per unit area.
vec2 sample_uniform_disk(const vec2& u);
float sample_uniform_disk_pdf();

// Uniform over a triangle: returns barycentrics (b0, b1, b2) with b0+b1+b2 = 1
// (Heitz 2019 low-distortion map); pdf = 1/area.
vec3 sample_uniform_triangle(const vec2& u);

// Point i of the n-point spherical Fibonacci lattice (Keinert et al. 2015, "Spherical Fibonacci
// Mapping"): z = 1 - (2i + 1)/n, azimuth 2 pi i / golden ratio. The points cover the sphere
// evenly, each standing for 4 pi / n sr; seed 002 §4.1.1 picks probe rays from it. i < n.
vec3 fibonacci_sphere(uint32_t i, uint32_t n);

// A rotation drawn uniformly from SO(3) (Shoemake 1992, "Uniform random rotations"), as a 3x3
// matrix, from three uniform numbers in [0, 1).
mat3 sample_uniform_rotation(const vec3& u);


// Piecewise-constant discrete distribution over non-negative weights (e.g. light powers).
// sample() returns an index with probability weight[i] / sum; pdf(i) returns that probability.
class DiscreteDistribution {
  public:
    DiscreteDistribution() = default;
    // Throws InvalidArgument if a weight is negative or non-finite.
    explicit DiscreteDistribution(const std::vector<float>& weights);

    bool empty() const { return total_ <= 0.0; }
    size_t size() const { return pdf_.size(); }
    double total() const { return total_; }

    // Index for u in [0,1); `u_remapped` (optional) receives u rescaled to [0,1) inside the bin,
    // so the same random number can be reused.
    uint32_t sample(float u, float* u_remapped = nullptr) const;
    float pdf(uint32_t index) const { return pdf_[index]; }

  private:
    std::vector<float> pdf_;
    std::vector<double> cdf_;  // cdf_[i] = sum of pdf_[0..i), cdf_.back() == 1
    double total_ = 0.0;
};

// Veach's power heuristic (beta = 2): the MIS weight of a sample drawn with pdf_a against a
// second strategy of pdf_b (both per unit solid angle).
inline float power_heuristic(float pdf_a, float pdf_b) {
    const float a2 = pdf_a * pdf_a;
    const float sum = a2 + pdf_b * pdf_b;
    return sum > 0.0f ? a2 / sum : 0.0f;
}

}  // namespace shgi
