#include "scene/ray.h"

namespace shgi {

const char* ray_problem(const Ray& ray) {
    if (!is_finite(ray.origin)) return "origin is not finite";
    if (!is_finite(ray.direction)) return "direction is not finite";
    if (max_abs_component(ray.origin) > kMaxRayComponent)
        return "origin exceeds 1e18 in magnitude (beyond Embree's range)";
    if (max_abs_component(ray.direction) > kMaxRayComponent)
        return "direction exceeds 1e18 in magnitude (beyond Embree's range)";
    if (ray.direction.x == 0.0f && ray.direction.y == 0.0f && ray.direction.z == 0.0f)
        return "direction is zero";
    // tmax may be +inf (an unbounded ray) but never NaN; tmin must be finite.
    if (!std::isfinite(ray.tmin) || ray.tmin < 0.0f) return "tmin must be finite and >= 0";
    if (std::isnan(ray.tmax)) return "tmax is NaN";
    if (ray.tmax < ray.tmin) return "tmax is less than tmin";
    return nullptr;
}

}  // namespace shgi
