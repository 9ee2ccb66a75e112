// PreviewRenderer: frames from any IndirectField (seed 000 §5.4: G-buffer, exact direct light,
// indirect light from the solved field), with the passes of the reference path tracer.
//
// Work: the frame pipeline (render/frame_pipeline.h, docs/frame-pipeline.md) cuts the frame into
// tiles (settings.tile_size), handed to the threads a few tiles at a time; inside a chunk of
// tiles, up to 256 pixels ("a wave", one 16 x 16 tile by default) move
// through the stages together, one sample index at a time:
// - primary (seed 000 Tables 5/6 "Screen G Buffer"): the wave's camera rays are built and
//   intersected as one Embree ray stream, and each first hit is shaded (surface point, BSDF,
//   emission the camera sees, the Col/Normal/Depth passes) and written to the frame-wide
//   G-buffer (render/g_buffer.h), which any later stage may read across tile borders;
// - direct: next-event estimation at each first hit (area lights give soft shadows over
//   samples), with all the wave's shadow rays traced as one occlusion stream;
// - indirect: indirect diffuse and glossy light from the field, Dirac / refraction lobes followed
//   by tracing (mirrors and glass show what they reflect and refract, up to
//   max_specular_bounces; next-event estimation where such a chain lands counts as direct), and
//   the sums into the film; before them, the lookup sharing stage (below) reads the G-buffer.
// After the tiles, the frame-wide stages added by add_frame_stage run in order over the whole
// frame (G-buffer and film), before the film commits.
// PathIntegrator (render/path_integrator.h, field mode) does the per-path work in these steps.
// Each stage's wall time is the frame's time split in proportion to the threads' time in it.
//
// With a null field the renderer shows direct light only (plus specular chains). Determinism:
// sample s of pixel i uses the stream (seed, stream_id(s, i)) as the path tracer does, and the
// waves depend only on the image and tile sizes, so frames are identical for any thread count.
// Progressive: render() adds samples to the film, and a render that fails or is cancelled leaves
// the film as it was, without the film being copied (render/film.h, ProgressiveFilm).
// The viewport shows only Combined: with combined_only the film sums nothing else, which saves
// most of the film's memory traffic per frame.
//
// Screen-space reuse of field lookups (render/lookup_sharing.h, in the spirit of seed 004's
// discontinuity-aware sharing of SH between neighbouring pixels): the pixels of each aligned
// 2 x 2 quad (waves hold whole quads; tiles have an even side) share one lookup, made at the
// first surface of a lead pixel that rotates with the sample index, when their own first
// surfaces lie within the field's reuse_distance() of it (a quarter of a photon lattice's finest
// cell or of a probe grid's spacing) and their normals agree within ~11 degrees; the others,
// across edges and depth jumps, make their own. Each pixel still evaluates irradiance and glossy
// light with its own normal and view direction, and later vertices of specular chains always
// look up for themselves. Fields that do not allow it (reuse_distance() 0, the default) and
// reuse_field_lookups = false give one lookup per pixel. The quads and leads depend only on
// pixel coordinates, the sample index and the G-buffer, so frames stay identical for any thread
// count and tile size.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "io/image.h"
#include "render/film.h"
#include "render/frame_pipeline.h"
#include "render/g_buffer.h"
#include "render/indirect_field.h"
#include "render/light_sampler.h"
#include "render/path_tracer.h"
#include "render/pixel_filter.h"
#include "render/shading.h"
#include "scene/camera.h"
#include "scene/scene.h"
#include "util/progress.h"

