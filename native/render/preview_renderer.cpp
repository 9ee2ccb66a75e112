#include "render/preview_renderer.h"

#include <algorithm>
#include <atomic>
#include <memory>
#include <new>
#include <optional>
#include <type_traits>
#include <vector>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "render/frame_pipeline.h"
#include "render/lookup_sharing.h"
#include "render/path_integrator.h"
#include "util/error.h"
#include "util/timer.h"
#include "util/parallel.h"
#include "util/rng.h"

namespace shgi {
namespace {

// Pixels whose paths go through the stages together: their camera rays and their first shadow
// rays are each one Embree stream. 256 is one 16 x 16 tile (PreviewSettings' default): coherent
// enough for Embree's packets, small enough that the wave's state (~0.7 KB per path: integrator,
// pass values, rays, hits; ~180 KB) stays in a core's L2 between the stages.
constexpr size_t kWavePixels = 256;
// Pixels per parallel work unit (a run of whole tiles): a 640 x 360 frame gives a few hundred
// units, plenty to balance the threads, and the per-unit setup stays negligible.
constexpr uint64_t kChunkPixels = 1024;

// Sets every pass of `values` to 0, as `values = PassValues{}` does. GCC's generic x86-64
// tuning clears the passes (16 x 12 bytes) with `rep stosq`, whose start-up cost made that one
// line ~1% of a preview frame (once per pixel and sample); 16-byte stores (and an 8-byte one
// for a remainder) do the same work in a few cycles.
void clear_pass_values(PassValues& values) {
#if defined(__SSE2__)
    constexpr size_t kWide = sizeof(PassValues) / 16;
    static_assert(sizeof(PassValues) % 16 == 0 || sizeof(PassValues) % 16 == 8,
                  "clear_pass_values stores 16-byte words and at most one 8-byte one");
    auto* bytes = reinterpret_cast<char*>(&values);
    const __m128i zero = _mm_setzero_si128();
    for (size_t k = 0; k < kWide; ++k)
        _mm_storeu_si128(reinterpret_cast<__m128i*>(bytes + 16 * k), zero);
    if constexpr (sizeof(PassValues) % 16 == 8)
        _mm_storel_epi64(reinterpret_cast<__m128i*>(bytes + 16 * kWide), zero);
#else
    values = PassValues{};
#endif
}

// Seconds one work unit spent in each stage.
struct StageSeconds {
    double primary = 0.0, direct = 0.0, indirect = 0.0;
};

// A tile side of tile_size rounded up to an even number, so that every tile is made of whole
// aligned 2 x 2 quads (the reuse of field lookups) whatever the setting; sides past 2^21 (above
// any image side, kMaxCameraResolution) cover the image alike and are cut to it first.
int even_tile_side(int tile_size) {
    const int side = std::min(tile_size, 1 << 21);
    return side + (side & 1);
}

// The stages' wall times: `wall` split in proportion to the threads' seconds in each stage.
PreviewTimings split_wall_time(double wall, const std::vector<StageSeconds>& busy) {
    StageSeconds sum;
    for (const StageSeconds& unit : busy) {  // a fixed order: the same split for any run
        sum.primary += unit.primary;
        sum.direct += unit.direct;
        sum.indirect += unit.indirect;
    }
    PreviewTimings timings;
    const double total = sum.primary + sum.direct + sum.indirect;
    if (total > 0.0) {
        timings.primary = wall * sum.primary / total;
        timings.direct = wall * sum.direct / total;
        timings.indirect = wall * sum.indirect / total;
    }
    return timings;
}

// The first surfaces of a wave that sample lights, one array per coordinate
// (LightSampler::sample_split_lanes), and what the light stage gave them.
struct LightLanes {
    // Sized once for the whole wave (resize) and written by index, the live count kept by
    // the caller: push_back's capacity test and end pointer per coordinate were ~9M
    // instructions a Cornell box frame (docs/frame-pipeline.md, 2026-11-30, perf10b).
    std::vector<uint32_t> path;  // the wave's path
    std::vector<float> x, y, z, u_select, ux, uy;
    std::vector<LightSample> samples;
    std::vector<int8_t> written;
    // Each path's sample direction in its shading frame (PathIntegrator::begin_direct), whether
    // a shadow ray may follow, and its BSDF's value there.
    std::vector<vec3> wi;
    std::vector<uint8_t> kept;
    std::vector<BsdfEval> eval;

