// INSTANT_GI: instant global illumination with a discontinuity-aware screen-space SH filter
// (seed 004, Segovia & Wald; docs/methods.md "Instant GI").
//
// Solve (refine, one pass): photons from every emitter (photon/photon_tracer.h) leave virtual
// point lights (VPLs) at their first hits and, with vpl_bounces > 1, at later hits: the power
// arriving there times the surface's diffuse albedo (and, with glossy_vpls, its rough glossy
// lobes' albedo), the surface found by a short ray back along the photon's path. The pass's VPLs are dealt in turn
// into sets_x × sets_y sets (§2.2–2.3, §3.2: uncorrelated sets, each an unbiased estimate of all
// the light when scaled by the number of sets); every pass adds new sets' worth of VPLs, and a
// set holds its VPLs of every pass so far (scaled by 1 / passes). A preview sample gathers
// passes_per_sample of the passes, the next ones after the previous sample's ("new sets per
// progressive pass"): a frame's samples average new VPLs instead of sharing one set's error.
//
// Render (a screen-space field, render/indirect_field.h shades_first_surfaces): the preview
// renderer's frame-wide stage, over its G-buffer:
//  1. gather: pixel (x, y) sums the VPLs of set (x mod sets_x, y mod sets_y) as L2 SH of the
//     incident radiance (§3.2, §4.1): a VPL at y with normal n_y and reflected flux Φ is a delta
//     of weight Φ cos θ_y / (π max(d², clamp_distance²)) in its direction, counted only when it
//     faces the pixel, lies above the pixel's geometric surface and an exact shadow ray finds the
//     segment free;
//  2. filter (§3): each pixel averages the SH of the pixels of an interleave-wide window
//     (sets_x or sets_x + 1 taps across — for even n, n + 1 taps with half weight on both ends so
//     each set counts once — and likewise down), skipping neighbours across depth, geometric-normal
//     and object edges but not across shading-normal changes; the G-buffer is frame-wide, so there
//     are no tile seams. The near field (near_field_reach) stays out of it: every set's VPLs
//     within a few window widths of the pixel, gathered by the pixel itself;
//  3. shade (§3.1, §3.3): the filtered SH through the pixel's own shading normal: diffuse closure
//     weight × E(n) / π (the clamped-cosine, i.e. Lambert, convolution of sh/sh_irradiance.h) and,
//     per glossy lobe, its albedo × the fitted GGX ZH lobe's pre-filtered radiance
//     (FieldLookup::glossy, sh/ggx_zh.h).
// By default only indirect light goes through the SH; direct light stays the renderer's
// next-event estimation (filter_direct: the world's and the lights' direct light too, in a plane
// of their own, written to DiffDir / GlossDir). The filter modes (filter_mode) Irradiance and
// Strict (the comparisons of §4.2, Figs. 2 and 4) filter each pixel's irradiance E(n_s)
// instead; Strict also stops at shading-normal changes. None keeps each pixel's own set.
//
// Elsewhere (specular chains), lookup(p, n) gathers every VPL of every set the same way (no
// filter); a preview sample reads the field through its sample_view, whose lookups gather every
// set's VPLs of that sample's passes alone (as its first surfaces do), so a sample costs the
// same however many passes are solved. Bakes interleave the sets over the lightmap's texels and filter them within UV charts
// (interleave(), set_radiance_sh; bake/lightmap_baker.h).
//
// Final gather (render/path_integrator.h): the preview then shades the first surfaces as any
// field's (next-event estimation and one BSDF-sampled gather ray, no frame-wide stage, so no
// filter), and each gather ray's hit reads one set of the sample's passes (gather_lookup, the
// set picked by the ray's number, which the preview stratifies over a pixel's samples), scaled
// by the sets: unbiased, at 1 / sets of the shadow rays of a lookup of every set. The VPLs
// within gather_near_radius of the hit it reads from every set instead (a grid over the
// sample's VPLs finds them), as the first surfaces' near field does.
//
// Determinism: photons as the tracer's (seed, pass); each pixel's gather and filter depend only
// on the G-buffer, so frames are identical for any thread count and tile size.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "render/gi_solver.h"
#include "render/indirect_field.h"
#include "render/light_sampler.h"
#include "scene/scene.h"
#include "util/progress.h"
#include "util/sampling.h"

