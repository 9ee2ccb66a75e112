// ProbeGrid figures (seed 002 Tables 5.1-5.3; docs/benchmarks.md, "Probe grid"), with the raw
// Embree incoherent ray rate measured in the same run.
//
// Scenes: the Cornell-like room of bench_scenes.h, and the same room holding a UV sphere of
// ~500k triangles. For each, printed: for L1, L2 and L4 probes (the fitted 8 x 8 x 8 grid, 256
// paths per probe), the update time of one pass (best of three), probe path samples per second
// and rays per second, each with its ratio to the raw rate; and the time a 16 x 16 x 8 grid of L2
// probes takes to converge until 95% of its active probes have a relative standard error of the
// DC luminance below 2% (ProbeGrid::relative_error; hysteresis 0.99 so that the exponential
// blend's noise floor lies below the threshold). A plain main printing figures: benchmarks are
// not tests.
// Beside the L1-L4 rates, the floor under them: the leanest Lambert probe update's ray ratio;
// and 640 x 360 viewport frames with the grid, with and without screen-space reuse of lookups.
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <vector>

#include "bench_scenes.h"
#include "probes/probe_grid.h"
#include "render/preview_renderer.h"
#include "render/shading.h"
#include "sh/sh_projection.h"
#include "util/parallel.h"
#include "util/sampling.h"

using namespace shgi;