    void resize(size_t size) {
        for (std::vector<float>* v : {&x, &y, &z, &u_select, &ux, &uy}) v->resize(size);
        path.resize(size);
        samples.resize(size);
        written.resize(size);
        wi.resize(size);
        kept.resize(size);
        eval.resize(size);
    }
};

// A wave's buffers, sized once (each thread keeps its wave: WaveLease): each PathIntegrator
// refers to its rng and values entries, so these vectors never reallocate while paths are in
// flight.
struct Wave {
    explicit Wave(size_t capacity)
        : x(capacity), y(capacity), pixel(capacity), rngs(capacity), samples(capacity),
          film(capacity), values(capacity), paths(capacity), live(capacity) {
        quads.reserve(capacity);
        rays.reserve(capacity);
        hits.reserve(capacity);
        shadow_rays.reserve(capacity);
        // Written by index (trace_direct): at most kMaxLightSplits shadow rays a path.
        shadow_paths.resize(capacity * kMaxLightSplits);
        shadow_slots.resize(capacity * kMaxLightSplits);
        occluded.reserve(capacity);
        light_lanes.resize(capacity);
    }
    size_t capacity() const { return x.size(); }

    size_t count = 0;  // pixels in the wave
    std::vector<int> x, y;
    // y * width + x, the pixel's G-buffer index: 32 bits hold it, as a G-buffer of 2^32 pixels
    // (256 GB) is refused by its memory check first.
    std::vector<uint32_t> pixel;
    std::vector<Pcg32> rngs;
    std::vector<PixelSample> samples;  // stratified jitter and first light sample
    std::vector<vec2> film;            // the camera ray's film point: pixel + jitter
    std::vector<PassValues> values;
    std::vector<std::optional<PathIntegrator>> paths;
    // paths[0, armed) were constructed for the frame `armed_frame` (FrameWork::id_: its scene,
    // field and settings) and are re-armed per pixel (PathIntegrator::restart); another frame's
    // first call starts again from 0. Built once a render_tiles call, the first of a work
    // unit's four waves constructed all its paths: a quarter of the pixels, ~18% of the render
    // loop's own CPU samples (docs/frame-pipeline.md, 2026-11-30, loop16).
    size_t armed = 0;
    uint64_t armed_frame = 0;  // no frame: FrameWork ids start at 1
    IntegratorClock clock;     // the paths' clock, zeroed by each render_tiles call
    std::vector<uint8_t> live;  // the path has a first surface to shade
    // The wave holds whole 2 x 2 quads (fewer pixels at the image border): quad q is pixels
    // [quads[q], quads[q + 1]) (the last one ends at count), and lookups[q] its shared lookup.
    std::vector<uint32_t> quads;
    std::vector<FieldLookup> lookups;
    std::vector<IrradianceMemo> irradiance;  // per quad: its lookup's irradiance, by normal
    std::vector<QuadGlossy> glossy;  // per quad: its pixels' glossy light, four lanes at once
    GgxZhMemo glossy_zh;  // every path's glossy band factors, by roughness (kept across waves)
    // Every path's last triangle normal and shading frame; reset for each render_tiles call,
    // since a kept wave may next serve another scene or revision.
    ShadingMemo shading;
    std::vector<Ray> rays;
    std::vector<Hit> hits;
    std::vector<Ray> shadow_rays;
    std::vector<uint32_t> shadow_paths;  // the path each shadow ray belongs to
    std::vector<uint8_t> shadow_slots;   // and which of its light samples (add_direct's k)
    std::vector<uint8_t> occluded;
    LightLanes light_lanes;  // the light stage's first surfaces (trace_direct)
};

// The calling thread's wave, at `capacity` pixels, empty. Each thread keeps one between work
// units and frames: a work unit of four tiles built its own (~0.35 MB, 256 paths of ~1.2 KB and
// their pass values, allocated and zeroed: ~80 MB of stores a 640 x 360 frame). The wave is
// taken out of the thread's slot while in use and put back by WaveLease's destructor, so a
// nested call on the same thread (a task stolen while this one waits) builds its own; every
// entry is written before a wave reads it, so frames are the same as with new waves.
class WaveLease {
  public:
    explicit WaveLease(size_t capacity) : wave_(std::move(slot())) {
        if (!wave_ || wave_->capacity() != capacity) wave_ = std::make_unique<Wave>(capacity);
        wave_->count = 0;
        wave_->quads.clear();
    }
    ~WaveLease() { slot() = std::move(wave_); }
    WaveLease(const WaveLease&) = delete;
    WaveLease& operator=(const WaveLease&) = delete;
    Wave& wave() { return *wave_; }

