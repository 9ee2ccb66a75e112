// Lookup sharing: the frame pipeline's stage that lets the pixels of a 2 x 2 quad share one field
// lookup (in the spirit of seed 004's discontinuity-aware sharing of SH between neighbouring
// pixels). A field's lookup (a 27-cell lattice sample, a photon map's k-nearest density estimate)
// is the costliest part of a preview pixel, and it changes little between neighbouring pixels on
// one surface.
//
// The stage reads only the G-buffer (render/g_buffer.h), by frame pixel index, so it may run over
// any set of quads, inside a tile or over the whole frame. For each aligned quad, the lead pixel
// is the first of the quad's pixels, from the one at sample index s mod the quad's size on, that
// has a first surface; the lead rotates with s so that a progressive render spreads the lookups.
// Every other pixel of the quad whose first surface lies within the field's reuse distance of
// the lead's and whose shading normal agrees within kReuseMinCosine takes the lead's lookup; the
// others, across edges and depth jumps, make their own. The choice depends only on pixel
// coordinates, the sample index and the G-buffer, so frames are identical for any thread count
// and tile size.
#pragma once

#include <cstdint>

#include "render/g_buffer.h"

namespace shgi {

// Cosine of the largest angle (~11 degrees) between the shading normals of pixels that share.
inline constexpr float kReuseMinCosine = 0.98f;

// The sharing within one quad: `lead` (0..size-1, or kNoLead when no pixel of the quad has a first
// surface) and the quad pixels that take the lead's lookup (bit k for quad pixel k, never the
// lead's own bit).
struct QuadLookupSharing {
    static constexpr uint32_t kNoLead = 0xFFFFFFFFu;
    uint32_t lead = kNoLead;
    uint32_t followers = 0;
};

// The sharing within the quad of frame pixels pixels[0..size) (size 1 to 4, row-major within
// the quad) at sample index `sample`, for a field whose reuse distance is `reuse_distance` (m).
QuadLookupSharing share_quad_lookup(const GBuffer& g_buffer, const uint32_t* pixels,
                                    uint32_t size, uint64_t sample, float reuse_distance);

}  // namespace shgi
