#include "scene/camera.h"

#include <algorithm>
#include <cmath>
#include <limits>
#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

#include "scene/validation.h"
#include "util/error.h"

namespace shgi {
namespace {

using namespace scene_detail;

// The image rectangle in camera space: on the plane z = -1 for a perspective camera (so x, y
// are tangents of the view angles), in metres on z = 0 for an orthographic one. In float for
// rays; validate_camera computes it in double, where extreme fields cannot overflow.
template <typename Real>
struct Viewplane {
    Real xmin, xmax, ymin, ymax;
};

// Blender spans the sensor height only with Vertical fit; Auto spans the larger image dimension
// with sensor_width.
bool spans_sensor_height(const Camera& camera) { return camera.sensor_fit == SensorFit::Vertical; }

// Blender's BKE_camera_params_compute_viewplane with pixel aspect 1 and no border: the sensor
// (or ortho_scale) spans the fitted axis; Auto fits the larger image dimension with
// sensor_width; the shift is in units of the fitted dimension.
template <typename Real>
Viewplane<Real> compute_viewplane(const Camera& camera) {
    const Real width = static_cast<Real>(camera.resolution_x);
    const Real height = static_cast<Real>(camera.resolution_y);
    const Real sensor_size =
        spans_sensor_height(camera) ? camera.sensor_height : camera.sensor_width;
    SensorFit fit = camera.sensor_fit;
    if (fit == SensorFit::Auto) fit = width >= height ? SensorFit::Horizontal : SensorFit::Vertical;
    const Real view_factor = fit == SensorFit::Horizontal ? width : height;
    const Real fitted_extent = camera.type == CameraType::Orthographic
                                   ? Real(camera.ortho_scale)
                                   : sensor_size / Real(camera.lens);
    const Real pixel_size = fitted_extent / view_factor;
    const Real dx = Real(camera.shift_x) * view_factor;
    const Real dy = Real(camera.shift_y) * view_factor;
    const Real half = Real(0.5);
    return {(-half * width + dx) * pixel_size, (half * width + dx) * pixel_size,
            (-half * height + dy) * pixel_size, (half * height + dy) * pixel_size};
}

// Blender's camera matrix with its scale removed (Cycles' transform_clear_scale): a scaled camera
// object renders as if unscaled. In double: the squared length of an axis scaled by 1e30 (or
// 1e-30), which validate_camera accepts, would overflow (underflow) a float.
mat4 unscaled(const mat4& world_from_camera) {
    mat4 m = world_from_camera;
    for (int axis = 0; axis < 3; ++axis)
        m[axis] = vec4(vec3(glm::normalize(glm::dvec3(vec3(m[axis])))), 0.0f);
    return m;
}

}  // namespace

Ray Camera::generate_ray(const vec2& film) const {
    return CameraRayGenerator(*this).generate_ray(film);
}

CameraRayGenerator::CameraRayGenerator(const Camera& camera)
    : type_(camera.type),
      frame_(unscaled(camera.world_from_camera)),
      width_(static_cast<float>(camera.resolution_x)),
      height_(static_cast<float>(camera.resolution_y)),
      clip_start_(camera.clip_start),
      clip_end_(camera.clip_end) {
    const Viewplane<float> plane = compute_viewplane<float>(camera);
    xmin_ = plane.xmin;
    xmax_ = plane.xmax;
    ymin_ = plane.ymin;
    ymax_ = plane.ymax;
}

Ray CameraRayGenerator::generate_ray(const vec2& film) const {
    const float u = film.x / width_;
    const float v = film.y / height_;
    // Film y grows downwards, camera y upwards.
    const float x = xmin_ + u * (xmax_ - xmin_);
    const float y = ymax_ - v * (ymax_ - ymin_);
    Ray ray;
    if (type_ == CameraType::Orthographic) {
        ray.origin = vec3(frame_ * vec4(x, y, 0.0f, 1.0f));
        ray.direction = glm::normalize(-vec3(frame_[2]));
        ray.tmin = clip_start_;
        ray.tmax = clip_end_;
        return ray;
    }
    const vec3 local(x, y, -1.0f);
    // Clip planes are distances along the view axis; along a ray whose view-axis component is
    // 1 / |local| per unit length they are |local| times longer.
    const float axis_to_ray = glm::length(local);
    ray.origin = vec3(frame_[3]);
    ray.direction = glm::normalize(vec3(frame_ * vec4(local, 0.0f)));
    ray.tmin = clip_start_ * axis_to_ray;
    ray.tmax = clip_end_ * axis_to_ray;
    return ray;
}

void CameraRayGenerator::generate_rays(const vec2* film, size_t count, Ray* out) const {
    size_t i = 0;
#if defined(__SSE2__)
    if (type_ == CameraType::Perspective) {
        static_assert(sizeof(Ray) == 8 * sizeof(float), "a ray is two rows of four floats");
        // generate_ray's arithmetic on four rays, operation for operation: glm's mat4 x vec4 is
        // (m0 x + m1 y) + (m2 z + m3 w), its dot product (x x + y y) + z z, normalize multiplies
        // by 1 / sqrt(dot), and without FMA in the build every product is rounded before its sum.
        const __m128 width = _mm_set1_ps(width_), height = _mm_set1_ps(height_);
        const __m128 xmin = _mm_set1_ps(xmin_), ymax = _mm_set1_ps(ymax_);
        const __m128 xspan = _mm_set1_ps(xmax_ - xmin_), yspan = _mm_set1_ps(ymax_ - ymin_);
        const __m128 one = _mm_set1_ps(1.0f), minus_one = _mm_set1_ps(-1.0f);
        const __m128 zero = _mm_setzero_ps();
        const __m128 clip_start = _mm_set1_ps(clip_start_), clip_end = _mm_set1_ps(clip_end_);
        __m128 column[4][3];
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 3; ++r) column[c][r] = _mm_set1_ps(frame_[c][r]);
        const vec3 origin(frame_[3]);
        for (; i + 4 <= count; i += 4) {
            const __m128 u =
                _mm_div_ps(_mm_setr_ps(film[i].x, film[i + 1].x, film[i + 2].x, film[i + 3].x),
                           width);
            const __m128 v =
                _mm_div_ps(_mm_setr_ps(film[i].y, film[i + 1].y, film[i + 2].y, film[i + 3].y),
                           height);
            const __m128 x = _mm_add_ps(xmin, _mm_mul_ps(u, xspan));
            const __m128 y = _mm_sub_ps(ymax, _mm_mul_ps(v, yspan));
            const __m128 axis_to_ray = _mm_sqrt_ps(_mm_add_ps(
                _mm_add_ps(_mm_mul_ps(x, x), _mm_mul_ps(y, y)), _mm_mul_ps(minus_one, minus_one)));
            __m128 d[3];
            for (int r = 0; r < 3; ++r)
                d[r] = _mm_add_ps(
                    _mm_add_ps(_mm_mul_ps(column[0][r], x), _mm_mul_ps(column[1][r], y)),
                    _mm_add_ps(_mm_mul_ps(column[2][r], minus_one), _mm_mul_ps(column[3][r], zero)));
            const __m128 length2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(d[0], d[0]), _mm_mul_ps(d[1], d[1])),
                                              _mm_mul_ps(d[2], d[2]));
            const __m128 inv_length = _mm_div_ps(one, _mm_sqrt_ps(length2));
            // Rows (origin x, y, z, direction x) and (direction y, z, tmin, tmax) per ray.
            __m128 first0 = _mm_set1_ps(origin.x), first1 = _mm_set1_ps(origin.y);
            __m128 first2 = _mm_set1_ps(origin.z), first3 = _mm_mul_ps(d[0], inv_length);
            __m128 second0 = _mm_mul_ps(d[1], inv_length), second1 = _mm_mul_ps(d[2], inv_length);
            __m128 second2 = _mm_mul_ps(clip_start, axis_to_ray);
            __m128 second3 = _mm_mul_ps(clip_end, axis_to_ray);
            _MM_TRANSPOSE4_PS(first0, first1, first2, first3);
            _MM_TRANSPOSE4_PS(second0, second1, second2, second3);
            float* ray = reinterpret_cast<float*>(out + i);
            const __m128 rows[8] = {first0, second0, first1, second1,
                                    first2, second2, first3, second3};
            for (int k = 0; k < 8; ++k) _mm_storeu_ps(ray + 4 * k, rows[k]);
        }
    }