  private:
    static std::unique_ptr<Wave>& slot() {
        thread_local std::unique_ptr<Wave> kept;
        return kept;
    }
    std::unique_ptr<Wave> wave_;
};

// Whether `field` lights the first surfaces itself in a frame-wide stage: a screen-space field
// (shades_first_surfaces) read without a final gather. Through one, the first surfaces are
// reference vertices and the field is read where their gather rays land, as any field's.
bool lights_first_surfaces(const IndirectField& field, bool final_gather) {
    return field.shades_first_surfaces() && !final_gather;
}

// One render() call: samples [first, first + count) of every pixel, summed onto the film's base
// into its target (which may be the base). Threads share it read-only; a work unit writes only
// its own pixels of the target and of the G-buffer.
class FrameWork {
  public:
    FrameWork(const Scene& scene, const Camera& camera, const CameraRayGenerator& camera_rays,
              const PixelFilter& pixel_filter, const LightSampler& lights,
              const MaterialLobeTable& material_lobes, const PathTracerSettings& settings,
              const IndirectField& field, const TileGrid& grid, uint64_t first, uint64_t count,
              GBuffer& g_buffer, Progress* progress, bool reuse_lookups, bool final_gather,
              bool combined_only)
        : scene_(scene), camera_(camera), camera_rays_(camera_rays),
          pixel_filter_(pixel_filter), lights_(lights), material_lobes_(material_lobes),
          settings_(settings), field_(field), grid_(grid), first_(first), count_(count),
          g_buffer_(&g_buffer), progress_(progress),
          screen_space_(lights_first_surfaces(field, final_gather)),
          reuse_(reuse_lookups && !final_gather && !field.is_zero() && !screen_space_
                     ? field.reuse_distance()
                     : 0.0f),
          final_gather_(final_gather ? 1 : 0),
          combined_only_(combined_only),
          id_(next_id()),
          camera_position_(camera.world_from_camera[3]),
          forward_(glm::normalize(-vec3(camera.world_from_camera[2]))) {}

    // Renders tiles [begin, end) of the grid in waves of whole 2 x 2 quads: quads in row-major
    // order within each tile, each quad's pixels row-major.
    void render_tiles(uint64_t begin, uint64_t end, Film& target, const Film& base,
                      StageSeconds* seconds) const {
        const uint64_t tile_pixels = uint64_t(grid_.tile) * uint64_t(grid_.tile);
        WaveLease lease(size_t(std::min<uint64_t>(kWavePixels, (end - begin) * tile_pixels)));
        Wave& wave = lease.wave();
        wave.shading.reset();
        if (wave.armed_frame != id_) {  // a kept wave's paths refer to another frame's objects
            wave.armed = 0;
            wave.armed_frame = id_;
        }
        wave.clock = IntegratorClock{};
        IntegratorClock& clock = wave.clock;
        for (uint64_t t = begin; t < end; ++t) {
            int x0, x1, y0, y1;
            grid_.bounds(t, &x0, &x1, &y0, &y1);
            for (int qy = y0; qy < y1; qy += 2)
                for (int qx = x0; qx < x1; qx += 2) {
                    if (wave.count + 4 > wave.capacity())
                        render_wave(wave, clock, target, base, seconds);
                    wave.quads.push_back(uint32_t(wave.count));
                    for (int y = qy; y < std::min(qy + 2, y1); ++y)
                        for (int x = qx; x < std::min(qx + 2, x1); ++x) {
                            wave.x[wave.count] = x;
                            wave.y[wave.count] = y;
                            wave.pixel[wave.count] = uint32_t(g_buffer_->index(x, y));
                            ++wave.count;
                        }
                }
        }
        if (wave.count > 0) render_wave(wave, clock, target, base, seconds);
    }

  private:
    static uint64_t next_id() {
        static std::atomic<uint64_t> last{0};
        return last.fetch_add(1, std::memory_order_relaxed) + 1;
    }

