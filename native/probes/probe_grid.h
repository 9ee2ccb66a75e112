// ProbeGrid: SH probe grids updated by path tracing (seed 002, Ikkala 2020, §4.1), with the
// probe placement and visibility of DDGI so that interiors do not leak (seed 002 §5.1.2, §7).
//
// Placement (constructor, reset): probes at the cell centres of each volume (probes/probe_field.h;
// no volumes: one volume fitted to the scene bounds with probes `spacing` apart). Each probe
// casts placement_rays rays of a fixed Fibonacci lattice; a probe that sees back faces of closed
// meshes (watertight and consistently wound: solids) in more than backface_threshold of them is
// inside geometry. Back faces of open meshes (single-sided walls, planes) do not count: their
// winding is arbitrary in Blender scenes, as Cycles shades both sides alike. With relocate, it steps through the
// nearest back face (and a probe closer than 0.1 spacing to a front face steps away from it),
// up to 3 times, by at most max_offset spacings along each volume axis; a probe still inside is
// made inactive (never updated, never read).
//
// Update (one pass of update()): every active probe traces rays_per_probe directions of a
// spherical Fibonacci lattice (util/sampling.h) under a uniformly random rotation drawn per probe
// and pass. Each direction is a camera-like path of render/path_integrator.h — the reference path
// tracer's BSDFs, light units, next-event estimation and MIS, with bounce limits one lower than
// `bounces`' counterparts in the renderer (the renderer's own surface is the first bounce).
// The path's radiance without emitters and world seen straight from the probe (the Emit and
// Env passes) is the probe's indirect incident radiance: renderers add direct light exactly
// (include_direct = true keeps it, for exports of total light). Each radiance sample is clamped
// to `clamp` (as Light Paths > Clamp: clamp_contribution; 0 = off) against fireflies (seed 002
// §4.1.1) and projected onto SH with weight 4 pi / N (the lattice's points stand for equal
// solid angles).
//
// Blending (seed 002 §4.1.1: "results from the previous pass are blended with the new ones using
// a constant ratio"): new = (1 - a) old + a pass with a = max(1 - hysteresis, 1 / passes), i.e. an
// exact running mean until the ratio reaches 1 - hysteresis, then an exponential moving average
// that keeps reacting to edits. The visibility moments blend the same way. Convergence per probe:
// the variance of its DC luminance estimate, propagated through the blend,
//   var <- (1 - a)^2 var + a^2 s^2 / N,   s^2 the pass's per-ray variance;
// relative_error() is sqrt(var) / DC.
//
// Threads: probes are split over threads; every ray has its own RNG stream (pass, probe, ray),
// so results are bit-identical for any thread count. update() builds the next ProbeGridData and
// swaps it in: field() snapshots stay valid and unchanged, so a renderer can draw with the latest
// snapshot while another thread runs update() (seed 002 Fig. 4.1). update() and reset() from
// two threads run one after the other; one called from the running call's progress callback
// (which that call waits for) throws instead of waiting for itself.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "probes/probe_field.h"
#include "render/gi_solver.h"
#include "render/indirect_field.h"
#include "scene/scene.h"
#include "util/progress.h"