namespace shgi {

struct PreviewSettings {
    uint32_t samples = 16;              // per pixel, used by render_preview
    uint64_t seed = 0;
    int max_specular_bounces = 8;       // Dirac and refraction bounces followed per path
    float clamp_indirect = 0.0f;        // as PathTracerSettings.clamp_indirect; 0 = off
    // As PathTracerSettings.filter_glossy, for the surfaces a path meets after a smooth bounce
    // (with final gather, the gather ray's; a refraction's); 0 = off.
    float filter_glossy = 0.0f;
    WorldSampling world_sampling = WorldSampling::Cosine;
    int light_splits = 4;               // as PathTracerSettings.light_splits (1..kMaxLightSplits)
    // As PathTracerSettings.pixel_filter and filter_width (render/pixel_filter.h).
    PixelFilterType pixel_filter = PixelFilterType::Box;
    float filter_width = 1.0f;
    int tile_size = 16;                 // rounded up to an even number (whole 2 x 2 quads)
    bool combined_only = false;         // sum only the Combined pass (the viewport's)
    // Screen-space reuse of the field's lookups within 2 x 2 pixel quads (see above); false: one
    // lookup per pixel, as the reference would make.
    bool reuse_field_lookups = true;
    // Final gather (render/path_integrator.h): the first surface sends one BSDF-sampled ray per
    // sample and the field is read where it lands after a diffuse bounce (a glossy one goes on
    // as a reference path), not at the first surface. Slower per sample, but the field's blocks
    // and leaks reach the picture only through one more bounce. A screen-space field
    // (INSTANT_GI) is then read like any other: no frame-wide stage lights the first surfaces
    // (nothing to filter), its gather rays each read one VPL set of the sample's passes
    // (IndirectField::gather_lookup), and its filter_direct light is left out (next-event
    // estimation gives it exactly).
    bool final_gather = false;
};

void validate_preview_settings(const PreviewSettings& settings);

// Wall-clock seconds of the last render() call (stages as in the header comment).
struct PreviewTimings {
    double primary = 0.0;   // camera rays, their intersection and the G-buffer of first hits
    double direct = 0.0;    // next-event estimation and its shadow rays
    double indirect = 0.0;  // field lookups, traced specular chains and the film sums
    double frame_stages = 0.0;  // the frame-wide stages after the tiles (a screen-space field's)
    double total = 0.0;
};

class PreviewRenderer {
  public:
    // The scene must be committed and outlive the renderer; `camera` replaces the scene's (a
    // solved field serves any camera, seed 000 §6.5).
    PreviewRenderer(const Scene& scene, const PreviewSettings& settings);
    PreviewRenderer(const Scene& scene, const Camera& camera, const PreviewSettings& settings);

    // Adds `samples` samples per pixel with indirect light from `field` (may be null). Cancel
    // leaves the film as it was (with a screen-space field, render/indirect_field.h, each sample
    // is a frame of its own and a cancel keeps the samples finished before it).
    // InvalidArgument if the scene was edited since construction.
    void render(const IndirectField* field, uint32_t samples, Progress* progress = nullptr);

    const Film& film() const { return film_.film(); }
    Image image() const { return film_.film().image(); }
    const PreviewTimings& timings() const { return timings_; }
    // The first surfaces of the latest sample index rendered (render/g_buffer.h); every pixel a
    // miss before the first render. 64 bytes a pixel.
    const GBuffer& g_buffer() const { return g_buffer_; }
    // Appends a stage run over the whole frame after its tiles, on every later render()
    // (render/frame_pipeline.h, FrameWideStage); InvalidArgument when it has no function.
    void add_frame_stage(FrameWideStage stage);
    const Camera& camera() const { return camera_; }
    const Scene& scene() const { return *scene_; }

  private:
    const LightSampler& lights_for(const IndirectField& field);

    const Scene* scene_;
    uint64_t scene_revision_;
    Camera camera_;
    CameraRayGenerator camera_rays_;  // camera_'s, made once
    PreviewSettings settings_;
    PixelFilter pixel_filter_;  // settings_'s pixel_filter and filter_width, tabulated once
    PathTracerSettings path_settings_;
    MaterialLobeTable material_lobes_;  // the scene's, built once
    LightSampler lights_;
    // The sampler for a field that carries some direct light itself (includes_world_direct,
    // includes_lights_direct), built by the first render with such a field, and which of the two
    // it leaves out.
    std::optional<LightSampler> field_lights_;
    bool without_world_ = false, without_lights_ = false;
    ProgressiveFilm film_;
    GBuffer g_buffer_;
    std::vector<FrameWideStage> frame_stages_;
    PreviewTimings timings_;
};

// Renders settings.samples samples per pixel and returns every pass (render/film.h), or only
// Combined with settings.combined_only.
Image render_preview(const Scene& scene, const IndirectField* field,
                     const PreviewSettings& settings, Progress* progress = nullptr,
                     PreviewTimings* timings = nullptr);

}  // namespace shgi