    // Every sample of the wave's pixels, one sample index at a time (each pixel's samples are
    // summed in order, as the path tracer does); empties the wave.
    void render_wave(Wave& wave, IntegratorClock& clock, Film& target, const Film& base,
                     StageSeconds* seconds) const {
        for (uint64_t s = first_; s < first_ + count_; ++s) {
            throw_if_cancelled(progress_);
            const TimePoint primary_start = now();
            trace_primary(wave, s, clock);
            const TimePoint direct_start = now();
            trace_direct(wave);
            const TimePoint shading_start = now();
            seconds->primary += seconds_between(primary_start, direct_start);
            seconds->direct += seconds_between(direct_start, shading_start);
            // Next-event estimation where a specular chain lands is direct light too: the
            // integrators add its time to `clock`.
            const double chain_direct = clock.direct;
            share_field_lookups(wave, s);
            const Film& sums = s == first_ ? base : target;
            for (size_t i = 0; i < wave.count; ++i) {
                // The film's lines load while the path is shaded (Film::prefetch).
                target.prefetch(wave.x[i], wave.y[i], sums);
                if (wave.live[i]) wave.paths[i]->finish();
                target.accumulate(wave.x[i], wave.y[i], sums, wave.values[i]);
            }
            const double shading = seconds_since(shading_start);
            const double chained = clock.direct - chain_direct;
            seconds->direct += chained;
            seconds->indirect += shading - chained;
        }
        wave.count = 0;
        wave.quads.clear();
    }

    // The lookup sharing stage (render/lookup_sharing.h) over the wave's quads, from the
    // G-buffer: each quad's lead makes its field lookup, its followers take it instead of their
    // own.
    void share_field_lookups(Wave& wave, uint64_t s) const {
        if (screen_space_) {  // the first surfaces' field light comes from a frame-wide stage
            for (size_t i = 0; i < wave.count; ++i)
                if (wave.live[i]) wave.paths[i]->share_first_field_lookup(&no_light_);
            return;
        }
        if (!(reuse_ > 0.0f)) return;
        // Grown to the most quads a wave has held (64 for full 16 x 16 tiles), not to the
        // wave's capacity: each lookup is ~0.3 KB to clear.
        if (wave.lookups.size() < wave.quads.size()) {
            wave.lookups.resize(wave.quads.size());
            wave.irradiance.resize(wave.quads.size());
            wave.glossy.resize(wave.quads.size());
        }
        for (size_t q = 0; q < wave.quads.size(); ++q) {
            const uint32_t first = wave.quads[q];
            const uint32_t size =
                (q + 1 < wave.quads.size() ? wave.quads[q + 1] : uint32_t(wave.count)) - first;
            const QuadLookupSharing sharing =
                share_quad_lookup(*g_buffer_, &wave.pixel[first], size, s, reuse_);
            if (sharing.lead == QuadLookupSharing::kNoLead) continue;
            PathIntegrator& lead = *wave.paths[first + sharing.lead];
            vec3 p, n, wo;
            if (!lead.first_field_query(&p, &n, &wo)) continue;
            // Built in the wave's entry (the call's return slot): assigning the returned value
            // would copy its ~0.3 KB.
            static_assert(std::is_trivially_destructible_v<FieldLookup>);
            ::new (static_cast<void*>(&wave.lookups[q])) FieldLookup(field_.view_lookup(p, n, wo));
            wave.irradiance[q].reset();
            wave.glossy[q].clear();
            lead.share_first_field_lookup(&wave.lookups[q], &wave.irradiance[q], &wave.glossy[q]);
            for (uint32_t k = 0; k < size; ++k)
                if (sharing.followers & (1u << k))
                    wave.paths[first + k]->share_first_field_lookup(
                        &wave.lookups[q], &wave.irradiance[q], &wave.glossy[q]);
        }
    }

