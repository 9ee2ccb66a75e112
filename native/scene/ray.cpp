#include "scene/ray.h"

namespace shgi {

const char* ray_problem(const Ray& ray, const RayLimits& limits, bool* out_of_range) {
    if (out_of_range != nullptr) *out_of_range = false;
    if (!is_finite(ray.origin)) return "origin is not finite";
    if (!is_finite(ray.direction)) return "direction is not finite";
    const bool origin_beyond = max_abs_component(ray.origin) > limits.origin;
    const bool direction_beyond = max_abs_component(ray.direction) > limits.direction;
    if (out_of_range != nullptr) *out_of_range = origin_beyond || direction_beyond;
    if (origin_beyond) return "origin exceeds the scene's ray range (beyond Embree's)";
    if (direction_beyond) return "direction exceeds the scene's ray range (beyond Embree's)";
    if (ray.direction.x == 0.0f && ray.direction.y == 0.0f && ray.direction.z == 0.0f)
        return "direction is zero";
    if (!(max_abs_component(ray.direction) > limits.min_direction)) {
        if (out_of_range != nullptr) *out_of_range = true;
        return "direction is shorter than the scene's ray range (hit distances in its units "
               "would pass float's range; normalise it)";
    }
    // tmax may be +inf (an unbounded ray) but never NaN; tmin must be finite.
    if (!std::isfinite(ray.tmin) || ray.tmin < 0.0f) return "tmin must be finite and >= 0";
    if (std::isnan(ray.tmax)) return "tmax is NaN";
    if (ray.tmax < ray.tmin) return "tmax is less than tmin";
    return nullptr;
}

}  // namespace shgi
