// PhotonLattice: the ISLLPM solver (seed 000): photons traced from the lights (photon/), the
// global photons injected into a coarse SH lattice for low-frequency indirect light and the
// caustic photons into a fine one (or kept in a photon map for a density estimate), lattices
// blurred in lattice space, then queried as an IndirectField by the preview renderer.
//
// Modes (seed 000 §6.5): interactive — each solve() traces one more budget of `photons` with
// its own RNG streams (pass k) and the lattices hold the average of all passes, so the field
// refines progressively; reset() starts over (after scene edits). Non-interactive — one solve()
// with many photons, then any number of frames from any camera.
//
// Bounces: a photon stored after m scatterings reaches the camera after m + 1, like a camera
// path with m bounces, so max_bounces = 4 matches Cycles' default Diffuse bounces (4).
// Blur: one pass by default. The 3x3x3 blur mixes only cells whose surfaces receive on the same sides
// (lattice/sh_lattice.h), because each cell's SH knows only the directions its own surfaces
// receive from (zero elsewhere): mixing floor cells with wall and corner cells darkened indirect
// light by 5-6% on the Cornell box and the sun room with one pass. As it is, one pass leaves the
// mean indirect diffuse light of both unchanged (within 0.2%) and lowers its RMS error against a
// converged (4M-photon) lattice by 19% and 26% at 200k photons.
//
// World light: with world_in_field photons from the world are stored at their first hit too, so the
// lattices carry the sky's direct light and renderers leave the world out of next-event
// estimation (docs/architecture.md has every consumer compute direct light exactly; an environment
// seen through openings is the exception, because sampling it per pixel is what makes previews
// noisy — the role Cycles' light portals play). world_in_field = false restores exact NEE.
//
// Lattice bounds: the scene's bounds, or [bounds_min, bounds_max] with use_bounds. The density
// estimate, blur and interpolation are those of lattice/sh_lattice.h.
//
// Photon batches (a solve split over machines, docs/farm.md): a pass's photons split into
// batches of consecutive photon indices, each traced apart (trace_photon_batch, on any machine
// with the same scene), and merged by solve_batches(). A batch returns its STORED photons in
// photon order, not per-cell sums: the lattices' sums are floating-point and order-dependent,
// so the merge concatenates the batches in photon order, which gives exactly the photon list
// of the whole pass (photon/photon_tracer.h: trace_photon_range), and injects, averages and
// blurs it as solve() does. solve() itself is one batch of the whole pass through the same
// code, so the merged lattice equals solve()'s bit for bit for any split and thread count.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lattice/sh_lattice.h"
#include "photon/photon_map.h"
#include "photon/photon_tracer.h"
#include "render/gi_solver.h"
#include "render/indirect_field.h"
#include "scene/scene.h"
#include "util/progress.h"

