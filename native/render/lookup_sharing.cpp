#include "render/lookup_sharing.h"

namespace shgi {

QuadLookupSharing share_quad_lookup(const GBuffer& g_buffer, const uint32_t* pixels,
                                    uint32_t size, uint64_t sample, float reuse_distance) {
    QuadLookupSharing sharing;
    for (uint32_t k = 0; k < size; ++k) {
        const uint32_t candidate = uint32_t((sample + k) % size);
        if (g_buffer.has_surface(pixels[candidate])) {
            sharing.lead = candidate;
            break;
        }
    }
    if (sharing.lead == QuadLookupSharing::kNoLead) return sharing;
    const vec3& p = g_buffer.position[pixels[sharing.lead]];
    const vec3& n = g_buffer.shading_normal[pixels[sharing.lead]];
    const float reuse2 = reuse_distance * reuse_distance;
    for (uint32_t k = 0; k < size; ++k) {
        const uint32_t pixel = pixels[k];
        if (k == sharing.lead || !g_buffer.has_surface(pixel)) continue;
        const vec3& pk = g_buffer.position[pixel];
        if (glm::dot(pk - p, pk - p) <= reuse2 &&
            glm::dot(g_buffer.shading_normal[pixel], n) >= kReuseMinCosine)
            sharing.followers |= 1u << k;
    }
    return sharing;
}

}  // namespace shgi
