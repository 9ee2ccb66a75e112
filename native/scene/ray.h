// Rays and hits: what goes into and comes out of the Embree queries (scene/scene.h).
//
// A ray is origin + t * direction for t in [tmin, tmax]; direction need not be unit length
// (t is then in units of |direction|). Scene validates every ray before it reaches Embree:
// Debian's Embree aborts the process on a non-finite ray.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "util/math.h"

namespace shgi {

inline constexpr uint32_t kInvalidId = 0xFFFFFFFFu;
inline constexpr float kInfinity = std::numeric_limits<float>::infinity();

struct Ray {
    vec3 origin{0.0f};
    vec3 direction{0.0f, 0.0f, 1.0f};
    float tmin = 0.0f;
    float tmax = kInfinity;
};

// Scene coordinates (vertices, instance bounds, lights, probes, field queries) stay within this
// magnitude: beyond it Embree's float arithmetic overflows (float32 ends at 3.4e38). Its triangle
// test multiplies three lengths (the hit distance's numerator is the dot product of a vertex's
// offset from the origin with the unnormalised normal, edge x edge): in a closed box of
// half-side 5e12 m, 64% of random rays from inside came back as hits at t = inf, and at 1e14 m
// all of them, while at 2e12 m none did (tests/cpp/scene/scene_test.cpp checks 1e12).
inline constexpr float kMaxCoordinate = 1e12f;

// Embree's bound on a ray's origin and direction components (its FLT_LARGE, 1.844e18): Debian's
// Embree is built with assertions and aborts the process on a ray beyond it, finite or not.
inline constexpr float kMaxRayComponent = 1e18f;

// The largest |component| of origin and direction a scene traces, and the smallest largest
// |component| of a direction (0: any non-zero direction). Embree checks the upper bounds again
// after mapping a ray into each instance's object space, where an instance that scales its mesh
// down magnifies the ray, and its float triangle test overflows for origins far from large
// triangles, for long directions, and for hit distances (in units of |direction|) past 3.4e38
// from short ones: a committed Scene sets limits that keep all of these in range
// (Scene::ray_limits).
struct RayLimits {
    float origin = kMaxRayComponent;
    float direction = kMaxRayComponent;
    float min_direction = 0.0f;
};

// True if the ray may be traced: finite origin and direction within the limits (the direction's
// largest |component| above min_direction: non-zero), 0 <= tmin <= tmax (tmax may be +inf),
// tmin finite. Every traced ray passes here, so
// it is inline and branch-free: each comparison is false for NaN, |x| <= limit also for ±inf,
// and the results are combined with & rather than &&.
inline bool is_valid_ray(const Ray& ray, const RayLimits& limits = RayLimits{}) {
    const bool interval_ok = (ray.tmin >= 0.0f) & (ray.tmin <= std::numeric_limits<float>::max()) &
                             (ray.tmax >= ray.tmin);
#if defined(__SSE2__)
    // The six components as two 4-lane words, (o.x, o.y, o.z, d.x) and (d.y, d.z, tmin, tmax),
    // each compared with its limit at once: the same comparisons as the scalar form below
    // (SSE2's ordered ones are false for NaN as well; the sign mask is fabs), in a third of its
    // instructions (two rays a preview pixel: ~1% of its frame).
    static_assert(sizeof(Ray) == 8 * sizeof(float), "Ray is eight packed floats");
    const auto* words = reinterpret_cast<const float*>(&ray);
    const __m128 sign = _mm_castsi128_ps(_mm_set1_epi32(0x7FFFFFFF));
    const __m128 a = _mm_and_ps(_mm_loadu_ps(words), sign);
    const __m128 b = _mm_and_ps(_mm_loadu_ps(words + 4), sign);
    const float lo = limits.origin, ld = limits.direction;
    const int within = _mm_movemask_ps(_mm_cmple_ps(a, _mm_setr_ps(lo, lo, lo, ld))) |
                       (_mm_movemask_ps(_mm_cmple_ps(b, _mm_set1_ps(ld))) << 4);
    const __m128 dmin = _mm_set1_ps(limits.min_direction);
    const int longer = (_mm_movemask_ps(_mm_cmpgt_ps(a, dmin)) & 0x8) |
                       (_mm_movemask_ps(_mm_cmpgt_ps(b, dmin)) & 0x3);
    return ((within & 0x3F) == 0x3F) & (longer != 0) & interval_ok;
#else
    const vec3 o = ray.origin, d = ray.direction;
    const float lo = limits.origin, ld = limits.direction;
    const bool origin_ok = (std::fabs(o.x) <= lo) & (std::fabs(o.y) <= lo) &
                           (std::fabs(o.z) <= lo);
    const float dmin = limits.min_direction;
    const bool direction_ok = (std::fabs(d.x) <= ld) & (std::fabs(d.y) <= ld) &
                              (std::fabs(d.z) <= ld) &
                              ((std::fabs(d.x) > dmin) | (std::fabs(d.y) > dmin) |
                               (std::fabs(d.z) > dmin));
    return origin_ok & direction_ok & interval_ok;
#endif
}
// The index of the first ray of rays[0, count) that is_valid_ray rejects, or count. In SSE2 four
// rays at a time, their eight floats transposed into lanes (ox, oy, oz, dx and dy, dz, tmin,
// tmax): is_valid_ray's comparisons, each on four rays at once, so one test per four rays where
// is_valid_ray needs its own ~30 instructions per ray (every batch of rays Scene traces comes
// through here). A group with an invalid ray is searched ray by ray with is_valid_ray.
inline size_t first_invalid_ray(const Ray* rays, size_t count,
                                const RayLimits& limits = RayLimits{}) {
    size_t i = 0;
#if defined(__SSE2__)
    static_assert(sizeof(Ray) == 8 * sizeof(float), "Ray is eight packed floats");
    const __m128 sign = _mm_castsi128_ps(_mm_set1_epi32(0x7FFFFFFF));
    const __m128 lo = _mm_set1_ps(limits.origin), ld = _mm_set1_ps(limits.direction);
    const __m128 dmin = _mm_set1_ps(limits.min_direction);
    const __m128 zero = _mm_setzero_ps();
    const __m128 largest = _mm_set1_ps(std::numeric_limits<float>::max());
    for (; i + 4 <= count; i += 4) {
        const auto* words = reinterpret_cast<const float*>(rays + i);
        __m128 ox = _mm_loadu_ps(words), oy = _mm_loadu_ps(words + 8),
               oz = _mm_loadu_ps(words + 16), dx = _mm_loadu_ps(words + 24);
        _MM_TRANSPOSE4_PS(ox, oy, oz, dx);
        __m128 dy = _mm_loadu_ps(words + 4), dz = _mm_loadu_ps(words + 12),
               tmin = _mm_loadu_ps(words + 20), tmax = _mm_loadu_ps(words + 28);
        _MM_TRANSPOSE4_PS(dy, dz, tmin, tmax);
        const __m128 adx = _mm_and_ps(dx, sign), ady = _mm_and_ps(dy, sign),
                     adz = _mm_and_ps(dz, sign);
        const __m128 origin_ok = _mm_and_ps(
            _mm_and_ps(_mm_cmple_ps(_mm_and_ps(ox, sign), lo),
                       _mm_cmple_ps(_mm_and_ps(oy, sign), lo)),
            _mm_cmple_ps(_mm_and_ps(oz, sign), lo));
        const __m128 direction_ok = _mm_and_ps(
            _mm_and_ps(_mm_and_ps(_mm_cmple_ps(adx, ld), _mm_cmple_ps(ady, ld)),
                       _mm_cmple_ps(adz, ld)),
            _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(adx, dmin), _mm_cmpgt_ps(ady, dmin)),
                      _mm_cmpgt_ps(adz, dmin)));
        const __m128 interval_ok =
            _mm_and_ps(_mm_and_ps(_mm_cmpge_ps(tmin, zero), _mm_cmple_ps(tmin, largest)),
                       _mm_cmpge_ps(tmax, tmin));
        if (_mm_movemask_ps(_mm_and_ps(_mm_and_ps(origin_ok, direction_ok), interval_ok)) != 0xF)
            break;
    }
