#include "util/math.h"

namespace shgi {

bool is_finite(const mat4& m) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(m[c][r])) return false;
    return true;
}

Frame Frame::from_z(const vec3& n) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float b = n.x * n.y * a;
    Frame frame;
    frame.x = vec3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    frame.y = vec3(b, sign + n.y * n.y * a, -n.y);
    frame.z = n;
    return frame;
}

}  // namespace shgi
