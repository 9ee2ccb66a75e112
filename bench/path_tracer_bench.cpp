// Path tracer throughput against the raw Embree ray rate, measured in the same run.
//
// Scene: a Cornell-box-like room (2 m closed box, red and green side walls, two inner blocks,
// a 0.5 m square area light under the ceiling), 128 x 128 pixels, perspective camera inside.
// Printed figures:
//  - path samples per second of PathTracer::render (all threads, default settings: 12 bounces
//    with Cycles' per-type limits, NEE + MIS, Russian roulette);
//  - incoherent rays per second: random origins inside the box and uniformly random directions,
//    through raw Embree on a flattened one-level scene (scene/embree_reference.h, rtcIntersect1)
//    and through Scene::intersect's batch interface, on the same rays, all threads;
//  - their ratio: the cost of one path sample in raw closest-hit rays (it folds in shadow
//    rays, shading and BSDF/light sampling, so it is not a count of rays traced).
// A plain main printing figures (docs/architecture.md: benchmarks are not tests).
#include <cstdio>

#include "bench_scenes.h"
#include "render/path_tracer.h"

using namespace shgi;

namespace {

constexpr uint32_t kResolution = 128;
constexpr uint32_t kSamples = 16;

}  // namespace

int main() {
    Scene scene = bench::cornell_box(kResolution, kResolution);
    scene.commit();

    PathTracerSettings settings;
    settings.samples = kSamples;
    PathTracer tracer(scene, settings);
    tracer.render(1);  // warm-up
    const auto start = now();
    tracer.render(kSamples);
    const double path_seconds = seconds_since(start);
    const double paths = double(kResolution) * kResolution * kSamples;
    const double paths_per_second = paths / path_seconds;
    const EmbreeReference embree(scene);
    const bench::RayRates rates = bench::incoherent_ray_rates(scene, embree);
    const double rays_per_second = rates.embree;

    std::printf("path tracer: %u x %u px, %u spp in %.3f s: %.3g path samples/s\n", kResolution,
                kResolution, kSamples, path_seconds, paths_per_second);
    std::printf("raw Embree incoherent closest-hit (flattened one-level scene, all threads): "
                "%.3g rays/s; through Scene::intersect %.3g rays/s (raw is %.2fx Scene)\n",
                rays_per_second, rates.scene, rays_per_second / rates.scene);
    std::printf("ratio: one path sample costs %.2f raw rays\n", rays_per_second / paths_per_second);
    return 0;
}
