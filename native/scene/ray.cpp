#include "scene/ray.h"

namespace shgi {

bool is_valid_ray(const Ray& ray) {
    if (!is_finite(ray.origin) || !is_finite(ray.direction)) return false;
    if (ray.direction.x == 0.0f && ray.direction.y == 0.0f && ray.direction.z == 0.0f) return false;
    // tmax may be +inf (an unbounded ray) but never NaN; tmin must be finite.
    if (!std::isfinite(ray.tmin) || ray.tmin < 0.0f) return false;
    if (std::isnan(ray.tmax) || ray.tmax < ray.tmin) return false;
    return true;
}

}  // namespace shgi