    // Camera rays of sample s as one stream, then each first surface's shading, written to the
    // G-buffer.
    void trace_primary(Wave& wave, uint64_t s, IntegratorClock& clock) const {
        wave.rays.resize(wave.count);
        pixel_samples(settings_.seed, wave.pixel.data(), wave.count, s, wave.samples.data());
        for (size_t i = 0; i < wave.count; ++i) {
            const uint64_t pixel = wave.pixel[i];
            wave.rngs[i] = Pcg32(settings_.seed, stream_id(s, pixel));
            wave.film[i] = vec2(float(wave.x[i]), float(wave.y[i])) +
                           pixel_filter_.film_offset(wave.samples[i].jitter);
        }
        camera_rays_.generate_rays(wave.film.data(), wave.count, wave.rays.data());
        scene_.intersect(wave.rays, wave.hits, nullptr, RayCoherence::Coherent);
        // The first hits' surface points four at a time (Scene::surface_point_lanes), the
        // wave's last (count % 4) one by one.
        SurfacePoint points[4];
        const size_t in_lanes = wave.count - wave.count % 4;
        for (size_t i = 0; i < wave.count; ++i) {
            if (i < in_lanes) {
                if (i % 4 == 0)
                    scene_.surface_point_lanes(&wave.hits[i], points, &wave.shading.triangle);
            } else if (wave.hits[i].valid()) {
                points[i % 4] = scene_.surface_point(wave.rays[i], wave.hits[i],
                                                     &wave.shading.triangle);
            }
            // A Combined-only path writes no other pass and its film reads no other
            // (PathIntegrator::set_combined_only): the rest keep whatever they held.
            if (combined_only_)
                wave.values[i][Pass::Combined] = vec3(0.0f);
            else
                clear_pass_values(wave.values[i]);
            // Slot i's path always traces into wave.rngs[i] and wave.values[i]: it is built once
            // a call and re-armed for each pixel after.
            if (i < wave.armed) {
                wave.paths[i]->restart();
            } else {
                PathIntegrator& path = wave.paths[i].emplace(
                    scene_, camera_, lights_, settings_, &field_, wave.rngs[i], wave.values[i],
                    &clock);
                path.set_final_gather(final_gather_);
                path.set_glossy_memo(&wave.glossy_zh);
                path.set_material_lobes(&material_lobes_);
                path.set_shading_memo(&wave.shading);
                if (combined_only_) path.set_combined_only();
                wave.armed = i + 1;
            }
            PathIntegrator& path = *wave.paths[i];
            path.set_first_light_sample(wave.samples[i].u_select, wave.samples[i].u_light);
            if (final_gather_ > 0)
                path.set_gather_number(gather_number(settings_.seed, wave.pixel[i], s));
            // The pixel's G-buffer lines are fetched while its path begins (the loop below
            // then stores to cached lines: ~4% less CPU a Cornell box frame).
            g_buffer_->prefetch(wave.pixel[i]);
            wave.live[i] = path.begin(wave.rays[i], wave.hits[i], points[i % 4]);
        }
        // The G-buffer in a loop of its own: its planes are frame-sized (64 bytes a pixel,
        // ~15 MB), so its stores miss the caches, and stores leave the store queue in order.
        // Written after each path's begin(), they held back the next pixel's L1 stores
        // (Scene::surface_point's, make_shading's) until the queue filled and stalled them:
        // Scene::surface_point was ~8% of the Cornell box bench's samples for ~4% of its
        // instructions. Together, the wave's misses overlap.
        for (size_t i = 0; i < wave.count; ++i) {
            if (wave.live[i])
                g_buffer_->set_surface(wave.pixel[i], scene_, wave.paths[i]->first_surface(),
                                       wave.hits[i], camera_position_, forward_,
                                       &material_lobes_);
            else
                g_buffer_->set_miss(wave.pixel[i]);
        }
    }

    // Each light stage path's BSDF toward its light sample, then its shadow ray (in path
    // order): PathIntegrator::prepare_direct's steps, with the evaluations of four paths whose
    // field lobes the lanes cover made together (PrincipledBsdf::eval_field_lanes), so that their
    // dependent chains overlap; the others one by one. Each group's paths are finished as soon
    // as it is evaluated, while their data is still in cache.
    template <typename AddShadows>
    void direct_from_lanes(Wave& wave, size_t count, const AddShadows& add_shadows) const {
        LightLanes& lanes = wave.light_lanes;
        Ray shadows[kMaxLightSplits];
        size_t finished = 0;  // lanes [0, finished) have their shadow rays
        const auto finish_until = [&](size_t end) {
            for (; finished < end; ++finished) {
                const size_t j = finished;
                PathIntegrator& path = *wave.paths[lanes.path[j]];
                int written = 0;
                if (lanes.written[j] < 0)
                    written = path.prepare_direct(shadows);
                else if (lanes.kept[j])
                    written = path.finish_direct(shadows, lanes.samples[j], lanes.wi[j],
                                                 lanes.eval[j]);
                add_shadows(lanes.path[j], shadows, written);
            }
        };
        const PrincipledBsdf* group_bsdf[4];
        const vec3* group_wo[4];
        const vec3* group_wi[4];
        BsdfEval* group_eval[4];
        int grouped = 0;
        BsdfEval padding;  // the value of a lane past a partial group's last, not read
        const auto evaluate_group = [&]() {
            for (int k = grouped; k < 4; ++k) {
                group_bsdf[k] = group_bsdf[0];
                group_wo[k] = group_wo[0];
                group_wi[k] = group_wi[0];
                group_eval[k] = &padding;
            }
            PrincipledBsdf::eval_field_lanes(group_bsdf, group_wo, group_wi, group_eval);
            grouped = 0;
        };
        for (size_t j = 0; j < count; ++j) {
            if (lanes.written[j] < 0) continue;  // the path samples its light itself (finish_until)
            PathIntegrator& path = *wave.paths[lanes.path[j]];
            lanes.kept[j] = path.begin_direct(&lanes.samples[j], lanes.written[j], &lanes.wi[j]);
            if (!lanes.kept[j]) continue;
            bool field_lobes;
            const PrincipledBsdf& bsdf = path.direct_bsdf(&field_lobes);
            const vec3& wo = path.first_surface().wo;
            if (!field_lobes || !bsdf.eval_field_in_lanes()) {
                lanes.eval[j] = field_lobes ? bsdf.eval_field(wo, lanes.wi[j])
                                            : bsdf.eval(wo, lanes.wi[j]);
                continue;
            }
            group_bsdf[grouped] = &bsdf;
            group_wo[grouped] = &wo;
            group_wi[grouped] = &lanes.wi[j];
            group_eval[grouped] = &lanes.eval[j];
            if (++grouped == 4) {
                evaluate_group();
                finish_until(j + 1);
            }
        }
        if (grouped > 0) evaluate_group();
        finish_until(count);
    }

