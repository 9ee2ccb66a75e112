// RadianceField: the radiance-field solver (seed 001, Chang, Park & Ihm): photons traced from the
// lights, their diffusely reflected flux gathered on the faces of a multilevel radiance grid
// (radiance/radiance_grid.h, §3.3), and an SH field of incident radiance at the centres of the
// cells near surfaces, built by gather rays that read the grid (§3.4), interpolated at shading
// points with the 27-neighbour cubic weights (§4.1).
//
// One pass (refine()):
//   voxelise   — at construction and reset(): the SH-grid's cells (cubes, `resolution` along the
//                longest side of the bounds) and the exact surface inside each (lattice/
//                sh_lattice.h's clipping, §3.1's boundary cells without a GPU voxeliser); sample
//                points at the centres of boundary cells and of their 26 neighbours.
//   photons    — one pass of `photons` photons (photon/photon_tracer.h) with the first hits
//                stored, traced for max_bounces − 1 scatterings (the grid reflects each hit once
//                more, so the field's light has at most max_bounces bounces where it is shaded,
//                as a camera path with max_bounces diffuse bounces; the photon lattice, which
//                stores arriving light, traces max_bounces); every hit scatters
//                reflected_power = diffuse albedo × arriving flux (found by a short ray back
//                along the photon's path: a stored photon keeps no material); with
//                glossy_in_grid, plus the directional albedo of the glossy lobes rougher than
//                specular_roughness, spread as if diffuse. The seed's grid holds diffuse
//                reflection only, but a Principled surface's default rough specular layer
//                reflects 4-10% of the light, which then reaches nothing: the Cornell box read
//                12% dark without it.
//   radiance_grid — the hits' flux on the faces, mean over passes, and the mips.
//   sh_field   — at each sample point, gather_rays directions of a spherical Fibonacci lattice
//                under a rotation drawn per pass (the same for every point), traced with Embree;
//                a hit reads the grid (RadianceGrid::radiance_toward) at the mip level whose face
//                area matches the ray's footprint 4πd²/(N cos β) (§3.4.3; use_mips), a miss reads
//                the world when world_in_field. Projected to L2 with weight 4π/N (eq. 1; the seed
//                prints θ over [0, 2π], it is [0, π]); the field is the mean over passes. Hit
//                distances go into a scalar L2 channel (§3.4.4). A point whose rays see back faces
//                of closed meshes (probes/probe_grid.h's test), or sides of any surface that no
//                photon has reached (the outside of a room's single-sided wall), in more than
//                backface_threshold of them is inside geometry or outside the lit scene and never
//                read. (A side no photon reached reads zero either way; with very few photons a
//                dim corner may count so too.)
//
// Field units and what it holds: incident radiance (W m⁻² sr⁻¹) of light that scattered at least
// once; emitters and the world seen directly are left to the consumer's exact direct light,
// unless world_in_field (then escaped rays read the world and includes_world_direct() is true).
//
// Shading (§4.1–4.3): the sample points of the 27 cells around p's cell, weighted by
// cubic_falloff(distance in cells), normalised; side_test drops points behind the tangent plane
// at p (a point behind a thin wall sees the other room); visibility_test drops points whose
// distance SH towards p says a surface lies between (shorter than their distance to p by more
// than a cell); occlusion_test (SHGI's, not the seed's) keeps only the sample points that see
// the one nearest p that p itself sees: one shadow ray from p (more when the nearest are
// hidden) and the sample points' mutual visibility, traced once at voxelisation (26 segments per
// point). The side test alone lets light through a room's wall into its floor and ceiling
// (sample points beyond the wall lie in front of those planes): the sun room's sunlit outside
// wall read into the room, 10-15% too bright, and the bright room of two_rooms into the dim one.
// When every point is dropped the tests are waived rather than return darkness.
// Irradiance and glossy come from the interpolated SH in closed form (IndirectField: exact for
// the SH), or with monte_carlo_gathers as the seed computes them: N_d = 32 cosine-distributed
// and N_g = 64 Phong-lobe directions evaluated on the SH (render/indirect_field.h). obscurance
// multiplies the SH by the seed's obscurance O(x) = (2/N_d) Σ ρ(d̄(x, ω_i)) cos θ_i over the N_d
// of 2 N_d sphere directions above the surface, ρ(d) = min(w_oc d / R_max, 1) (the seed prints
// max, which is never below 1 and brightens); an ambient-occlusion look, not light transport:
// off by default.
//
// Determinism: photon streams per pass (photon_tracer.h), per-cell sums in hit order, one gather
// per sample point summed in ray order: bit-identical for any thread count.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "radiance/radiance_grid.h"
#include "render/gi_solver.h"
#include "render/indirect_field.h"
#include "scene/scene.h"
#include "sh/sh_volume.h"
#include "util/progress.h"

