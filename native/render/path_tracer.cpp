#include "render/path_tracer.h"

#include <algorithm>
#include <cmath>

#include "render/frame_pipeline.h"
#include "render/path_integrator.h"
#include "util/error.h"
#include "util/parallel.h"
#include "util/rng.h"

namespace shgi {
namespace {

const PathTracerSettings& validated(const PathTracerSettings& settings) {
    validate_path_tracer_settings(settings);
    return settings;
}

}  // namespace

void validate_path_tracer_settings(const PathTracerSettings& settings) {
    auto check_non_negative = [](int value, const char* name) {
        if (value < 0)
            throw InvalidArgument(format_message("PathTracerSettings.", name, " is ", value,
                                                 "; it must be >= 0"));
    };
    check_non_negative(settings.max_bounces, "max_bounces");
    check_non_negative(settings.diffuse_bounces, "diffuse_bounces");
    check_non_negative(settings.glossy_bounces, "glossy_bounces");
    check_non_negative(settings.transmission_bounces, "transmission_bounces");
    check_non_negative(settings.russian_roulette_depth, "russian_roulette_depth");
    if (settings.samples == 0 || settings.samples > kMaxPathTracerSamples)
        throw InvalidArgument(format_message("PathTracerSettings.samples is ", settings.samples,
                                             "; it must be in [1, ", kMaxPathTracerSamples, "]"));
    if (!std::isfinite(settings.clamp_indirect) || settings.clamp_indirect < 0.0f)
        throw InvalidArgument(format_message("PathTracerSettings.clamp_indirect is ",
                                             settings.clamp_indirect,
                                             "; it must be finite and >= 0 (0 = off)"));
    if (!std::isfinite(settings.filter_glossy) || settings.filter_glossy < 0.0f)
        throw InvalidArgument(format_message("PathTracerSettings.filter_glossy is ",
                                             settings.filter_glossy,
                                             "; it must be finite and >= 0 (0 = off)"));
    validate_filter_width(settings.filter_width, "PathTracerSettings");
    if (settings.light_splits < 1 || settings.light_splits > kMaxLightSplits)
        throw InvalidArgument(format_message("PathTracerSettings.light_splits is ",
                                             settings.light_splits, "; it must be in [1, ",
                                             kMaxLightSplits, "] (1: one light per shadow ray)"));
    if (settings.tile_size < 1)
        throw InvalidArgument(format_message("PathTracerSettings.tile_size is ",
                                             settings.tile_size, "; it must be >= 1"));
}

PathTracer::PathTracer(const Scene& scene, const PathTracerSettings& settings)
    : scene_(&scene),
      scene_revision_(scene.revision()),
      settings_(validated(settings)),
      lights_(scene, settings.world_sampling, true, settings.light_splits),
      pixel_filter_(settings.pixel_filter, settings.filter_width) {
    const Camera& camera = scene.camera();
    film_ = ProgressiveFilm(int(camera.resolution_x), int(camera.resolution_y));
}

void PathTracer::render(uint32_t samples, Progress* progress) {
    if (scene_->revision() != scene_revision_ || !scene_->committed())
        throw InvalidArgument(format_message(
            "PathTracer::render: the scene was edited after this PathTracer was created "
            "(revision ", scene_revision_, ", now ", scene_->revision(),
            "); commit it and create a new PathTracer"));
    const uint64_t first = film_.film().samples();
    if (samples == 0) return;
    if (first + samples > kMaxPathTracerSamples)
        throw InvalidArgument(format_message("PathTracer::render: ", first, " + ", samples,
                                             " samples exceed the limit of ",
                                             kMaxPathTracerSamples, " per pixel"));
    const Camera& camera = scene_->camera();
    const CameraRayGenerator camera_rays(camera);
    const TileGrid grid(film_.film().width(), film_.film().height(), settings_.tile_size);
    // Each pixel sums its samples in order, the first onto the sums as they were before this
    // render (render/film.h, ProgressiveFilm).
    auto render_tiles = [&](uint64_t begin, uint64_t end, Film& target, const Film& base) {
        for (uint64_t t = begin; t < end; ++t) {
            int x0, x1, y0, y1;
            grid.bounds(t, &x0, &x1, &y0, &y1);
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    const uint64_t pixel = uint64_t(y) * uint64_t(grid.width) + uint64_t(x);
                    for (uint64_t s = first; s < first + samples; ++s) {
                        throw_if_cancelled(progress);  // one relaxed atomic load per path
                        Pcg32 rng(settings_.seed, stream_id(s, pixel));
                        const PixelSample stratified = pixel_sample(settings_.seed, pixel, s, true);
                        PassValues values;
                        PathIntegrator integrator(*scene_, camera, lights_, settings_, nullptr,
                                                  rng, values);
                        integrator.set_first_light_sample(stratified.u_select,
                                                          stratified.u_light);
                        integrator.set_first_bsdf_sample(stratified.u_lobe, stratified.u_bsdf);
                        integrator.trace(camera_rays.generate_ray(
                            vec2(float(x), float(y)) +
                            pixel_filter_.film_offset(stratified.jitter)));
                        if (s == first)
                            target.accumulate(x, y, base, values);
                        else
                            target.add(x, y, values);
                    }
                }
        }
    };
    render_frame_tiles(film_, grid, 1, samples, progress, render_tiles);
}

Image render_path_traced(const Scene& scene, const PathTracerSettings& settings,
                         Progress* progress) {
    PathTracer tracer(scene, settings);
    tracer.render(settings.samples, progress);
    return tracer.image();
}

}  // namespace shgi
