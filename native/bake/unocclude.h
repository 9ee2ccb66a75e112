// Unocclude: moves the ray origins of lightmap samples that lie inside other geometry out of it,
// so texels partly under a wall or a box standing on a floor do not come out black (Godot's
// lightmapper does the same in its "unocclude" pass, modules/lightmapper_rd/lm_compute.glsl).
//
// A floor texel crossed by a wall's edge has some samples under the wall: every ray leaving
// them hits the wall's inside, and the texel (and, through bilinear filtering, its neighbours)
// goes dark. For each sample, unocclude() casts ray_count rays in the tangent plane of its
// geometric normal, at evenly spaced azimuths, from just above the surface, up to
// search_radius texels (TexelSample::texel_size) away. A ray that meets a back face — the
// inside of closed geometry — within that distance means the sample is inside something; its
// ray_origin moves to the nearest such hit, push_distance texels beyond it along the hit's
// normal (out of the wall). Front-face hits are ignored: a wall seen from outside is a real
// occluder. The move is bounded by search_radius + push_distance texels.
//
// Assumes closed (watertight, outward-facing) occluders, as Godot does: a single-sided plane
// seen from behind within search_radius also moves samples to its front side.
//
// Deterministic: fixed directions, one result per sample, any thread count.
#pragma once

#include <cstdint>
#include <vector>

#include "bake/texel_rasterizer.h"
#include "scene/scene.h"
#include "util/progress.h"

namespace shgi {

struct UnoccludeSettings {
    uint32_t ray_count = 8;       // tangent-plane directions per sample, 1..64
    // How far (texels) from a sample the inside of a wall is looked for. A wall edge through a
    // texel passes within half a texel of its centre and within ~1 texel of most of its
    // samples; a larger radius would move samples deep under a wall, whose texels no one sees.
    float search_radius = 1.0f;  // (0, 16]
    // How far (texels) past the back face the ray origin is put: clear of the wall's surface
    // by more than float round-off, small enough to stay within the texel's neighbourhood.
    float push_distance = 0.05f;  // [0, 16]
};

struct UnoccludeReport {
    uint64_t samples = 0;        // samples examined
    uint64_t moved_samples = 0;  // samples whose ray_origin moved out of geometry
};

// Updates map.samples[*].ray_origin in place (positions and normals are kept). `scene` must be
// committed and be the one the map's samples lie in. Throws InvalidArgument for an uncommitted
// scene or settings out of range; polls `progress` between chunks (Cancelled).
UnoccludeReport unocclude(const Scene& scene, TexelMap& map, const UnoccludeSettings& settings,
                          Progress* progress = nullptr);
// Only the samples of the texels in `tiles` (lightmap tiles of tile_size texels, numbered as
// bake_lightmap numbers them; all samples when empty): what a shard bakes, so a shard prepares
// its own share of the lightmap, not all of it. Samples are independent, so each moves exactly
// as in a whole unocclude(). InvalidArgument for a tile out of range.
UnoccludeReport unocclude(const Scene& scene, TexelMap& map, const UnoccludeSettings& settings,
                          const std::vector<uint32_t>& tiles, uint32_t tile_size,
                          Progress* progress = nullptr);

}  // namespace shgi
