// The frame pipeline: the tile grid covers the image exactly once; a frame-wide stage runs after
// every tile, sees the whole G-buffer across tile borders and the film with the frame's samples;
// a stage that fails leaves the film as it was (ProgressiveFilm's contract).
#include "render/frame_pipeline.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "render/preview_renderer.h"
#include "render_test_scenes.h"

namespace shgi {
namespace {

constexpr float kCameraHeight = 0.5f;  // test::plane_scene's camera, m above the plane
constexpr uint32_t kResolution = 8;

TEST(FramePipeline, TileGridCoversTheImageOnce) {
    for (const int side : {1, 2, 3, 16, 1 << 20}) {
        const TileGrid grid(7, 5, side);
        std::vector<int> covered(35, 0);
        for (uint64_t t = 0; t < grid.count(); ++t) {
            int x0, x1, y0, y1;
            grid.bounds(t, &x0, &x1, &y0, &y1);
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) ++covered[size_t(y * 7 + x)];
        }
        for (size_t i = 0; i < covered.size(); ++i)
            EXPECT_EQ(covered[i], 1) << "pixel " << i << ", tile side " << side;
    }
    EXPECT_THROW(TileGrid(4, 4, 0), InvalidArgument);
}

TEST(FramePipeline, StagesHaveTheirNames) {
    EXPECT_STREQ(frame_stage_name(FrameStage::CameraRays), "camera_rays");
    EXPECT_STREQ(frame_stage_name(FrameStage::FrameFilters), "frame_filters");
    EXPECT_STREQ(frame_stage_name(FrameStage::Film), "film");
}

// Tiles of 2 x 2 on an 8 x 8 frame: a frame-wide stage reads each pixel's right and lower
// neighbours, half of them in another tile, and finds every one written (the plane fills the
// view, at depth 0.5 m), on one thread and on two.
TEST(FramePipeline, FrameWideStageReadsNeighboursAcrossTileBorders) {
    Scene scene = test::plane_scene(0.5f, kResolution);
    scene.commit();
    for (const int threads : {1, 2}) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        PreviewSettings settings;
        settings.tile_size = 2;
        PreviewRenderer renderer(scene, settings);
        int across_borders = 0, written = 0, calls = 0;
        uint32_t film_samples = 0;
        renderer.add_frame_stage({"neighbour_depth", [&](const GBuffer& g, Film& film, uint64_t,
                                                         uint64_t count, Progress*) {
            ++calls;
            film_samples = film.samples() + uint32_t(count);
            for (int y = 0; y + 1 < g.height(); ++y)
                for (int x = 0; x + 1 < g.width(); ++x)
                    for (const size_t n : {g.index(x + 1, y), g.index(x, y + 1)}) {
                        const bool other_tile = (x + 1) % 2 == 0 || (y + 1) % 2 == 0;
                        across_borders += other_tile ? 1 : 0;
                        if (g.has_surface(n) && std::abs(g.depth[n] - kCameraHeight) < 1e-5f)
                            ++written;
                    }
        }});
        renderer.render(nullptr, 2);
        EXPECT_EQ(calls, 1);
        EXPECT_EQ(film_samples, 2u);
        EXPECT_EQ(written, 2 * 7 * 7) << threads << " threads";
        EXPECT_GT(across_borders, 0);
    }
}

// A frame-wide stage that throws: the render rethrows and the film keeps its samples and sums.
TEST(FramePipeline, FailingFrameWideStageLeavesTheFilmAsItWas) {
    Scene scene = test::plane_scene(0.5f, kResolution);
    scene.add_light(test::point_light(vec3(0.0f, 0.0f, 1.0f), 10.0f));
    scene.commit();
    PreviewRenderer renderer(scene, PreviewSettings{});
    renderer.render(nullptr, 1);
    const std::vector<float> before = renderer.film().pixels(Pass::Combined);
    bool fail = true;
    renderer.add_frame_stage({"failing", [&](const GBuffer&, Film&, uint64_t, uint64_t,
                                             Progress*) {
        if (fail) throw std::runtime_error("stage failed");
    }});
    EXPECT_THROW(renderer.render(nullptr, 1), std::runtime_error);
    EXPECT_EQ(renderer.film().samples(), 1u);
    EXPECT_EQ(renderer.film().pixels(Pass::Combined), before);
    fail = false;
    renderer.render(nullptr, 1);
    EXPECT_EQ(renderer.film().samples(), 2u);
    EXPECT_THROW(renderer.add_frame_stage({"empty", {}}), InvalidArgument);
}

}  // namespace
}  // namespace shgi
