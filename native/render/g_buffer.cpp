#include "render/g_buffer.h"

#include "util/error.h"
#include "util/memory.h"

namespace shgi {

GBuffer::GBuffer(int width, int height) : width_(width), height_(height) {
    if (width < 0 || height < 0)
        throw InvalidArgument(format_message("GBuffer: size ", width, " x ", height,
                                             "; both sides must be >= 0"));
    const size_t count = pixel_count();
    // Four vec3 planes and four 32-bit planes.
    constexpr uint64_t kBytesPerPixel = 4 * sizeof(vec3) + 4 * sizeof(uint32_t);
    require_memory(saturating_mul(uint64_t(count), kBytesPerPixel),
                   format_message("the G-buffer of ", width, " x ", height, " pixels"),
                   "lower the camera's resolution_x / resolution_y (or Blender's resolution %)");
    position.assign(count, vec3(0.0f));
    shading_normal.assign(count, vec3(0.0f));
    geometric_normal.assign(count, vec3(0.0f));
    albedo.assign(count, vec3(0.0f));
    roughness.assign(count, 0.0f);
    depth.assign(count, 0.0f);
    object_id.assign(count, kNoSurface);
    material_id.assign(count, kNoSurface);
}

void GBuffer::set_field_lobes_at(size_t pixel, const Shading& shading) {
    field_diffuse[pixel] = shading.bsdf.field_diffuse(shading.wo);
    PrincipledBsdf::GlossyLobe lobes[2];
    const int n = shading.bsdf.field_glossy_lobes(shading.wo, lobes);
    for (int k = 0; k < 2; ++k) {
        glossy_albedo[k][pixel] = k < n ? lobes[k].albedo : vec3(0.0f);
        glossy_roughness[k][pixel] = k < n ? lobes[k].roughness : 0.0f;
    }
    if (!shgi::diffuse_bump(shading, &diffuse_bump[pixel])) diffuse_bump[pixel] = DiffuseBump{};
}

void GBuffer::set_field_lobes(bool on) {
    if (on == has_field_lobes()) return;
    const size_t count = on ? pixel_count() : 0;
    if (on)
        require_memory(saturating_mul(uint64_t(count), uint64_t(3 * sizeof(vec3) + 2 * sizeof(float) +
                                                                sizeof(DiffuseBump))),
                       format_message("the G-buffer's field lobes of ", width_, " x ", height_,
                                      " pixels"),
                       "lower the camera's resolution_x / resolution_y (or Blender's resolution %)");
    field_diffuse.assign(count, vec3(0.0f));
    diffuse_bump.assign(count, DiffuseBump{});
    for (int k = 0; k < 2; ++k) {
        glossy_albedo[k].assign(count, vec3(0.0f));
        glossy_roughness[k].assign(count, 0.0f);
    }
    if (!on) {
        field_diffuse.shrink_to_fit();
        diffuse_bump.shrink_to_fit();
        for (int k = 0; k < 2; ++k) {
            glossy_albedo[k].shrink_to_fit();
            glossy_roughness[k].shrink_to_fit();
        }
    }
}

void GBuffer::set_miss(size_t pixel) {
    position[pixel] = vec3(0.0f);
    shading_normal[pixel] = vec3(0.0f);
    geometric_normal[pixel] = vec3(0.0f);
    albedo[pixel] = vec3(0.0f);
    roughness[pixel] = 0.0f;
    depth[pixel] = 0.0f;
    object_id[pixel] = kNoSurface;
    material_id[pixel] = kNoSurface;
    if (has_field_lobes()) {
        field_diffuse[pixel] = vec3(0.0f);
        diffuse_bump[pixel] = DiffuseBump{};
        for (int k = 0; k < 2; ++k) {
            glossy_albedo[k][pixel] = vec3(0.0f);
            glossy_roughness[k][pixel] = 0.0f;
        }
    }
}

}  // namespace shgi
