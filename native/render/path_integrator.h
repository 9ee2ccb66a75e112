// PathIntegrator: one camera path with Cycles' pass bookkeeping, shared by the reference path
// tracer (render/path_tracer.h) and the preview renderer (render/preview_renderer.h).
//
// Without a field it is the reference estimator: NEE + BSDF sampling with MIS at every vertex.
// With an IndirectField (preview), each vertex splits its BSDF (render/bsdf.h): the field lobes
// (non-Dirac diffuse and glossy reflection) get direct light by NEE alone (weight 1: the field
// holds no direct light, so there is no second strategy to weight against) and indirect light
// from the field — diffuse closure weight x E(p, n) / pi, and per glossy lobe its directional
// albedo x the field's pre-filtered glossy radiance — while the traced lobes (Dirac lobes,
// refraction) continue the path, which then sees emitters with weight 1. Field light has
// scattered at least twice on its way to the camera, so it lands in the Ind passes.
//
// Final gather (Jensen's photon mapping with final gathering; seed 001 §4.2): with
// set_final_gather(n), the field is read only once the path has made n diffuse scatterings.
// Until then each vertex is a reference vertex (NEE and BSDF sampling with MIS, the whole BSDF
// sampled), so with n = 1 the first surface sends one gather ray per sample, and where it lands
// after a diffuse bounce the field vertex adds direct light by NEE and indirect light from the
// field. The field's errors (blocks, leaks) then reach the picture only after one more bounce.
// A glossy gather ray does not count: the field behind a gather is solved one diffuse bounce
// shallower (Light Paths > Diffuse, as the add-on's settings.light_path_fields gives it), so a
// path that reached it by a glossy bounce would miss its last diffuse bounce (the two-room
// scene's dim room read 0.9% darker, a closed room's glossy indirect light 5% darker); it goes
// on as a reference path until it scatters diffusely. Those lookups go through
// IndirectField::gather_lookup with set_gather_number's u: a field may answer one unbiased
// estimate of itself there (INSTANT_GI: one VPL set).
//
// Steps: trace() runs a whole path. A renderer that traces many paths at once can instead run
// each path's steps itself: begin() (what the camera ray meets, the first surface's shading),
// prepare_direct() (next-event estimation up to its shadow rays: one per light sample, more than
// one where the light sampler splits, render/light_tree.h), add_direct(k) (for each shadow ray k
// that was not occluded), finish() (field light and the rest of the path); and trace the shadow
// rays of many paths as one Embree stream between the second and third step. The random numbers
// and the order of every addition are those of trace(), so the result is bit-identical.
//
// Not thread-safe: one integrator per path, on one thread.
#pragma once

#include <cstring>
#include <new>
#include <optional>
#include <type_traits>

#include "render/bsdf.h"
#include "render/bump_irradiance.h"
#include "render/film.h"
#include "render/indirect_field.h"
#include "render/light_sampler.h"
#include "render/path_tracer.h"
#include "render/quad_glossy.h"
#include "render/shading.h"
#include "sh/ggx_zh.h"
#include "scene/camera.h"
#include "scene/scene.h"
#include "util/rng.h"

