// Texel rasterizer: where on an object each lightmap texel lies (docs/baking.md, step 1).
//
// An instance's lightmap-UV triangles (one named UV set of its Mesh) are rasterized into a
// width x height texel grid. Every texel gets a list of samples: points on the surface, each
// with its world position, interpolated (shading) and geometric normals, triangle and weight.
// A baker evaluates lighting at the samples and averages them by weight into the texel.
//
// Texel grid convention (Blender's image convention): texel (x, y) covers the UV square
// [x / width, (x + 1) / width] x [y / height, (y + 1) / height], so row y = 0 is at v = 0, the
// bottom of the image, as Blender's Image.pixels stores it. Texel index = y * width + x.
//
// Samples: each texel has an n x n stratified pattern of sample positions at the stratum
// centres ((i + 0.5) / n, (j + 0.5) / n) (deterministic, no jitter). A position is inside a
// triangle by exact edge functions in double with a top-left tie rule, so a position on an edge
// shared by two triangles belongs to exactly one of them. Conservative coverage: a triangle that
// overlaps a texel with positive area but contains none of its sample positions (a sliver
// thinner than the sample spacing) gets one sample at the point of the triangle-within-texel
// closest to the texel centre, so thin triangles still own the texels they touch.
//
// Weights: the exact area of (triangle ∩ texel), obtained by clipping the UV triangle against
// the texel square, divided evenly among that triangle's samples in the texel, in units of
// texel area. A texel's coverage is the sum of its samples' weights clamped to 1, so a texel
// fully inside the UV layout has coverage 1 and the covered UV area is exact, not sampled.
// Overlapping UV triangles (an authoring error in a lightmap UV set) are both kept; texels where
// their areas sum past 1 are counted in the report.
//
// UVs outside [0, 1]: not wrapped. A lightmap texel must stand for one place in the world, and
// wrapping would fold distant surfaces onto the same texels; parts outside the grid are clipped
// away and the triangles that reach outside are counted (TexelRasterReport::clipped_triangles)
// so the caller can warn that the UV layout does not fit the lightmap.
//
// Units: positions in metres (world space, Z up); normals unit length, world space, mapped by
// the inverse-transpose of world_from_object as Scene does (a mirrored object keeps its front
// side as the front); texel_size in metres. Triangle ids index the mesh's triangles as Scene
// stores them (after degenerate triangles were dropped), i.e. they equal Hit::triangle_id.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "util/math.h"
#include "util/progress.h"

