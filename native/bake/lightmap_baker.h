// Lightmap baker (docs/baking.md, step 3): the light arriving at every texel of a TexelMap, from
// the reference path tracer (ground truth) or from any IndirectField (a solved photon lattice or
// probe grid), with an optional L1 or L2 SH of the incident radiance per texel (directional
// lightmaps, LightmapSettings.sh_order).
//
// What a texel holds (LightmapContent), in Cycles' DIFFUSE bake units so that a user can swap
// one baker for the other: the diffuse pass divided by its colour, i.e. for a Lambert surface
// E / pi (W m^-2 sr^-1: the outgoing radiance of a white diffuse surface under irradiance E).
//   - Indirect:       Cycles' DIFFUSE with pass_filter {INDIRECT}: light that scattered at least
//                     once before reaching the texel;
//   - Direct:         {DIRECT}: light straight from emitters (lights, emissive triangles, world);
//   - DirectIndirect: {DIRECT, INDIRECT} (the default);
//   - Full:           {DIRECT, INDIRECT, COLOR}: the above times the diffuse colour (DiffCol),
//                     the outgoing diffuse radiance (emission is not included, as in Cycles).
// Like Cycles' bake, a texel is seen by a camera ray along its shading normal, so its diffuse
// lobe is the material's (principled diffuse as Cycles 3.4 evaluates it, render/bsdf.h), and the
// "colour division" uses that lobe's own closure weight; surfaces with no diffuse closure
// (metals, black) are baked as Lambert.
//
// Estimators, per sample position of a texel (bake/texel_rasterizer.h; rays leave from the
// possibly unoccluded ray_origin):
//   - path tracer: next-event estimation (one light sample, LightSampler) and one hemisphere ray
//     per sample, weighted against each other by the power heuristic; the hemisphere ray's
//     radiance beyond its first hit is the reference PathIntegrator's (Combined - Emit - Env of
//     a path started at that hit, with the same BSDFs, light units and NEE). Hemisphere rays are
//     cosine-distributed, or uniform when `directional` (an SH projection divides by the pdf;
//     1 / cos has infinite variance near the horizon, 1 / uniform does not).
//     Bounce limits mean Cycles' Light Paths: the texel's own scattering is the first diffuse
//     bounce, so a limit of 0 bakes no indirect light.
//   - IndirectField: direct light by next-event estimation alone, indirect light from the field
//     once per sample position: its irradiance through the diffuse lobe (as the preview renderer
//     shades), and its radiance SH for the directional data. An interleaved field (INSTANT_GI's
//     VPL sets, IndirectField::interleave; seed 004 applied to texels) is read once per texel
//     instead: texel (x, y) gathers set (x mod n, y mod m) alone, and each texel takes the mean
//     over the sets of their nearest texels in its own UV chart and on its surface
//     (render/interleave_window.h: the paper's window, with sets a chart's edge cuts off read a
//     period nearer), no luminance edge-stop; each tile gathers the halo its windows reach
//     itself, so the result does not depend on tiles or shards (whose samples must be
//     unoccluded over lightmap_read_tiles). With final_gather, the path
//     tracer's estimator whose hemisphere ray reads the field where it lands (the continuation
//     is a PathIntegrator with the field at its first vertex).
// Stratification: sample i of a sample position takes point i of that position's own
// Owen-scrambled Sobol' sequences (render/path_integrator.h pixel_sample, keyed by the
// position's index in TexelMap::samples) for the hemisphere direction and the light sample, and
// Pcg32 stream (i, that index) for the rest of the path; the seed is mixed with the instance id. The result of a texel therefore depends only on the seed, the instance and the texel:
// identical for any thread count, tile order or shard split.
//
// settings.samples per texel are shared evenly by its sample positions (at least one each); a
// texel's value is the coverage-weighted mean of its positions' means. Variance: of the texel
// mean's luminance (Rec.709), from the per-position sample variances (a confidence layer).
//
// Directional data: the L1 (or, with sh_order 2, L2) SH (real, orthonormal, shgi.sh
// conventions; index l(l+1)+m) of the incident radiance
// over the texel's upper hemisphere (W m^-2 sr^-1), direct + indirect as the content says
// (Full: also times DiffCol). Irradiance for another normal n' (a normal map) is
// sh_irradiance(sh, n'); the plain value above stays the exact E / pi for the texel's own normal,
// where the L1 reconstruction is only an approximation.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bake/texel_rasterizer.h"
#include "render/indirect_field.h"
#include "scene/scene.h"
#include "util/progress.h"

