// ProbeGrid figures (issue 6, seed 002 Tables 5.1-5.3), with the raw Embree incoherent ray rate
// measured in the same run.
//
// Scenes: the Cornell-like room of bench_scenes.h, and the same room holding a UV sphere of
// ~500k triangles. For each, printed: for L1, L2 and L4 probes (the fitted 8 x 8 x 8 grid, 256
// paths per probe), the update time of one pass (best of three), probe path samples per second
// and rays per second, each with its ratio to the raw rate; and the time a 16 x 16 x 8 grid of L2
// probes takes to converge until 95% of its active probes have a relative standard error of the
// DC luminance below 2% (ProbeGrid::relative_error; hysteresis 0.99 so that the exponential
// blend's noise floor lies below the threshold). A plain main printing figures: benchmarks are
// not tests.
#include <algorithm>
#include <cstdio>
#include <vector>

#include "bench_scenes.h"
#include "probes/probe_grid.h"

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

void run(const char* name, Scene& scene) {
    scene.commit();
    const double raw = bench::incoherent_ray_rate(scene);
    std::printf("%s: %zu triangles\n", name, size_t(scene.stats().instanced_triangles));
    std::printf("  embree incoherent closest-hit: %.3g rays/s\n", raw);
    update_rates(scene, raw);
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
