// ShLattice: a regular grid of RGB SH (L1 or L2) holding incident radiance L_i(x, ω) in
// W m^-2 sr^-1, filled by photon injection (seed 000 §5.3, §6.4), blurred in lattice space
// (§5.4, §6.4) and sampled at shading points by trilinear or 27-neighbour cubic weighting
// (seed 001 §4.1).
//
// Cells are cubes of side cell_size() = (longest side of the bounds) / resolution, laid from
// origin() (the bounds' lower corner); dims() counts cells per axis (>= 1 each). Cell (i, j, k) is
// [origin + (i, j, k) cell_size, origin + (i+1, j+1, k+1) cell_size); its index is
// i + dims.x (j + dims.y k). Coefficients are stored per cell coefficient-major [coeff][rgb]
// (DESIGN.md), the basis of sh/sh_basis.h.
//
// Density estimate (why the lattice's irradiance agrees with the path tracer): a photon of power
// Φ arriving from direction ω on a surface inside cell c estimates the radiance arriving from ω
// at the cell's surfaces. The flux the cell's surfaces receive from a small cone dω around ω is
// L_i(ω) D_c(ω) dω, where D_c(ω) = Σ_triangles A_t |n_t · ω| is the projected area of the
// surface inside the cell seen from ω (both sides of every triangle receive). So
//     L_lm(c) += Φ Y_lm(ω) / D_c(ω)
// is an unbiased estimate of the projection of L_i wherever D_c(ω) > 0 (for a single plane of
// area A it is the familiar Φ / (A cos θ)). measure_surfaces() computes each cell's surface
// exactly (triangles clipped to the cell box) and keeps D_c compactly: three orientation bins
// per cell (by the dominant axis of the normal, sign-folded) with their areas and area-weighted
// mean normals, D_c(ω) ≈ Σ_b A_b |n̄_b · ω| (exact for axis-aligned walls). D is floored at
// kMinProjectedFraction × A_c so grazing photons cannot blow up.
//
// Sampling at (p, n): the position p + normal_offset · cell_size · n picks the neighbour cells
// (trilinear: the 8 around it; cubic: the 27 around its cell, w(d) = 2d³/r³ − 3d²/r² + 1 for
// d < r = 1.75 cells, d the distance to the cell centre in cells). Each neighbour's weight is
// multiplied by D_c(n), how much of the cell's surface faces like the shading point, and the
// weights are normalised: empty cells and cells whose surfaces face elsewhere (the floor cell
// next to a wall point) do not darken or bias the result. All zero weights give zero radiance.
//
// Blur: one pass mixes each cell with its 26 neighbours with symmetric weights
// P_cn = A_n min(1/S_c, 1/S_n), S_c = Σ_{m in 3x3x3(c)} A_m, P_cc = 1 − Σ_{n≠c} P_cn
// (A = surface area per cell). In a uniformly covered region this is the seed's uniform 3x3x3
// kernel; everywhere it keeps a uniform field uniform and preserves the total Σ_c A_c L(c)
// (the energy the cells' surfaces receive) exactly. Cells without surface stay empty.
#pragma once

#include <cstdint>
#include <vector>

#include "photon/photon.h"
#include "scene/scene.h"
#include "sh/sh_coeffs.h"
#include "util/progress.h"

namespace shgi {

inline constexpr float kMinProjectedFraction = 0.05f;
inline constexpr float kCubicRadiusCells = 1.75f;

class ShLattice {
  public:
    ShLattice() = default;
    // Throws InvalidArgument for empty or non-finite bounds, resolution outside [1, 1024], order
    // outside [1, 2], or more than 2^27 cells.
    ShLattice(const Bounds3& bounds, int resolution, int order);

    int order() const { return order_; }
    int num_coefficients() const { return (order_ + 1) * (order_ + 1); }
    ivec3 dims() const { return dims_; }
    vec3 origin() const { return origin_; }
    float cell_size() const { return cell_size_; }
    size_t cell_count() const { return size_t(dims_.x) * size_t(dims_.y) * size_t(dims_.z); }
    size_t cell_index(const ivec3& cell) const {
        return size_t(cell.x) + size_t(dims_.x) * (size_t(cell.y) + size_t(dims_.y) * size_t(cell.z));
    }
    // The cell containing p, or (-1, -1, -1) when p is outside the lattice.
    ivec3 cell_of(const vec3& p) const;

    // Surface inside every cell from the scene's instanced triangles (exact clipping). The scene
    // must be committed. Cancellable.
    void measure_surfaces(const Scene& scene, Progress* progress = nullptr);
    float surface_area(size_t cell) const;
    // D_c(dir): projected surface area of the cell seen from unit direction dir (both sides).
    float projected_area(size_t cell, const vec3& dir) const;

    // Adds scale × Φ Y(ω) / max(D_c(ω), kMinProjectedFraction A_c) per photon to its cell.
    // Photons outside the lattice or in cells without surface are skipped; returns how many were
    // injected. Deterministic (per-cell sums in photon order) and parallel.
    uint64_t inject(const std::vector<Photon>& photons, float scale, Progress* progress = nullptr);
    void clear();                  // all coefficients to zero (surfaces are kept)
    void scale(float factor);      // all coefficients times factor
    void blur(int passes);         // see above

    ShRgb cell_radiance(size_t cell) const;
    void set_cell_radiance(size_t cell, const ShRgb& radiance);  // order must match

    ShRgb sample_trilinear(const vec3& p, const vec3& n, float normal_offset) const;
    ShRgb sample_cubic(const vec3& p, const vec3& n, float normal_offset) const;

    // Raw storage: cell_count() x num_coefficients() x 3 floats.
    const std::vector<float>& coefficients() const { return coeffs_; }
    size_t memory_bytes() const;

  private:
    struct SurfaceBin {
        float area = 0.0f;
        vec3 normal{0.0f};  // area-weighted sum of sign-folded normals
    };
    int order_ = 1;
    ivec3 dims_{0};
    vec3 origin_{0.0f};
    float cell_size_ = 1.0f;
    std::vector<float> coeffs_;
    std::vector<SurfaceBin> bins_;   // 3 per cell
};

}  // namespace shgi
