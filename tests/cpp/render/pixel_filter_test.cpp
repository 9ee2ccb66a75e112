// Film > Pixel Filter (render/pixel_filter.h) against Cycles' filter functions integrated
// independently of the sampler's table: stratified samples land in each bin of the span with the
// filter's share of its integral; the box of one pixel is the jitter bit for bit; offsets are
// symmetric, monotone and inside the span; bad widths are refused; and an edge rendered through a
// Blackman-Harris filter has the filter's cumulative profile across it.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "render/path_tracer.h"
#include "render/pixel_filter.h"
#include "render/preview_renderer.h"
#include "render_test_scenes.h"
#include "support/expect_error.h"

namespace shgi {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Cycles' filter_func_* over its table's span (scene/film.cpp), transcribed independently of
// pixel_filter.cpp: Gaussian width w -> span 3 w, Blackman-Harris width w -> span 2 w.
double cycles_weight(PixelFilterType type, double v, double width) {
    if (type == PixelFilterType::Gaussian) {
        const double span = 3.0 * width;
        const double t = v * 6.0 / span;
        return std::exp(-2.0 * t * t);
    }
    if (type == PixelFilterType::BlackmanHarris) {
        const double span = 2.0 * width;
        const double a = 2.0 * kPi * (v / span + 0.5);
        return 0.35875 - 0.48829 * std::cos(a) + 0.14128 * std::cos(2.0 * a) -
               0.01168 * std::cos(3.0 * a);
    }
    return 1.0;
}

double half_span(PixelFilterType type, double width) {
    return type == PixelFilterType::Gaussian ? 1.5 * width
           : type == PixelFilterType::BlackmanHarris ? width
                                                      : 0.5 * width;
}

// The filter's integral over [a, b] by Simpson's rule on 2000 intervals.
double integral(PixelFilterType type, double width, double a, double b) {
    const int n = 2000;
    const double h = (b - a) / n;
    double sum = cycles_weight(type, a, width) + cycles_weight(type, b, width);
    for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * cycles_weight(type, a + i * h, width);
    return sum * h / 3.0;
}

struct FilterCase {
    PixelFilterType type;
    float width;
};

class PixelFilterShares : public ::testing::TestWithParam<FilterCase> {};

// 2^16 stratified u: bin j of 30 over the span holds its share of the filter's integral within
// 1e-3 (the table's 1024 bins put a midpoint error of ~1e-5 on each share; stratification puts
// at most 1/2^16 on a count).
TEST_P(PixelFilterShares, StratifiedSamplesFillEachBinWithTheFiltersShare) {
    const FilterCase c = GetParam();
    const PixelFilter filter(c.type, c.width);
    const double half = half_span(c.type, c.width);
    EXPECT_FLOAT_EQ(filter.half_span(), float(half));
    const int n = 1 << 16, bins = 30;
    std::vector<int> counts(bins, 0);
    for (int i = 0; i < n; ++i) {
        const float x = filter.offset((float(i) + 0.5f) / float(n));
        ASSERT_LE(std::fabs(x), float(half) * (1.0f + 1e-6f));
        const int j = std::clamp(int((x + half) / (2.0 * half) * bins), 0, bins - 1);
        ++counts[size_t(j)];
    }
    const double total = integral(c.type, c.width, -half, half);
    for (int j = 0; j < bins; ++j) {
        const double a = -half + 2.0 * half * j / bins, b = a + 2.0 * half / bins;
        EXPECT_NEAR(double(counts[size_t(j)]) / n, integral(c.type, c.width, a, b) / total, 1e-3)
            << "bin " << j;
    }
}

INSTANTIATE_TEST_SUITE_P(CyclesFilters, PixelFilterShares,
                         ::testing::Values(FilterCase{PixelFilterType::BlackmanHarris, 1.5f},
                                           FilterCase{PixelFilterType::BlackmanHarris, 0.5f},
                                           FilterCase{PixelFilterType::Gaussian, 1.5f},
                                           FilterCase{PixelFilterType::Box, 2.0f}));

TEST(PixelFilter, BoxOfOnePixelIsTheJitterBitForBit) {
    const PixelFilter filter;
    for (const float u : {0.0f, 1e-7f, 0.25f, 0.5f, 0.7f, 0.99999994f}) {
        const vec2 jitter(u, 1.0f - u * 0.5f);
        const vec2 film = filter.film_offset(jitter);
        EXPECT_EQ(film.x, jitter.x);
        EXPECT_EQ(film.y, jitter.y);
    }
}

TEST(PixelFilter, OffsetsAreMonotoneSymmetricAndInsideTheSpan) {
    const PixelFilter filter(PixelFilterType::BlackmanHarris, 1.5f);
    float last = -2.0f;
    for (int i = 0; i <= 4096; ++i) {
        const float u = std::min(float(i) / 4096.0f, 0.99999994f);
        const float x = filter.offset(u);
        EXPECT_GE(x, last);
        EXPECT_LE(std::fabs(x), 1.5f);
        EXPECT_NEAR(x, -filter.offset(1.0f - u), 2e-4f) << u;  // the table's float rounding
        last = x;
    }
    // The density the sampler draws from integrates to 1 over the span.
    double sum = 0.0;
    for (int i = 0; i < 3000; ++i) sum += filter.density(-1.5f + 3.0f * (i + 0.5f) / 3000.0f);
    EXPECT_NEAR(sum * 3.0 / 3000.0, 1.0, 1e-4);
    EXPECT_EQ(filter.density(1.6f), 0.0f);
}

TEST(PixelFilter, RefusesWidthsOutsideCyclesRange) {
    for (const float bad : {0.0f, 0.005f, 10.5f, std::nanf(""), INFINITY}) {
        testing::expect_invalid_argument(
            [&] { PixelFilter filter(PixelFilterType::BlackmanHarris, bad); }, "filter_width");
        PathTracerSettings path;
        path.filter_width = bad;
        testing::expect_invalid_argument([&] { validate_path_tracer_settings(path); },
                                         "PathTracerSettings.filter_width");
        PreviewSettings preview;
        preview.filter_width = bad;
        testing::expect_invalid_argument([&] { validate_preview_settings(preview); },
                                         "PreviewSettings.filter_width");
    }
}

// The filter's integral from -half span to d, normalised (its CDF).
double cdf(PixelFilterType type, double width, double d) {
    const double half = half_span(type, width);
    d = std::clamp(d, -half, half);
    return integral(type, width, -half, d) / integral(type, width, -half, half);
}

// An emitter of radiance 1 over x < 0 seen straight down by a 16-pixel orthographic camera of
// 1 m pixels: the edge lies at film x = 8 pixels, so column c's mean is the share of its samples
// whose film point c + 0.5 + t falls left of it, the filter's CDF at 8 - c - 0.5 (mirrored when
// the film's x runs the other way).
Scene half_lit_floor() {
    Scene scene;
    Material material = test::lambert(0.0f);
    material.emission_color = vec3(1.0f);
    material.emission_strength = 1.0f;
    scene.add_material(material);
    scene.add_instance(scene.add_mesh(test::quad(vec3(-20.0f, -20.0f, 0.0f),
                                                 vec3(20.0f, 0.0f, 0.0f),
                                                 vec3(0.0f, 40.0f, 0.0f))),
                       mat4(1.0f));
    scene.set_world(test::black_world());
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 1.0f), 16.0f, 16));
    scene.commit();
    return scene;
}

