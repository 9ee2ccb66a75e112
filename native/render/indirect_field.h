// IndirectField: what every solver produces and every consumer (preview renderer, baker) reads —
// indirect incident light at a surface point, independent of how it was solved
// (docs/architecture.md, "Data flow").
//
// Units: radiance in W m^-2 sr^-1, irradiance in W m^-2. A field carries only indirect light
// (light that scattered at least once after leaving an emitter); consumers add direct light
// exactly with shadow rays. Queries are const and thread-safe.
//
// lookup() returns the SH at (p, n) plus any irradiance the SH does not carry (a photon map's
// density estimate of caustics); renderers call it once per shading point and derive both
// answers from it: irradiance = max(0, clamped-cosine convolution of the SH) (sh/sh_irradiance.h)
// + the extra irradiance; glossy = the split-sum pre-filtered radiance of the fitted GGX ZH lobe
// in the reflected direction (seed 002 §4.2.2 and Appendix A, sh/ggx_zh.h), which the consumer
// multiplies by the lobe's directional albedo.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>

#include "sh/sh_coeffs.h"
#include "util/math.h"

namespace shgi {

struct DiffuseBump;  // render/bump_irradiance.h
class Film;
class GBuffer;
class GgxZhMemo;  // sh/ggx_zh.h
class Progress;

// The dominant direction of a GGX lobe of `roughness` clipped at the horizon of n, for the
// reflected view direction `reflected` (unit): the cosine-weighted lobe leans from it towards n,
// the more the rougher and the more grazing the view (Lagarde & de Rousiers 2014, "Moving
// Frostbite to Physically Based Rendering", getSpecularDominantDir, alpha = roughness^2). Unit;
// n for a view from below n. Inline: FieldLookup::glossy calls it per lookup.
inline vec3 glossy_dominant_direction(const vec3& n, const vec3& reflected, float roughness) {
    const float alpha = roughness * roughness;
    const float lean = (1.0f - alpha) * (std::sqrt(1.0f - alpha) + alpha);
    const vec3 towards = n + lean * (reflected - n);
    const float length2 = glm::dot(towards, towards);  // 0 only for a view from below n
    return length2 > 1e-12f ? towards / std::sqrt(length2) : n;
}

struct FieldLookup {
    ShRgb radiance;                  // incident radiance SH, W m^-2 sr^-1
    vec3 extra_irradiance{0.0f};     // W m^-2 not represented in `radiance`
    // Monte Carlo gathers of `radiance` in place of the closed forms (seed 001 §4.2-4.3, the
    // radiance field's monte_carlo_gathers): irradiance from diffuse_rays cosine-distributed
    // directions, π/N Σ L(ω_i); glossy from glossy_rays directions of the normalised Phong lobe
    // of exponent (2/α² − 2)/4 (α = roughness²) about the reflected direction, 1/N Σ L(ω_i).
    // 0: the closed form. gather_key seeds the directions (per shading point: deterministic).
    uint32_t diffuse_rays = 0;
    uint32_t glossy_rays = 0;
    uint64_t gather_key = 0;
    // True when `radiance` holds light from above the surface's horizon only, zero below it (the
    // photon lattice: each cell holds what its surfaces receive). glossy()'s closed form then
    // reads the lobe about its dominant direction (between reflected and n) divided by what it
    // reads there of the upper hemisphere's SH (1 above the horizon, truncated alike): even light
    // from above reads as itself at every view angle. The truncated step reads 1/2 at the horizon
    // and 1.15 along n (roughness 0.5); the lattice's glossy light read 0.51 of the path tracer's
    // 80° from a floor's normal, 1.22 along a wall's (docs/methods.md). Irradiance needs no such
    // factor (the clamped cosine reads the step exactly); gathers (glossy_rays) ignore it.
    bool horizon = false;

