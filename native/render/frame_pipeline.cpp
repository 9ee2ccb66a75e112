#include "render/frame_pipeline.h"

#include <algorithm>

#include "util/error.h"

namespace shgi {

const char* frame_stage_name(FrameStage stage) {
    static const char* const kNames[kFrameStageCount] = {
        "camera_rays", "intersect", "surface", "direct_light",
        "field_lookup", "frame_filters", "shade", "film"};
    return kNames[size_t(stage)];
}

TileGrid::TileGrid(int image_width, int image_height, int tile_side)
    : width(image_width), height(image_height), tile(tile_side),
      columns(tile_side > 0 ? (int64_t(image_width) + tile_side - 1) / tile_side : 0),
      rows(tile_side > 0 ? (int64_t(image_height) + tile_side - 1) / tile_side : 0) {
    if (tile_side < 1)
        throw InvalidArgument(format_message("TileGrid: tile side ", tile_side,
                                             "; it must be >= 1"));
}

void TileGrid::bounds(uint64_t t, int* x0, int* x1, int* y0, int* y1) const {
    const int64_t left = int64_t(t % uint64_t(columns)) * tile;
    const int64_t top = int64_t(t / uint64_t(columns)) * tile;
    *x0 = int(left);
    *y0 = int(top);
    *x1 = int(std::min<int64_t>(left + tile, width));
    *y1 = int(std::min<int64_t>(top + tile, height));
}

}  // namespace shgi