namespace shgi {

struct RadianceFieldSettings {
    uint64_t photons = 200000;          // emitted per pass
    uint64_t seed = 0;
    int max_bounces = 4;                // bounces of the field's light, as Light Paths > Diffuse
    int glossy_bounces = 4;             // photons' glossy scatterings, as Light Paths > Glossy
    float specular_roughness = 0.1f;    // lobes up to this roughness count as specular
    bool world_in_field = false;        // escaped gather rays read the world (see above)
    bool glossy_in_grid = true;         // rough glossy reflection enters the grid (see above)
    int resolution = 32;                // SH-grid cells along the longest side (seed: 32³, 64³)
    int gather_rays = 400;              // N_sh per sample point and pass (seed §3.4.2)
    FaceEstimator face_estimator = FaceEstimator::ProjectedArea;
    float face_sigma = 0.5f;            // rad: std. dev. of the faces' Gaussian g(α) (§3.4.2)
    bool use_mips = true;               // footprint filtering over the mip chain (§3.4.3)
    int mip_levels = 4;                 // levels of the radiance grid, the finest included
    float min_footprint_cosine = 0.1f;  // cos β floor of the footprint 4πd²/(N cos β)
    float backface_threshold = 0.25f;   // back-face share marking a sample point inside geometry
    bool side_test = true;              // §4.1: drop sample points behind the tangent plane
    bool visibility_test = false;       // drop sample points the distance SH says are hidden
    bool occlusion_test = true;         // drop sample points a surface separates from p
    bool monte_carlo_gathers = false;   // §4.2-4.3's gathers instead of the closed forms
    int diffuse_gather_rays = 32;       // N_d
    int glossy_gather_rays = 64;        // N_g (a Phong lobe)
    bool obscurance = false;            // §4.4's AO multiplier (not light transport)
    float obscurance_weight = 1.0f;     // w_oc
    float obscurance_distance = 0.0f;   // R_max, m; 0 = two cells
    int obscurance_rays = 32;           // N_d of the obscurance estimate
    bool use_bounds = false;
    vec3 bounds_min{0.0f};
    vec3 bounds_max{0.0f};
};

// Throws InvalidArgument naming the field and the accepted range.
void validate_radiance_field_settings(const RadianceFieldSettings& settings);

// The last pass's stage timings (seed 001 Table 1) and counts.
struct RadianceFieldTimings {
    double voxelise = 0.0;       // the last construction or reset()
    double photons = 0.0;
    double radiance_grid = 0.0;
    double sh_field = 0.0;
    uint64_t photons_emitted = 0;
    uint64_t hits = 0;           // reflected hits in the radiance grid
    uint64_t sample_points = 0;  // active sample points
    uint64_t gather_rays = 0;    // traced in the last pass
};

class RadianceField : public IndirectField, public GiSolver {
  public:
    // The scene must be committed and outlive the solver. Voxelises it (see above).
    RadianceField(const Scene& scene, const RadianceFieldSettings& settings,
                  Progress* progress = nullptr);
    ~RadianceField() override;