#endif
    for (; i < count; ++i) out[i] = generate_ray(film[i]);
}

bool Camera::project(const vec3& p, vec2* film) const {
    const vec3 local = vec3(glm::inverse(unscaled(world_from_camera)) * vec4(p, 1.0f));
    float x = local.x, y = local.y;
    if (type == CameraType::Perspective) {
        if (!(local.z < 0.0f)) return false;
        x /= -local.z;
        y /= -local.z;
    } else if (local.z > 0.0f) {
        return false;
    }
    const Viewplane<float> plane = compute_viewplane<float>(*this);
    if (film) {
        film->x = (x - plane.xmin) / (plane.xmax - plane.xmin) * static_cast<float>(resolution_x);
        film->y = (plane.ymax - y) / (plane.ymax - plane.ymin) * static_cast<float>(resolution_y);
    }
    return true;
}

namespace {

// Each field may be finite while the rays they make together are not (shift_x = 1e38 puts the
// image plane past float range; ortho_scale = 1e20 starts rays beyond any scene): the image
// plane's reach, in double, must stay within kMaxCoordinate, and a perspective ray's clip_start
// (longer along rays off the view axis) finite. The message names the fields that set it.
void validate_image_plane(const Camera& camera, const std::string& item) {
    const Viewplane<double> plane = compute_viewplane<double>(camera);
    const double reach = std::max({std::fabs(plane.xmin), std::fabs(plane.xmax),
                                   std::fabs(plane.ymin), std::fabs(plane.ymax)});
    const bool ortho = camera.type == CameraType::Orthographic;
    const bool sensor_height = spans_sensor_height(camera);
    const std::string fields =
        ortho ? format_message("ortho_scale = ", camera.ortho_scale)
              : format_message("lens = ", camera.lens, " mm, ",
                               sensor_height ? "sensor_height = " : "sensor_width = ",
                               sensor_height ? camera.sensor_height : camera.sensor_width, " mm");
    if (!(reach <= double(kMaxCoordinate)))
        throw InvalidArgument(format_message(
            item, ": shift_x = ", camera.shift_x, " and shift_y = ", camera.shift_y, " with ",
            fields, " put the image plane's edge ", reach, ortho ? " m" : " (a tangent)",
            " from the view axis, past ", kMaxCoordinate, "; lower ",
            std::max(std::fabs(camera.shift_x), std::fabs(camera.shift_y)) > 1.0f
                ? "shift_x / shift_y"
                : (ortho ? "ortho_scale" : "the sensor size or raise lens")));
    if (ortho) return;
    const double clip_start = double(camera.clip_start) * std::sqrt(1.0 + 2.0 * reach * reach);
    if (!(clip_start <= double(std::numeric_limits<float>::max())))
        throw InvalidArgument(format_message(
            item, ": clip_start = ", camera.clip_start, " m is ", clip_start, " m along the "
            "image corner's ray (", fields, "), past float range; lower clip_start"));
}

}  // namespace

