#include "render/preview_renderer.h"

#include <algorithm>
#include <vector>

#include "render/path_integrator.h"
#include "util/error.h"
#include "util/timer.h"
#include "util/parallel.h"
#include "util/rng.h"

namespace shgi {
namespace {

// Camera samples traced per batch: bounds the memory of the G-buffer (rays and hits).
constexpr uint64_t kMaxBatchSamples = uint64_t(1) << 20;

// The path tracer settings that make PathIntegrator follow only specular chains: every
// scattering of a field path is a traced lobe (Dirac or refraction).
PathTracerSettings path_settings_for(const PreviewSettings& settings) {
    PathTracerSettings path;
    path.seed = settings.seed;
    path.max_bounces = settings.max_specular_bounces;
    path.diffuse_bounces = settings.max_specular_bounces;
    path.glossy_bounces = settings.max_specular_bounces;
    path.transmission_bounces = settings.max_specular_bounces;
    path.russian_roulette_depth = settings.max_specular_bounces + 1;  // chains are short
    path.clamp_indirect = settings.clamp_indirect;
    path.world_sampling = settings.world_sampling;
    path.tile_size = settings.tile_size;
    return path;
}

const PreviewSettings& validated(const PreviewSettings& settings) {
    validate_preview_settings(settings);
    return settings;
}

}  // namespace

void validate_preview_settings(const PreviewSettings& settings) {
    if (settings.samples == 0 || settings.samples > kMaxPathTracerSamples)
        throw InvalidArgument(format_message("PreviewSettings.samples is ", settings.samples,
                                             "; it must be in [1, ", kMaxPathTracerSamples, "]"));
    if (settings.max_specular_bounces < 0)
        throw InvalidArgument(format_message("PreviewSettings.max_specular_bounces is ",
                                             settings.max_specular_bounces, "; it must be >= 0"));
    if (!std::isfinite(settings.clamp_indirect) || settings.clamp_indirect < 0.0f)
        throw InvalidArgument(format_message("PreviewSettings.clamp_indirect is ",
                                             settings.clamp_indirect,
                                             "; it must be finite and >= 0 (0 = off)"));
    if (settings.tile_size < 1)
        throw InvalidArgument(format_message("PreviewSettings.tile_size is ", settings.tile_size,
                                             "; it must be >= 1"));
}

PreviewRenderer::PreviewRenderer(const Scene& scene, const PreviewSettings& settings)
    : PreviewRenderer(scene, scene.camera(), settings) {}

PreviewRenderer::PreviewRenderer(const Scene& scene, const Camera& camera,
                                 const PreviewSettings& settings)
    : scene_(&scene),
      scene_revision_(scene.revision()),
      camera_(camera),
      settings_(validated(settings)),
      path_settings_(path_settings_for(settings)),
      lights_(scene, settings.world_sampling),
      lights_without_world_(scene, settings.world_sampling, false) {
    validate_camera(camera_);
    film_ = Film(int(camera_.resolution_x), int(camera_.resolution_y));
}

void PreviewRenderer::render(const IndirectField* field, uint32_t samples, Progress* progress) {
    if (scene_->revision() != scene_revision_ || !scene_->committed())
        throw InvalidArgument(format_message(
            "PreviewRenderer::render: the scene was edited after this renderer was created "
            "(revision ", scene_revision_, ", now ", scene_->revision(),
            "); commit it and create a new PreviewRenderer"));
    const uint64_t first = film_.samples();
    if (samples == 0) return;
    if (first + samples > kMaxPathTracerSamples)
        throw InvalidArgument(format_message("PreviewRenderer::render: ", first, " + ", samples,
                                             " samples exceed the limit of ",
                                             kMaxPathTracerSamples, " per pixel"));
    const ZeroField no_field;
    if (field == nullptr) field = &no_field;  // direct light only, still in preview mode
    const LightSampler& lights = field->includes_world_direct() ? lights_without_world_ : lights_;
    const auto frame_start = now();
    PreviewTimings timings;
    const int width = film_.width(), height = film_.height();
    const uint64_t pixels = uint64_t(width) * uint64_t(height);
    const uint64_t samples_per_batch = std::max<uint64_t>(1, kMaxBatchSamples / pixels);
    Film scratch = film_;  // committed only when every batch finished
    std::vector<Ray> rays;
    std::vector<Hit> hits;
    for (uint64_t batch = first; batch < first + samples; batch += samples_per_batch) {
        const uint64_t batch_samples = std::min<uint64_t>(samples_per_batch, first + samples - batch);
        // Primary: camera rays of the batch, sample-major per pixel, intersected as streams.
        auto stage_start = now();
        rays.resize(pixels * batch_samples);
        parallel_for(0, pixels, 4096, [&](uint64_t begin, uint64_t end) {
            for (uint64_t pixel = begin; pixel < end; ++pixel) {
                const vec2 position(float(pixel % uint64_t(width)), float(pixel / uint64_t(width)));
                for (uint64_t s = 0; s < batch_samples; ++s) {
                    Pcg32 rng(settings_.seed, stream_id(batch + s, pixel));
                    rays[pixel * batch_samples + s] = camera_.generate_ray(position + rng.next_vec2());
                }
            }
        }, progress);
        scene_->intersect(rays, hits, progress);
        timings.primary += seconds_since(stage_start);

        // Shading: tiles of pixels, each sample continuing from its primary hit.
        stage_start = now();
        const int tile = settings_.tile_size;
        const int tiles_x = (width + tile - 1) / tile, tiles_y = (height + tile - 1) / tile;
        std::vector<IntegratorClock> clocks(size_t(tiles_x) * size_t(tiles_y));
        std::vector<double> busy(clocks.size(), 0.0);
        parallel_for(0, uint64_t(tiles_x) * uint64_t(tiles_y), 1, [&](uint64_t begin, uint64_t end) {
            for (uint64_t t = begin; t < end; ++t) {
                const auto tile_start = now();
                const int x0 = int(t % uint64_t(tiles_x)) * tile;
                const int y0 = int(t / uint64_t(tiles_x)) * tile;
                for (int y = y0; y < std::min(y0 + tile, height); ++y) {
                    for (int x = x0; x < std::min(x0 + tile, width); ++x) {
                        const uint64_t pixel = uint64_t(y) * uint64_t(width) + uint64_t(x);
                        for (uint64_t s = 0; s < batch_samples; ++s) {
                            throw_if_cancelled(progress);
                            Pcg32 rng(settings_.seed, stream_id(batch + s, pixel));
                            rng.next_vec2();  // the jitter the primary stage used
                            PassValues values;
                            PathIntegrator integrator(*scene_, lights, path_settings_, field,
                                                      rng, values, &clocks[t]);
                            const uint64_t index = pixel * batch_samples + s;
                            integrator.trace(rays[index], hits[index]);
                            scratch.add(x, y, values);
                        }
                    }
                }
                busy[t] = seconds_since(tile_start);
            }
        }, progress);
        const double shading = seconds_since(stage_start);
        double direct = 0.0, total_busy = 0.0;
        for (size_t t = 0; t < clocks.size(); ++t) {
            direct += clocks[t].direct;
            total_busy += busy[t];
        }
        const double direct_share = total_busy > 0.0 ? std::min(1.0, direct / total_busy) : 0.0;
        timings.direct += shading * direct_share;
        timings.indirect += shading * (1.0 - direct_share);
    }
    scratch.set_samples(uint32_t(first + samples));
    film_ = std::move(scratch);
    timings.total = seconds_since(frame_start);
    timings_ = timings;
}

Image render_preview(const Scene& scene, const IndirectField* field,
                     const PreviewSettings& settings, Progress* progress,
                     PreviewTimings* timings) {
    PreviewRenderer renderer(scene, settings);
    renderer.render(field, settings.samples, progress);
    if (timings != nullptr) *timings = renderer.timings();
    return renderer.image();
}

}  // namespace shgi
