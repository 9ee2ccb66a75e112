// PropagationVolume: the light propagation volume method (seed 003, Martin 2012: LPV and its
// higher-order form HOLPV, after Kaplanyan & Dachsbacher 2010) as an SHGI solver.
//
// A pass (refine):
//   1. VPLs (§3.1): photons traced from the lights (photon/photon_tracer.h) stand in for the
//      reflective shadow maps. Each photon's first surface hit is a virtual point light whose
//      flux is the light that surface scatters diffusely (PhotonFirstHit::reflected_power, in
//      Cycles' units whatever the light type). With vpl_bounces = n > 1 the photons' later hits,
//      up to the n-th, are VPLs too (the surface's diffuse albedo, found by a short ray back onto
//      it, times the arriving power), so the volume carries n bounces instead of the seed's one.
//      With glossy_vpls every VPL carries its surface's rough glossy lobes' light too.
//   2. Injection (eqs. 3.1–3.2): each VPL is a clamped-cosine lobe of its flux along its normal
//      (propagation/propagation_stencil.h), added to the cell that holds its position moved half
//      a cell along the normal (Kaplanyan & Dachsbacher's shift against self-lighting). Passes
//      average: the injected volume is the mean of every pass's injection.
//   3. Geometry volume (§3.2.2), made once per reset: a lattice of the same cell size offset by
//      half a cell, so its cell centres are the propagation cells' corners, holding each cell's
//      exact surface (lattice/sh_lattice.h, triangles clipped to the cell). A cell blocks light
//      along ω with potential B(ω) = min(1, D_c(ω) / (s² max_i |ω_i|)), D_c the projected area
//      of its surface seen from ω (both sides), s the cell size and s² max_i |ω_i| what a wall
//      across the transfer shows of the cell (the seed's s² for face neighbours; in a cell the
//      lattice's overhang puts partly outside the scene's bounds, the inside part's cross-section,
//      so that a wall filling the inside blocks fully); the seed's L1
//      expansion of a cosine lobe is replaced by this exact measure. The transfer from a
//      neighbour at offset d is attenuated by 1 − B(d/|d|) interpolated trilinearly at the
//      midpoint of the two cell centres: bilinear over the 4 corners of the shared face (face
//      neighbours, as in the seed), linear over the 2 ends of the shared edge, the shared corner
//      itself. The same transmittances of all 26 neighbours weight the field's lookup
//      (propagation_field.h).
//   4. Propagation (eq. 3.3, §3.3, §4.3): `steps` gather steps with ping-pong volumes, each added
//      to the accumulation volume (which starts with the injection); occlusion is skipped on the
//      first step (§3.2.3: the VPLs' own surfaces would block them) unless occlude_first_step
//      (then a VPL beside a thin wall, injected into the cell the wall runs through, does not
//      send its light across). Stencil, flux factor and
//      clamping: propagation_stencil.h (Ω_f/π instead of eq. 3.3's Ω_f/4π; clamp then rescale,
//      or with unclamped_transfer no clamp, clamp_at_surfaces keeping the clamp where walls
//      stop light);
//      the light crossing a face is re-injected along the face's normal (the seed) or, with
//      travel_reinjection, along its travel direction (propagation_stencil.h, "Re-injection").
//      With settle_fraction the steps stop once the light has settled; with furnace_scale the
//      accumulation is scaled to what a settled closed room needs (settled_room_excess).
// The field (propagation/propagation_field.h) is an immutable snapshot of the accumulation
// volume: renderers read it while the next pass runs.
//
// Order: 1 is the LPV (L1 lobes, 6 face neighbours × 5 faces), 2 the HOLPV (L2 lobes, the 26
// neighbours' 54 outer faces).
//
// Cells: cubes of side s = (longest side of the scene's bounds) / resolution (the geometry
// lattice's rule, lattice/sh_lattice.h), one more per axis than the geometry lattice so that
// every surface is inside.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lattice/sh_lattice.h"
#include "photon/photon.h"
#include "propagation/propagation_field.h"
#include "propagation/propagation_stencil.h"
#include "render/gi_solver.h"
#include "scene/scene.h"
#include "util/progress.h"

