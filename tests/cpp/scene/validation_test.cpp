// validate_material / validate_texture / validate_light / validate_world / validate_camera:
// each bad field is rejected with a message naming the item, the field and the value.
#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "scene/camera.h"
#include "scene/light.h"
#include "scene/material.h"
#include "support/expect_error.h"
#include "util/error.h"

namespace shgi {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

using testing::expect_contains;
using testing::rejection;

TEST(MaterialValidation, DefaultIsValid) {
    EXPECT_EQ(rejection([] { validate_material(Material{}, 0); }), "");
}

TEST(MaterialValidation, RejectsEachBadField) {
    const auto bad = [](const std::function<void(Material&)>& edit) {
        Material material;
        material.name = "Red";
        edit(material);
        return rejection([&] { validate_material(material, 1); });
    };
    expect_contains(bad([](Material& m) { m.base_color.y = kNaN; }),
                    "material 'Red': base_color = (0.8, nan, 0.8) is not finite");
    expect_contains(bad([](Material& m) { m.roughness = 1.5f; }),
                    "material 'Red': roughness = 1.5 is outside [0, 1]");
    expect_contains(bad([](Material& m) { m.metallic = -0.1f; }), "metallic = -0.1");
    expect_contains(bad([](Material& m) { m.ior = 0.5f; }), "ior = 0.5 must be >= 1");
    expect_contains(bad([](Material& m) { m.emission_strength = -1.0f; }),
                    "emission_strength = -1 must be >= 0");
    expect_contains(bad([](Material& m) { m.emission_color = vec3(-1, 0, 0); }),
                    "emission_color = (-1, 0, 0) must have every component >= 0");
    expect_contains(bad([](Material& m) { m.base_color_texture = 3; }),
                    "base_color_texture = 3 but the scene has 1 textures");
    // Finite but absurd values whose products overflow float (inf pixels) are refused by name.
    expect_contains(bad([](Material& m) { m.base_color = vec3(1e38f, 0.5f, 0.5f); }),
                    "material 'Red': base_color = (1e+38, 0.5, 0.5) has component 1e+38 above "
                    "1000");
    EXPECT_EQ(bad([](Material& m) { m.base_color = vec3(1000.0f); }), "");
    expect_contains(bad([](Material& m) {
                        m.emission_color = vec3(1e30f, 1, 1);
                        m.emission_strength = 1e10f;
                    }),
                    "emission_color = (1e+30, 1, 1) times emission_strength = 1e+10");
    // A negative id other than -1 is named, not compared as 4294967294 against the count.
    expect_contains(bad([](Material& m) { m.base_color_texture = -2; }),
                    "material 'Red': base_color_texture = -2 is negative; use -1 for none");
}

TEST(TextureValidation, RejectsSizeMismatchAndNaN) {
    Texture texture;
    texture.name = "Bricks";
    texture.width = 2;
    texture.height = 2;
    texture.texels.assign(3, vec4(1));
    expect_contains(rejection([&] { validate_texture(texture); }),
                    "texture 'Bricks': texels has 3 elements but width x height = 4");
    texture.texels.assign(4, vec4(1));
    texture.texels[2].w = kNaN;
    expect_contains(rejection([&] { validate_texture(texture); }), "texels[2] = (1, 1, 1, nan)");
    texture.texels[2] = vec4(1, 2e3f, 1, 1);
    expect_contains(rejection([&] { validate_texture(texture); }),
                    "texels[2] = (1, 2000, 1) has a component above 1000");
}

TEST(LightValidation, RejectsEachBadField) {
    const auto bad = [](LightType type, const std::function<void(Light&)>& edit) {
        Light light;
        light.name = "Key";
        light.type = type;
        edit(light);
        return rejection([&] { validate_light(light); });
    };
    expect_contains(bad(LightType::Point, [](Light& l) { l.power = -5.0f; }),
                    "light 'Key': power = -5 must be >= 0");
    expect_contains(bad(LightType::Point, [](Light& l) { l.color.x = kNaN; }),
                    "light 'Key': color = (nan, 1, 1) is not finite");
    expect_contains(bad(LightType::Point, [](Light& l) { l.world_from_light[2] = vec4(0); }),
                    "light 'Key': world_from_light is singular");
    expect_contains(bad(LightType::Point, [](Light& l) { l.world_from_light[3].x = kNaN; }),
                    "world_from_light has a non-finite");
    expect_contains(bad(LightType::Spot, [](Light& l) { l.spot_size = 4.0f; }),
                    "spot_size = 4 rad must be in (0, pi]");
    expect_contains(bad(LightType::Spot, [](Light& l) { l.spot_blend = 2.0f; }),
                    "spot_blend = 2 is outside [0, 1]");
    expect_contains(bad(LightType::Sun, [](Light& l) { l.angle = -0.1f; }),
                    "angle = -0.1 rad must be in [0, pi)");
    expect_contains(bad(LightType::Sun, [](Light& l) { l.strength = kNaN; }),
                    "strength = nan is not finite");
    expect_contains(bad(LightType::Area, [](Light& l) { l.size_x = 0.0f; }),
                    "size_x = 0 must be > 0");
    expect_contains(bad(LightType::Area,
                        [](Light& l) {
                            l.shape = AreaShape::Rectangle;
                            l.size_y = -1.0f;
                        }),
                    "size_y = -1 must be > 0");
    // A colour whose product with the power overflows float is blamed on the colour.
    expect_contains(bad(LightType::Point, [](Light& l) { l.color = vec3(1e38f, 1, 1); }),
                    "light 'Key': color = (1e+38, 1, 1) (brightest component 1e+38) times power");
    // A point light ignores the area size.
    EXPECT_EQ(bad(LightType::Point, [](Light& l) { l.size_x = 0.0f; }), "");
    // Rays start anywhere on a light: beyond Embree's range its emission would abort the process.
    expect_contains(bad(LightType::Area, [](Light& l) { l.size_x = 1e20f; }),
                    "beyond 1e+12 m; lower the light's scale (its object's scale in Blender) or "
                    "its size");
    // A scale whose float squares overflow is named, not reported as reaching NaN metres.
    expect_contains(bad(LightType::Area,
                        [](Light& l) { l.world_from_light = glm::scale(mat4(1.0f), vec3(1e20f)); }),
                    "world_from_light scales it by 1e+20, so its size (1 m) reaches 1e+20 m");
    expect_contains(bad(LightType::Area,
                        [](Light& l) { l.world_from_light = glm::scale(mat4(1.0f), vec3(1e19f)); }),
                    "reaches 1e+19 m");
    expect_contains(bad(LightType::Point,
                        [](Light& l) {
                            l.radius = 1e8f;
                            l.world_from_light = glm::scale(mat4(1.0f), vec3(1e8f));
                        }),
                    "reaches 1e+16 m");
    // A square light's unused size_y does not count towards its reach.
    EXPECT_EQ(bad(LightType::Area, [](Light& l) { l.size_y = 1e20f; }), "");
    // A projective bottom row is no object transform.
    expect_contains(bad(LightType::Point, [](Light& l) { l.world_from_light[3].w = 0.0f; }),
                    "world_from_light has the bottom row (0, 0, 0, 0)");
}

TEST(WorldValidation, RejectsNegativeStrength) {
    World world;
    world.strength = -1.0f;
    expect_contains(rejection([&] { validate_world(world); }), "world: strength = -1 must be >= 0");
}

TEST(CameraValidation, RejectsEachBadField) {
    const auto bad = [](const std::function<void(Camera&)>& edit) {
        Camera camera;
        edit(camera);
        return rejection([&] { validate_camera(camera); });
    };
    EXPECT_EQ(bad([](Camera&) {}), "");
    expect_contains(bad([](Camera& c) { c.lens = 0.0f; }), "camera: lens = 0 must be > 0");
    expect_contains(bad([](Camera& c) { c.sensor_width = -36.0f; }),
                    "camera: sensor_width = -36 must be > 0");
    expect_contains(bad([](Camera& c) { c.ortho_scale = kNaN; }),
                    "camera: ortho_scale = nan is not finite");
    expect_contains(bad([](Camera& c) { c.clip_start = 10.0f, c.clip_end = 1.0f; }),
                    "camera: clip_start = 10 must be < clip_end = 1");
    expect_contains(bad([](Camera& c) { c.resolution_x = 0; }),
                    "camera: resolution 0 x 480 must be at least 1 x 1");
    // Found by fuzzing: 2^31 passed and a film of "-2147483648 x 480" was refused later.
    expect_contains(bad([](Camera& c) { c.resolution_x = 1u << 31; }),
                    "camera: resolution 2147483648 x 480 has a side above 1048576");
    EXPECT_EQ(bad([](Camera& c) { c.resolution_y = kMaxCameraResolution; }), "");
    expect_contains(bad([](Camera& c) { c.world_from_camera[0] = vec4(0); }),
                    "camera: world_from_camera is singular");
    expect_contains(bad([](Camera& c) { c.shift_x = kNaN; }), "camera: shift_x = nan");
}

// Finite fields whose rays together are not: each message names the fields and what to change.
TEST(CameraValidation, RejectsAnImagePlaneBeyondFloatRange) {
    const auto bad = [](const std::function<void(Camera&)>& edit) {
        Camera camera;
        edit(camera);
        return rejection([&] { validate_camera(camera); });
    };
    const std::string shifted = bad([](Camera& c) { c.shift_x = 1e38f; });
    expect_contains(shifted, "camera: shift_x = 1e+38 and shift_y = 0 with lens = 50 mm");
    expect_contains(shifted, "lower shift_x / shift_y");
    const std::string wide = bad([](Camera& c) {
        c.type = CameraType::Orthographic;
        c.ortho_scale = 1e20f;
    });
    expect_contains(wide, "with ortho_scale = 1e+20 put the image plane's edge");
    expect_contains(wide, "lower ortho_scale");
    expect_contains(bad([](Camera& c) { c.lens = 1e-30f; }), "lower the sensor size or raise lens");
    // Auto fit spans a portrait image's height with sensor_width, as Blender does.
    expect_contains(bad([](Camera& c) {
                        c.resolution_x = 480, c.resolution_y = 640;
                        c.lens = 1e-30f;
                    }),
                    "with lens = 1e-30 mm, sensor_width = 36 mm put");
    expect_contains(bad([](Camera& c) {
                        c.lens = 1e-6f;
                        c.clip_start = 1e33f;
                        c.clip_end = 2e33f;
                    }),
                    "camera: clip_start = 1e+33 m is");
    // Unused by a perspective camera, and within range for an orthographic one: accepted.
    EXPECT_EQ(bad([](Camera& c) { c.ortho_scale = 1e20f; }), "");
    EXPECT_EQ(bad([](Camera& c) {
                  c.type = CameraType::Orthographic;
                  c.ortho_scale = 1e6f;
                  c.shift_y = 2.0f;
              }),
              "");
}

}  // namespace
}  // namespace shgi