void validate_camera(const Camera& camera) {
    const std::string item = "camera";
    require_transform(item, "world_from_camera", camera.world_from_camera);
    if (camera.type != CameraType::Perspective && camera.type != CameraType::Orthographic)
        throw InvalidArgument(format_message(item, ": type = ", static_cast<int>(camera.type),
                                             " is unknown"));
    require_positive(item, "lens", camera.lens);
    require_positive(item, "sensor_width", camera.sensor_width);
    require_positive(item, "sensor_height", camera.sensor_height);
    require_positive(item, "ortho_scale", camera.ortho_scale);
    require_finite(item, "shift_x", camera.shift_x);
    require_finite(item, "shift_y", camera.shift_y);
    require_non_negative(item, "clip_start", camera.clip_start);
    require_finite(item, "clip_end", camera.clip_end);
    if (!(camera.clip_start < camera.clip_end))
        throw InvalidArgument(format_message(item, ": clip_start = ", camera.clip_start,
                                             " must be < clip_end = ", camera.clip_end));
    if (camera.resolution_x == 0 || camera.resolution_y == 0)
        throw InvalidArgument(format_message(item, ": resolution ", camera.resolution_x, " x ",
                                             camera.resolution_y, " must be at least 1 x 1"));
    // Films and images take int sides: a larger side would wrap to a negative size.
    if (camera.resolution_x > kMaxCameraResolution || camera.resolution_y > kMaxCameraResolution)
        throw InvalidArgument(format_message(item, ": resolution ", camera.resolution_x, " x ",
                                             camera.resolution_y, " has a side above ",
                                             kMaxCameraResolution, "; render it in tiles"));
    validate_image_plane(camera, item);
}

}  // namespace shgi
