#include "scene/ray.h"

namespace shgi {

const char* ray_problem(const Ray& ray, const RayLimits& limits) {
    if (!is_finite(ray.origin)) return "origin is not finite";
    if (!is_finite(ray.direction)) return "direction is not finite";
    if (max_abs_component(ray.origin) > limits.origin)
        return "origin exceeds the scene's ray range (beyond Embree's)";
    if (max_abs_component(ray.direction) > limits.direction)
        return "direction exceeds the scene's ray range (beyond Embree's)";
    if (ray.direction.x == 0.0f && ray.direction.y == 0.0f && ray.direction.z == 0.0f)
        return "direction is zero";
    // tmax may be +inf (an unbounded ray) but never NaN; tmin must be finite.
    if (!std::isfinite(ray.tmin) || ray.tmin < 0.0f) return "tmin must be finite and >= 0";
    if (std::isnan(ray.tmax)) return "tmax is NaN";
    if (ray.tmax < ray.tmin) return "tmax is less than tmin";
    return nullptr;
}

}  // namespace shgi
