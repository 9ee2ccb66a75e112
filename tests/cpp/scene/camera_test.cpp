// Camera rays against Blender's camera model, worked out by hand: the sensor (or ortho_scale)
// spans the fitted image axis, Auto fits the larger dimension with sensor_width, shift is in
// units of the fitted dimension, clip distances are measured along the view axis.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "scene/camera.h"

namespace shgi {
namespace {

// Float rounding of a few multiplications: directions and positions of unit magnitude.
constexpr float kTolerance = 1e-5f;
// Film positions after a generate_ray -> project round trip (pixels).
constexpr float kFilmTolerance = 1e-3f;

void expect_near(const vec3& actual, const vec3& expected, float tolerance = kTolerance) {
    EXPECT_NEAR(actual.x, expected.x, tolerance);
    EXPECT_NEAR(actual.y, expected.y, tolerance);
    EXPECT_NEAR(actual.z, expected.z, tolerance);
}

TEST(Camera, CenterPixelLooksDownMinusZ) {
    Camera camera;  // identity: at the origin, looking down -Z, 640 x 480
    const Ray ray = camera.generate_ray(vec2(320, 240));
    expect_near(ray.origin, vec3(0));
    expect_near(ray.direction, vec3(0, 0, -1));
    EXPECT_FLOAT_EQ(ray.tmin, camera.clip_start);
    EXPECT_FLOAT_EQ(ray.tmax, camera.clip_end);
}

TEST(Camera, AutoFitSpansTheWiderAxisWithSensorWidth) {
    Camera camera;  // 640 x 480 landscape, lens 50, sensor 36: tan(half width) = 18 / 50
    const Ray corner = camera.generate_ray(vec2(0, 0));
    expect_near(corner.direction, glm::normalize(vec3(-0.36f, 0.27f, -1.0f)));
    // Clip planes are perpendicular to the view axis: along this ray they are further away.
    EXPECT_NEAR(corner.tmin, camera.clip_start * glm::length(vec3(0.36f, 0.27f, 1.0f)), 1e-6f);

    camera.resolution_x = 480;  // portrait: Auto fits the height with sensor_width
    camera.resolution_y = 640;
    expect_near(camera.generate_ray(vec2(480, 640)).direction,
                glm::normalize(vec3(0.27f, -0.36f, -1.0f)));
}

TEST(Camera, VerticalFitUsesSensorHeight) {
    Camera camera;
    camera.sensor_fit = SensorFit::Vertical;  // 24 mm across 480 px: tan = 12 / 50 = 0.24
    expect_near(camera.generate_ray(vec2(640, 0)).direction,
                glm::normalize(vec3(0.32f, 0.24f, -1.0f)));
}

TEST(Camera, HorizontalFitOnPortraitImage) {
    Camera camera;
    camera.sensor_fit = SensorFit::Horizontal;
    camera.resolution_x = 480;
    camera.resolution_y = 640;  // width spans 36 mm: tan(half width) = 0.36, height 0.48
    expect_near(camera.generate_ray(vec2(0, 640)).direction,
                glm::normalize(vec3(-0.36f, -0.48f, -1.0f)));
}

TEST(Camera, ShiftIsInUnitsOfTheFittedDimension) {
    Camera camera;
    camera.shift_x = 0.1f;   // 0.1 * 36 / 50 = 0.072 along x
    camera.shift_y = -0.2f;  // -0.2 * 0.72 = -0.144 along y (also the larger dimension)
    expect_near(camera.generate_ray(vec2(320, 240)).direction,
                glm::normalize(vec3(0.072f, -0.144f, -1.0f)));
}

TEST(Camera, OrthographicRaysAreParallelAndSpanOrthoScale) {
    Camera camera;
    camera.type = CameraType::Orthographic;
    camera.ortho_scale = 4.0f;  // 4 m across 640 px, so 3 m across 480 px
    camera.world_from_camera = glm::translate(mat4(1.0f), vec3(0, 0, 10));
    const Ray corner = camera.generate_ray(vec2(0, 0));
    expect_near(corner.origin, vec3(-2.0f, 1.5f, 10.0f));
    expect_near(corner.direction, vec3(0, 0, -1));
    EXPECT_FLOAT_EQ(corner.tmin, camera.clip_start);
}

TEST(Camera, ScaleOfTheCameraObjectIsIgnored) {
    Camera camera;
    camera.world_from_camera = glm::scale(mat4(1.0f), vec3(3.0f));
    expect_near(camera.generate_ray(vec2(0, 0)).direction,
                glm::normalize(vec3(-0.36f, 0.27f, -1.0f)));
}

// Any finite non-zero scale: an axis scaled by 1e30 (or 1e-30) squares to beyond (below) float.
TEST(Camera, ExtremeScalesOfTheCameraObjectAreIgnored) {
    Camera unit;
    unit.world_from_camera = glm::rotate(mat4(1.0f), 0.4f, glm::normalize(vec3(1, 2, 3)));
    for (const float scale : {1e30f, 1e-30f}) {
        Camera scaled = unit;
        scaled.world_from_camera = unit.world_from_camera * glm::scale(mat4(1.0f), vec3(scale));
        ASSERT_NO_THROW(validate_camera(scaled)) << scale;
        for (const vec2 film : {vec2(0, 0), vec2(320, 240), vec2(639.5f, 10)}) {
            const Ray ray = scaled.generate_ray(film);
            ASSERT_TRUE(is_finite(ray.direction)) << scale;
            expect_near(ray.direction, unit.generate_ray(film).direction);
            vec2 projected;
            ASSERT_TRUE(scaled.project(ray.origin + 5.0f * ray.direction, &projected));
            EXPECT_NEAR(projected.x, film.x, kFilmTolerance);
            EXPECT_NEAR(projected.y, film.y, kFilmTolerance);
        }
    }
}

TEST(Camera, ProjectInvertsGenerateRay) {
    for (const CameraType type : {CameraType::Perspective, CameraType::Orthographic}) {
        Camera camera;
        camera.type = type;
        camera.shift_x = 0.05f;
        camera.sensor_fit = SensorFit::Vertical;
        camera.world_from_camera = glm::translate(mat4(1.0f), vec3(1, -2, 3)) *
                                   glm::rotate(mat4(1.0f), 1.1f, glm::normalize(vec3(1, 2, 3)));
        for (const vec2 film :
             {vec2(0.5f, 0.5f), vec2(320, 240), vec2(639.5f, 10), vec2(17, 470)}) {
            const Ray ray = camera.generate_ray(film);
            vec2 projected;
            ASSERT_TRUE(camera.project(ray.origin + 5.0f * ray.direction, &projected));
            EXPECT_NEAR(projected.x, film.x, kFilmTolerance);
            EXPECT_NEAR(projected.y, film.y, kFilmTolerance);
        }
    }
}

void expect_same_ray(const Ray& actual, const Ray& expected) {
    EXPECT_EQ(actual.origin, expected.origin);
    EXPECT_EQ(actual.direction, expected.direction);
    EXPECT_EQ(actual.tmin, expected.tmin);
    EXPECT_EQ(actual.tmax, expected.tmax);
}

// A generator is a snapshot: editing the camera afterwards (a viewport moving on while a frame
// renders) does not change the rays of a generator built before.
TEST(Camera, RayGeneratorKeepsTheCameraItWasBuiltFrom) {
    for (const CameraType type : {CameraType::Perspective, CameraType::Orthographic}) {
        Camera camera;
        camera.type = type;
        camera.shift_y = -0.1f;
        camera.world_from_camera = glm::rotate(mat4(1.0f), 0.7f, vec3(0, 0, 1)) *
                                   glm::scale(mat4(1.0f), vec3(2.0f));  // scale is ignored
        const Camera before = camera;
        const CameraRayGenerator rays(camera);
        camera.lens = 24.0f;
        camera.ortho_scale = 3.0f;
        camera.world_from_camera = mat4(1.0f);
        for (const vec2 film : {vec2(0, 0), vec2(320.25f, 240.75f), vec2(640, 480)})
            expect_same_ray(rays.generate_ray(film), before.generate_ray(film));
    }
}

// generate_rays (four perspective rays at a time in SSE2) gives generate_ray's rays bit for
// bit: both camera types, a rotated, shifted and translated camera, counts with and without a
// remainder, film points at the corners, inside and outside the image.
TEST(Camera, GenerateRaysIsGenerateRayBitForBit) {
    std::vector<vec2> film;
    uint32_t x = 99u;
    for (int i = 0; i < 23; ++i) {
        x = x * 1664525u + 1013904223u;
        film.push_back(vec2(float(x % 1000u) * 0.73f - 40.0f, float(x >> 22) * 0.51f - 30.0f));
    }
    film[0] = vec2(0.0f);
    film[1] = vec2(640.0f, 480.0f);
    for (const CameraType type : {CameraType::Perspective, CameraType::Orthographic}) {
        Camera camera;
        camera.type = type;
        camera.shift_x = 0.05f;
        camera.clip_start = 0.03f;
        camera.world_from_camera = glm::translate(mat4(1.0f), vec3(1, -2, 3)) *
                                   glm::rotate(mat4(1.0f), 1.1f, glm::normalize(vec3(1, 2, 3)));
        const CameraRayGenerator generator(camera);
        for (const size_t count : {size_t(0), size_t(3), size_t(4), size_t(23)}) {
            std::vector<Ray> rays(count);
            generator.generate_rays(film.data(), count, rays.data());
            for (size_t i = 0; i < count; ++i) {
                const Ray one = generator.generate_ray(film[i]);
                EXPECT_EQ(std::memcmp(&rays[i], &one, sizeof(Ray)), 0)
                    << "camera type " << int(type) << ", film point " << film[i].x << ", "
                    << film[i].y;
            }
        }
    }
}

TEST(Camera, ProjectRejectsPointsBehind) {
    Camera camera;
    vec2 film;
    EXPECT_FALSE(camera.project(vec3(0, 0, 1), &film));
    EXPECT_TRUE(camera.project(vec3(0, 0, -1), &film));
    EXPECT_NEAR(film.x, 320.0f, kFilmTolerance);
    EXPECT_NEAR(film.y, 240.0f, kFilmTolerance);
}

}  // namespace
}  // namespace shgi
