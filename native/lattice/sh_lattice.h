// ShLattice: a regular grid of RGB SH (L1 or L2) holding incident radiance L_i(x, ω) in
// W m^-2 sr^-1, filled by photon injection (seed 000 §5.3, §6.4), blurred in lattice space
// (§5.4, §6.4) and sampled at shading points by trilinear or 27-neighbour cubic weighting
// (seed 001 §4.1).
//
// Cells are cubes of side cell_size() ≈ (longest side of the bounds) / resolution, laid from
// origin() just below the bounds' lower corner; dims() counts cells per axis (>= 1 each). The
// grid is centred on the bounds and overhangs them by a small margin (1e-4 of the longest side,
// at least 10 µm) so that surfaces on the bounds are inside; an axis whose extent is a whole
// number of cells keeps that number (the cells grow by at most 0.1% instead of adding a nearly
// empty layer), so dims() = (8, 2, 2) for bounds of 4 x 1 x 1 m at resolution 8. Cell (i, j, k)
// is [origin + (i, j, k) cell_size, origin + (i+1, j+1, k+1) cell_size); its index is
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

#include <cmath>
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
    // must be committed. Cancellable (the previous surfaces are then kept).
    void measure_surfaces(const Scene& scene, Progress* progress = nullptr);
    float surface_area(size_t cell) const;
    // D_c(dir): projected surface area of the cell seen from unit direction dir (both sides).
    float projected_area(size_t cell, const vec3& dir) const;

    // Adds scale × Φ Y(ω) / max(D_c(ω), kMinProjectedFraction A_c) per photon to its cell.
    // Photons outside the lattice or in cells without surface are skipped; returns how many were
    // injected. Deterministic (per-cell sums in photon order) and parallel. Fewer than 2^32
    // photons per call. Cancellable; after Cancelled some cells hold their photons and others do
    // not, so clear() before injecting again.
    uint64_t inject(const std::vector<Photon>& photons, float scale, Progress* progress = nullptr);
    void clear();                  // all coefficients to zero (surfaces are kept)
    void scale(float factor);      // all coefficients times factor
    void blur(int passes);         // see above

    ShRgb cell_radiance(size_t cell) const;
    void set_cell_radiance(size_t cell, const ShRgb& radiance);  // order must match

    // Incident radiance at p for a shading point with unit normal n; normal_offset in cells.
    ShRgb sample_trilinear(const vec3& p, const vec3& n, float normal_offset) const;
    ShRgb sample_cubic(const vec3& p, const vec3& n, float normal_offset) const;

    // Raw storage: cell_count() x num_coefficients() x 3 floats.
    const std::vector<float>& coefficients() const { return coeffs_; }
    size_t memory_bytes() const;

  private:
    // The surface of a cell that has one: A_c and, per orientation bin, A_b n̄_b (the bin's area
    // times the unit mean of its sign-folded normals), so that D_c(ω) = Σ_b |(A_b n̄_b) · ω| costs
    // three dot products. Surfaces are 2D, so only an index is stored per cell.
    struct CellSurface {
        float area = 0.0f;
        vec3 projected[3] = {vec3(0.0f), vec3(0.0f), vec3(0.0f)};

        float projected_area(const vec3& dir) const {  // D_c(dir)
            return std::fabs(glm::dot(projected[0], dir)) + std::fabs(glm::dot(projected[1], dir)) +
                   std::fabs(glm::dot(projected[2], dir));
        }
    };
    static constexpr uint32_t kNoSurface = 0xFFFFFFFFu;

    void check_cell(size_t cell, const char* what) const;
    const CellSurface* cell_surface(size_t cell) const {  // nullptr without surface
        const uint32_t index = surface_index_[cell];
        return index == kNoSurface ? nullptr : &surfaces_[index];
    }
    float cell_area(size_t cell) const {  // A_c, no range check
        const CellSurface* surface = cell_surface(cell);
        return surface ? surface->area : 0.0f;
    }
    // Normalised blend of the cells for_each_cell(visit) visits, weighted by D_c(n) (sampling).
    template <typename ForEachCell>
    ShRgb blend(const vec3& n, ForEachCell&& for_each_cell) const;
    const float* cell_coefficients(size_t cell) const {
        return coeffs_.data() + cell * size_t(num_coefficients()) * 3;
    }

    int order_ = 1;
    ivec3 dims_{0};
    vec3 origin_{0.0f};
    float cell_size_ = 1.0f;
    std::vector<float> coeffs_;
    std::vector<uint32_t> surface_index_;  // per cell: index into surfaces_, or kNoSurface
    std::vector<CellSurface> surfaces_;    // cells with surface, in order of first measurement
};

}  // namespace shgi
