// The frame pipeline: the tile loop every camera renderer shares, its named stages, and the
// frame-wide stages that run over the whole frame once the tiles finish. The shape is pbrt-v4's
// wavefront integrator (src/pbrt/wavefront/integrator.h): generate camera rays -> intersect ->
// surface set-up -> direct light -> field lookup -> frame-wide filters -> shade -> film, over
// frame-wide structure-of-arrays state (render/g_buffer.h); docs/frame-pipeline.md draws it.
//
// Tiles are the unit of threads, progress and cancel: the frame is cut into square tiles of
// tile_side pixels (the last column and row cut by the image border), handed to parallel_for a
// run of tiles_per_unit at a time. A tile's body writes only its own pixels of the film and of
// the G-buffer, so any pixel may be read by a later stage across tile borders, and the frame is
// bit-identical for any thread count (util/parallel.h). The film follows ProgressiveFilm's
// contract (render/film.h): a frame that fails or is cancelled, in a tile or in a frame-wide
// stage, leaves the film as it was.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "render/film.h"
#include "render/g_buffer.h"
#include "util/parallel.h"
#include "util/progress.h"

namespace shgi {

// The stages of a frame, in order (docs/frame-pipeline.md says what each reads and writes).
enum class FrameStage : uint8_t {
    CameraRays, Intersect, Surface, DirectLight, FieldLookup, FrameFilters, Shade, Film,
};
inline constexpr int kFrameStageCount = 8;
// "camera_rays", "intersect", ...
const char* frame_stage_name(FrameStage stage);

// The frame's tiles, row-major.
struct TileGrid {
    TileGrid(int image_width, int image_height, int tile_side);
    uint64_t count() const { return uint64_t(columns) * uint64_t(rows); }
    // Pixel bounds [x0, x1) x [y0, y1) of tile t.
    void bounds(uint64_t t, int* x0, int* x1, int* y0, int* y1) const;

    int width, height, tile;
    int64_t columns, rows;
};

// A stage over the whole frame, run after every tile finished and before the film is committed:
// it may read any pixel of the G-buffer and read or write any pixel of `film` (the frame's
// target, holding the sums with this frame's samples). `first` and `count` are the frame's
// sample indices. It must not depend on the thread count (parallel_for over pixels is fine).
struct FrameWideStage {
    std::string name;
    std::function<void(const GBuffer& g_buffer, Film& film, uint64_t first, uint64_t count,
                       Progress* progress)> run;
};

// One frame of samples [film.film().samples(), + samples): tile_body(begin, end, target, base)
// for every run of tiles, then each frame-wide stage in order, then the film commits. On any
// exception (Cancelled included) the film is abandoned and the exception rethrown.
template <typename TileBody>
void render_frame_tiles(ProgressiveFilm& film, const TileGrid& grid, uint64_t tiles_per_unit,
                        uint32_t samples, Progress* progress, TileBody&& tile_body,
                        const GBuffer* g_buffer = nullptr,
                        const std::vector<FrameWideStage>& frame_stages = {}) {
    const uint64_t first = film.film().samples();
    Film& target = film.begin();
    const Film& base = film.base();
    try {
        parallel_for(0, grid.count(), tiles_per_unit, [&](uint64_t begin, uint64_t end) {
            tile_body(begin, end, target, base);
        }, progress);
        for (const FrameWideStage& stage : frame_stages) {
            throw_if_cancelled(progress);
            stage.run(*g_buffer, target, first, samples, progress);
        }
    } catch (...) {
        film.abandon();
        throw;
    }
    film.commit(uint32_t(first + samples));
}

}  // namespace shgi