namespace shgi {

struct PropagationSettings {
    uint64_t photons = 100000;   // light paths traced per pass for the VPLs
    uint64_t seed = 0;
    // Surface hits per light path that become VPLs: 1 is the seed's single bounce (the first
    // hits); n also makes VPLs of the next n − 1 hits (n bounces of indirect light).
    int vpl_bounces = 4;
    // A VPL's surface scatters with its rough glossy lobes too (roughness above 0.1, spread as
    // if diffuse: Instant GI's glossy_vpls, the radiance field's glossy_in_grid), not with its
    // diffuse lobe alone. Off, the volume misses the light a glossy layer reflects onto other
    // surfaces: the Principled BSDF's default Specular 0.5 adds 22% to a closed room's indirect
    // light in the path tracer and 7% in the volume (docs/methods.md, "Closed rooms: the
    // furnace").
    bool glossy_vpls = false;
    // Glossy scatterings of a light path before a VPL, a budget of their own beside vpl_bounces
    // (as a camera path's Light Paths > Glossy beside Diffuse; Instant GI's glossy_bounces);
    // -1: they count against vpl_bounces.
    int glossy_bounces = -1;
    // Scale the accumulated light to what a closed room reads once its light has settled (the
    // furnace: a closed room of known albedo under uniform emission has an exact answer)
    // instead of the single VPL's near field the radiance scales were fitted to
    // (propagation_field.h): × 1 / settled_room_excess() of the transfer (1.22-1.37). Needs
    // travel_reinjection.
    bool furnace_scale = false;
    int resolution = 32;         // cells along the longest side of the scene
    // Propagation steps (§3.3); 0 (the default) takes them from `distance`.
    int steps = 0;
    // How far the light travels, in cells, when `steps` is 0: each order takes the steps its
    // stencil needs to carry light this far (distance / propagation_speed, rounded: the LPV's
    // steps move light 0.915 cells, the HOLPV's 1.415), so that both orders reach as far. The
    // default, 32 cells (35 LPV steps, 23 HOLPV), with the defaults below puts both orders within
    // 10% of the path tracer on the Cornell box, the sun room and the two rooms
    // (docs/methods.md, "One default for both orders").
    float distance = 32.0f;
    // Stop propagating once the light still in flight (Σ |band 0| over the volume) is at most
    // this fraction of the injected light: the accumulation has settled. The steps above (or
    // the distance's) are then the most it takes. 0: off, every step is taken.
    float settle_fraction = 0.0f;
    int order = 2;               // 1: LPV (L1, 6 directions); 2: HOLPV (L2, 26 directions)
    bool occlusion = true;       // geometry volume blocking (§3.2.2), from the second step
    // Cells along the surface's interpolated normal (not a normal-mapped one) the lookup moves
    // before sampling, against self-lighting and light leaking through walls: a wall's far side
    // holds VPLs half a cell beyond it, and a trilinear lookup less than a cell in front of the
    // wall reaches them. In the sun room (the sunlit outside of its walls and roof) half a cell
    // gave 5.9x the path tracer's indirect light (L1), one cell 0.97x.
    float normal_offset = 1.0f;
    // Seed 003 §3.2.4 (Kaplanyan & Dachsbacher 2010): damp the lookup where the light arriving
    // along −n is stronger half a cell behind the lookup point than half a cell in front of it
    // (the surface's own light or light from behind a wall), by front / back.
    bool damping = true;
    // Occlusion on the first step too (the seed skips it, §3.2.3). A VPL within half a cell of
    // a thin wall is injected into the cell the wall runs through, and with the first step
    // unoccluded its light crosses the wall: in the two rooms that was +20% (LPV) and +36%
    // (HOLPV) of the dim room's indirect light, 2% with this on (docs/methods.md).
    bool occlude_first_step = true;
    // Drop the VPLs that can light nothing: those on the scene's bounds facing out (a sunlit
    // roof or outer wall), whose lit half-space holds none of the scene. Exact: their light
    // reached the interior (the sun room's outside put 0.31 of its indirect light inside) and
    // hid the closed rooms' shortfall there (docs/methods.md).
    bool drop_outward_vpls = true;
    // Re-inject the light crossing each face along its travel direction (a projected beam,
    // Reinjection::TravelDirection: keeps the light's first moment) instead of as a cosine lobe
    // along the face's normal (the seed). The seed's lobes keep 0.37 (LPV) and 0.55 (HOLPV) of
    // the light's momentum per step, so the light random-walks and lingers: in the Cornell box
    // (occluded from the first step) 27% (LPV) and 14% (HOLPV) of the flux is still in flight
    // after 32 steps and 15% and 3.3% after 64, against 17% and 5.3%, 1.5% and 0.3% with this
    // on (docs/methods.md). It needs more steps than the seed's lobes, and its near field is
    // less even.
    bool travel_reinjection = true;
    // With travel_reinjection: window the re-injected beam's band 2 (× 4/5,
    // Reinjection::WindowedTravelDirection) so that it lights nothing behind it. The L2 beam's
    // back lobe sends light back onto the surfaces it left: the sun room's sunlit floor patch
    // reads 2.95x the path tracer's indirect light, windowed 1.14x (the plain beams' radiance
    // scale, propagation_field.h), and the HOLPV's image comes closer to the path tracer's on
    // all three test scenes (docs/methods.md, "The HOLPV's self-lighting"). No effect on the LPV
    // (no band 2).
    bool windowed_reinjection = true;
    // Propagate the light's lobes unclamped (LobeClamp::None: each step a linear map, one
    // transfer per neighbour offset, the alternative issue 51 names to clamping then rescaling
    // the source lobe, LobeClamp::Rescaled). Flux is kept either way; unclamped, an L1/L2 lobe's
    // negative back half travels too (with clamp_at_surfaces, not into walls). Rescaled in free
    // space the LPV's L1 light diffuses and its sun room stays 0.67-0.91x the path tracer's
    // whatever the steps (docs/methods.md).
    bool unclamped_transfer = true;
    // With unclamped_transfer: clamp the lobes of the cells whose light a wall stops in part,
    // linear elsewhere, so that walls neither make light nor return what goes into them
    // (LobeClamp::AtSurfaces). Unclamped, a wall stops a lobe's negative half like its positive
    // light, and stopping negative flux makes light (in a closed box 1.138x the VPL's flux in
    // flight for L1, 1.026x for L2). No effect without unclamped_transfer.
    bool clamp_at_surfaces = true;
    // The HOLPV's (order 2 only) with clamp_at_surfaces: clamp only the transfers a wall stops
    // in part, not every transfer of such a cell (LobeClamp::AtBlockedTransfers). Clamping all
    // of them spreads the L2 lobes along the walls and moves the HOLPV's light off a room's
    // edges (docs/methods.md, "Clamped per transfer"). The LPV (order 1) ignores it and clamps
    // every transfer of such a cell (LobeClamp::AtSurfaces): per transfer its L1 light ramps
    // towards a room's edges (27% more light there in the furnace) and its sun room loses 0.8 dB.
    bool clamp_per_transfer = true;
    // Photons' choice of lamp (photon_emitter.h): this share of them spread evenly over the
    // lamps (a light, an emissive object, the world), the rest by flux, each photon's power
    // divided by its mixed probability (unbiased), in [0, 1]. By flux alone a dim lamp beside a
    // bright one gets few photons and its VPLs are noisy: the two rooms' dim room, all the
    // camera sees, got 1% of them (docs/methods.md, "A share of the photons per lamp").
    float light_share_uniform = 0.5f;
    // Give the cells whose centres lie outside the scene's bounds (or on them) the light of the
    // inside cell next to them (extend_to_bounds) once propagated. Walls at the bounds run
    // through those cells: the geometry volume blocks their exchange with the inside, so they
    // hold no light, and the lookups within half a cell of such a wall read them: a dark strip
    // along every edge of a room (the two rooms' floor reads 0.004–0.019 W/m² within 0.09 m of
    // a wall, 1.1–1.3 beyond). Off: with it the HOLPV's two rooms read 1.118x the path tracer's
    // indirect light, out of the 10% (docs/methods.md, "Dark edges").
    bool extend_to_bounds = false;
    // Cascades (Kaplanyan & Dachsbacher 2010; seed 000 §4.4), for scenes larger than one volume
    // can resolve: 1 is a single volume over the scene (`resolution` cells along its longest
    // side). With n > 1 that volume is the coarsest of n nested levels; each finer level halves
    // the cell size and spans `resolution` cells per axis (fewer where the scene is smaller)
    // around the camera (cascade_follow_camera) or cascade_center, kept inside the scene. Every
    // level injects the VPLs it holds and propagates on its own; a lookup reads the finest level that covers it, blended into the
    // next coarser one over a band at the level's border (propagation_field.h).
    int cascades = 1;
    // Centre the finer levels on the scene's camera (its position at reset()) when the scene
    // has one; else, or with this off, on cascade_center. Used only with cascades > 1.
    bool cascade_follow_camera = true;
    // The point the finer levels are centred on (world space) without the camera: a point of
    // interest for a bake.
    vec3 cascade_center{0.0f};
};

// What a closed room whose light has settled reads at the field's radiance scales (fitted to a
// single VPL's near field, propagation_field.h) over its exact light, per transfer: the furnace
// (scenes.closed_room(): 3 × 3 × 2.5 m, every wall emitting radiance 1 and reflecting half,
// Lambert; 16 cells, light carried 96 cells, extend_to_bounds; the area mean over all six walls;
// bench/propagation_furnace.py). PropagationSettings::furnace_scale divides the accumulation by
// it. Measured for the travel re-injections only (the face normals' lobes random-walk and do
// not settle within the distance's limit): InvalidArgument otherwise.
float settled_room_excess(int order, LobeClamp clamp, Reinjection reinjection);

// Throws InvalidArgument naming the field and its allowed range.
void validate_propagation_settings(const PropagationSettings& settings);

// The steps a volume of these settings propagates: `steps`, or with steps 0 the distance over
// the order's stencil speed, rounded to the nearest step.
int propagation_steps(const PropagationSettings& settings);

// A VPL: a clamped-cosine emitter of `power` (W, the flux it scatters) along unit `normal`.
struct VirtualPointLight {
    vec3 position{0.0f};
    vec3 normal{0.0f, 0.0f, 1.0f};
    vec3 power{0.0f};
};

class PropagationVolume : public GiSolver {
  public:
    // The scene must be committed and outlive the solver; builds the geometry volume.
    PropagationVolume(const Scene& scene, const PropagationSettings& settings,
                      Progress* progress = nullptr);
    ~PropagationVolume() override;

