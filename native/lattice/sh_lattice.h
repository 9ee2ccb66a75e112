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
// (docs/architecture.md), the basis of sh/sh_basis.h.
//
// Density estimate (why the lattice's irradiance agrees with the path tracer): a photon of power
// Φ arriving from direction ω on a surface inside cell c estimates the radiance arriving from ω
// at the cell's surfaces. The flux the cell's surfaces receive from a small cone dω around ω is
// L_i(ω) D_c(ω) dω, where D_c(ω) is the projected area, seen from ω, of the cell's surface sides
// that receive light and face ω. So
//     L_lm(c) += Φ Y_lm(ω) / D_c(ω)
// is an unbiased estimate of the projection of L_i wherever D_c(ω) > 0 (for a single plane of
// area A it is the familiar Φ / (A cos θ)). Counting sides that cannot receive from ω biases it
// low: at a room's floor/wall edge, a photon reaching the floor while travelling away from the
// wall could never have reached the wall's inner side, and counting the wall there (both sides
// of every triangle, as an unsigned |n · ω| does) gave 0.81 π L instead of π L in a uniform field.
//
// measure_surfaces() computes each cell's surface exactly (triangles clipped to the cell box)
// and keeps D_c compactly: three orientation bins per cell (by the dominant axis of the normal)
// with their areas A_b and area-weighted mean normals n̄_b, folded so that n̄_b points along +axis.
// Each bin has two sides, outward normals +n̄_b and −n̄_b. inject() records which sides receive:
// a photon's stored normal is the outward normal of the side it arrived on (photon/photon.h), and
// it marks the side of the bin whose mean normal is closest to that normal (largest |cos|), in
// its cell. Then
//     D_c(ω) = Σ_b [+ side receives] A_b max(0, n̄_b · ω) + [− side receives] A_b max(0, −n̄_b · ω)
// (ω pointing back towards where the light came from), exact for axis-aligned walls lit on any
// set of sides; a thin panel lit on both sides has both sides marked and counts |n̄_b · ω|. A cell
// none of whose sides has received a photon counts every side. An inject() call marks the sides
// its photons reach before it adds any of them, so one call must hold a complete estimate (all
// photons of a tracing pass): photons of one estimate split over several calls would be divided
// by the sides known so far and come out too bright. The marks are ORed per cell, so they do not
// depend on the thread count, and they accumulate across calls until clear() or
// measure_surfaces(): each interactive pass (PhotonLattice sums passes) injects with every side
// known so far, and a side first reached in pass k changes D only for passes >= k, a bias that
// fades as 1/passes instead of recurring every pass. The sides are per bin, not per triangle: in
// a cell holding a floor (lit from above) and a shelf lit from below, the floor's underside counts
// as receiving too. D is floored at kMinProjectedFraction × A_c so grazing photons cannot blow up.
//
// Sampling at (p, n): the position p + normal_offset · cell_size · n picks the neighbour cells
// (trilinear: the 8 around it; cubic: the 27 around its cell, w(d) = 2d³/r³ − 3d²/r² + 1 for
// d < r = 1.75 cells, d the distance to the cell centre in cells). Each neighbour's weight is
// multiplied by D_c(n), how much of the cell's receiving surface faces like the shading point
// (receiving sides whose outward normal is within 90° of n, weighted by the cosine), and the
// weights are normalised: empty cells and cells whose surfaces face elsewhere (the floor cell
// next to a wall point, the ceiling cell above a floor point) do not darken or bias the result.
// All zero weights give zero radiance.
//
// Blur: one pass mixes each cell with those of its 26 neighbours that have the same receiving
// sides (like(c)), with symmetric weights
//     P_cn = A_n min(1/S_c, 1/S_n) for n in like(c), S_c = Σ_{m in 3x3x3(c) ∩ like(c)} A_m,
//     P_cc = 1 − Σ_{n≠c} P_cn
// (A = surface area per cell). In a uniformly covered region this is the seed's uniform 3x3x3
// kernel; everywhere it keeps a uniform field uniform and preserves the total Σ_c A_c L(c)
// exactly. Cells without surface stay empty. A cell's SH holds only the directions its own sides
// receive from (zero elsewhere: a floor cell's only the upper hemisphere), so mixing a floor cell
// with a wall or corner cell would mix in zeros and darken both; floors blur with floors, corners
// with corners. Cells that have not received photons (sides unknown) blur with each other.
//
// Visibility: a wall thinner than the cells still parts them (its two faces land in neighbouring
// cells, or in one), and the cubic weights reach 1.75 cells: a lookup on the dark side of the wall
// blended the lit side's cells into it. In the two-rooms scene (a 2000 W lamp beyond a 0.1 m wall,
// 0.375 m cells) that read the dim room 1.57x too bright. So measure_surfaces() also gives every
// cell with surface an anchor, its surface's area-weighted centroid moved 0.01 cells off it along
// its mean front normal (the side its triangles face), and every cell without surface its middle;
// per cell of the padded lattice (the block centres of surface_near_), a 27-bit mask of the cells
// of its block whose anchors its anchor sees (the segment between them hits no triangle). Samples
// read only the cells their block centre sees (as the 8 trilinear cells lie in that block, both
// samplers), or every cell of the block when none of those faces n (an anchor behind a surface
// whose normals face away from its light: no black hole, the old blend); the blur mixes only cells
// that see each other (segments are traced from the cell with the lower index, so the relation is
// symmetric and the blur keeps Σ A_c L). Costs: one short ray per (block centre, surface cell of
// its block) pair at reset (measure_surfaces),
// 4 bytes per cell, nothing per lookup. Not covered: two surfaces closer than the sample's normal
// offset (a quarter cell), or both in one cell, still share a cell's radiance.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "photon/photon.h"
#include "scene/scene.h"
#include "sh/sh_coeffs.h"
#include "sh/sh_volume.h"  // kCubicRadiusCells, cubic_falloff: the seed 001 §4.1 filter
#include "util/progress.h"