namespace shgi {

enum class CausticMode : uint8_t {
    Off,        // caustic photons are dropped
    Lattice,    // injected into the fine caustic lattice
    PhotonMap,  // density estimate of the caustic photon map (k nearest photons)
};

enum class LatticeInterpolation : uint8_t {
    Trilinear,  // the 8 surrounding cells
    Cubic,      // the 27-neighbour weighting of seed 001 §4.1
};

struct PhotonLatticeSettings {
    uint64_t photons = 200000;          // emitted per solve()
    uint64_t seed = 0;
    int max_bounces = 4;                // photon scatterings after emission (see below)
    // Glossy scatterings have a budget of their own, as a camera path's Light Paths > Glossy
    // beside Diffuse (PhotonTracerSettings::max_glossy_bounces; the radiance field's
    // glossy_bounces): counted against max_bounces, a Principled surface's specular reflections
    // took the diffuse bounces of the rooms' light (the sun room read -7.1%, the dim room of the
    // two rooms -8.6%). -1: every scattering counts against max_bounces (lattices saved before
    // this setting read back so).
    int glossy_bounces = 4;
    float specular_roughness = 0.1f;    // lobes up to this roughness make caustic paths
    // The lattices also carry the world's direct light (see below) and renderers skip the world
    // in next-event estimation: sky light through windows is then noise-free in previews.
    bool world_in_field = false;
    int resolution = 16;                // global lattice: cells along the longest side
    int order = 2;                      // global lattice SH order (1 or 2)
    int blur_passes = 1;                // 3x3x3 blurs of the global lattice (see below)
    CausticMode caustics = CausticMode::Lattice;
    int caustic_resolution = 64;        // caustic lattice: cells along the longest side
    int caustic_order = 1;
    int caustic_blur_passes = 0;
    int caustic_neighbours = 50;        // k of the photon map density estimate
    float caustic_radius = 0.0f;        // m: its max radius; 0 = 2% of the bounds' diagonal
    LatticeInterpolation interpolation = LatticeInterpolation::Cubic;
    float normal_offset = 0.25f;        // cells along the normal before sampling
    bool use_bounds = false;
    vec3 bounds_min{0.0f};
    vec3 bounds_max{0.0f};
};

void validate_photon_lattice_settings(const PhotonLatticeSettings& settings);
// The photon tracer's settings a lattice with `settings` traces its photons with.
PhotonTracerSettings photon_lattice_tracer_settings(const PhotonLatticeSettings& settings);

// Seconds of the last solve() (seed 000 Tables 5 and 6), and the photon counts behind them.
struct PhotonLatticeTimings {
    double emit_trace = 0.0;
    double injection = 0.0;
    double blur = 0.0;
    uint64_t photons_emitted = 0;   // by the last solve
    uint64_t photons_stored = 0;    // global + caustic, by the last solve
    uint64_t bounces = 0;           // rays traced by the last solve
};

// Photons [begin, end) of pass `pass` of a lattice with `settings`: its stored photons in photon
// order (each photon's emission depends on its index and on settings.photons, the whole pass's
// count). What solve_batches() merges; to_bytes()/from_bytes() carry it between processes.
struct PhotonBatch {
    PhotonLatticeSettings settings;  // of the lattice it was traced for
    uint64_t pass = 0;
    uint64_t begin = 0, end = 0;
    std::vector<Photon> global, caustic;  // in photon order, each photon's stores by bounce
    uint64_t emitted = 0;                 // photons emitted (end - begin; 0 without emitters)
    uint64_t bounces = 0;                 // rays traced
    double seconds = 0.0;                 // tracing time

    // SHGI's binary (little-endian, float32 as held: exact). from_bytes throws IoError naming
    // `what` for bytes that are not a batch (truncated, another format, invalid settings).
    std::string to_bytes() const;
    static PhotonBatch from_bytes(const std::string& bytes, const std::string& what = "bytes");
};

// Traces a batch (any thread count gives the same photons). InvalidArgument for invalid
// settings, an uncommitted scene, or a range not inside [0, settings.photons]; Cancelled.
PhotonBatch trace_photon_batch(const Scene& scene, const PhotonLatticeSettings& settings,
                               uint64_t pass, uint64_t begin, uint64_t end,
                               Progress* progress = nullptr);

class PhotonLattice : public IndirectField, public GiSolver {
  public:
    // The scene must be committed and outlive the solver. Measures the lattices' surfaces.
    PhotonLattice(const Scene& scene, const PhotonLatticeSettings& settings,
                  Progress* progress = nullptr);
    ~PhotonLattice() override;