namespace shgi {

// Seconds spent by one thread in the direct-light part of its paths (next-event estimation), and
// the rays its integrators traced themselves (path continuations and shadow rays of trace() and
// finish(); not the rays a caller traces for them, such as batched camera or shadow rays).
// Timing reads the clock twice per path vertex (~6% of a probe update): a caller that only
// counts rays sets time_direct to false.
struct IntegratorClock {
    double direct = 0.0;
    uint64_t rays = 0;
    bool time_direct = true;
};

// The stratified numbers of sample s of a pixel: its jitter inside the pixel and its first
// light sample, each from the pixel's own Owen-scrambled Sobol' sequence (util/owen_sobol.h), so
// that every power-of-two count of samples covers the pixel and the lights evenly.
struct PixelSample {
    vec2 jitter{0.5f};
    float u_select = 0.0f;
    vec2 u_light{0.0f};
    float u_lobe = 0.0f;  // the first surface's BSDF sample (lobe choice and direction)
    vec2 u_bsdf{0.0f};
};
// With `first_bsdf`, also u_lobe and u_bsdf (the path tracer's first bounce), one 3-D point
// (owen_sobol_3d: u_bsdf its x and y, u_lobe its z) so that each lobe's directions are
// stratified; without, they stay 0: the preview and the bake do not use them, and two more
// scrambled points a pixel were ~2% of a preview frame.
PixelSample pixel_sample(uint64_t seed, uint64_t pixel, uint64_t sample, bool first_bsdf = false);
// The number sample s of a pixel passes to PathIntegrator::set_gather_number: a dimension of the
// pixel's own Owen-scrambled Sobol' sequence, so that every power-of-two count of its samples
// spreads over [0, 1) evenly (16 samples: one in each sixteenth, i.e. each of INSTANT_GI's
// default 4 x 4 sets once).
float gather_number(uint64_t seed, uint64_t pixel, uint64_t sample);
// The instruction set pixel_samples runs on: Auto takes AVX2 (eight pixels at a time) when the
// CPU has it (util/cpu_features.h), else SSE2 (four); tests name each to check it. All give the
// same bits (integer work, and the same float conversions).
enum class PixelSamplesIsa : uint8_t { Auto, Sse2, Avx2, Avx512, Avx512Gfni };
// pixel_sample(seed, pixels[i], sample) for i in [0, count) into out[i] (without first_bsdf),
// bit for bit, several pixels at a time (the preview's wave: the seed hashes and scrambles are
// integer work the same for every pixel). Auto takes Avx512Gfni (Avx512 with GFNI's bit
// reversal) where the CPU has it, else Avx512 (AVX2 with AVX-512DQ's 64-bit multiply), else
// Avx2, else Sse2. An instruction set the CPU lacks is an InvalidArgument.
void pixel_samples(uint64_t seed, const uint32_t* pixels, size_t count, uint64_t sample,
                   PixelSample* out, PixelSamplesIsa isa = PixelSamplesIsa::Auto);

// FieldLookup::irradiance of one lookup, kept for the last normal it was asked for. The pixels
// that share a lookup (render/lookup_sharing.h) on one flat surface have bit-identical normals,
// so their irradiance is evaluated once; it is a function of the lookup and the normal alone,
// so the value is the one a new evaluation would give, bit for bit. Call reset() whenever the
// lookup it serves changes.
class IrradianceMemo {
  public:
    vec3 irradiance(const FieldLookup& lookup, const vec3& n) {
        // Bits, not ==: -0 and +0 compare equal but need not give the same irradiance.
        if (!valid_ || std::memcmp(&n, &normal_, sizeof(vec3)) != 0) {
            normal_ = n;
            irradiance_ = lookup.irradiance(n);
            valid_ = true;
        }
        return irradiance_;
    }
    void reset() { valid_ = false; }

  private:
    bool valid_ = false;
    vec3 normal_{0.0f}, irradiance_{0.0f};
};

// The radiance a path started with PathIntegrator::trace(ray, first_hit) brought back along its
// ray, for tracers whose rays leave a surface or a probe rather than a camera (probe updates,
// lightmap texels): Combined, less what its first segment met straight from emitters (Emit,
// Env) unless include_direct (then only light that scattered at least once is left), floored
// at 0, clamped to `clamp` as Light Paths > Clamp (clamp_contribution; 0: off); 0 when not
// finite.
vec3 path_radiance(const PassValues& values, bool include_direct, float clamp);

class PathIntegrator {
  public:
    // `camera` is the one whose rays are traced (its view axis gives the Depth pass). `field`
    // null: reference path tracing. `clock` null: no timing.
    PathIntegrator(const Scene& scene, const Camera& camera, const LightSampler& lights,
                   const PathTracerSettings& settings, const IndirectField* field, Pcg32& rng,
                   PassValues& out, IntegratorClock* clock = nullptr)
        : scene_(scene), camera_(camera), lights_(lights), settings_(settings), field_(field),
          rng_(rng), out_(out), clock_(clock) {}