    // GiSolver. A cancelled pass throws Cancelled and keeps the previous solution.
    void refine(Progress* progress = nullptr) override;
    void reset(Progress* progress = nullptr) override;
    uint64_t passes() const override { return passes_; }
    std::shared_ptr<const IndirectField> current_field() const override;
    std::vector<StageSeconds> stage_seconds() const override;
    size_t memory_bytes() const override;

    const Scene& scene() const { return *scene_; }
    const RadianceFieldSettings& settings() const { return settings_; }
    const RadianceFieldTimings& timings() const { return timings_; }
    const RadianceGrid& radiance_grid() const { return grid_; }
    // Tests: the grid to gather from (e.g. faces set by hand), then rebuild_field() gathers one
    // pass from it without tracing photons and makes it the only pass.
    RadianceGrid& mutable_radiance_grid() { return grid_; }
    void rebuild_field(Progress* progress = nullptr);
    // The SH at sample point `cell` (zero for cells that are not sample points) and whether it is
    // one (active: near surface and not inside geometry).
    ShRgb sample_point_sh(const ivec3& cell) const;
    bool is_sample_point(const ivec3& cell) const;
    const ShVolume& sh_volume() const { return field_; }

    // IndirectField.
    ShRgb radiance_sh(const vec3& p, const vec3& n) const override;
    // With monte_carlo_gathers, the lookup asks for the seed's gathers (FieldLookup's
    // diffuse_rays and glossy_rays), their directions keyed by p and the seed.
    FieldLookup lookup(const vec3& p, const vec3& n) const override;
    float reuse_distance() const override;
    bool includes_world_direct() const override { return settings_.world_in_field; }
    bool is_zero() const override { return passes_ == 0; }
    // The obscurance O(p) of §4.4 (1 without distance data).
    float obscurance(const vec3& p, const vec3& n) const;

  private:
    struct Gathered;
    void check_scene() const;
    std::vector<ReflectedHit> reflected_hits(Progress* progress, RadianceFieldTimings* timings);
    Gathered gather(uint64_t pass, Progress* progress) const;
    // Adds a pass's gather to the sums (passes_ already counts it), updates the means and which
    // sample points are inside geometry; returns how many are not.
    uint64_t fold_in(const Gathered& gathered);
    // Normalised cubic weights of the sample points around p (the tests of the header); calls
    // visit(cell index, weight) for each, returns false when none counts.
    template <typename Visit>
    bool for_each_neighbour(const vec3& p, const vec3& n, bool tests, Visit&& visit) const;
    // visibility_test: the distance SH of sample point `index` (at `centre`) says a surface
    // lies between it and p (more than a cell nearer than p).
    bool hidden_by_distance(size_t index, const vec3& centre, const vec3& p) const;

    const Scene* scene_ = nullptr;
    uint64_t scene_revision_ = 0;
    RadianceFieldSettings settings_;
    std::vector<uint8_t> closed_instance_;  // per instance: its mesh is a closed surface
    RadianceGrid grid_;
    std::vector<uint32_t> sample_cells_;  // cell indices of the sample points, ascending
    std::vector<uint8_t> active_;         // per cell: 1 = a sample point outside geometry
    // Per cell: bit (dz + 1) * 9 + (dy + 1) * 3 + (dx + 1) set when the segment from the cell's
    // centre to that neighbour's is unoccluded (sample points only; occlusion_test).
    std::vector<uint32_t> sees_;
    ShVolume field_;                      // mean of the passes' gathers
    std::vector<float> distance_;         // per cell: L2 distance SH (9 floats), mean of passes
    ShVolume field_sum_;                  // sums over passes
    std::vector<float> distance_sum_;
    std::vector<uint32_t> inside_votes_;  // per sample point: passes that found it inside
    uint64_t passes_ = 0;
    RadianceFieldTimings timings_;
};

}  // namespace shgi