    // Next-event estimation at every first surface, its shadow rays as one occlusion stream.
    void trace_direct(Wave& wave) const {
        wave.shadow_rays.clear();
        Ray shadows[kMaxLightSplits];
        const auto add_shadows = [&](size_t i, const Ray* rays, int count) {
            for (int k = 0; k < count; ++k) {
                wave.shadow_paths[wave.shadow_rays.size()] = uint32_t(i);
                wave.shadow_slots[wave.shadow_rays.size()] = uint8_t(k);
                wave.shadow_rays.push_back(rays[k]);
            }
        };
        if (lights_.samples_one_rectangle()) {
            // The light stage: the light samples of the wave's first surfaces, four at a time
            // (LightSampler::sample_split_lanes, the same samples as each path's own), then
            // each path's BSDF toward its sample. The shadow rays come in the same order.
            LightLanes& lanes = wave.light_lanes;
            // Sized for the wave's capacity (Wave's constructor).
            size_t count = 0;
            for (size_t i = 0; i < wave.count; ++i) {
                if (!wave.live[i] || !wave.paths[i]->samples_lights()) continue;
                const vec3& p = wave.paths[i]->first_surface().position;
                const PixelSample& sample = wave.samples[i];
                lanes.path[count] = uint32_t(i);
                lanes.x[count] = p.x;
                lanes.y[count] = p.y;
                lanes.z[count] = p.z;
                lanes.u_select[count] = sample.u_select;
                lanes.ux[count] = sample.u_light.x;
                lanes.uy[count] = sample.u_light.y;
                ++count;
            }
            lights_.sample_split_lanes(count, lanes.x.data(), lanes.y.data(), lanes.z.data(),
                                       lanes.u_select.data(), lanes.ux.data(), lanes.uy.data(),
                                       lanes.samples.data(), lanes.written.data());
            direct_from_lanes(wave, count, add_shadows);
        } else {
            for (size_t i = 0; i < wave.count; ++i)
                if (wave.live[i]) add_shadows(i, shadows, wave.paths[i]->prepare_direct(shadows));
        }
        if (wave.shadow_rays.empty()) return;
        scene_.occluded(wave.shadow_rays, wave.occluded, nullptr, RayCoherence::Coherent);
        for (size_t j = 0; j < wave.shadow_rays.size(); ++j)
            if (!wave.occluded[j]) wave.paths[wave.shadow_paths[j]]->add_direct(wave.shadow_slots[j]);
    }