    // Makes the integrator ready for a new camera path, as if just constructed with the same
    // arguments and then given the same set_final_gather, set_combined_only, set_glossy_memo,
    // set_material_lobes and set_shading_memo: every member a path or the other setters change
    // goes back to its initial value (first_light_sample, first BSDF sample, gather number,
    // first ray pdf, shared lookup unset). A caller that traces one path after another into the
    // same rng and values (the preview's wave) re-arms one integrator per path slot instead of
    // constructing one a path (~45 member initialisations and the setters a pixel).
    void restart() {
        static_assert(kLobeClassCount == 3);
        shared_lookup_ = nullptr;
        shared_irradiance_ = nullptr;
        shared_glossy_ = nullptr;
        // Disengaged by construction, not reset(): reset() loads the engaged flag to test it,
        // and that load was the first touch of the next slot's line (a cache miss the render
        // loop waited on); a store does not wait. Trivially destructible: nothing to destroy.
        static_assert(std::is_trivially_destructible_v<std::optional<FirstLightSample>>);
        ::new (&first_light_sample_) std::optional<FirstLightSample>();
        ::new (&first_bsdf_sample_) std::optional<FirstLightSample>();
        terminate_on_next_surface_ = false;
        throughput_ = vec3(1.0f);
        write_denoising_features_ = !combined_only_;
        denoising_throughput_ = vec3(1.0f);
        vertex_ = 0;
        gather_u_ = 0.0f;
        bounces_[0] = bounces_[1] = bounces_[2] = 0;
        last_delta_ = true;
        last_pdf_ = 0.0f;
        min_ray_pdf_ = kInfinity;
        last_normal_ = vec3(0.0f, 0.0f, 1.0f);
        class_fraction_[0] = class_fraction_[1] = class_fraction_[2] = 0.0f;
    }

    // Traces a camera ray.
    void trace(const Ray& ray);
    // Traces a camera ray whose first hit is already known (batched primary rays).
    void trace(const Ray& ray, const Hit& first_hit);

    // --- trace(ray, first_hit) in steps (see the header comment) ---
    // Adds what the camera ray meets and shades its first surface; false when the path ends
    // there (a miss). The steps below may be called only after it returned true.
    bool begin(const Ray& camera_ray, const Hit& first_hit);
    // The same with the first hit's Scene::surface_point already made (the wave's, four at a
    // time: Scene::surface_point_lanes); `first_point` is read only when the hit is valid.
    bool begin(const Ray& camera_ray, const Hit& first_hit, const SurfacePoint& first_point);
    // Samples lights for the current surface and evaluates the BSDF: returns how many
    // contributions wait on the shadow rays written to shadows[0, count) (room for
    // kMaxLightSplits).
    int prepare_direct(Ray* shadows);
    // prepare_direct() at the first surface with its light sample already drawn by the caller,
    // in two halves around the BSDF's evaluation toward it, which a wave's light stage makes for
    // four paths at once (PrincipledBsdf::eval_field_lanes). samples[0, sampled), sampled <= 1,
    // are what LightSampler::sample_split gives for the surface's position and shading normal
    // and the numbers set by set_first_light_sample (LightSampler::sample_split_lanes); only
    // right after begin(), with set_first_light_sample. begin_direct: false when no shadow ray
    // follows (no sample, or the shading and geometric normals disagree on its side), else the
    // sample's direction in the shading frame; then the caller evaluates the BSDF (direct_bsdf
    // says which evaluation) and finish_direct writes the shadow ray if the value is not zero
    // (returns how many: 0 or 1), the same steps, so the same bits.
    bool begin_direct(const LightSample* samples, int sampled, vec3* wi);
    // The surface's BSDF, and whether the light stage evaluates it by eval_field (the field
    // lobes; else eval).
    const PrincipledBsdf& direct_bsdf(bool* field_lobes) const {
        *field_lobes = vertex_field() != nullptr;
        return shading_.value.bsdf;
    }
    int finish_direct(Ray* shadows, const LightSample& sample, const vec3& wi,
                      const BsdfEval& eval);
    // Whether prepare_direct() samples lights here (a surface with lobes a light sample can
    // meet); after begin().
    bool samples_lights() const { return shading_.value.bsdf.has_smooth_lobes(); }
    // Adds waiting contribution k; call it after prepare_direct() and only when shadow ray k
    // was not occluded, in increasing k.
    void add_direct(int k);
    // Indirect light at the current surface and the rest of the path.
    void finish();