    // E(n), >= 0.
    vec3 irradiance(const vec3& n) const;
    // E for a diffuse lobe whose normal n a normal map bent, with its bump shadowing toward
    // each direction (render/bump_irradiance.h), >= 0: the closed form's kernel is the cosine
    // times the shadowing, projected; a gather weighs each of its directions by the shadowing.
    // extra_irradiance (a density estimate, without directions) is added as it is.
    vec3 irradiance(const vec3& n, const DiffuseBump& bump) const;
    // Pre-filtered radiance leaving towards wo (unit, on n's side) for a GGX lobe, >= 0.
    // `zh` (optional): the caller's memo of the lobe's band factors, the same values.
    vec3 glossy(const vec3& n, const vec3& wo, float roughness, GgxZhMemo* zh = nullptr) const;
    // The Phong exponent of glossy_rays' lobe for a roughness (finite for roughness 0).
    static float gather_phong_exponent(float roughness);
};

class IndirectField {
  public:
    virtual ~IndirectField() = default;

    // Incident indirect radiance around p as SH (order of the field), for a surface with unit
    // normal n (fields use n to pick the samples that belong to that surface).
    virtual ShRgb radiance_sh(const vec3& p, const vec3& n) const = 0;
    // Everything a shading point needs; the default has no extra irradiance.
    virtual FieldLookup lookup(const vec3& p, const vec3& n) const;
    // The same for a point seen along unit wo (towards the viewer, world space): fields that
    // bias their lookup towards the viewer (probe grids' view_bias) override it; by default wo
    // is ignored. Renderers call this one.
    virtual FieldLookup view_lookup(const vec3& p, const vec3& n, const vec3& wo) const {
        static_cast<void>(wo);
        return lookup(p, n);
    }
    // The lookup where a final gather ray lands (PathIntegrator::set_final_gather): there any
    // unbiased estimate of the field serves, since the gather's samples average it. `u` in
    // [0, 1) is the caller's number for this ray (the preview stratifies it over a pixel's
    // samples). Interleaved fields (INSTANT_GI) read the one set u picks, scaled by the sets
    // (seed 004 §2.2: each set estimates all the light), for 1 / sets of the shadow rays.
    // By default view_lookup: the same answer whatever u.
    virtual FieldLookup gather_lookup(const vec3& p, const vec3& n, const vec3& wo,
                                      float u) const {
        static_cast<void>(u);
        return view_lookup(p, n, wo);
    }

    // Screen-space reuse (render/preview_renderer.h): how far apart (m) two shading points of
    // neighbouring pixels may lie, their normals agreeing, for one view_lookup() to serve both,
    // the field changing too little over that distance to show. 0 (the default): never.
    virtual float reuse_distance() const { return 0.0f; }
    // True when the field also carries the world's direct light (photons from the world stored
    // at their first hit): consumers then leave the world out of next-event estimation.
    virtual bool includes_world_direct() const { return false; }
    // True when the field also carries the direct light of the scene's lights (point, spot, area,
    // sun; INSTANT_GI's filter_direct): consumers then leave those lights out of next-event
    // estimation (LightSampler's sample_lights), as includes_world_direct does for the world.
    virtual bool includes_lights_direct() const { return false; }
    // The same field without the direct light it carries (includes_world_direct,
    // includes_lights_direct), for consumers that want its indirect light alone (an INDIRECT
    // bake); nullptr when it cannot separate the two (the default).
    virtual std::shared_ptr<const IndirectField> without_direct() const { return nullptr; }
    // True when the field holds no light anywhere (no field; a solver before its first solve):
    // consumers may then skip its lookups, whose answers would all be zero.
    virtual bool is_zero() const { return false; }
    // For a field another thread may change while it is read (ProbeGrid's update()): an
    // immutable snapshot of its current state, which keeps that state alive. nullptr for fields
    // that are read directly (the default). Consumers of many lookups take it once through
    // PinnedField, rather than have each lookup pin the state again.
    virtual std::shared_ptr<const IndirectField> snapshot() const { return nullptr; }

    // Fields whose preview samples each read light of their own (INSTANT_GI's passes_per_sample):
    // the field as preview sample `sample` reads it at every lookup() (the points specular chains
    // reach), for a renderer that renders one sample index at a time, as the preview renderer
    // does for a field that shades_first_surfaces. It refers to this field, which must outlive
    // it. nullptr (the default): every sample reads the field itself. Bakes do not use it.
    virtual std::unique_ptr<const IndirectField> sample_view(uint64_t sample) const {
        static_cast<void>(sample);
        return nullptr;
    }