    // One pass: traces settings.photons more light paths, injects their VPLs (the mean over
    // passes) and propagates. Cancel keeps the previous field. InvalidArgument after a scene edit
    // without reset().
    void refine(Progress* progress = nullptr) override;
    void reset(Progress* progress = nullptr) override;
    uint64_t passes() const override { return passes_; }
    std::shared_ptr<const IndirectField> current_field() const override { return field_; }
    // vpl_trace, vpl_reflect (vpl_bounces > 1), injection, geometry_volume (of the last reset),
    // propagation_step_1 … propagation_step_N; with cascades, the last four per level, prefixed
    // level_<l>_ (0 the finest): level_0_injection, level_0_geometry_volume, …
    std::vector<StageSeconds> stage_seconds() const override { return stage_seconds_; }
    size_t memory_bytes() const override;
    // Bytes a solver of these settings holds for the scene (its volumes and transmittances; the
    // geometry lattices and a pass's VPLs come on top), from the cell counts alone.
    static size_t estimate_memory_bytes(const Scene& scene, const PropagationSettings& settings);

    const PropagationSettings& settings() const { return settings_; }
    // The volumes' layout: origin, cell size, counts (the field's; the coarsest level's).
    const ShVolume& injected() const { return levels_.back().injected; }
    // Cascades that follow a moving camera (the viewport's view, which is not the scene's
    // camera): every finer level whose inner region (the middle half of its box along each axis)
    // no longer holds `point` is moved to be centred on it, snapped to its own cells and kept
    // inside the scene as reset() places the levels, and only those levels are rebuilt: their
    // geometry volume, the injection of every pass so far (each pass's VPLs traced again with
    // its own seed) and their propagation. The result is what a volume reset with the levels
    // centred on `point` gives after as many passes, bit for bit; the other levels are kept as
    // they are. Returns the levels moved, finest first (none without cascades, or when `point`
    // is still inside every inner region, or a level cannot move: it is against the scene's
    // bounds). Cancel keeps the solver and its field as they were. Throws InvalidArgument for a
    // point that is not finite, or after a scene edit without reset().
    std::vector<int> recenter(const vec3& point, Progress* progress = nullptr);
    // Cascade levels (1 without cascades), the finest first; level l's injected volume.
    size_t level_count() const { return levels_.size(); }
    const ShVolume& level_injected(size_t level) const { return levels_.at(level).injected; }
    const std::shared_ptr<const PropagationField>& field() const { return field_; }
    // VPLs of the last pass (kept for tests and inspection).
    uint64_t last_vpl_count() const { return last_vpl_count_; }