namespace shgi {

struct ProbeGridSettings {
    int order = 2;                      // SH order of the probes, 1..4
    std::vector<ProbeVolume> volumes;   // empty: one volume fitted to the scene bounds
    float spacing = 0.0f;               // m, for the fitted volume; 0 = longest side / 8
    uint32_t rays_per_probe = 256;      // per update pass
    uint64_t seed = 0;
    float hysteresis = 0.95f;           // in [0, 1): history weight once blending is exponential
    float clamp = 0.0f;                 // a radiance sample's clamp_contribution limit; 0 = off
    bool include_direct = false;        // keep emitters and world seen straight from the probe
    int bounces = 3;                    // diffuse and glossy scatterings along a probe's path
    int light_splits = 4;               // as PathTracerSettings.light_splits, for probe paths
    // Leak prevention (probes/probe_visibility.h; EEVEE's Bias, Bleed Bias, Blur).
    bool visibility = true;
    int visibility_resolution = 8;      // octahedral texels per side, per probe
    float visibility_blur = 0.10f;      // ~ angular radius (rad) of the distance filter
    float normal_bias = 0.25f;          // probe spacings along the interpolated normal
    float view_bias = 0.0f;             // probe spacings towards the viewer
    float bleed_bias = 0.0f;
    // Placement.
    bool relocate = true;
    float max_offset = 0.45f;           // probe spacings along each volume axis
    float backface_threshold = 0.25f;   // fraction of back-face hits that marks a probe inside
    uint32_t placement_rays = 128;
};

void validate_probe_grid_settings(const ProbeGridSettings& settings);

// The lookup part of the settings (visibility, normal_bias, view_bias, bleed_bias).
ProbeLookupSettings probe_lookup_settings(const ProbeGridSettings& settings);

struct ProbeGridTimings {
    double placement = 0.0;   // seconds of the last construction or reset()
    double update = 0.0;      // seconds of the last update()
    uint64_t rays = 0;        // rays traced by the last update (probe, shadow and path rays)
    uint64_t paths = 0;       // probe directions traced by the last update
};

class ProbeGrid : public IndirectField, public GiSolver {
  public:
    // The scene must be committed and outlive the grid. Places the probes.
    ProbeGrid(const Scene& scene, const ProbeGridSettings& settings, Progress* progress = nullptr);
    // Continues from stored probes (probes/probe_storage.h); their order and volumes replace the
    // settings' (their positions, active flags and SH are kept; reset() re-places).
    ProbeGrid(const Scene& scene, const ProbeGridSettings& settings, const ProbeGridData& data);

    // One update pass over every active probe, blended in. Cancel keeps the previous state.
    void update(Progress* progress = nullptr);
    // One update pass over the active probes first .. first + count - 1 only (a brick of a
    // solve split over machines, clamped to the probes there are); the others keep their state
    // and the pass still counts. A probe's pass depends only on (seed, pass, probe) and its own
    // history, so bricks updated apart and spliced (splice_probes) equal update() bit for bit.
    void update_probes(uint64_t first, uint64_t count, Progress* progress = nullptr);
    // Forgets every pass and re-places the probes (after scene edits and commit()).
    void reset(Progress* progress = nullptr) override;

    // GiSolver: a refinement pass is one update(); the field is an immutable snapshot (field()).
    void refine(Progress* progress = nullptr) override { update(progress); }
    std::shared_ptr<const IndirectField> current_field() const override { return field(); }
    std::vector<StageSeconds> stage_seconds() const override;

    const Scene& scene() const { return *scene_; }
    const ProbeGridSettings& settings() const { return settings_; }
    const ProbeGridTimings& timings() const { return timings_; }
    uint64_t passes() const override { return field()->data().passes; }
    size_t probe_count() const { return field()->data().probe_count(); }
    size_t active_count() const;
    // Per probe: sqrt(variance) / DC luminance (0 for a black probe, inf before any pass).
    std::vector<float> relative_error() const;
    size_t memory_bytes() const override;

    // The current state, shared with every field() taken from it. Valid until the next update()
    // or reset(): while another thread may call those, read field()->data() instead.
    const ProbeGridData& data() const { return field()->data(); }
    // An immutable snapshot for renderers (valid after later updates; see the header).
    std::shared_ptr<const ProbeField> field() const;

    // Each call reads field() (safe beside update() on another thread, but it takes a lock):
    // renderers read snapshot() instead, once per frame.
    ShRgb radiance_sh(const vec3& p, const vec3& n) const override;
    FieldLookup view_lookup(const vec3& p, const vec3& n, const vec3& wo) const override;
    std::shared_ptr<const IndirectField> snapshot() const override { return field(); }
    float reuse_distance() const override { return field()->reuse_distance(); }

  private:
    void check_scene(const char* what) const;
    ProbeGridData place(Progress* progress) const;
    void publish(std::shared_ptr<const ProbeGridData> data);
    // Holds update_mutex_ for one update() or reset() (`what`), refusing re-entry from it.
    class Serial;

    const Scene* scene_;
    uint64_t scene_revision_ = 0;
    ProbeGridSettings settings_;
    bool fitted_ = false;             // settings_.volumes[0] was fitted to the scene
    // update() and reset() run one at a time (they read the current probes and settings_ and
    // replace them); field_mutex_ guards field_ itself, which lookups and field() read.
    std::mutex update_mutex_;
    std::atomic<std::thread::id> serial_thread_{};        // the thread holding it
    std::atomic<const Progress*> serial_progress_{nullptr};  // the Progress of its call
    mutable std::mutex field_mutex_;
    std::shared_ptr<const ProbeField> field_;
    ProbeGridTimings timings_;
};

}  // namespace shgi
