// PhotonLattice and preview renderer figures (issue 4, seed 000 Tables 5 and 6), with the raw
// Embree incoherent ray rate measured in the same run.
//
// Scenes: the Cornell-like room of bench_scenes.h, and the same room holding a UV sphere of
// ~500k triangles. For each, printed: photon bounces (rays traced by the photon tracer) per
// second and their ratio to the raw rate, and a bounce's time split into the ray query (at the
// raw rate) and the rest; injection rate (stored photons per second); the
// solve's stage times; and the frame time of a 640 x 360 preview with the solved field, at 1
// sample per pixel (one progressive viewport frame) and 16 (PreviewSettings' default), with its
// stage times, best of three runs each; and the best of 40 1-spp frames added to one renderer.
// A plain main printing figures: benchmarks are not tests.
#include <algorithm>
#include <cstdio>

#include "bench_scenes.h"
#include "lattice/photon_lattice.h"
#include "render/preview_renderer.h"

using namespace shgi;

namespace {

constexpr int kRuns = 3;
constexpr int kProgressiveFrames = 40;

void run(const char* name, Scene& scene) {
    scene.commit();
    const double raw = bench::incoherent_ray_rate(scene);
    PhotonLatticeSettings settings;
    PhotonLattice lattice(scene, settings);
    PhotonLatticeTimings best;
    best.emit_trace = best.injection = best.blur = 1e30;
    for (int run = 0; run < kRuns; ++run) {
        lattice.reset();
        lattice.solve();
        const PhotonLatticeTimings& t = lattice.timings();
        if (t.emit_trace < best.emit_trace) best = t;
    }
    const double bounce_rate = double(best.bounces) / best.emit_trace;
    std::printf("%s: %zu triangles\n", name, size_t(scene.stats().instanced_triangles));
    std::printf("  embree incoherent closest-hit: %.3g rays/s\n", raw);
    std::printf("  photons: %llu emitted, %llu stored, %llu bounces in %.3f s: %.3g bounces/s, "
                "ratio to raw %.2f\n",
                (unsigned long long)best.photons_emitted, (unsigned long long)best.photons_stored,
                (unsigned long long)best.bounces, best.emit_trace, bounce_rate, bounce_rate / raw);
    // Where a bounce's time goes: the same ray query as the raw rate, plus everything else
    // (emission, surface set-up, BSDF sampling, storing); issue 4's 0.7 needs the rest to fit in
    // 0.43 ray queries.
    const double bounce_ns = 1e9 / bounce_rate, ray_ns = 1e9 / raw;
    std::printf("  per bounce: %.1f ns = %.1f ns ray query + %.1f ns the rest (%.2f ray queries)\n",
                bounce_ns, ray_ns, bounce_ns - ray_ns, (bounce_ns - ray_ns) / ray_ns);
    std::printf("  injection: %.4f s (%.3g photons/s), blur %.4f s\n", best.injection,
                double(best.photons_stored) / best.injection, best.blur);
    for (uint32_t samples : {1u, 16u}) {
        PreviewSettings preview;
        preview.samples = samples;
        PreviewTimings fastest;
        fastest.total = 1e30;
        for (int run = 0; run < kRuns; ++run) {
            PreviewTimings t;
            render_preview(scene, &lattice, preview, nullptr, &t);
            if (t.total < fastest.total) fastest = t;
        }
        std::printf("  preview 640x360, %2u spp: %.1f ms (primary %.1f, direct %.1f, indirect "
                    "%.1f)\n",
                    samples, fastest.total * 1e3, fastest.primary * 1e3, fastest.direct * 1e3,
                    fastest.indirect * 1e3);
    }
    // The viewport's pattern: one renderer, a 1-spp frame added per redraw (each pixel's sample
    // is accumulated onto the film it already has). Best of kProgressiveFrames.
    PreviewSettings preview;
    PreviewRenderer renderer(scene, preview);
    PreviewTimings fastest;
    fastest.total = 1e30;
    for (int frame = 0; frame < kProgressiveFrames; ++frame) {
        renderer.render(&lattice, 1);
        if (renderer.timings().total < fastest.total) fastest = renderer.timings();
    }
    std::printf("  preview 640x360, progressive 1-spp frames (best of %d): %.1f ms (primary %.1f, "
                "direct %.1f, indirect %.1f)\n",
                kProgressiveFrames, fastest.total * 1e3, fastest.primary * 1e3,
                fastest.direct * 1e3, fastest.indirect * 1e3);
}

}  // namespace

int main() {
    Scene cornell = bench::cornell_box(640, 360);
    run("cornell box", cornell);
    Scene dense = bench::cornell_box_with_dense_sphere(640, 360);
    run("cornell box + dense sphere", dense);
    return 0;
}