namespace shgi {

class BinaryReader;
class BinaryWriter;

inline constexpr float kMinProjectedFraction = 0.05f;

class ShLattice {
  public:
    ShLattice() = default;
    // Throws InvalidArgument for empty or non-finite bounds, resolution outside [1, 1024], order
    // outside [1, 2], or more than 2^27 cells.
    ShLattice(const Bounds3& bounds, int resolution, int order);
    // A lattice of the given grid (cells of side cell_size from origin, dims per axis), e.g. a
    // part of a finer subdivision of another lattice's grid (the propagation volume's cascades).
    // Throws InvalidArgument for a non-finite origin, a cell size that is not finite and
    // positive, a count below 1, order outside [1, 2] or more than 2^27 cells.
    ShLattice(const vec3& origin, float cell_size, const ivec3& dims, int order);

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

    // Surface inside every cell from the scene's instanced triangles (exact clipping), and with
    // `visibility` which neighbours each cell sees (Visibility, above). The scene must be
    // committed. Cancellable (the previous surfaces are then kept).
    void measure_surfaces(const Scene& scene, Progress* progress = nullptr,
                          bool visibility = true);
    float surface_area(size_t cell) const;
    // D_c(dir): projected area, seen from unit direction dir, of the cell's receiving sides that
    // face dir (every side while the cell has received no photon); see above.
    float projected_area(size_t cell, const vec3& dir) const;
    // The sides of the cell's orientation bins that photons have arrived on (bits of side_bit()),
    // 0 when none has.
    uint8_t receiving_sides(size_t cell) const;
    // The bit of the side of the bin of `axis` whose outward normal points along +axis
    // (positive) or −axis.
    static constexpr uint8_t side_bit(int axis, bool positive) {
        return uint8_t(1u << (2 * axis + (positive ? 0 : 1)));
    }
    static constexpr uint8_t kAllSides = 0x3F;

    // Marks the sides the photons arrive on, then adds scale × Φ Y(ω) / max(D_c(ω),
    // kMinProjectedFraction A_c) per photon to its cell; `photons` must be a complete estimate
    // (see above). Photons outside the lattice or in cells without surface are skipped; returns
    // how many were injected. Deterministic (per-cell sums in photon order) and parallel. Fewer
    // than 2^32 photons per call. Cancellable; after Cancelled some cells hold their photons and
    // others do not, so clear() before injecting again.
    uint64_t inject(const std::vector<Photon>& photons, float scale, Progress* progress = nullptr);
    // All coefficients to zero and every side back to "no photon yet" (surfaces are kept).
    void clear();
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

    // The whole state (cells, surfaces with their receiving sides, visibility masks,
    // coefficients), for a saved PhotonLattice: read() gives back a lattice that samples bit for
    // bit as this one, and throws IoError naming the file for contents no lattice has.
    void write(BinaryWriter& out) const;
    // `with_visibility` false reads a lattice written before the visibility masks (lattice file
    // version 1): it samples as it did then, every cell of a block seen.
    static ShLattice read(BinaryReader& in, bool with_visibility = true);

  private:
    // Checks the memory (`what` begins the message) and sizes the per-cell arrays.
    void allocate(const std::string& what);
    // The surface of a cell that has one: A_c and, per orientation bin, A_b n̄_b (the bin's area
    // times the unit mean of its normals folded to +axis), so that D_c(ω) costs a dot product
    // per bin that holds surface (most cells hold one wall: one bin); and the bin sides photons
    // have arrived on. Surfaces are 2D, so only an index is stored per cell.
    struct CellSurface {
        float area = 0.0f;
        vec3 projected[3] = {vec3(0.0f), vec3(0.0f), vec3(0.0f)};
        uint8_t bins = 0;       // bit b: projected[b] is not zero
        uint8_t receiving = 0;  // side_bit()s