namespace shgi {

enum class InstantGiFilter : uint8_t { Sh, Irradiance, Strict, None };

struct InstantGiSettings {
    int sets_x = 4;                   // n: interleave period across
    int sets_y = 4;                   // m: interleave period down
    uint64_t photons_per_set = 16;    // light paths traced per set and pass
    // Hits of a light path that leave a VPL (1: first only); the add-on: Light Paths > Diffuse.
    int vpl_bounces = 4;
    // Glossy scatterings of a light path before a VPL, a budget of their own beside
    // vpl_bounces, as a camera path's Light Paths > Glossy beside Diffuse (the add-on: Light
    // Paths > Glossy). Counting them against vpl_bounces (as before) cut the light paths that
    // bounce off the Principled specular layer short of the path tracer's: the sun room's
    // DiffInd converged to 0.964x the path tracer's, and 1.008x with this budget.
    int glossy_bounces = 4;
    float clamp_distance = 0.05f;     // m: d² below clamp_distance² counts as clamp_distance²
    InstantGiFilter filter_mode = InstantGiFilter::Sh;
    float depth_threshold = 0.1f;     // neighbours whose depth differs by more (relative) stop
    float normal_threshold = 0.9f;    // ... whose normals' cosine is below this stop
    // Rough glossy lobes (roughness above 0.1) of a VPL's surface scatter into it as if diffuse,
    // as the radiance field's glossy_in_grid: with the diffuse lobe alone a VPL loses the light
    // the surface's specular layer reflects (Principled specular 0.5: the Cornell box's DiffInd
    // came out 0.89x the path tracer's, the sun room's 0.93x).
    bool glossy_vpls = true;
    // Direct light through the SH filter, as the paper filters direct light (§3.2):
    // - the world (sky): every pass adds photons_per_set directional VPLs to each set (uniform
    //   directions over the sphere, each weighing the world's radiance × 4π / the set's
    //   directions), gathered with a shadow ray to infinity;
    // - the scene's lights (point, spot, area, sun): each set holds samples of each light (one
    //   for a delta light — point or spot of radius 0, sun of angle 0 — made at the first pass;
    //   photons_per_set more per pass for a light with extent), each a delta of the light's
    //   incident radiance / pdf in its direction, divided among that light's samples in the
    //   set, with the exact shadow ray;
    // - emissive triangles: photons_per_set samples per set and pass, each a triangle chosen by
    //   its power and a uniform point on it (LightSampler::sample_emissive_triangle), weighed
    //   as a lamp sample / the choice's probability / the set's triangle samples;
    // all filtered like the VPLs in a plane of their own that the stage writes to DiffDir /
    // GlossDir; the renderer then leaves the world, the lights and the emissive triangles out
    // of next-event estimation (includes_world_direct, includes_lights_direct). Off by
    // default: L2 SH blurs direct light (a point light's L2 reconstruction is off by up to
    // +6.25% and leaks 3/32 of its normal-incidence irradiance at the horizon); a uniform sky's
    // hemisphere is exact in L2.
    bool filter_direct = false;
    // Glossy lobes at least 0.3 rough read the VPLs directly instead of the L2 SH: each
    // VPL's delta weighed by the lobe (the prefiltering GGX lobe the SH's fitted ZH lobe
    // approximates, around the reflected view direction, normalised to unit integral), the
    // pixel's sum then filtered over the same window as the SH. Sharper glossy light at the
    // same mean (the sun room, 64 passes: 33.14 dB against 32.95 dB, GlossInd 0.841 x the
    // path tracer's against 0.845 x: L2 is not what it lacks); off by default.
    bool glossy_from_vpls = false;
    // Pixels whose filter window an edge cuts (a neighbour in it fails the depth, normal or
    // object test, so the window no longer averages every set evenly around the pixel) gather
    // every set themselves, each scaled by 1 / the sets, and keep that instead of the window's
    // average: the filter blurs light towards the side of an edge it can still read (the
    // normal-mapped floor's wall foot read 1.5x brute force), a full gather does not. Costs
    // those pixels sets_x × sets_y times the shadow rays; off by default.
    bool gather_cut_windows = false;
    // The near field: a pixel gathers the VPLs nearer to it than near_field_reach × its filter
    // window's reach (the farthest neighbour the window joins) from every set, each scaled by 1
    // / the sets, and keeps them out of the filter; the rest of its set's VPLs go through the
    // filter as before. The filter assumes the incident light varies little across the window,
    // and a VPL that near breaks that: its 1/d² and cosines change within the window, most of
    // all where two surfaces meet (the normal-mapped floor's wall foot read 1.5x brute force
    // through the window; 4 brings every interleave phase within 1% of brute force there).
    // 0: off (the paper's filter); filter_mode None: off. A pixel's near field holds at most
    // (near_field_reach / 8)² of a set's VPLs, the nearest (on small frames a window covers
    // more of the scene); glossy_from_vpls' lobes still read the rest of it. Costs the near
    // VPLs' shadow rays and the grid lookups that find them: a frame's CPU 1.11-1.19 × (Cornell
    // box) at 640 × 360, 1.48 × on the 128 × 128 Cornell box and 1.69 × on the sun room's 64 × 48
    // test frame, whose windows reach far (2.87 × and 2.88 × without the cap).
    float near_field_reach = 4.0f;
    // Passes of VPLs a preview sample gathers: sample i gathers passes i k .. i k + k - 1
    // (mod the field's passes), k = passes_per_sample, each set scaled by sets / k; with no
    // more passes than k every sample gathers them all (as before this setting). The samples
    // of a frame then average more passes than one gathers, at the cost of k per sample: each
    // VPL's error is no longer shared by every sample (the sun room, 16 samples: 64 passes at
    // k = 4 read 32.7 dB, 4 passes 30.9 dB, at the same shadow rays per sample). filter_direct's
    // sky directions and samples of lights with extent and emissive triangles are gathered by
    // the same passes (a delta light's one sample by every sample). Lookups elsewhere and
    // bakes gather every pass.
    int passes_per_sample = 4;
    // Final gather (gather_lookup): where a gather ray lands, the VPLs nearer than this (m) are
    // read from every set of the sample's passes (each scaled by 1 / those passes) and only the
    // farther ones from the ray's one set (scaled by the sets): still unbiased, since the split
    // depends on the hit alone, not on the ray's set. A near VPL's 1/d² makes the one-set
    // estimate's largest errors (sets × its light, or nothing), which Light Paths > Clamp then
    // cuts one way: the two rooms' dim room as the add-on renders it read 0.967 × the path
    // tracer's over seeds 0..7 (0.978 × without the clamp), 0.976 × with 0.25 m, the same as
    // with 0.5 m or 1 m, at 1.007 × the VPLs a lookup reads (Cornell box: 1.13 ×; 0.5 m: 1.58 ×).
    // 0: off (a lookup reads its one set whole).
    float gather_near_radius = 0.25f;
    uint64_t seed = 0;
};

// InvalidArgument naming the field and its range.
void validate_instant_gi_settings(const InstantGiSettings& settings);

struct InstantVpl {
    vec3 position{0.0f};
    vec3 normal{0.0f, 0.0f, 1.0f};  // the side the light left from
    vec3 power{0.0f};               // W reflected diffusely
};

// Adds one VPL's incident radiance at `p` (geometric normal `ng`, facing the viewer) to `sh`
// (order 2) as a delta of weight `scale` Φ cos θ_y / (π max(d², clamp²)), without the shadow
// test; false (nothing added) when the VPL faces away or lies below the surface.
bool add_vpl_sh(ShRgb& sh, const vec3& p, const vec3& ng, const InstantVpl& vpl, float scale,
                float clamp_distance);

// One sample of a scene light or of the emissive triangles held by a set (filter_direct):
// LightSampler::sample_light's (or sample_emissive_triangle's) u.
struct InstantLampSample {
    uint32_t light = 0;  // index into Scene::lights(), or Scene::emissive_triangles() (triangle)
    vec2 u{0.0f};
    bool triangle = false;   // an emissive triangle's sample
    float selection = 1.0f;  // a triangle's: the probability it was chosen among them
    // A delta light's one sample (made at the first pass): every preview sample gathers it,
    // whichever passes it gathers of the lights with extent.
    bool delta = false;
};

// Per-frame timings of the last frame-wide stage (seconds).
struct InstantGiFrameTimings {
    double gather = 0.0;  // VPL SH and shadow rays
    double filter = 0.0;
    double shade = 0.0;   // SH dot products and film
};

// Lookups of a field beyond the first surfaces (radiance_sh, set_radiance_sh and its sample
// views' lookups; bakes' too) since its latest sample_view() was made, or since it was made.
struct InstantGiLookupCounts {
    uint64_t lookups = 0;
    uint64_t vpls = 0;  // VPLs, sky directions and lamp samples they read: a shadow ray each at most
};

// The solved VPL sets: an immutable snapshot, the field the renderers read.
class InstantGiField : public IndirectField {
  public:
    // pass_ends: per set, the end of each pass's VPLs in it (passes entries; empty: the passes
    // cannot be told apart and every sample gathers them all); lamp_pass_ends likewise of its
    // lamp samples (with lamp_sets and pass_ends). Every pass adds as many sky directions to
    // each set.
    // sky_sets: per set, the directions of its directional VPLs for the world (filter_direct;
    // empty otherwise). lamp_sets: per set, its samples of the scene's lights (filter_direct;
    // empty otherwise), every set holding as many samples of each light, drawn through `lamps`
    // (a LightSampler of the scene, required with lamp_sets; the solver's, shared by its fields).
    InstantGiField(const Scene& scene, const InstantGiSettings& settings,
                   std::vector<std::vector<InstantVpl>> sets, uint64_t passes,
                   std::vector<std::vector<vec3>> sky_sets = {},
                   std::vector<std::vector<InstantLampSample>> lamp_sets = {},
                   std::shared_ptr<const LightSampler> lamps = nullptr,
                   std::vector<std::vector<uint64_t>> pass_ends = {},
                   std::vector<std::vector<uint64_t>> lamp_pass_ends = {});