void expect_edge_profile(const std::vector<float>& emit, const FilterCase& c, const char* who) {
    const int side = 16;
    std::vector<double> column(side, 0.0);
    for (int y = 0; y < side; ++y)
        for (int x = 0; x < side; ++x) column[size_t(x)] += emit[size_t((y * side + x) * 3)] / side;
    const bool left_lit = column[0] > column[side - 1];
    for (int x = 0; x < side; ++x) {
        const double expected = cdf(c.type, c.width, 0.5 * side - x - 0.5);
        EXPECT_NEAR(column[size_t(x)], left_lit ? expected : 1.0 - expected, 3e-3)
            << who << " column " << x;
    }
}

// Both renderers' first rays go through the filter: the edge's profile is its CDF, within the
// stratified samples' error (1024 a pixel, 16 rows a column).
TEST(PixelFilter, AnEdgeSeenThroughTheFilterHasItsCumulativeProfile) {
    const Scene scene = half_lit_floor();
    for (const FilterCase c : {FilterCase{PixelFilterType::BlackmanHarris, 1.5f},
                               FilterCase{PixelFilterType::Gaussian, 1.5f},
                               FilterCase{PixelFilterType::Box, 1.0f}}) {
        PathTracerSettings path = test::settings_with_samples(1024);
        path.pixel_filter = c.type;
        path.filter_width = c.width;
        PathTracer tracer(scene, path);
        tracer.render(1024);
        expect_edge_profile(tracer.film().pixels(Pass::Emit), c, "path tracer");
        PreviewSettings preview;
        preview.pixel_filter = c.type;
        preview.filter_width = c.width;
        PreviewRenderer renderer(scene, preview);
        renderer.render(nullptr, 1024);
        expect_edge_profile(renderer.film().pixels(Pass::Emit), c, "preview");
    }
}

}  // namespace
}  // namespace shgi
