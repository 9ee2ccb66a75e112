// ShVolume: a dense regular grid of RGB SH expansions, one per cell, sampled at world points by
// trilinear interpolation or by the normalised 27-neighbour cubic filter of seed 001 §4.1.
//
// The SH-grid of the radiance-field method (seed 001 §3.2–3.3, Fig. 3): gather rays fill each
// cell's expansion of the incident radiance at its centre, and shading points interpolate the
// expansions around them. The volume only stores and samples; what the coefficients mean is the
// filler's (by convention incident radiance L_i in W m⁻² sr⁻¹, sh/sh_coeffs.h), and neither
// sampler looks at surfaces: every cell counts, whether or not geometry lies in it.
//
// Layout: cells are cubes of side cell_size() (m) laid from origin() (the lower corner of cell
// (0, 0, 0)); counts() cells per axis. Cell (i, j, k) spans [origin + (i, j, k) s,
// origin + (i + 1, j + 1, k + 1) s), its expansion belongs to its centre origin + (i + ½, …) s,
// its index is i + nx (j + ny k). Coefficients are stored cell after cell, each cell
// coefficient-major [coeff][rgb] float32 (docs/architecture.md), the basis of sh/sh_basis.h.
// Orders 0..2 (1, 2 or 3 bands: 1, 4 or 9 coefficients; the seed uses 3 bands).
//
// Sampling at a world point p, in cell units q = (p − origin) / cell_size:
//   trilinear — the 8 cell centres around q, with q first clamped to the box of cell centres
//       [½, n − ½] per axis, so points outside the volume take the nearest boundary values and a
//       field linear in the cell index is reproduced inside the volume;
//   cubic — q clamped into the volume [0, n], then the 27 cells of the 3×3×3 block around the
//       cell holding q (those inside the volume), each weighted by cubic_falloff(d) with d the
//       distance from q to the cell's centre in cells, and the weighted sum divided by the sum of
//       weights. The cell holding q is at most √3/2 < r away, so the weights never all vanish.
// Both return zero coefficients for a non-finite point (a broken shading point must not stop a
// frame).
#pragma once

#include <cstddef>
#include <vector>

#include "sh/sh_coeffs.h"
#include "util/math.h"

namespace shgi {

// Reach of the cubic filter in cells (seed 001 §4.1's r_max): a little over √3, so that from a
// cell's centre even the corner cells of its 3×3×3 block keep a small weight.
inline constexpr float kCubicRadiusCells = 1.75f;

// The seed's weight w(d) = 2d³/r³ − 3d²/r² + 1 for d < r, 0 beyond (d and r in the same unit):
// 1 at d = 0, falls smoothly to 0 with zero slope at d = r.
inline float cubic_falloff(float d, float radius = kCubicRadiusCells) {
    if (d >= radius) return 0.0f;
    const float x = d * (1.0f / radius);
    return (2.0f * x - 3.0f) * x * x + 1.0f;
}

inline constexpr int kMaxShVolumeOrder = 2;
// More cells than this are refused (the SH lattice's bound: 2^27 cells of L2 RGB are 14.5 GB).
inline constexpr uint64_t kMaxShVolumeCells = uint64_t(1) << 27;

class ShVolume {
  public:
    ShVolume() = default;
    // All-zero volume. Throws InvalidArgument naming the field for a non-finite origin, a
    // cell_size that is not finite and positive, a count below 1, more than kMaxShVolumeCells
    // cells, a far corner that is not finite, or an order outside 0..kMaxShVolumeOrder;
    // OutOfMemory (before allocating) when the coefficients do not fit.
    ShVolume(const vec3& origin, float cell_size, const ivec3& counts, int order);

    vec3 origin() const { return origin_; }
    float cell_size() const { return cell_size_; }
    ivec3 counts() const { return counts_; }
    int order() const { return order_; }
    int num_coefficients() const { return sh_num_coefficients(order_); }
    // Floats per cell: 3 × num_coefficients().
    int floats_per_cell() const { return 3 * num_coefficients(); }
    size_t cell_count() const { return size_t(counts_.x) * size_t(counts_.y) * size_t(counts_.z); }
    size_t cell_index(const ivec3& cell) const {
        return size_t(cell.x) +
               size_t(counts_.x) * (size_t(cell.y) + size_t(counts_.y) * size_t(cell.z));
    }
    // Whether `cell` lies inside the volume (0 <= cell < counts() on every axis).
    bool contains(const ivec3& cell) const {
        return !glm::any(glm::lessThan(cell, ivec3(0))) &&
               !glm::any(glm::greaterThanEqual(cell, counts_));
    }
    // The cell at cell_index `index` (its inverse).
    ivec3 cell_at(size_t index) const {
        const size_t x = size_t(counts_.x), y = size_t(counts_.y);
        return ivec3(int(index % x), int((index / x) % y), int(index / (x * y)));
    }
    vec3 cell_centre(const ivec3& cell) const {
        return origin_ + (vec3(cell) + 0.5f) * cell_size_;
    }

    // One cell's expansion; throw InvalidArgument for a cell outside the volume or (set) an
    // expansion of another order.
    ShRgb cell_coefficients(const ivec3& cell) const;
    void set_cell_coefficients(const ivec3& cell, const ShRgb& coefficients);
    // All coefficients, cell_count() × floats_per_cell() floats in the layout above.
    const std::vector<float>& coefficients() const { return coefficients_; }
    float* cell_data(size_t index) { return coefficients_.data() + index * floats_per_cell(); }
    const float* cell_data(size_t index) const {
        return coefficients_.data() + index * floats_per_cell();
    }

    // The interpolated expansion at world point p (see the header comment).
    ShRgb sample_trilinear(const vec3& p) const;
    ShRgb sample_cubic(const vec3& p) const;

  private:
    void check_cell(const ivec3& cell, const char* what) const;

    vec3 origin_{0.0f};
    float cell_size_ = 1.0f;
    ivec3 counts_{0};
    int order_ = 0;
    std::vector<float> coefficients_;
};

}  // namespace shgi