    ShRgb radiance_sh(const vec3& p, const vec3& n) const override;
    // radiance_sh, marked as light from above the surface only (FieldLookup::horizon).
    FieldLookup lookup(const vec3& p, const vec3& n) const override;
    // The sets as an interleave pattern (bakes: texel (x, y) gathers one set, a filter within
    // the UV chart restores the whole; filter_mode None keeps each texel's own set).
    Interleave interleave() const override;
    ShRgb set_radiance_sh(const vec3& p, const vec3& n, int set_x, int set_y) const override;
    // Where a final gather ray lands: the set u picks (u × the sets, rounded down) alone,
    // scaled as set_radiance_sh scales it; an unbiased estimate of radiance_sh for u uniform.
    FieldLookup gather_lookup(const vec3& p, const vec3& n, const vec3& wo,
                              float u) const override;
    bool is_zero() const override {
        return passes_ == 0 || (vpl_count_ == 0 && sky_sets_.empty() && lamp_sets_.empty());
    }
    bool shades_first_surfaces() const override { return true; }
    // filter_direct: the sky's direct light is the field's (its directional VPLs).
    bool includes_world_direct() const override { return settings_.filter_direct; }
    // filter_direct: the lights' direct light is the field's too (their samples).
    bool includes_lights_direct() const override { return settings_.filter_direct; }
    // filter_direct: the same sets without their sky directions and lamp samples.
    std::shared_ptr<const IndirectField> without_direct() const override;
    // The field as preview sample `sample` reads it: lookups gather every set's VPLs, sky
    // directions and lamp samples of sample_passes(sample) alone (each VPL scaled by
    // 1 / those passes), an estimate of the whole field as the sample's first surfaces' one is;
    // the rest as this field. Resets lookup_counts().
    std::unique_ptr<const IndirectField> sample_view(uint64_t sample) const override;
    void shade_first_surfaces(const GBuffer& g_buffer, const vec3& camera_position,
                              float clamp_indirect, Film& film, uint64_t first, uint64_t count,
                              Progress* progress) const override;

