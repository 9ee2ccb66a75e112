// PreviewRenderer: frames from any IndirectField (seed 000 §5.4: G-buffer, exact direct light,
// indirect light from the solved field), with the passes of the reference path tracer.
//
// Stages (timed as seed 000 Tables 5 and 6): primary — every camera ray of the frame is built
// and intersected as Embree ray streams (Scene::intersect batches); shading — per pixel sample,
// PathIntegrator in field mode (render/path_integrator.h): next-event estimation with a shadow
// ray for direct light (area lights give soft shadows over samples), indirect diffuse and glossy
// from the field, and Dirac / refraction lobes followed by tracing (mirrors and glass show what
// they reflect and refract, up to max_specular_bounces). The shading stage's wall time is split
// into direct and indirect by the threads' time in next-event estimation.
//
// With a null field the renderer shows direct light only (plus specular chains). Determinism:
// sample s of pixel i uses the stream (seed, stream_id(s, i)) as the path tracer does, so frames
// are identical for any thread count. Progressive: render() adds samples to the film.
#pragma once

#include <cstdint>

#include "io/image.h"
#include "render/film.h"
#include "render/indirect_field.h"
#include "render/light_sampler.h"
#include "render/path_tracer.h"
#include "scene/camera.h"
#include "scene/scene.h"
#include "util/progress.h"

namespace shgi {

struct PreviewSettings {
    uint32_t samples = 16;              // per pixel, used by render_preview
    uint64_t seed = 0;
    int max_specular_bounces = 8;       // Dirac and refraction bounces followed per path
    float clamp_indirect = 0.0f;        // as PathTracerSettings.clamp_indirect; 0 = off
    WorldSampling world_sampling = WorldSampling::Cosine;
    int tile_size = 16;
};

void validate_preview_settings(const PreviewSettings& settings);

// Wall-clock seconds of the last render() call.
struct PreviewTimings {
    double primary = 0.0;   // building and intersecting camera rays
    double direct = 0.0;    // next-event estimation (share of the shading stage)
    double indirect = 0.0;  // field lookups and traced specular chains (the rest of shading)
    double total = 0.0;
};

class PreviewRenderer {
  public:
    // The scene must be committed and outlive the renderer; `camera` replaces the scene's (a
    // solved field serves any camera, seed 000 §6.5).
    PreviewRenderer(const Scene& scene, const PreviewSettings& settings);
    PreviewRenderer(const Scene& scene, const Camera& camera, const PreviewSettings& settings);

    // Adds `samples` samples per pixel with indirect light from `field` (may be null). Cancel
    // leaves the film as it was. InvalidArgument if the scene was edited since construction.
    void render(const IndirectField* field, uint32_t samples, Progress* progress = nullptr);

    const Film& film() const { return film_; }
    Image image() const { return film_.image(); }
    const PreviewTimings& timings() const { return timings_; }
    const Camera& camera() const { return camera_; }
    const Scene& scene() const { return *scene_; }

  private:
    const Scene* scene_;
    uint64_t scene_revision_;
    Camera camera_;
    PreviewSettings settings_;
    PathTracerSettings path_settings_;
    LightSampler lights_;
    LightSampler lights_without_world_;  // for fields that carry the world's direct light
    Film film_;
    PreviewTimings timings_;
};

// Renders settings.samples samples per pixel and returns every pass (render/film.h).
Image render_preview(const Scene& scene, const IndirectField* field,
                     const PreviewSettings& settings, Progress* progress = nullptr,
                     PreviewTimings* timings = nullptr);

}  // namespace shgi