        float projected_area(const vec3& dir) const {  // D_c(dir)
            const uint8_t counted = receiving != 0 ? receiving : kAllSides;
            float sum = 0.0f;
            for (int b = 0; b < 3; ++b) {
                // An empty bin would add |0 · dir| = 0: skipping it leaves the sum's bits as
                // they are.
                if (!(bins & (1u << b))) continue;
                const float cosine_area = glm::dot(projected[b], dir);
                // Both bits are constants once the loop is unrolled (a select, not a shift).
                const uint8_t side = cosine_area >= 0.0f ? side_bit(b, true) : side_bit(b, false);
                if (counted & side) sum += std::fabs(cosine_area);
            }
            return sum;
        }
        // |A_b n̄_b| per bin: computed once per cell for side_facing's per-photon test.
        std::array<float, 3> bin_lengths() const;
        // The side of the bin whose mean normal is closest to ±normal (largest |cos|), or 0 when
        // no bin has a component along it; `lengths` = bin_lengths().
        uint8_t side_facing(const vec3& normal, const std::array<float, 3>& lengths) const;
    };
    static constexpr uint32_t kNoSurface = 0xFFFFFFFFu;

    void check_cell(size_t cell, const char* what) const;
    const CellSurface* cell_surface(size_t cell) const {  // nullptr without surface
        const uint32_t index = surface_index_[cell];
        return index == kNoSurface ? nullptr : &surfaces_[index];
    }
    CellSurface* cell_surface(size_t cell) {
        const uint32_t index = surface_index_[cell];
        return index == kNoSurface ? nullptr : &surfaces_[index];
    }
    float cell_area(size_t cell) const {  // A_c, no range check
        const CellSurface* surface = cell_surface(cell);
        return surface ? surface->area : 0.0f;
    }
    // Marks the sides photons[order[0 .. count)] arrive on in `cell`, then adds their estimate.
    void inject_cell(size_t cell, const std::vector<Photon>& photons, const uint32_t* order,
                     uint32_t count, float scale);
    // Normalised blend of the cells for_each_cell(mask, facing, visit) visits, weighted by
    // D_c(n): those of block mask `seen`, or of `near` when none of those faces n.
    template <typename ForEachCell>
    ShRgb blend(const vec3& n, uint32_t near, uint32_t seen, ForEachCell&& for_each_cell) const;
    // A new surfaces_id_, after anything that changes the cells or their surfaces.
    void renew_surfaces_id();
    // Recomputes visible_near_ from surface_near_ and the surfaces' anchors. Cancellable;
    // reports progress from `reported` to `span` units (measure_surfaces' second half).
    void update_visible_near(const Scene& scene, const std::vector<vec3>& anchors,
                             Progress* progress, uint64_t reported, uint64_t span);
    // False when no cell a sample reads holds radiance, for a sample whose cell (floor of its
    // lattice coordinates) is `centre`.
    bool radiance_near_block(const ivec3& centre) const;
    void update_radiance_near();  // recomputes radiance_near_ from the coefficients
    void update_surface_near();   // recomputes surface_near_ from surface_index_
    // Index in surface_near_ of a cell of the lattice padded by one cell on every side.
    size_t padded_index(const ivec3& cell) const;
    const float* cell_coefficients(size_t cell) const {
        return coeffs_.data() + cell * size_t(num_coefficients()) * 3;
    }

    int order_ = 1;
    ivec3 dims_{0};
    vec3 origin_{0.0f};
    float cell_size_ = 1.0f;
    std::vector<float> coeffs_;
    std::vector<uint32_t> surface_index_;  // per cell: index into surfaces_, or kNoSurface
    std::vector<CellSurface> surfaces_;    // cells with surface, in cell order
    // Per cell of the lattice padded by one cell on every side (the centres of every 3x3x3 block
    // that holds a lattice cell; padded_index): a 27-bit mask of the lattice cells of its block
    // that hold surface, bit (dz + 1) * 9 + (dy + 1) * 3 + (dx + 1) for the cell at offset (dx,
    // dy, dz). Cubic samples visit only those cells.
    std::vector<uint32_t> surface_near_;
    // Per cell of the padded lattice, like surface_near_: the cells of its block whose surface
    // it sees (measure_surfaces; kFullBlock before any measuring). Lookups centred there and the
    // blur read only those, so light does not cross a wall between two cells.
    std::vector<uint32_t> visible_near_;
    static constexpr uint32_t kFullBlock = (uint32_t(1) << 27) - 1;
    // Per cell: 1 when a cell of its 3x3x3 block may hold nonzero radiance; 0 guarantees that all
    // of them are zero, so that samples there return zero at once (a caustic lattice away from
    // its caustics). Kept by every operation that changes coefficients.
    std::vector<uint8_t> radiance_near_;
    // Names the cells' surfaces (with their receiving sides) and the grid: renewed from a
    // process-wide counter by every change to them, kept by copies (which hold the same
    // surfaces), 0 for a default lattice. sample_cubic's per-thread memo of D_c(n) over a block
    // is keyed on it, so that a memo never outlives the surfaces it was computed from.
    uint64_t surfaces_id_ = 0;
};

}  // namespace shgi