namespace {

constexpr int kRuns = 3;
constexpr float kConvergedError = 0.02f;
constexpr int kMaxPasses = 400;

float percentile95(std::vector<float> values) {
    if (values.empty()) return 0.0f;
    const size_t k = (values.size() * 95) / 100;
    std::nth_element(values.begin(), values.begin() + long(std::min(k, values.size() - 1)),
                     values.end());
    return values[std::min(k, values.size() - 1)];
}

void update_rates(const Scene& scene, double raw) {
    for (int order : {1, 2, 4}) {
        ProbeGridSettings settings;
        settings.order = order;
        ProbeGrid grid(scene, settings);
        ProbeGridTimings best;
        best.update = 1e30;
        for (int run = 0; run < kRuns; ++run) {
            grid.update();
            if (grid.timings().update < best.update) best = grid.timings();
        }
        const double paths = double(best.paths) / best.update;
        const double rays = double(best.rays) / best.update;
        std::printf("  L%d: %zu probes (%zu active), one pass %.3f s: %.3g paths/s (ratio to raw "
                    "%.3f), %.3g rays/s (ratio %.2f, %.2f rays per path)\n",
                    order, grid.probe_count(), grid.active_count(), best.update, paths,
                    paths / raw, rays, rays / raw, double(best.rays) / double(best.paths));
    }
}

// The viewport's frames with a probe grid (the fitted grid after one pass of L2 probes) at
// 640 x 360: best of kFrames progressive 1-spp Combined-only frames, alternating frame by frame
// with a renderer that makes one probe lookup per pixel (no screen-space reuse).
void preview_frames(const Scene& scene) {
    constexpr int kFrames = 20;
    ProbeGrid grid(scene, ProbeGridSettings{});
    grid.update();
    Camera camera = scene.camera();
    camera.resolution_x = 640;
    camera.resolution_y = 360;
    PreviewSettings settings;
    settings.combined_only = true;
    PreviewRenderer shared(scene, camera, settings);
    settings.reuse_field_lookups = false;
    PreviewRenderer own(scene, camera, settings);
    double best_shared = 1e30, best_own = 1e30;
    for (int frame = 0; frame < kFrames; ++frame) {
        shared.render(&grid, 1);
        best_shared = std::min(best_shared, shared.timings().total);
        own.render(&grid, 1);
        best_own = std::min(best_own, own.timings().total);
    }
    std::printf("  preview 640x360 with the L2 grid, progressive 1-spp Combined-only frames (best "
                "of %d): %.1f ms, %.1f ms with one lookup per pixel\n",
                kFrames, best_shared * 1e3, best_own * 1e3);
}

void convergence(const Scene& scene) {
    ProbeGridSettings settings;
    settings.hysteresis = 0.99f;
    ProbeVolume volume;
    const Bounds3 bounds = scene.bounds();
    const vec3 centre = 0.5f * (bounds.lower + bounds.upper);
    volume.world_from_volume = glm::translate(mat4(1.0f), centre) *
                               glm::scale(mat4(1.0f), 0.5f * bounds.extent());
    volume.resolution = ivec3(16, 16, 8);
    settings.volumes = {volume};
    const auto start = now();
    ProbeGrid grid(scene, settings);
    float p95 = 0.0f;
    int passes = 0;
    while (passes < kMaxPasses) {
        grid.update();
        ++passes;
        const std::vector<float> error = grid.relative_error();
        std::vector<float> active;
        for (size_t i = 0; i < error.size(); ++i)
            if (grid.data().active[i]) active.push_back(error[i]);
        p95 = percentile95(active);
        if (p95 <= kConvergedError) break;
    }
    std::printf("  16x16x8 L2 grid (%zu active probes, 256 paths per pass): 95th-percentile "
                "relative error %.4f after %d passes, %.2f s (placement %.3f s)\n",
                grid.active_count(), p95, passes, seconds_since(start), grid.timings().placement);
}

// The floor under the probe ray ratio: the leanest probe update there is in the bench rooms, for
// scale beside the real one. From each of the fitted grid's probe positions (the 8 x 8 x 8 lattice
// of cell centres in the scene's box), paths along Fibonacci directions do, at every hit, only
// what any path-traced probe must: the surface point, next-event estimation with one shadow ray
// to a random point of the area light (Lambert), Russian roulette by the material's base colour
// and a cosine-weighted Lambert bounce; the path's radiance goes into the probe's L2 SH. No BSDF,
// no MIS, no visibility moments, no passes. The same single-ray queries as ProbeGrid::update, on
// all threads; rays per second (closest-hit and shadow rays) and rays per path, best of kRuns.
struct ProbeFloor {
    double rays_per_second = 0.0, rays_per_path = 0.0;
};

ProbeFloor lean_probe_floor(const Scene& scene) {
    constexpr int kSide = 8;
    constexpr uint32_t kPaths = 256;
    constexpr float kLightArea = bench::kLightSide * bench::kLightSide;
    const float light_radiance = bench::kLightPower / (kPi * kLightArea);
    const Bounds3 bounds = scene.bounds();
    ProbeFloor best;
    for (int run = 0; run < kRuns; ++run) {
        std::atomic<uint64_t> rays{0};
        const auto start = now();
        parallel_for(0, uint64_t(kSide * kSide * kSide), 8, [&](uint64_t begin, uint64_t end) {
            uint64_t local_rays = 0;
            for (uint64_t probe = begin; probe < end; ++probe) {
                const vec3 cell(float(probe % kSide), float(probe / kSide % kSide),
                                float(probe / (kSide * kSide)));
                const vec3 position =
                    bounds.lower + (cell + 0.5f) / float(kSide) * bounds.extent();
                ShRgb estimate(2);
                for (uint32_t r = 0; r < kPaths; ++r) {
                    Pcg32 rng(uint64_t(run), probe * kPaths + r);
                    Ray ray;
                    ray.origin = position;
                    ray.direction = fibonacci_sphere(r, kPaths);
                    const vec3 first_direction = ray.direction;
                    vec3 throughput(1.0f), radiance(0.0f);
                    for (int bounce = 0; bounce < 8; ++bounce) {
                        const Hit hit = scene.intersect(ray);
                        ++local_rays;
                        if (!hit.valid()) break;
                        const SurfacePoint sp = scene.surface_point(ray, hit);
                        vec3 n = sp.geometric_normal;
                        if (glm::dot(n, ray.direction) > 0.0f) n = -n;
                        const vec3 albedo = scene.materials()[sp.material_id].base_color;
                        const vec3 to_light = bench::point_on_light(rng) - sp.position;
                        const float d2 = glm::dot(to_light, to_light);
                        const vec3 wi = to_light / std::sqrt(d2);
                        const float cos_surface = glm::dot(wi, n), cos_light = -wi.z;
                        if (cos_surface > 0.0f && cos_light > 0.0f) {
                            Ray shadow;
                            shadow.origin = offset_origin(sp.position, n);
                            shadow.direction = to_light;
                            shadow.tmax = 0.999f;
                            ++local_rays;
                            if (!scene.occluded(shadow))
                                radiance += throughput * albedo *
                                            (kInvPi * light_radiance * cos_surface * cos_light *
                                             kLightArea / d2);
                        }
                        const float survive = max_component(albedo);
                        if (rng.next_float() >= survive) break;
                        throughput *= albedo / survive;
                        ray.origin = offset_origin(sp.position, n);
                        ray.direction = Frame::from_z(n).to_world(
                            sample_cosine_hemisphere(rng.next_vec2()));
                        ray.tmin = 0.0f;
                        ray.tmax = kInfinity;
                    }
                    sh_add_sample(estimate, first_direction, radiance * (kFourPi / kPaths));
                }
                if (!(estimate[0].x >= 0.0f)) std::printf("  (negative probe)\n");  // keeps it live
            }
            rays += local_rays;
        });
        const double rate = double(rays.load()) / seconds_since(start);
        if (rate > best.rays_per_second)
            best = {rate, double(rays.load()) / double(kSide * kSide * kSide * kPaths)};
    }
    return best;
}

void run(const char* name, Scene& scene) {
    scene.commit();
    const double raw = bench::incoherent_ray_rate(scene);
    std::printf("%s: %zu triangles\n", name, size_t(scene.stats().instanced_triangles));
    std::printf("  embree incoherent closest-hit: %.3g rays/s\n", raw);
    update_rates(scene, raw);
    const ProbeFloor floor = lean_probe_floor(scene);
    std::printf("  leanest Lambert probe update (no BSDF, no MIS, no visibility): %.3g rays/s "
                "(ratio %.2f, %.2f rays per path)\n",
                floor.rays_per_second, floor.rays_per_second / raw, floor.rays_per_path);
    preview_frames(scene);
    convergence(scene);
}

}  // namespace

int main() {
    Scene cornell = bench::cornell_box(64, 64);
    run("cornell box", cornell);
    Scene dense = bench::cornell_box_with_dense_sphere(64, 64);
    run("cornell box + dense sphere", dense);
    return 0;
}