    // Diffuse scatterings the path makes before it reads the field (0: at the first surface;
    // 1: final gather). Call before begin().
    void set_final_gather(int diffuse_bounces) { field_from_ = diffuse_bounces; }
    // The number in [0, 1) this path's field lookups behind its final-gather bounces pass to
    // IndirectField::gather_lookup (which estimate of the field they read: INSTANT_GI's set),
    // e.g. stratified over a pixel's samples; 0 unless set. Call before begin().
    void set_gather_number(float u) { gather_u_ = u; }

    // For paths whose ray leaves a surface the caller sampled (a lightmap texel's hemisphere
    // ray): the pdf of that bounce (sr^-1), the path's lowest so far for Filter Glossy
    // (PathTracerSettings.filter_glossy). Call before begin().
    void set_first_ray_pdf(float pdf) { min_ray_pdf_ = pdf; }

    // Only the Combined pass is read (a FilmPasses::CombinedOnly film, the viewport's): the
    // first surface's colour, normal and depth passes, the denoising guides and the light
    // passes (Emit, Env, Dir and Ind), which Combined does not depend on, are not written (the
    // first surface's passes alone were ~4% of a preview frame); Combined gets the same
    // additions in the same order. Call before begin().
    void set_combined_only() {
        combined_only_ = true;
        write_denoising_features_ = false;
    }

    // Stratified numbers for next-event estimation at the first surface (light selection and
    // the light's 2D sample), e.g. one pixel's Owen-scrambled Sobol' points: they replace the
    // path's random numbers there (which are still drawn, so the rest of the path is unchanged).
    void set_first_light_sample(float u_select, const vec2& u) {
        first_light_sample_ = FirstLightSample{u_select, u};
    }

    // Stratified numbers for the BSDF sample at the first surface (lobe choice and direction),
    // as set_first_light_sample: the first bounce of every power-of-two count of samples
    // covers the hemisphere evenly (indirect light that comes from a small bright patch, as the
    // sun room's sunlit floor, is found at a steadier rate).
    void set_first_bsdf_sample(float u_lobe, const vec2& u) {
        first_bsdf_sample_ = FirstLightSample{u_lobe, u};
    }

