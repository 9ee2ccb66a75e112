#include "bake/dilation.h"

#include <atomic>

#include "util/error.h"
#include "util/parallel.h"

namespace shgi {
namespace {

// Rows per parallel chunk.
constexpr uint64_t kRowsPerChunk = 16;

void check_sizes(uint32_t width, uint32_t height, uint32_t channels,
                 const std::vector<float>& values, const std::vector<uint8_t>& filled) {
    if (width == 0 || height == 0 || channels == 0)
        throw InvalidArgument(format_message("dilate: width = ", width, ", height = ", height,
                                             ", channels = ", channels, " must all be >= 1"));
    const uint64_t texels = uint64_t(width) * height;
    if (values.size() != texels * channels)
        throw InvalidArgument(format_message("dilate: values has ", values.size(),
                                             " floats but width * height * channels = ",
                                             texels * channels));
    if (filled.size() != texels)
        throw InvalidArgument(format_message("dilate: filled has ", filled.size(),
                                             " flags but width * height = ", texels));
}

// Fills the empty texels of row y that touch a texel filled before this pass (`before`);
// marks them in `after`. Returns how many it filled.
uint64_t dilate_row(uint32_t width, uint32_t height, uint32_t channels, uint32_t y,
                    const std::vector<uint8_t>& before, std::vector<uint8_t>& after,
                    std::vector<float>& values) {
    uint64_t count = 0;
    for (uint32_t x = 0; x < width; ++x) {
        const uint64_t texel = uint64_t(y) * width + x;
        if (before[texel]) continue;
        float* out = &values[texel * channels];
        uint32_t neighbours = 0;
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const int64_t nx = int64_t(x) + dx, ny = int64_t(y) + dy;
                if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= width || ny >= height)
                    continue;
                const uint64_t neighbour = uint64_t(ny) * width + uint64_t(nx);
                if (!before[neighbour]) continue;
                // Neighbours filled before this pass are never written during it.
                const float* in = &values[neighbour * channels];
                if (neighbours == 0)
                    for (uint32_t c = 0; c < channels; ++c) out[c] = 0.0f;
                for (uint32_t c = 0; c < channels; ++c) out[c] += in[c];
                ++neighbours;
            }
        if (neighbours == 0) continue;
        for (uint32_t c = 0; c < channels; ++c) out[c] /= float(neighbours);
        after[texel] = 1;
        ++count;
    }
    return count;
}

}  // namespace

uint64_t dilate(uint32_t width, uint32_t height, uint32_t channels, std::vector<float>& values,
                std::vector<uint8_t>& filled, const DilationSettings& settings,
                Progress* progress) {
    check_sizes(width, height, channels, values, filled);
    uint64_t total = 0;
    std::vector<uint8_t> before;
    for (uint32_t pass = 0; pass < settings.padding; ++pass) {
        throw_if_cancelled(progress);
        before = filled;
        std::atomic<uint64_t> count{0};
        parallel_for(0, height, kRowsPerChunk, [&](uint64_t begin, uint64_t end) {
            uint64_t here = 0;
            for (uint64_t y = begin; y < end; ++y)
                here += dilate_row(width, height, channels, uint32_t(y), before, filled, values);
            count += here;
        });
        total += count.load();
        if (progress) progress->report(pass + 1, settings.padding);
        if (count.load() == 0) break;  // nothing left to grow into
    }
    return total;
}

}  // namespace shgi
