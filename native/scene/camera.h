// Cameras from Blender's parameters: perspective and orthographic.
//
// world_from_camera is Blender's camera matrix_world (the camera looks down its local -Z with +Y
// up). The sensor fit, lens, sensor size and shift follow Blender's camera data; resolution is
// the render size in pixels. Film coordinates: (0,0) is the top-left corner of the image, x to
// the right, y down, in pixels (pixel (i,j) covers [i,i+1) x [j,j+1)).
#pragma once

#include <cstdint>

#include "scene/ray.h"
#include "util/math.h"

namespace shgi {

enum class CameraType : uint8_t { Perspective, Orthographic };
enum class SensorFit : uint8_t { Auto, Horizontal, Vertical };

struct Camera {
    CameraType type = CameraType::Perspective;
    mat4 world_from_camera{1.0f};
    float lens = 50.0f;            // mm (perspective)
    float sensor_width = 36.0f;    // mm
    float sensor_height = 24.0f;   // mm
    SensorFit sensor_fit = SensorFit::Auto;
    float ortho_scale = 7.314f;    // m across the fitted axis (orthographic)
    float shift_x = 0.0f, shift_y = 0.0f;  // in units of the larger image dimension, as Blender
    float clip_start = 0.1f, clip_end = 1000.0f;  // m
    uint32_t resolution_x = 640, resolution_y = 480;

    // A ray through film point `film` (pixels, see above); direction is unit length, tmin and
    // tmax are the clip distances along the view axis converted to distances along the ray.
    Ray generate_ray(const vec2& film) const;

    // Inverse of generate_ray for points in front of the camera: the film position of world
    // point p, or false when p is behind the camera.
    bool project(const vec3& p, vec2* film) const;
};

// Camera::generate_ray for many film points: the image rectangle on the viewplane and the
// camera frame without its scale, which generate_ray derives from the camera's fields on every
// call, are computed once here (renderers build one per frame). Rays are bit-identical to
// generate_ray's; the generator keeps copies, so later edits of the camera do not reach it.
class CameraRayGenerator {
  public:
    explicit CameraRayGenerator(const Camera& camera);
    Ray generate_ray(const vec2& film) const;
    // out[i] = generate_ray(film[i]) for i in [0, count), bit for bit; a perspective camera's
    // rays four at a time in SSE2 (the same operations in the same order on every lane).
    void generate_rays(const vec2* film, size_t count, Ray* out) const;

  private:
    CameraType type_;
    mat4 frame_;  // world_from_camera without scale
    float xmin_, xmax_, ymin_, ymax_;  // the viewplane (camera space)
    float width_, height_;  // resolution in pixels
    float clip_start_, clip_end_;
};

// Throws InvalidArgument naming the field (NaN/Inf transform, non-positive lens or sensor,
// a resolution of 0 or above kMaxCameraResolution, clip_start >= clip_end, ...).
void validate_camera(const Camera& camera);
// The largest resolution_x or resolution_y: an image's largest side (io/image.h's
// kMaxImageDimension, which static_asserts that they agree).
inline constexpr uint32_t kMaxCameraResolution = 1u << 20;

}  // namespace shgi
