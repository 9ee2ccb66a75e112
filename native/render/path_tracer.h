// PathTracer: the reference unidirectional path tracer every SHGI solver is checked against.
//
// Algorithm (Veach 1997, ch. 9; pbrt-v4 §13.4 "PathIntegrator"): at each surface, next-event
// estimation samples an emitter (LightSampler, chosen by a light tree; where the tree's nodes
// are large seen from the shading point, one emitter from each of up to `light_splits` nodes,
// render/light_tree.h) and the BSDF (PrincipledBsdf)
// is sampled to continue; emitters found by BSDF rays (emissive triangles, point/spot disks,
// area lights, sun cones, the world) are weighted against NEE by the power heuristic (beta = 2).
// Russian roulette starts after `russian_roulette_depth` surfaces with survival probability
// min(1, sqrt(T)), T the path throughput's largest component, as Cycles'
// (path_state_continuation_probability): the square root follows the display's response, so a
// dim path lives longer than with min(1, T). In a closed, light-coloured room, where light
// bounces many times, min(1, T) ended paths that still carried a visible share of the pixel
// (docs/equal-time.md, "Where the sun room's noise is").
//
// Bounce limits mean what Cycles' Light Paths panel means: max_bounces = 0 is direct light only
// (emitters reached after one scattering, by NEE or by the BSDF ray); each scattering counts as
// one bounce of its lobe class, and a path whose counts exceed a limit still adds the emission
// its last ray meets, then stops (Cycles' PATH_RAY_TERMINATE_ON_NEXT_SURFACE).
//
// Tiles: the frame pipeline's tile loop (render/frame_pipeline.h), shared with the preview.
// Determinism: sample s of pixel i uses its own Pcg32 stream (seed, stream_id(s, i)) and point s
// of the pixel's Owen-scrambled Sobol' sequences for its jitter, first light sample and first
// BSDF sample (pixel_sample in render/path_integrator.h), so the image is bit-identical for any
// thread count, any tile split and any split of the samples into progressive render() calls.
// Pixel filter: PathTracerSettings.pixel_filter and filter_width (render/pixel_filter.h), by
// default a box of one pixel (the stratified jitter), where Cycles (and the add-on) default to
// a Blackman-Harris of Filter Size 1.5.
// Passes: see render/film.h. Units and emitters: see render/light_sampler.h.
#pragma once

#include <cstdint>

#include "io/image.h"
#include "render/bsdf.h"
#include "render/film.h"
#include "render/light_sampler.h"
#include "render/pixel_filter.h"
#include "scene/scene.h"
#include "util/progress.h"

namespace shgi {

// How Russian roulette's survival probability follows the path throughput T (its largest RGB
// component).
enum class RouletteSurvival : uint8_t {
    SqrtThroughput,  // min(1, sqrt(T)), Cycles'
    Throughput,      // min(1, T): ends dim paths sooner (the probe, bake and preview paths)
};

struct PathTracerSettings {
    uint32_t samples = 64;             // per pixel, used by render_path_traced
    uint64_t seed = 0;
    int max_bounces = 12;              // Cycles' defaults for the four limits
    int diffuse_bounces = 4;
    int glossy_bounces = 4;
    int transmission_bounces = 12;
    int russian_roulette_depth = 3;    // surfaces before roulette may end a path
    RouletteSurvival roulette_survival = RouletteSurvival::SqrtThroughput;
    // Light Paths > Clamp Indirect as Cycles': an indirect contribution whose components average
    // more than this is scaled down to it (render/shading.h, clamp_contribution); 0 = off.
    float clamp_indirect = 0.0f;
    // Light Paths > Filter Glossy as Cycles' (blur_glossy): a surface a path reaches after a
    // bounce whose BSDF pdf was below this value (the lowest of the path's non-Dirac bounces, per
    // steradian) has its glossy and glass lobes widened to a GGX alpha of
    // sqrt(1 - min_pdf / filter_glossy) / 2 (PrincipledBsdf::blur): a mirror or sharp glass seen
    // through a diffuse or rough bounce scatters light sampling can reach, trading the caustic
    // fireflies of such paths for a little blur. The camera's first surface is never widened.
    // 0 = off.
    float filter_glossy = 0.0f;
    WorldSampling world_sampling = WorldSampling::Cosine;
    // Most emitters one next-event estimate samples, [1, kMaxLightSplits]: the light tree's
    // splitting (render/light_tree.h); 1 = one emitter per shadow ray.
    int light_splits = 4;
    // Film > Pixel Filter as Cycles' (render/pixel_filter.h): its type and Filter Size in pixels,
    // [kMinFilterWidth, kMaxFilterWidth]. The default, a box of one pixel, is Cycles' Box 1.
    PixelFilterType pixel_filter = PixelFilterType::Box;
    float filter_width = 1.0f;
    int tile_size = 16;                // pixels per tile side (work unit of the thread pool)
};

// Largest total sample count per pixel: sample indices name RNG streams (util/rng.h stream_id).
inline constexpr uint64_t kMaxPathTracerSamples = uint64_t(1) << 24;

// Throws InvalidArgument naming the field and its value.
void validate_path_tracer_settings(const PathTracerSettings& settings);

class PathTracer {
  public:
    // The scene must be committed and have a camera; it must outlive the PathTracer.
    PathTracer(const Scene& scene, const PathTracerSettings& settings);

    // Adds `samples` samples per pixel to the film (progressive). On Cancelled or any other
    // error the film is left as it was before the call. Throws InvalidArgument when the scene
    // was edited since construction: the light tables and film no longer match it.
    void render(uint32_t samples, Progress* progress = nullptr);

    const Film& film() const { return film_.film(); }
    uint32_t samples_done() const { return film_.film().samples(); }
    const PathTracerSettings& settings() const { return settings_; }
    const Scene& scene() const { return *scene_; }
    Image image() const { return film_.film().image(); }

  private:
    const Scene* scene_;
    uint64_t scene_revision_;  // Scene::revision() the light tables and film were built for
    PathTracerSettings settings_;
    LightSampler lights_;
    PixelFilter pixel_filter_;
    ProgressiveFilm film_;  // a failed render leaves it as it was, without copying it
};

// Renders settings.samples samples per pixel and returns every pass (render/film.h).
Image render_path_traced(const Scene& scene, const PathTracerSettings& settings,
                         Progress* progress = nullptr);

}  // namespace shgi