namespace shgi {

enum class LightmapContent : uint8_t { Indirect, Direct, DirectIndirect, Full };

// "INDIRECT", "DIRECT", "DIRECT_INDIRECT", "FULL" (the Python / add-on names).
const char* lightmap_content_name(LightmapContent content);
// The inverse; throws InvalidArgument listing the valid names.
LightmapContent lightmap_content_from_name(const std::string& name);

struct LightmapSettings {
    LightmapContent content = LightmapContent::DirectIndirect;
    uint32_t samples = 256;   // per texel, 1 .. 2^20
    uint64_t seed = 0;
    bool directional = false;  // also the SH of the incident radiance per texel
    // The directional data's SH order: 1 (L1, 4 coefficients per channel, the default) or 2
    // (L2, 9). Read only when directional.
    int sh_order = 1;
    // Cycles' Light Paths limits (as PathTracerSettings), counting the texel's own bounce.
    int max_bounces = 12;
    int diffuse_bounces = 4;
    int glossy_bounces = 4;
    int transmission_bounces = 12;
    float clamp_indirect = 0.0f;  // max component of an indirect sample's radiance; 0 = off
    // As PathTracerSettings.filter_glossy: the texel's own bounce is the first one (its
    // hemisphere sample's pdf starts the path's lowest pdf); 0 = off.
    float filter_glossy = 0.0f;
    // Most emitters one next-event estimate samples, as PathTracerSettings.light_splits (the
    // light tree's splitting; 1 = one emitter per shadow ray), 1 .. kMaxLightSplits.
    int light_splits = 4;
    // With a field: final gather (seed 001 §4.2, as PreviewSettings::final_gather). Each sample
    // traces one hemisphere ray, as the path tracer does, and where it lands adds direct light by
    // next-event estimation and indirect light from the field, instead of reading the field at
    // the texel: the field's blocks and leaks reach the lightmap one bounce later. Direct light
    // at the texel is then weighted against that ray (MIS), as the path tracer's is. Ignored
    // without a field.
    bool final_gather = false;
    // Side (texels) of the square tiles the lightmap is baked in: the unit of work of threads,
    // of progress and cancel, and of shards (lightmap_tiles). 4 .. 1024.
    uint32_t tile_size = 16;
};

// Throws InvalidArgument naming the field and its value.
void validate_lightmap_settings(const LightmapSettings& settings);

// Texels of one baked lightmap, row-major with row 0 at v = 0 (the TexelMap grid).
struct LightmapTexels {
    uint32_t width = 0, height = 0;
    bool directional = false;
    int sh_order = 1;             // when directional: 1 (L1) or 2 (L2)
    std::vector<float> color;     // 3 per texel, RGB (units: see LightmapContent)
    std::vector<float> sh;        // sh_floats() per texel: [coefficient][RGB]
    std::vector<float> variance;  // 1 per texel: of the texel's luminance estimate
    std::vector<uint8_t> baked;   // 1 where this bake computed the texel (covered, in its tiles)

    uint64_t texel_count() const { return uint64_t(width) * height; }
    // SH coefficients per channel and floats per texel of the directional data (0 without).
    int sh_coefficients() const { return directional ? (sh_order + 1) * (sh_order + 1) : 0; }
    int sh_floats() const { return 3 * sh_coefficients(); }
};

inline constexpr int kLightmapShCoefficients = 4;  // L1
inline constexpr int kLightmapShFloats = 3 * kLightmapShCoefficients;
inline constexpr int kLightmapMaxShOrder = 2;  // L2: 9 coefficients
inline constexpr int kLightmapMaxShFloats =
    3 * (kLightmapMaxShOrder + 1) * (kLightmapMaxShOrder + 1);

// Number of tiles of a width x height lightmap; tile i covers texels
// [tx * size, (tx + 1) * size) x [ty * size, ...) with tx = i % tiles_x, ty = i / tiles_x.
uint32_t lightmap_tile_count(uint32_t width, uint32_t height, uint32_t tile_size);
// The tiles shard `shard` of `shards` bakes: every tile i with i % shards == shard.
std::vector<uint32_t> lightmap_shard_tiles(uint32_t width, uint32_t height, uint32_t tile_size,
                                           uint32_t shard, uint32_t shards);

// The tiles whose texels a bake of `tiles` reads: `tiles` itself, and with an interleaved field
// (IndirectField::interleave, filtered) every tile its filter window reaches from them. A shard
// prepares (unocclude) these texels' samples, not only its own. Empty `tiles` (all): empty.
std::vector<uint32_t> lightmap_read_tiles(uint32_t width, uint32_t height, uint32_t tile_size,
                                          const std::vector<uint32_t>& tiles,
                                          const IndirectField* field);

// Bakes `tiles` (all tiles when empty) of `map`, an instance of `scene` (committed; map from
// rasterize_texels(scene, ...)). field null: the path tracer; otherwise the field's indirect
// light (it must belong to this scene). Throws InvalidArgument for bad settings, a tile out of
// range, an uncommitted scene or a map of another scene's instance; polls `progress` per tile
// (Cancelled, well within 0.2 s at default settings).
LightmapTexels bake_lightmap(const Scene& scene, const TexelMap& map, const IndirectField* field,
                             const LightmapSettings& settings,
                             const std::vector<uint32_t>& tiles = {},
                             Progress* progress = nullptr);

// Copies the texels `part` baked into `into` (same size, directional flag and SH order;
// InvalidArgument otherwise, or when a texel was baked by both: shards must not overlap). Merging the shards of
// one bake gives exactly the single bake.
void merge_lightmap(LightmapTexels& into, const LightmapTexels& part);

}  // namespace shgi