    // The field query finish() will make at the first surface (after begin()): its position,
    // the normal the lookup is made for (field_lookup_normal) and the direction towards the
    // viewer, world space. False without a field
    // to query (none, or one that holds no light).
    bool first_field_query(vec3* position, vec3* normal, vec3* wo) const;
    // A lookup made for another path's first surface (screen-space reuse, see
    // render/preview_renderer.h) for finish() to use at this path's first surface instead of
    // its own; it must outlive finish(). `irradiance` (optional, reset by the caller when the
    // lookup changes): the irradiance memo of the paths that share it. `glossy` (optional,
    // cleared by the caller when the lookup changes): the quad's QuadGlossy, which this path
    // adds its glossy lobe's query to, for finish() to read its glossy light from (the same
    // bits); every path that shares the lookup joins it before the first finish().
    void share_first_field_lookup(const FieldLookup* lookup, IrradianceMemo* irradiance = nullptr,
                                  QuadGlossy* glossy = nullptr) {
        shared_lookup_ = lookup;
        shared_irradiance_ = irradiance;
        shared_glossy_ = glossy;
        if (glossy != nullptr) glossy_slot_ = join_quad_glossy(glossy);
    }
    // A memo of the glossy lobes' band factors (sh/ggx_zh.h) for this path's field light to
    // use, kept by the caller across paths (one per thread); it must outlive finish(). Without
    // one each glossy lookup computes them itself (the same values).
    void set_glossy_memo(GgxZhMemo* memo) { glossy_memo_ = memo; }
    // The scene's MaterialLobeTable (render/shading.h) for every surface this path shades, kept
    // by the caller; it must outlive the path. Without one each surface sets its lobes up
    // itself (the same values).
    void set_material_lobes(const MaterialLobeTable* lobes) { material_lobes_ = lobes; }
    // The caller's ShadingMemo (render/shading.h) for every surface this path shades, kept
    // across paths on one thread and reset for each new scene state; it must outlive the path.
    // Without one each surface computes its triangle's normal and frame itself (the same
    // values).
    void set_shading_memo(ShadingMemo* memo) { shading_memo_ = memo; }
    // The first surface as begin() shaded it (position, shading frame, BSDF), for the G-buffer
    // (render/g_buffer.h); valid after begin() returned true and before finish().
    const Shading& first_surface() const { return shading_.value; }

  private:
    const FieldLookup* shared_lookup_ = nullptr;
    GgxZhMemo* glossy_memo_ = nullptr;
    const MaterialLobeTable* material_lobes_ = nullptr;
    ShadingMemo* shading_memo_ = nullptr;
    IrradianceMemo* shared_irradiance_ = nullptr;
    // The quad's glossy light and this path's slot in it (-1: none; read only with a shared
    // lookup and shared_glossy_ set).
    QuadGlossy* shared_glossy_ = nullptr;
    int glossy_slot_ = -1;
    struct FirstLightSample {
        float u_select;
        vec2 u;
    };
    std::optional<FirstLightSample> first_light_sample_;
    std::optional<FirstLightSample> first_bsdf_sample_;  // u_select holds u_lobe

    // A next-event estimate waiting on its shadow ray: the light sample, its direction in the
    // shading frame and f |cos| by class there.
    struct PendingDirect {
        LightSample light;
        vec3 wi{0.0f};
        BsdfEval eval;
    };