#endif
    while (i < count && is_valid_ray(rays[i], limits)) ++i;
    return i;
}

// Why is_valid_ray rejects `ray` ("direction is zero", ...), or nullptr for a valid ray;
// *out_of_range (if given) says whether the problem is a finite value beyond the limits.
const char* ray_problem(const Ray& ray, const RayLimits& limits = RayLimits{},
                        bool* out_of_range = nullptr);

// m * n, bit for bit as glm computes it ((m[0] n.x + m[1] n.y) + m[2] n.z per component), on
// three SSE2 lanes at once: the same operations in the same order (no FMA in the baseline x86-64
// build), a third of the scalar form's instructions. Scene turns every hit's Embree normal into
// world space with it. The last column is loaded from one float before it, so that no load
// reads past the matrix; the fourth lanes are not used.
inline vec3 transform_normal(const mat3& m, const vec3& n) {
#if defined(__SSE2__)
    static_assert(sizeof(mat3) == 9 * sizeof(float), "mat3 is nine packed floats");
    const float* columns = &m[0][0];
    const __m128 c0 = _mm_loadu_ps(columns), c1 = _mm_loadu_ps(columns + 3);
    const __m128 shifted = _mm_loadu_ps(columns + 5);
    const __m128 c2 = _mm_shuffle_ps(shifted, shifted, _MM_SHUFFLE(3, 3, 2, 1));
    const __m128 r = _mm_add_ps(
        _mm_add_ps(_mm_mul_ps(c0, _mm_set1_ps(n.x)), _mm_mul_ps(c1, _mm_set1_ps(n.y))),
        _mm_mul_ps(c2, _mm_set1_ps(n.z)));
    vec3 out;
    _mm_storel_pi(reinterpret_cast<__m64*>(&out.x), r);
    _mm_store_ss(&out.z, _mm_movehl_ps(r, r));
    return out;
#else
    return m * n;
#endif
}

// A hint for batches of rays: Coherent rays (a tile's camera rays, shadow rays from neighbouring
// pixels to one light) start close together and point alike, so Embree traverses them as packets.
// Results are the same either way; only the speed differs.
enum class RayCoherence { Incoherent, Coherent };

struct Hit {
    float t = kInfinity;
    uint32_t instance_id = kInvalidId;  // index into Scene::instances()
    uint32_t triangle_id = kInvalidId;  // triangle index within the instance's mesh (after
                                        // degenerate triangles were dropped)
    vec2 barycentrics{0.0f};            // (b1, b2): p = (1-b1-b2) p0 + b1 p1 + b2 p2
    vec3 geometric_normal{0.0f};        // world space, unnormalised, facing as wound (CCW)

    bool valid() const { return instance_id != kInvalidId; }
};

}  // namespace shgi
