#include "bake/unocclude.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <utility>

#include "bake/lightmap_baker.h"
#include "render/shading.h"
#include "util/error.h"
#include "util/parallel.h"

namespace shgi {
namespace {

constexpr uint32_t kMaxRayCount = 64;
// The farthest (texels) a search or a push may reach: a sample moved further than a few texels
// lies under other texels, whose light it would give its own (and 1e38 texels put ray origins
// out of Embree's range, where the bake refused them without naming the setting).
constexpr float kMaxMoveTexels = 16.0f;
// Samples per parallel chunk: ray_count rays each, a few ms per chunk (polls cancel often).
constexpr uint64_t kSamplesPerChunk = 1024;

void check_settings(const Scene& scene, const UnoccludeSettings& settings) {
    if (!scene.committed())
        throw InvalidArgument("unocclude: the scene is not committed; call Scene::commit() first");
    if (settings.ray_count < 1 || settings.ray_count > kMaxRayCount)
        throw InvalidArgument(format_message("UnoccludeSettings.ray_count = ", settings.ray_count,
                                             " is outside [1, ", kMaxRayCount, "]"));
    if (!(settings.search_radius > 0.0f && settings.search_radius <= kMaxMoveTexels))
        throw InvalidArgument(format_message("UnoccludeSettings.search_radius = ",
                                             settings.search_radius, " must be in (0, ",
                                             kMaxMoveTexels, "] texels"));
    if (!(settings.push_distance >= 0.0f && settings.push_distance <= kMaxMoveTexels))
        throw InvalidArgument(format_message("UnoccludeSettings.push_distance = ",
                                             settings.push_distance, " must be in [0, ",
                                             kMaxMoveTexels, "] texels"));
}

// Moves one sample's ray origin out of the geometry it lies in; returns whether it moved.
bool unocclude_sample(const Scene& scene, const UnoccludeSettings& settings,
                      TexelSample& sample) {
    // Start from the unmoved origin (so a second call does not move the sample twice).
    const vec3 origin = offset_origin(sample.position, sample.geometric_normal);
    const Frame frame = Frame::from_z(sample.geometric_normal);
    float nearest = kInfinity;
    vec3 nearest_direction{0.0f}, nearest_normal{0.0f};
    for (uint32_t k = 0; k < settings.ray_count; ++k) {
        const float phi = kTwoPi * (float(k) + 0.5f) / float(settings.ray_count);
        Ray ray;
        ray.origin = origin;
        ray.direction = std::cos(phi) * frame.x + std::sin(phi) * frame.y;
        ray.tmax = settings.search_radius * sample.texel_size;
        const Hit hit = scene.intersect(ray);
        // A back face: the ray leaves closed geometry there, so the origin was inside it.
        if (hit.valid() && hit.t < nearest && glm::dot(hit.geometric_normal, ray.direction) > 0) {
            nearest = hit.t;
            nearest_direction = ray.direction;
            nearest_normal = glm::normalize(hit.geometric_normal);
        }
    }
    if (nearest == kInfinity) return false;
    const vec3 exit = origin + nearest * nearest_direction;
    sample.ray_origin = offset_origin(
        exit + nearest_normal * (settings.push_distance * sample.texel_size), nearest_normal);
    return true;
}

}  // namespace

UnoccludeReport unocclude(const Scene& scene, TexelMap& map, const UnoccludeSettings& settings,
                          const std::vector<uint32_t>& tiles, uint32_t tile_size,
                          Progress* progress) {
    if (tiles.empty()) return unocclude(scene, map, settings, progress);
    check_settings(scene, settings);
    check_texel_map(scene, map, "unocclude");
    if (map.sample_offsets.size() != map.texel_count() + 1)
        throw InvalidArgument("unocclude: the texel map is incomplete");
    const uint32_t tile_count = lightmap_tile_count(map.width, map.height, tile_size);
    const uint32_t tiles_x = (map.width + tile_size - 1) / tile_size;
    // Each tile row's texels are consecutive, so its samples are one range.
    std::vector<std::pair<uint64_t, uint64_t>> ranges;
    for (uint32_t tile : tiles) {
        if (tile >= tile_count)
            throw InvalidArgument(format_message("unocclude: tile ", tile, " but a ", map.width,
                                                 " x ", map.height, " lightmap has ", tile_count,
                                                 " tiles of ", tile_size, " texels"));
        const uint32_t x0 = (tile % tiles_x) * tile_size, y0 = (tile / tiles_x) * tile_size;
        const uint32_t x1 = std::min(x0 + tile_size, map.width);
        for (uint32_t y = y0; y < std::min(y0 + tile_size, map.height); ++y) {
            const uint64_t row = uint64_t(y) * map.width;
            ranges.emplace_back(map.sample_offsets[row + x0], map.sample_offsets[row + x1]);
        }
    }
    std::atomic<uint64_t> moved{0}, examined{0};
    parallel_for(
        0, ranges.size(), 1,
        [&](uint64_t begin, uint64_t end) {
            uint64_t moved_here = 0, examined_here = 0;
            for (uint64_t r = begin; r < end; ++r) {
                for (uint64_t i = ranges[r].first; i < ranges[r].second; ++i)
                    moved_here += unocclude_sample(scene, settings, map.samples[i]);
                examined_here += ranges[r].second - ranges[r].first;
            }
            moved += moved_here;
            examined += examined_here;
        },
        progress);
    UnoccludeReport report;
    report.samples = examined.load();
    report.moved_samples = moved.load();
    return report;
}

UnoccludeReport unocclude(const Scene& scene, TexelMap& map, const UnoccludeSettings& settings,
                          Progress* progress) {
    check_settings(scene, settings);
    check_texel_map(scene, map, "unocclude");
    std::atomic<uint64_t> moved{0};
    parallel_for(
        0, map.samples.size(), kSamplesPerChunk,
        [&](uint64_t begin, uint64_t end) {
            uint64_t moved_here = 0;
            for (uint64_t i = begin; i < end; ++i)
                moved_here += unocclude_sample(scene, settings, map.samples[i]);
            moved += moved_here;
        },
        progress);
    UnoccludeReport report;
    report.samples = map.samples.size();
    report.moved_samples = moved.load();
    return report;
}

}  // namespace shgi