  private:
    // One volume of the cascade (the only one without cascades).
    struct Level {
        ShVolume injected_sum;   // Σ over passes of each pass's injection
        ShVolume injected;       // the mean: what the last propagation started from
        PropagationTransmittance transmittance;  // of the stencil (propagation)
        // Of all 26 neighbours (the field's lookup); null without occlusion.
        std::shared_ptr<const NeighbourTransmittance> lookup_transmittance;
        uint8_t blend_faces = 0;  // PropagationLevel::blend_faces
        double geometry_seconds = 0.0;
        // The level's first lattice cell on its own grid over the scene (recenter's snap).
        ivec3 start{0};
    };

    void check_scene(const char* what) const;
    // A propagated level's accumulation made the field's: extend_to_bounds, furnace_scale.
    void finish_accumulation(ShVolume& accumulated) const;
    // Pass `pass`'s VPLs (its seed); the seconds finding later hits' albedo go to reflect_seconds.
    std::vector<VirtualPointLight> trace_vpls(uint64_t pass, Progress* progress,
                                              double* reflect_seconds) const;
    // A level of the geometry lattice `geometry` (its surfaces measured here): its volumes of
    // one more cell per axis, offset by half a cell, and with occlusion its transmittances.
    Level make_level(ShLattice geometry, uint8_t blend_faces, Progress* progress) const;
    // One level's part of a pass: injects `vpls` (the new injection sum and mean into `sum` and
    // `mean`, the solver unchanged), propagates, appends the level's stage timings.
    PropagationLevel pass_level(size_t level, const std::vector<VirtualPointLight>& vpls,
                                const PropagationStep& step, Progress* progress,
                                std::vector<StageSeconds>& stages, ShVolume& sum,
                                ShVolume& mean) const;