    const Scene& scene_;
    const Camera& camera_;
    const CameraRayGenerator& camera_rays_;
    const PixelFilter& pixel_filter_;  // PreviewSettings.pixel_filter and filter_width
    const LightSampler& lights_;
    const MaterialLobeTable& material_lobes_;
    const PathTracerSettings& settings_;
    const IndirectField& field_;
    const TileGrid& grid_;
    uint64_t first_, count_;
    GBuffer* g_buffer_;  // written by the work units, each in its own pixels
    Progress* progress_;
    bool screen_space_;  // lights_first_surfaces()
    const FieldLookup no_light_{ShRgb(2), vec3(0.0f)};  // first surfaces' lookup then
    float reuse_;  // the field's reuse distance; 0: every pixel makes its own lookup
    int final_gather_;  // diffuse bounces before a path reads the field (PreviewSettings)
    bool combined_only_;  // the film sums only Combined: the paths write no other pass
    // Unique in the process (next_id), so a wave kept by a thread knows whether its paths were
    // built for this frame's objects, whatever addresses a later frame's objects reuse.
    uint64_t id_;
    vec3 camera_position_, forward_;  // the camera's, for the G-buffer's depth
};

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
    path.roulette_survival = RouletteSurvival::Throughput;  // min(1, T), as before
    path.clamp_indirect = settings.clamp_indirect;
    path.filter_glossy = settings.filter_glossy;
    path.world_sampling = settings.world_sampling;
    path.light_splits = settings.light_splits;
    return path;
}

const PreviewSettings& validated(const PreviewSettings& settings) {
    validate_preview_settings(settings);
    return settings;
}

const Camera& validated(const Camera& camera) {
    validate_camera(camera);
    return camera;
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
    if (!std::isfinite(settings.filter_glossy) || settings.filter_glossy < 0.0f)
        throw InvalidArgument(format_message("PreviewSettings.filter_glossy is ",
                                             settings.filter_glossy,
                                             "; it must be finite and >= 0 (0 = off)"));
    validate_filter_width(settings.filter_width, "PreviewSettings");
    if (settings.tile_size < 1)
        throw InvalidArgument(format_message("PreviewSettings.tile_size is ", settings.tile_size,
                                             "; it must be >= 1"));
    if (settings.light_splits < 1 || settings.light_splits > kMaxLightSplits)
        throw InvalidArgument(format_message("PreviewSettings.light_splits is ",
                                             settings.light_splits, "; it must be in [1, ",
                                             kMaxLightSplits, "]"));
}

PreviewRenderer::PreviewRenderer(const Scene& scene, const PreviewSettings& settings)
    : PreviewRenderer(scene, scene.camera(), settings) {}

PreviewRenderer::PreviewRenderer(const Scene& scene, const Camera& camera,
                                 const PreviewSettings& settings)
    : scene_(&scene),
      scene_revision_(scene.revision()),
      camera_(validated(camera)),
      camera_rays_(camera),
      settings_(validated(settings)),
      pixel_filter_(settings.pixel_filter, settings.filter_width),
      path_settings_(path_settings_for(settings)),
      material_lobes_(scene),
      lights_(scene, settings.world_sampling, true, path_settings_.light_splits) {
    film_ = ProgressiveFilm(int(camera_.resolution_x), int(camera_.resolution_y),
                            settings.combined_only ? FilmPasses::CombinedOnly : FilmPasses::All);
    g_buffer_ = GBuffer(int(camera_.resolution_x), int(camera_.resolution_y));
}

void PreviewRenderer::add_frame_stage(FrameWideStage stage) {
    if (!stage.run)
        throw InvalidArgument(format_message("PreviewRenderer::add_frame_stage: stage '",
                                             stage.name, "' has no function to run"));
    frame_stages_.push_back(std::move(stage));
}

const LightSampler& PreviewRenderer::lights_for(const IndirectField& field) {
    const bool world = field.includes_world_direct(), lamps = field.includes_lights_direct();
    if (!world && !lamps) return lights_;
    if (!field_lights_ || without_world_ != world || without_lights_ != lamps) {
        field_lights_.emplace(*scene_, settings_.world_sampling, !world,
                              path_settings_.light_splits, !lamps);
        without_world_ = world;
        without_lights_ = lamps;
    }
    return *field_lights_;
}

void PreviewRenderer::render(const IndirectField* field, uint32_t samples, Progress* progress) {
    if (scene_->revision() != scene_revision_ || !scene_->committed())
        throw InvalidArgument(format_message(
            "PreviewRenderer::render: the scene was edited after this renderer was created "
            "(revision ", scene_revision_, ", now ", scene_->revision(),
            "); commit it and create a new PreviewRenderer"));
    const uint64_t first = film_.film().samples();
    if (samples == 0) return;
    if (first + samples > kMaxPathTracerSamples)
        throw InvalidArgument(format_message("PreviewRenderer::render: ", first, " + ", samples,
                                             " samples exceed the limit of ",
                                             kMaxPathTracerSamples, " per pixel"));
    const ZeroField no_field;
    const PinnedField pinned(field);  // one state of the field for the whole frame
    field = pinned.get() != nullptr ? pinned.get() : &no_field;  // none: direct light only
    // Through a final gather, a screen-space field's direct light (INSTANT_GI's filter_direct)
    // is left out: next-event estimation gives it exactly at the first surface and where the
    // gather ray lands, which a field that carries it would leave to BSDF sampling alone at
    // the first surface (and point lights to nothing).
    std::shared_ptr<const IndirectField> indirect;
    if (settings_.final_gather && field->shades_first_surfaces() &&
        (field->includes_world_direct() || field->includes_lights_direct()))
        indirect = field->without_direct();
    if (indirect) field = indirect.get();
    if (field->shades_first_surfaces() && samples > 1) {
        // A screen-space field lights the G-buffer of one sample index, and its gather rays read
        // that sample's view of it (sample_view): one frame per sample, so that n samples at
        // once give the frames of n calls of one sample each. A cancel keeps the samples
        // finished before it.
        PreviewTimings sum;
        for (uint32_t s = 0; s < samples; ++s) {
            render(field, 1, progress);
            sum.primary += timings_.primary;
            sum.direct += timings_.direct;
            sum.indirect += timings_.indirect;
            sum.frame_stages += timings_.frame_stages;
            sum.total += timings_.total;
        }
        timings_ = sum;
        return;
    }
    // A field whose samples each read light of their own: sample `first`'s view of it, for
    // the lookups of every path (one sample index per call here).
    const std::unique_ptr<const IndirectField> view =
        samples == 1 ? field->sample_view(first) : nullptr;
    if (view) field = view.get();
    const TimePoint frame_start = now();
    const LightSampler& lights = lights_for(*field);
    const bool screen_space = lights_first_surfaces(*field, settings_.final_gather);
    g_buffer_.set_field_lobes(screen_space);
    // A screen-space field's frame-wide stage runs first, so later stages see its light. Every
    // frame-wide stage is timed apart from the tiles.
    double stage_seconds = 0.0;
    std::vector<FrameWideStage> screen_stages;
    if (screen_space) {
        const vec3 camera_position(camera_.world_from_camera[3]);
        const float clamp = settings_.clamp_indirect;
        screen_stages.push_back({"screen_space_field",
                                 [field, camera_position, clamp](const GBuffer& g, Film& film,
                                                                 uint64_t first_sample,
                                                                 uint64_t count, Progress* p) {
                                     field->shade_first_surfaces(g, camera_position, clamp, film,
                                                                 first_sample, count, p);
                                 }});
        screen_stages.insert(screen_stages.end(), frame_stages_.begin(), frame_stages_.end());
    } else {
        screen_stages = frame_stages_;
    }
    for (FrameWideStage& stage : screen_stages)
        stage.run = [run = std::move(stage.run), &stage_seconds](
                        const GBuffer& g, Film& film, uint64_t first_sample, uint64_t count,
                        Progress* p) {
            const TimePoint start = now();
            run(g, film, first_sample, count, p);
            stage_seconds += seconds_since(start);
        };
    const TileGrid grid(film_.film().width(), film_.film().height(),
                        even_tile_side(settings_.tile_size));
    const FrameWork work(*scene_, camera_, camera_rays_, pixel_filter_, lights, material_lobes_,
                         path_settings_, *field, grid, first, samples, g_buffer_, progress,
                         settings_.reuse_field_lookups, settings_.final_gather,
                         settings_.combined_only);
    const uint64_t tile_pixels = uint64_t(grid.tile) * uint64_t(grid.tile);
    const uint64_t tiles_per_unit = std::max<uint64_t>(1, kChunkPixels / tile_pixels);
    std::vector<StageSeconds> busy(grid.count());  // per work unit, at its first tile
    const TimePoint tiles_start = now();
    render_frame_tiles(
        film_, grid, tiles_per_unit, samples, progress,
        [&](uint64_t begin, uint64_t end, Film& target, const Film& base) {
            work.render_tiles(begin, end, target, base, &busy[begin]);
        },
        &g_buffer_, screen_stages);
    PreviewTimings timings =
        split_wall_time(std::max(0.0, seconds_since(tiles_start) - stage_seconds), busy);
    timings.frame_stages = stage_seconds;
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
