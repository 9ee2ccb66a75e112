// GBuffer: the first surface every pixel's camera ray met, for the whole frame, as a structure of
// arrays (one plane per attribute, indexed y * width + x with y = 0 the top row), in the shape of
// pbrt-v4's wavefront integrator (its SOA pixel state, src/pbrt/wavefront/integrator.h) and of
// seed 000 §5.4's screen G-buffer.
//
// The frame pipeline (render/frame_pipeline.h) writes it in tiles, one pixel by the thread that
// owns the pixel's tile, and a stage may then read any pixel, across tile borders: the frame-wide
// stages that run after the tiles finish (denoiser guides, screen-space SH filters) and the lookup
// sharing stage (render/lookup_sharing.h) read their neighbours here.
//
// Contents are those of the latest sample index the frame rendered (a progressive frame of one
// sample: that sample). Units and conventions: world space, metres; normals unit length and facing
// the camera (render/shading.h: flipped to the side the ray came from); `depth` the distance along
// the camera's view axis (the Depth pass, Cycles' z-depth); `albedo` the sum of the first
// surface's closure weights (DiffCol + GlossCol + TransCol, OpenImageDenoise's albedo guide);
// `roughness` the material's Principled roughness. Where the ray met nothing, object_id is
// kNoSurface and the other planes hold zeros.
#pragma once

#include <cstdint>
#include <vector>

#include "render/bump_irradiance.h"
#include "render/shading.h"
#include "scene/scene.h"
#include "util/math.h"

namespace shgi {

class GBuffer {
  public:
    // object_id and material_id where a pixel's camera ray met no surface.
    static constexpr uint32_t kNoSurface = 0xFFFFFFFFu;

    GBuffer() = default;
    // A width x height buffer, every pixel a miss.
    GBuffer(int width, int height);

    int width() const { return width_; }
    int height() const { return height_; }
    size_t pixel_count() const { return size_t(width_) * size_t(height_); }
    size_t index(int x, int y) const { return size_t(y) * size_t(width_) + size_t(x); }
    bool has_surface(size_t pixel) const { return object_id[pixel] != kNoSurface; }

    // Pixel `pixel` sees `shading`, the shaded first hit `hit` of a ray from the camera whose
    // position and unit view axis are `camera_position` and `forward`. `material_lobes`
    // (optional): the scene's MaterialLobeTable, whose albedo of a material it holds is the
    // shading's.
    // Inline, the field lobes out of line: the preview writes every pixel and sample, and the
    // call of eight arguments cost about as much as its stores.
    void set_surface(size_t pixel, const Scene& scene, const Shading& shading, const Hit& hit,
                     const vec3& camera_position, const vec3& forward,
                     const MaterialLobeTable* material_lobes = nullptr) {
        const Mesh& mesh = scene.meshes()[scene.instances()[hit.instance_id].mesh_id];
        // Meshes without per-triangle materials use material 0 (scene/mesh.h).
        const uint32_t material =
            mesh.material_indices.empty() ? 0u : mesh.material_indices[hit.triangle_id];
        position[pixel] = shading.position;
        shading_normal[pixel] = shading.frame.z;
        geometric_normal[pixel] = shading.geometric_normal;
        const vec3* material_albedo =
            material_lobes != nullptr ? material_lobes->albedo(material) : nullptr;
        albedo[pixel] =
            material_albedo != nullptr ? *material_albedo : shading.bsdf.class_color_sum();
        roughness[pixel] = scene.materials()[material].roughness;
        depth[pixel] = glm::dot(shading.position - camera_position, forward);
        object_id[pixel] = hit.instance_id;
        material_id[pixel] = material;
        if (has_field_lobes()) set_field_lobes_at(pixel, shading);
    }
    // Pixel `pixel` sees no surface.
    void set_miss(size_t pixel);
    // Asks the caches for the lines set_surface and set_miss will write at `pixel` (the eight
    // planes; not the field-lobe planes): a frame-sized plane's lines are rarely cached, and a
    // store that misses holds back every later store (they leave the store queue in order).
    // Always inline: GCC 12 finds no side effect in a prefetch, so it deleted the call to this
    // function (not inlined early) as a call of a const function whose result nobody reads.
    __attribute__((always_inline)) void prefetch(size_t pixel) const {
        __builtin_prefetch(&position[pixel], 1, 3);
        __builtin_prefetch(&shading_normal[pixel], 1, 3);
        __builtin_prefetch(&geometric_normal[pixel], 1, 3);
        __builtin_prefetch(&albedo[pixel], 1, 3);
        __builtin_prefetch(&roughness[pixel], 1, 3);
        __builtin_prefetch(&depth[pixel], 1, 3);
        __builtin_prefetch(&object_id[pixel], 1, 3);
        __builtin_prefetch(&material_id[pixel], 1, 3);
    }

    // The planes (public: stages read them directly, as pbrt-v4's SOA arrays).
    std::vector<vec3> position;          // m, world space
    std::vector<vec3> shading_normal;    // the shading frame's z (after normal maps)
    std::vector<vec3> geometric_normal;  // the triangle's normal
    std::vector<vec3> albedo;            // sum of the closure weights, linear Rec.709
    std::vector<float> roughness;        // Principled roughness, 0..1
    std::vector<float> depth;            // m along the view axis
    std::vector<uint32_t> object_id;     // index into Scene::instances(), or kNoSurface
    std::vector<uint32_t> material_id;   // index into Scene::materials(), or kNoSurface

    // The first surface's field lobes (render/bsdf.h: field_diffuse, field_glossy_lobes; what
    // a screen-space field's light is weighted by), only with set_field_lobes(true): empty
    // otherwise. Up to two glossy lobes; an absent lobe has albedo 0.
    std::vector<vec3> field_diffuse;
    std::vector<vec3> glossy_albedo[2];
    std::vector<float> glossy_roughness[2];
    // The diffuse lobe's bump shadowing (render/bump_irradiance.h) where a normal map bent its
    // normal; a zero smooth_normal elsewhere.
    std::vector<DiffuseBump> diffuse_bump;
    bool has_field_lobes() const { return !field_diffuse.empty(); }
    // Allocates (all zero) or frees the field-lobe planes; 60 more bytes a pixel.
    void set_field_lobes(bool on);

  private:
    // set_surface's field-lobe planes.
    void set_field_lobes_at(size_t pixel, const Shading& shading);

    int width_ = 0, height_ = 0;
};

}  // namespace shgi