    const Scene* scene_;
    PropagationSettings settings_;
    uint64_t scene_revision_ = 0;
    uint64_t passes_ = 0;
    uint64_t last_vpl_count_ = 0;
    std::vector<Level> levels_;  // finest first
    // The coarsest level's lattice (the scene's at `resolution`): the finer levels' grids.
    vec3 coarse_origin_{0.0f};
    float coarse_cell_size_ = 1.0f;
    ivec3 coarse_dims_{1};
    std::shared_ptr<const PropagationField> field_;
    std::vector<StageSeconds> stage_seconds_;
};

// Injects `vpls` into `volume` (a zero volume of the layout to fill): each a cosine lobe of its
// power in the cell holding position + ½ cell along its normal (VPLs outside are dropped).
// Deterministic (per-cell sums in VPL order, util/cell_sort.h). Cancellable.
void inject_vpls(ShVolume& volume, const std::vector<VirtualPointLight>& vpls,
                 Progress* progress = nullptr);

// `steps` steps from `injected` (see above), fewer with settle_fraction > 0 (stops after the
// first step that leaves at most that fraction of the injected light in flight: see
// PropagationSettings::settle_fraction), the accumulation returned; `transmittance` (may be
// null) applies from the second step, or from the first with occlude_first_step. Seconds of
// each step are appended to `step_seconds` when it is not null; progress is reported per step.
ShVolume propagate(const ShVolume& injected, const PropagationStep& step, int steps,
                   const PropagationTransmittance* transmittance, Progress* progress = nullptr,
                   std::vector<double>* step_seconds = nullptr,
                   bool occlude_first_step = false, float settle_fraction = 0.0f);

// Gives every cell of `volume` whose centre is not strictly inside `bounds` (within 1e-4 cells)
// the light of the nearest cell that is: its index clamped, axis by axis, to the inside cells
// (PropagationSettings::extend_to_bounds). Axes along which no centre is inside (flat bounds)
// are left as they are.
void extend_to_bounds(ShVolume& volume, const Bounds3& bounds);

}  // namespace shgi
