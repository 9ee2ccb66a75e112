// Equal-time convergence (docs/benchmarks.md): PSNR against a long path-traced reference after
// 0.25, 0.5, 1 and 2 s of wall time, for the photon lattice with the preview renderer and for
// the plain path tracer given the same time, on the Cornell-like room of bench_scenes.h and on
// that room with a sphere of 502,636 triangles, at 320 x 180.
//
// PSNR is the tests' (tests/python/test_photon_lattice.py): the reference's mean luminance mapped
// to 0.18 (auto-exposure), both images through the sRGB curve and clamped to [0, 1], then
// 10 log10(1 / MSE) over the RGB of all pixels.
//
// Policies for a budget T (wall clock, everything included: construction, photons, frames):
//   path tracer — 1-spp progressive passes while the next pass is predicted to fit in T;
//   photon lattice — photon passes of the default budget (PhotonLatticeSettings) for up to T/4
//     (at least one), then 1-spp preview passes while the next is predicted to fit.
// Prints the time actually spent and the counts behind each figure. A plain main printing
// figures: benchmarks are not tests.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "bench_scenes.h"
#include "io/png_image.h"
#include "lattice/photon_lattice.h"
#include "render/path_tracer.h"
#include "render/preview_renderer.h"

using namespace shgi;

namespace {

constexpr uint32_t kWidth = 320, kHeight = 180;
constexpr uint32_t kReferenceSamples = 2048;
constexpr double kBudgets[] = {0.25, 0.5, 1.0, 2.0};
constexpr float kMiddleGrey = 0.18f;
constexpr float kPhotonShare = 0.25f;  // of the budget, for photon passes

std::vector<float> combined_rgb(const Image& image) {
    const std::vector<float> rgba = image.layer_pixels("Combined");
    std::vector<float> rgb;
    rgb.reserve(rgba.size() / 4 * 3);
    for (size_t i = 0; i < rgba.size(); i += 4) rgb.insert(rgb.end(), &rgba[i], &rgba[i] + 3);
    return rgb;
}

double psnr(const std::vector<float>& reference, const std::vector<float>& image) {
    double mean_luminance = 0.0;
    for (size_t i = 0; i < reference.size(); i += 3)
        mean_luminance += luminance(vec3(reference[i], reference[i + 1], reference[i + 2]));
    mean_luminance /= double(reference.size() / 3);
    const float exposure = float(kMiddleGrey / mean_luminance);
    auto display = [&](float linear) {
        return std::clamp(srgb_from_linear(std::max(0.0f, linear * exposure)), 0.0f, 1.0f);
    };
    double squared = 0.0;
    for (size_t i = 0; i < reference.size(); ++i) {
        const double d = double(display(reference[i])) - double(display(image[i]));
        squared += d * d;
    }
    return 10.0 * std::log10(double(reference.size()) / squared);
}

// Calls step() while the next call, predicted to last as long as the slowest so far, fits in
// the budget (measured from `start`); returns how many calls were made (at least `minimum`).
template <typename Step>
int run_until(const TimePoint& start, double budget, int minimum, Step&& step) {
    int calls = 0;
    double slowest = 0.0;
    while (calls < minimum || seconds_since(start) + slowest <= budget) {
        const auto call_start = now();
        step();
        slowest = std::max(slowest, seconds_since(call_start));
        ++calls;
    }
    return calls;
}

void run(const char* name, Scene& scene) {
    scene.commit();
    std::printf("%s %ux%u, reference: path tracer %u spp ...\n", name, kWidth, kHeight,
                kReferenceSamples);
    std::fflush(stdout);
    PathTracerSettings reference_settings;
    reference_settings.samples = kReferenceSamples;
    reference_settings.seed = 1000;
    const std::vector<float> reference =
        combined_rgb(render_path_traced(scene, reference_settings));

    std::printf("  budget | path tracer: PSNR   spp   time  | photon lattice: PSNR  passes spp "
                "  time\n");
    for (const double budget : kBudgets) {
        auto start = now();
        PathTracer tracer(scene, PathTracerSettings{});
        run_until(start, budget, 1, [&] { tracer.render(1); });
        const double traced_time = seconds_since(start);
        const double traced_psnr = psnr(reference, combined_rgb(tracer.image()));

        start = now();
        PhotonLattice lattice(scene, PhotonLatticeSettings{});
        const int passes = run_until(start, kPhotonShare * budget, 1, [&] { lattice.solve(); });
        PreviewRenderer preview(scene, PreviewSettings{});
        const int samples = run_until(start, budget, 1, [&] { preview.render(&lattice, 1); });
        const double preview_time = seconds_since(start);
        const double preview_psnr = psnr(reference, combined_rgb(preview.image()));

        std::printf("  %5.2f s |            %5.1f dB %4u %5.2f s |                %5.1f dB %3d "
                    "%4d %5.2f s\n",
                    budget, traced_psnr, tracer.samples_done(), traced_time, preview_psnr, passes,
                    samples, preview_time);
    }
}

}  // namespace

int main() {
    Scene cornell = bench::cornell_box(kWidth, kHeight);
    run("cornell box", cornell);
    Scene dense = bench::cornell_box_with_dense_sphere(kWidth, kHeight);
    run("cornell box + dense sphere", dense);
    return 0;
}