    // Traces one more pass of settings.photons and rebuilds the lattices (average of all
    // passes). Cancel leaves the previous solution intact. InvalidArgument if the scene was
    // edited since construction or reset().
    void solve(Progress* progress = nullptr);
    // The next pass (passes()) from batches traced apart that together cover its photons
    // [0, settings.photons) (in any order: they are put in photon order), equal bit for bit to
    // what solve() would have made. InvalidArgument (nothing changes) for a batch traced with
    // other settings, of another pass, or ranges that overlap or leave photons out (or a null
    // batch); Cancelled keeps the previous solution. The batches are not changed: a pass of
    // several batches holds one concatenated copy of their photons while it is injected.
    void solve_batches(const std::vector<const PhotonBatch*>& batches,
                       Progress* progress = nullptr);
    void solve_batches(const std::vector<PhotonBatch>& batches, Progress* progress = nullptr);
    // Forgets every pass and re-measures the scene (call after edits and commit()).
    void reset(Progress* progress = nullptr) override;

    // GiSolver: a refinement pass is one solve(); the field is the lattice itself (not to be
    // read while a pass runs).
    void refine(Progress* progress = nullptr) override { solve(progress); }
    std::shared_ptr<const IndirectField> current_field() const override;
    std::vector<StageSeconds> stage_seconds() const override;

    uint64_t passes() const override { return passes_; }
    // The scene it solves; InvalidArgument for a lattice load() read (it has none).
    const Scene& scene() const;
    const PhotonLatticeSettings& settings() const { return settings_; }
    const PhotonLatticeTimings& timings() const { return timings_; }
    const ShLattice& global_lattice() const { return global_; }
    const ShLattice& caustic_lattice() const { return caustic_; }
    const PhotonMap& caustic_map() const { return caustic_map_; }
    size_t memory_bytes() const override;

    ShRgb radiance_sh(const vec3& p, const vec3& n) const override;
    FieldLookup lookup(const vec3& p, const vec3& n) const override;
    // A quarter of the finest cell queried (the caustic lattice's when it holds photons), or of
    // the photon map's radius with caustics = PhotonMap: small beside the interpolation's own
    // reach (1.75 cells for the cubic weights, the k nearest photons' disk).
    float reuse_distance() const override;
    bool includes_world_direct() const override { return settings_.world_in_field; }
    bool is_zero() const override { return passes_ == 0; }  // nothing solved yet

    // A solved lattice on disk, so that a frozen solution outlives the process: save() writes
    // the settings, the solved (averaged, blurred) lattices with their cell surfaces, the
    // caustic photons and the last pass's timings to `path` (SHGI's binary, little-endian,
    // float32 as held: exact); load() reads them back into a lattice whose lookups equal the
    // saved one's (bit for bit; a caustic photon map rebuilds its k-d tree, which may change
    // the rounding of its sums). A loaded lattice renders and reports but has no scene:
    // solve() and reset() throw InvalidArgument. IoError names the file that cannot be written
    // or read.
    void save(const std::string& path) const;
    static std::unique_ptr<PhotonLattice> load(const std::string& path);

  private:
    PhotonLattice() = default;  // load()'s, without a scene
    void check_scene(const char* what) const;
    // The pass's stored photons (in photon order) injected, averaged and blurred: the end of
    // solve() and solve_batches().
    void add_pass(const std::vector<Photon>& global_photons,
                  const std::vector<Photon>& caustic_photons, PhotonLatticeTimings timings,
                  Progress* progress);
    ShRgb sample(const ShLattice& lattice, const vec3& p, const vec3& n) const;
    // The caustic photon map's irradiance at (p, n) with caustics = PhotonMap, else zero.
    vec3 caustic_map_irradiance(const vec3& p, const vec3& n) const;

    const Scene* scene_ = nullptr;
    std::string loaded_from_;  // the file load() read, for messages
    uint64_t scene_revision_ = 0;
    PhotonLatticeSettings settings_;
    Bounds3 bounds_;
    uint64_t passes_ = 0;
    ShLattice global_raw_, caustic_raw_;  // sums over passes, unblurred
    ShLattice global_, caustic_;          // averaged and blurred: what queries read
    PhotonMap caustic_map_;
    float caustic_radius_ = 0.0f;
    uint64_t caustic_photons_injected_ = 0;  // over all passes: 0 skips the caustic lattice
    PhotonLatticeTimings timings_;
};

}  // namespace shgi