    // Screen-space fields (seed 004, INSTANT_GI): true when the field lights the camera's first
    // surfaces itself, over the whole frame. The preview renderer then gives first surfaces no
    // lookup (no final gather either), records their field lobes in the G-buffer, and calls
    // shade_first_surfaces as its first frame-wide stage (docs/frame-pipeline.md); lookups at
    // later vertices (specular chains) and bakes still go through lookup().
    virtual bool shades_first_surfaces() const { return false; }
    // Adds `count` samples' worth of the first surfaces' indirect light (DiffInd, GlossInd and
    // Combined) to `film` from the frame's G-buffer; `camera_position` gives each pixel's view
    // direction, `clamp_indirect` the renderer's clamp of an indirect sample (each lobe class's
    // light per pixel and sample clamped to it, as PathIntegrator clamps; 0: off). Deterministic
    // for any thread count; throws Cancelled on cancel.
    virtual void shade_first_surfaces(const GBuffer& g_buffer, const vec3& camera_position,
                                      float clamp_indirect, Film& film, uint64_t first,
                                      uint64_t count, Progress* progress) const {
        static_cast<void>(g_buffer), static_cast<void>(camera_position),
            static_cast<void>(clamp_indirect), static_cast<void>(film), static_cast<void>(first),
            static_cast<void>(count), static_cast<void>(progress);
    }

    // Interleaved sets (seed 004 §2.2–2.3, INSTANT_GI): a field whose light is dealt into
    // sets_x × sets_y uncorrelated sets, each an unbiased estimate of all of it. A consumer may
    // have element (x, y) of a grid (a lightmap's texels) read set (x mod sets_x, y mod sets_y)
    // alone through set_radiance_sh, then average an interleave-wide window of neighbours that
    // lie on the same surface (geometric normals' cosine at least normal_threshold) to restore
    // the whole: 1 / (sets_x sets_y) of the lookups' cost. `filter` false: each element keeps its
    // own set. The default, one set, is no interleave.
    struct Interleave {
        int sets_x = 1, sets_y = 1;
        float normal_threshold = 0.9f;
        bool filter = true;
        bool interleaved() const { return sets_x * sets_y > 1; }
        // The filter's taps along an axis of `sets` sets: offsets -half_width .. half_width; for
        // an even count (sets + 1 taps) the two end taps weigh 1/2, so each set counts once.
        static int half_width(int sets) { return sets / 2; }
        static float tap_weight(int sets, int offset) {
            return sets % 2 == 0 && (offset == -sets / 2 || offset == sets / 2) ? 0.5f : 1.0f;
        }
    };
    virtual Interleave interleave() const { return {}; }
    // The incident radiance SH at p (unit geometric normal n) from set (set_x, set_y) alone,
    // scaled to estimate all of the field's light (what radiance_sh gives from every set).
    virtual ShRgb set_radiance_sh(const vec3& p, const vec3& n, int set_x, int set_y) const {
        static_cast<void>(set_x), static_cast<void>(set_y);
        return radiance_sh(p, n);
    }

    vec3 irradiance(const vec3& p, const vec3& n) const { return lookup(p, n).irradiance(n); }
    vec3 glossy(const vec3& p, const vec3& n, const vec3& wo, float roughness) const {
        return lookup(p, n).glossy(n, wo, roughness);
    }
};

// A field held for one render, bake or batch of queries: its snapshot() when it has one (kept
// alive here), else the field itself. get() is null for a null field.
class PinnedField {
  public:
    explicit PinnedField(const IndirectField* field)
        : snapshot_(field != nullptr ? field->snapshot() : nullptr),
          field_(snapshot_ ? snapshot_.get() : field) {}
    const IndirectField* get() const { return field_; }

  private:
    std::shared_ptr<const IndirectField> snapshot_;
    const IndirectField* field_;
};

// No indirect light: what the preview renderer uses when it is given no field.
class ZeroField : public IndirectField {
  public:
    ShRgb radiance_sh(const vec3&, const vec3&) const override { return ShRgb(1); }
    bool is_zero() const override { return true; }
};

}  // namespace shgi