    const std::vector<std::vector<InstantVpl>>& sets() const { return sets_; }
    const std::vector<std::vector<vec3>>& sky_sets() const { return sky_sets_; }
    const std::vector<std::vector<InstantLampSample>>& lamp_sets() const { return lamp_sets_; }
    uint64_t vpl_count() const { return vpl_count_; }
    uint64_t sky_count() const { return sky_count_; }  // directions over every sky set
    uint64_t lamp_count() const { return lamp_count_; }  // samples over every lamp set
    uint64_t passes() const { return passes_; }
    const std::vector<std::vector<uint64_t>>& pass_ends() const { return pass_ends_; }
    const std::vector<std::vector<uint64_t>>& lamp_pass_ends() const { return lamp_pass_ends_; }
    // The passes preview sample `sample` gathers (passes_per_sample): their indices in order.
    std::vector<uint64_t> sample_passes(uint64_t sample) const;
    // Timings of the latest shade_first_surfaces (one frame at a time per field).
    InstantGiFrameTimings frame_timings() const;
    InstantGiLookupCounts lookup_counts() const;

  private:
    class SampleView;
    struct VplRange {
        uint64_t begin, end;  // indices [begin, end) into a set's VPLs, sky directions or lamps
        bool deltas_only = false;  // lamps: only the delta lights' samples of the range
    };
    // The indices `ranges` hold.
    static uint64_t range_count(const std::vector<VplRange>& ranges);
    // What preview sample `sample` gathers of each set: the VPLs, sky directions and lamp
    // samples of its sample_passes (and the delta lights' samples, made at the first pass).
    struct SampleGather {
        std::vector<std::vector<VplRange>> vpls, sky, lamps;  // per set
        uint64_t passes = 0;     // the passes gathered
        float vpl_scale = 0.0f;  // each VPL's: the sets over the passes gathered
    };
    SampleGather sample_gather(uint64_t sample) const;
    // gather_lookup's set for u in [0, 1).
    size_t gather_set_index(float u) const;
    // Adds set `set`'s VPLs (each scaled by vpl_scale) and, with filter_direct, its sky
    // directions (each of radiance sky_weight) and its lamp samples (each scaled by lamp_scale
    // / that light's samples among the passes gathered) seen from p as SH, with exact shadow
    // rays: those of `gather`'s ranges, or every one (nullptr); VPLs nearer to p than
    // sqrt(near_radius2) are left out (gather_near_radius). Counted in lookup_counts().
    void gather_set(ShRgb& sh, const vec3& p, const vec3& n, size_t set,
                    const SampleGather* gather, float vpl_scale, const vec3& sky_weight,
                    float lamp_scale, float near_radius2 = 0.0f) const;
    // Adds one VPL's delta seen from p (normal n, shadow rays from `origin`) to sh, scaled by
    // vpl_scale, when it faces p and the shadow ray finds the segment free.
    void add_vpl(ShRgb& sh, const vec3& origin, const vec3& p, const vec3& n,
                 const InstantVpl& vpl, float vpl_scale) const;
    // A lamp sample's delta seen from p (geometric normal ng), among `passes` passes'
    // samples gathered: its weight (zero when the light cannot reach p or lies below the
    // surface), direction and the shadow ray's length.
    vec3 lamp_delta(const InstantLampSample& sample, const vec3& p, const vec3& ng,
                    float lamp_scale, uint64_t passes, vec3* direction, float* distance) const;