namespace shgi {

// Largest lightmap side accepted: 16384^2 texels already need tens of GB of samples; larger maps
// must be baked in tiles.
inline constexpr uint32_t kMaxLightmapResolution = 16384;
// Throws InvalidArgument "<what> = <side> is outside [1, 16384]; ..." for a side out of range.
void check_lightmap_side(const char* what, uint32_t side);

struct TexelRasterSettings {
    uint32_t width = 256;   // texels along u
    uint32_t height = 256;  // texels along v
    // The lightmap UV set, by name (Blender's UV map name).
    std::string uv_set = "LightmapUV";
    // Sample positions per texel are samples_per_axis^2, on a stratified grid; 1..16.
    uint32_t samples_per_axis = 2;
};

// One point on the surface standing for part of a texel.
struct TexelSample {
    vec3 position{0.0f};                     // world space, m, on the surface
    vec3 normal{0.0f, 0.0f, 1.0f};           // interpolated vertex normal (or geometric), unit
    vec3 geometric_normal{0.0f, 0.0f, 1.0f};  // of the triangle as wound (CCW = front), unit
    // Where rays leaving the front side start: the position moved kRayOffset off the surface
    // along the geometric normal (render/shading.h); unocclude() may move it out of walls.
    vec3 ray_origin{0.0f};
    vec2 uv{0.0f};                 // lightmap UV of the sample
    // (b1, b2) in the mesh triangle's own vertex order, as Hit::barycentrics: the sample is a
    // hit on triangle_id that Scene::surface_point can shade (materials, textures).
    vec2 barycentrics{0.0f};
    uint32_t triangle_id = kInvalidId;
    float weight = 0.0f;           // fraction of the texel's area this sample stands for
    // World-space edge length (m) of one texel on this sample's triangle: sqrt(world area /
    // area in texels). Distances the bake measures "in texels" use it.
    float texel_size = 0.0f;
};

struct TexelRasterReport {
    uint64_t triangles = 0;             // triangles of the mesh
    uint64_t degenerate_uv = 0;         // skipped: zero area in UV space (collapsed UVs)
    uint64_t degenerate_world = 0;      // skipped: zero area in world space (not validated)
    uint64_t clipped_triangles = 0;     // reaching outside [0, 1]^2 (the outside part is lost)
    uint64_t conservative_samples = 0;  // samples added for slivers that contain no position
    uint64_t overlapping_texels = 0;    // texels whose triangles' areas sum past 1 (UV overlap)
};

// The samples of every texel of one instance's lightmap, in compressed-row form: the samples
// of texel t are samples[sample_offsets[t] .. sample_offsets[t + 1]), ordered by triangle id,
// then by stratum (row-major within the texel).
struct TexelMap {
    uint32_t width = 0, height = 0;
    uint32_t instance_id = kInvalidId;  // kInvalidId when rasterized from a bare Mesh
    // What the map was made from (rasterize_texels(scene, instance, ...)): the Scene's uid(),
    // the instance's mesh, that mesh's revision and the instance's transform. A bake or
    // unocclude on another scene, or after the instance moved or its mesh changed, is refused
    // (check_texel_map): its samples would lie where the surface no longer is.
    uint64_t scene_uid = 0;  // 0 for a bare Mesh
    uint32_t mesh_id = kInvalidId;
    uint64_t mesh_revision = 0;
    mat4 world_from_object{1.0f};
    std::vector<uint64_t> sample_offsets;  // width * height + 1
    std::vector<TexelSample> samples;
    std::vector<float> coverage;  // width * height, fraction of each texel covered, in [0, 1]
    // UV charts: triangles that share a corner with the same world position and the same
    // lightmap UV are one chart (a seam, where the UVs of a shared edge differ, separates them).
    // chart[t] is the chart of the sample with the largest weight in texel t (kInvalidId where
    // nothing is covered); charts are numbered 0.. in order of their lowest triangle id.
    // Filters that must not blur across seams compare these.
    std::vector<uint32_t> chart;
    uint32_t chart_count = 0;
    TexelRasterReport report;

    uint64_t texel_count() const { return uint64_t(width) * height; }
    uint64_t texel_index(uint32_t x, uint32_t y) const { return uint64_t(y) * width + x; }
    uint64_t sample_count(uint64_t texel) const {
        return sample_offsets[texel + 1] - sample_offsets[texel];
    }
    const TexelSample* samples_begin(uint64_t texel) const {
        return samples.data() + sample_offsets[texel];
    }
    const TexelSample* samples_end(uint64_t texel) const {
        return samples.data() + sample_offsets[texel + 1];
    }
    // True when at least one sample lies in the texel (coverage > 0).
    bool covered(uint64_t texel) const { return sample_count(texel) > 0; }
};

// Rasterizes the UV set settings.uv_set of `mesh`, placed by world_from_object.
// Throws InvalidArgument naming the mesh and the fix for: a missing UV set (listing the sets it
// has), non-finite UVs or positions, array sizes or vertex indices that do not match, a
// non-finite transform, and settings out of range. Polls `progress` between chunks of
// triangles (Cancelled). The result is identical for any thread count.
TexelMap rasterize_texels(const Mesh& mesh, const mat4& world_from_object,
                          const TexelRasterSettings& settings, Progress* progress = nullptr);

// The same for instance `instance_id` of `scene` (which need not be committed); the map's
// instance_id is set. Throws InvalidArgument for an instance id out of range.
TexelMap rasterize_texels(const Scene& scene, uint32_t instance_id,
                          const TexelRasterSettings& settings, Progress* progress = nullptr);

// Throws InvalidArgument when `map` was not made by rasterize_texels(scene, map.instance_id, ...)
// for this scene as it is now: made from a bare Mesh or for another Scene, or before the
// instance moved (set_instance_transform) or its mesh was replaced (set_mesh). The message says
// which, starting with `operation`, and to call rasterize_texels again.
void check_texel_map(const Scene& scene, const TexelMap& map, const char* operation);

}  // namespace shgi
