// Four vec3 in the lanes of SSE2 vectors, and the lane operations the render lanes share
// (QuadGlossy's glossy reads, eval_field_lanes' BSDF values). Each operation is glm's scalar
// operation in its order, so a lane gives the scalar code's bits (-ffp-contract=off: no FMA).
#pragma once

#if defined(__SSE2__)
#include <emmintrin.h>

namespace shgi {

// Four vec3, one per lane.
struct Vec3Lanes {
    __m128 x, y, z;
};

// glm::dot's order: (a.x b.x + a.y b.y) + a.z b.z.
inline __m128 dot_lanes(const Vec3Lanes& a, const Vec3Lanes& b) {
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(a.x, b.x), _mm_mul_ps(a.y, b.y)),
                      _mm_mul_ps(a.z, b.z));
}

// where ? a : b, per lane.
inline __m128 select_lanes(__m128 where, __m128 a, __m128 b) {
    return _mm_or_ps(_mm_and_ps(where, a), _mm_andnot_ps(where, b));
}

}  // namespace shgi
#endif