    const Scene* scene_;
    InstantGiSettings settings_;
    std::vector<std::vector<InstantVpl>> sets_;
    std::vector<std::vector<vec3>> sky_sets_;
    std::vector<std::vector<InstantLampSample>> lamp_sets_;
    std::vector<std::vector<uint64_t>> pass_ends_;  // per set: each pass's end
    std::vector<std::vector<uint64_t>> lamp_pass_ends_;  // per set: each pass's lamp samples' end
    std::vector<uint32_t> lamp_samples_;  // per scene light: its samples in a set
    uint32_t triangle_samples_ = 0;       // a set's emissive-triangle samples
    std::shared_ptr<const LightSampler> lamps_;  // with lamp_sets_: sample_light
    uint64_t passes_ = 0, vpl_count_ = 0, sky_count_ = 0, lamp_count_ = 0;
    float set_scale_ = 0.0f;  // sets / passes
    std::shared_ptr<InstantGiFrameTimings> timings_;
    struct LookupCounter {
        std::atomic<uint64_t> lookups{0}, vpls{0};
    };
    std::shared_ptr<LookupCounter> lookup_counter_;
};

class InstantGi : public GiSolver {
  public:
    InstantGi(const Scene& scene, const InstantGiSettings& settings, Progress* progress = nullptr);

    void refine(Progress* progress = nullptr) override;
    void reset(Progress* progress = nullptr) override;
    uint64_t passes() const override { return passes_; }
    std::shared_ptr<const IndirectField> current_field() const override { return field_; }
    std::vector<StageSeconds> stage_seconds() const override { return stage_seconds_; }
    size_t memory_bytes() const override;

    const InstantGiSettings& settings() const { return settings_; }
    std::shared_ptr<const InstantGiField> field() const { return field_; }

  private:
    void check_scene(const char* what) const;

    const Scene* scene_;
    InstantGiSettings settings_;
    uint64_t scene_revision_ = 0;
    uint64_t passes_ = 0;
    std::shared_ptr<const InstantGiField> field_;
    // filter_direct: the scene's lights for the lamp samples (made at reset; every field shares
    // it). Null otherwise.
    std::shared_ptr<const LightSampler> lamps_;
    // filter_direct: the emissive triangles by power (the lamp samples' choice). Empty otherwise.
    DiscreteDistribution triangle_power_;
    std::vector<StageSeconds> stage_seconds_;
};

}  // namespace shgi
