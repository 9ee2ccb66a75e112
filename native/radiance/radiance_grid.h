// RadianceGrid: the multilevel radiance grid (R-grid) of the radiance-field method (seed 001
// §3.3): per cell, the radiance reflected diffusely by the cell's surfaces through each of its six
// directional faces (+x, −x, +y, −y, +z, −z), estimated from photon hits, and a mip chain of
// coarser levels (§3.4.3) that gather rays read with a footprint filter.
//
// Input: reflected hits — where light arrives on a surface (position, the outward normal of the
// side it arrives on, the direction back towards its source) and the flux the surface scatters
// diffusely there (W: diffuse albedo × arriving flux, photon/photon.h's reflected_power). Output:
// face radiance in W m⁻² sr⁻¹.
//
// Face estimators, for cell c and face j of outward normal n_j:
//   ProjectedArea (default) — L_j = (1/π) Σ_i Φr_i max(0, n_i · n_j) / D_c(n_j), with D_c the
//       projected area seen from n_j of the cell's receiving surface sides (the surface measure
//       of lattice/sh_lattice.h, exact clipping). For any lit plane of area A in the cell,
//       D_c(n_j) = A (n · n_j) and the sum is Φr (n · n_j) / A: L_j = ρE/π exactly, for every face
//       the plane faces, whatever its tilt against the grid.
//   Paper — the seed's form L_j = (1/π) Σ_i Φr_i δ_ij / A_face, δ_ij = (o_i · n_j)² for the faces
//       the outgoing direction o_i (the incoming one mirrored about n_i) points through, A_face
//       the face's area. It reads ρE/π only for planes that fill the cell's face and are lit at
//       normal incidence; a tilted plane splits its flux over two or three faces by δ and each
//       face reads a share of the true radiance. (The seed multiplies the stored photons' power
//       by f_r; SHGI's photons are Russian-roulette survivors stored before they scatter, so the
//       albedo is applied once, through Φr.) Kept for comparison.
// Faces count only where the cell has surface facing them (D_c(n_j) > 0): a face without surface
// reflects nothing and is not read, so a floor cell's ±x faces do not darken a floor seen at an
// angle. The receiving sides come from the hits (ShLattice::inject marks them).
//
// Passes: each build() adds one pass of hits to the per-face flux sums; the radiance is the sums'
// mean over passes divided by the current D (sides first reached in a later pass change D for
// the earlier passes' flux too: the estimate of an unchanged scene only gets closer).
//
// Mips (§3.3, §3.4.3): level m + 1 halves the cells per axis; a parent face's radiance is the
// mean of its children's same faces weighted by their D (the radiance averaged over the surface
// that faces that way), its D their sum: faces without surface do not dilute the mean.
//
// Reading (§3.4.2): radiance_toward(x, hit, d, side, level) is the radiance arriving at x along
// unit d from the surface point `hit`, whose side seen from x has the unit normal `side`: in the
// cell holding `hit` (on the side facing x), the faces with surface that face x and that `side`
// reflects through (side · n_j > 0: a crease cell of floor and wall also holds the wall's
// outside, whose face may point towards x too; read, the sun room's creases came out 1.5-2.5
// times too bright), weighted by g(α_j) cos β_j / Σ_k g(α_k) cos β_k, with α_j the angle
// between d and the direction from x to the face's centre, g a Gaussian of standard deviation
// sigma, and β_j the angle between n_j and −d (the seed measures it towards x from the face's
// centre, which points the wrong way when x lies in or beside the hit cell). (The seed
// normalises by Σ g alone and multiplies L_j by cos β_j after, which reads a uniform field dark;
// with cos β inside the normalisation a uniform field reads exactly its radiance.) A fractional
// level interpolates the two levels around it. Determinism: sums per cell in hit order
// (util/cell_sort.h), for any thread count.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "lattice/sh_lattice.h"
#include "util/math.h"
#include "util/progress.h"

namespace shgi {

enum class FaceEstimator : uint8_t {
    ProjectedArea,  // exact for lit planes (see above)
    Paper,          // seed 001 §3.3's δ-weighted flux over the face area
};

// A surface point that scatters light: see the header comment.
struct ReflectedHit {
    vec3 position{0.0f};
    vec3 normal{0.0f, 0.0f, 1.0f};     // outward normal of the side the light arrives on
    vec3 direction{0.0f, 0.0f, 1.0f};  // towards the light's source, dot(normal, direction) > 0
    vec3 reflected_power{0.0f};        // W
};

inline constexpr int kFaceCount = 6;
// Outward normal of face j: +x, −x, +y, −y, +z, −z.
vec3 face_normal(int face);

class RadianceGrid {
  public:
    RadianceGrid() = default;
    // Over the cells of `surfaces` (measured: ShLattice::measure_surfaces), with `levels` levels
    // (1 = no mips; capped where a level would have one cell along every axis).
    RadianceGrid(ShLattice surfaces, int levels, FaceEstimator estimator);

    // Adds one pass of hits (see "Passes"); marks the sides they arrive on, then rebuilds every
    // level. Cancellable (throws Cancelled; call clear() before building again).
    void add_pass(const std::vector<ReflectedHit>& hits, Progress* progress = nullptr);
    void clear();  // forgets every pass and every receiving side

    int levels() const { return int(levels_.size()); }
    ivec3 dims(int level) const { return levels_[size_t(level)].dims; }
    float cell_size(int level) const { return levels_[size_t(level)].cell_size; }
    vec3 origin() const { return surfaces_.origin(); }
    const ShLattice& surfaces() const { return surfaces_; }
    uint64_t passes() const { return passes_; }

    // The level-0 cell holding surface point p seen from the side of unit `toward` (p nudged a
    // little that way; the other side when that cell holds no surface); (-1, -1, -1) outside.
    ivec3 surface_cell(const vec3& p, const vec3& toward) const;
    vec3 face_radiance(int level, const ivec3& cell, int face) const;
    float face_area(int level, const ivec3& cell, int face) const;  // D_c(n_j), m²
    // Tests: sets one level-0 face's radiance, then rebuilds the mips from level 0.
    void set_face_radiance(const ivec3& cell, int face, const vec3& radiance);

    // Radiance arriving at x along unit d from surface point `hit` (see "Reading"). *lit (when
    // given) is false when no face of the finest cell there both holds surface that light has
    // reached and faces x: x looks at a side no light arrives on (the outside of a room's wall,
    // seen from beyond it), whose radiance is then zero.
    vec3 radiance_toward(const vec3& x, const vec3& hit, const vec3& d, const vec3& side,
                         float level, float sigma, bool* lit = nullptr) const;

    size_t memory_bytes() const;

  private:
    struct Level {
        ivec3 dims{0};
        float cell_size = 0.0f;
        std::vector<float> area;      // cells × 6: D_c(n_j)
        std::vector<float> radiance;  // cells × 6 × 3
        size_t index(const ivec3& c) const {
            return size_t(c.x) + size_t(dims.x) * (size_t(c.y) + size_t(dims.y) * size_t(c.z));
        }
    };
    void update_levels(Progress* progress);  // level 0 from the sums, then the mips
    void build_mips();
    vec3 read_level(int level, const ivec3& cell0, const vec3& x, const vec3& d, const vec3& side,
                    float sigma, bool* lit) const;

    ShLattice surfaces_;
    FaceEstimator estimator_ = FaceEstimator::ProjectedArea;
    std::vector<Level> levels_;
    std::vector<float> flux_sums_;  // level-0 cells × 6 × 3: the estimator's numerators
    uint64_t passes_ = 0;
};

}  // namespace shgi