    // The field this vertex reads: null before the path's final-gather bounces are made (and
    // without a field), which makes the vertex a reference vertex.
    const IndirectField* vertex_field() const {
        return bounces_[int(LobeClass::Diffuse)] >= field_from_ ? field_ : nullptr;
    }
    bool enter_surface(const Hit& hit, const SurfacePoint* point = nullptr);
    void blur_glossy(Shading* shading) const;
    void find_emission(const Ray& ray, const Hit& hit);
    void add_emission(const vec3& radiance, float light_pdf, bool is_world);
    void record_first_hit(const Shading& shading, const Ray& ray, const Hit& hit);
    void record_denoising_features(const Shading& shading);
    void sample_direct();
    int direct_from_samples(Ray* shadows, const LightSample* samples, int sampled);
    // direct_from_samples' steps for one sample, which begin_direct and finish_direct take too:
    // the sample's direction in the shading frame into *wi, false where the shading and
    // geometric normals disagree on its side; then shadow ray k and its waiting contribution,
    // false where the BSDF's value toward it is zero.
    bool light_direction(const LightSample& ls, vec3* wi) const;
    bool add_pending_direct(Ray* shadows, int k, const LightSample& ls, const vec3& wi,
                            const BsdfEval& eval);
    void add_field(const Shading& shading);
    // Adds the first surface's glossy field query to `glossy`: its slot, or -1 without a free
    // one. The query is made from the normal, view and roughness add_field_light reads, so the
    // quad's radiance is the bits field.glossy would give there. A surface without a glossy
    // field lobe takes a slot too (it never reads it): testing for one cost more than the lane
    // it fills. Inline: the lookup sharing stage calls it once a pixel.
    int join_quad_glossy(QuadGlossy* glossy) const {
        const Shading& shading = shading_.value;
        return glossy->add(shading.frame.z, shading.frame.to_world(shading.wo),
                           shading.bsdf.field_glossy_roughness(), shading.wo.z,
                           shading.bsdf.field_diffuse_roughness());
    }
    // The quad whose glossy light and albedo reads hold this path's first surface (a slot in
    // shared_glossy_), or null.
    QuadGlossy* joined_quad() const { return glossy_slot_ >= 0 ? shared_glossy_ : nullptr; }
    // The field lobes of the current surface (render/bsdf.h): what field light is weighted by.
    struct FieldLobes {
        vec3 diffuse{0.0f};
        PrincipledBsdf::GlossyLobe glossy[2];
        int glossy_count = 0;
        // The diffuse lobe's bump shadowing (render/bump_irradiance.h), where a normal map bent
        // its normal.
        bool bumped = false;
        DiffuseBump bump;
    };
    // `irradiance`: field.irradiance(n), or null to evaluate it here (unused for a bumped
    // diffuse lobe, whose irradiance depends on more than the normal). `glossy`: the quad this
    // path joined (joined_quad(): its glossy light in slot glossy_slot_), read for lobes of its
    // roughness, or null.
    void add_field_light(const FieldLookup& field, const FieldLobes& lobes, const vec3& n,
                         const vec3& wo, IrradianceMemo* irradiance = nullptr,
                         QuadGlossy* glossy = nullptr);
    bool scatter(const Shading& shading, Ray* ray);
    void add_light(const vec3& contribution, int lobe_class, bool direct);
    void add_split(const vec3& contribution, bool direct);
    // An already clamped contribution into its pass and Combined (skipped when not finite).
    void add_to_passes(const vec3& value, int lobe_class, bool direct);

    const Scene& scene_;
    const Camera& camera_;
    const LightSampler& lights_;
    const PathTracerSettings& settings_;
    const IndirectField* field_;
    Pcg32& rng_;
    PassValues& out_;
    IntegratorClock* clock_;

    // Storage left uninitialised by the constructor: enter_surface() and prepare_direct() build
    // their objects in it before anything reads them. Zeroing them (~1 KB) for every path was
    // ~3% of a preview frame (`rep stos` in the wave loop that constructs a path per pixel).
    template <class T>
    union Uninitialized {
        Uninitialized() {}
        T value;
    };
    static_assert(std::is_trivially_destructible_v<PendingDirect>);

    Ray ray_;                          // the ray that reached the current surface
    Uninitialized<Shading> shading_;   // the current surface (set by enter_surface)
    Uninitialized<PendingDirect> pending_[kMaxLightSplits];
    bool terminate_on_next_surface_ = false;
    vec3 throughput_{1.0f};
    // The denoiser's guides (render/film.h): written once, at the first surface that is not
    // (nearly) perfectly specular; until then the product of the specular surfaces' albedos.
    bool write_denoising_features_ = true;
    bool combined_only_ = false;       // set_combined_only()
    vec3 denoising_throughput_{1.0f};
    int vertex_ = 0;                   // surfaces shaded so far
    int field_from_ = 0;               // diffuse scatterings before the field is read
    float gather_u_ = 0.0f;            // set_gather_number()
    int bounces_[kLobeClassCount] = {0, 0, 0};  // scatterings so far by class
    bool last_delta_ = true;           // camera rays and Dirac lobes take no MIS weight
    float last_pdf_ = 0.0f;
    // Filter Glossy: the lowest pdf of the path's non-Dirac bounces (Cycles' min_ray_pdf; a Dirac
    // bounce, whose pdf Cycles takes as 1e6, leaves it).
    float min_ray_pdf_ = kInfinity;
    vec3 last_normal_{0.0f, 0.0f, 1.0f};
    float class_fraction_[kLobeClassCount] = {0.0f, 0.0f, 0.0f};  // of the first scattering
};

}  // namespace shgi
