// Tests for io/gltf_loader: a small glTF written by the test (embedded base64 buffer and PNG)
// with a quad, a child triangle, a material with extensions, three punctual lights and a
// camera; expected values are worked out by hand from the conventions in gltf_loader.h.
#include "io/gltf_loader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "support/expect_error.h"
#include "support/log_capture.h"
#include "support/test_folder.h"
#include "util/error.h"
#include "util/log.h"

namespace shgi {
namespace {

// Float comparisons of values computed in float from exact inputs.
constexpr float kTolerance = 1e-5f;

// A 2x2 RGBA PNG: top row red, green; bottom row blue, sRGB grey 128 with alpha 128.
constexpr const char* kPng2x2 =
    "iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAYAAABytg0kAAAAFElEQVR4nGP4z8DwHwyB9P8GIAAARNIH+zqrED4AAAA"
    "ASUVORK5CYII=";

using testing::test_file_path;
using testing::write_file;

std::string base64(const std::vector<uint8_t>& bytes) {
    static const char* alphabet =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < bytes.size(); i += 3) {
        uint32_t chunk = uint32_t(bytes[i]) << 16;
        if (i + 1 < bytes.size()) chunk |= uint32_t(bytes[i + 1]) << 8;
        if (i + 2 < bytes.size()) chunk |= uint32_t(bytes[i + 2]);
        out += alphabet[(chunk >> 18) & 63];
        out += alphabet[(chunk >> 12) & 63];
        out += i + 1 < bytes.size() ? alphabet[(chunk >> 6) & 63] : '=';
        out += i + 2 < bytes.size() ? alphabet[chunk & 63] : '=';
    }
    return out;
}

template <typename T>
void append(std::vector<uint8_t>& buffer, std::initializer_list<T> values) {
    for (T v : values) {
        uint8_t bytes[sizeof(T)];
        std::memcpy(bytes, &v, sizeof(T));
        buffer.insert(buffer.end(), bytes, bytes + sizeof(T));
    }
}

// Buffer layout (bytes): quad positions 0-47, normals 48-95, uvs 96-127, uint16 indices 128-139,
// triangle positions 140-175. The quad lies in glTF's y = 0 plane facing +Y (up).
std::vector<uint8_t> scene_buffer(uint16_t last_index) {
    std::vector<uint8_t> buffer;
    append<float>(buffer, {-1, 0, 1, 1, 0, 1, 1, 0, -1, -1, 0, -1});
    append<float>(buffer, {0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0});
    append<float>(buffer, {0, 0, 1, 0, 1, 1, 0, 1});
    append<uint16_t>(buffer, {0, 1, 2, 0, 2, last_index});
    append<float>(buffer, {0, 0, 0, 1, 0, 0, 0, 1, 0});
    return buffer;
}

std::string scene_json(uint16_t last_index = 3, const std::string& image_base64 = kPng2x2) {
    const std::vector<uint8_t> buffer = scene_buffer(last_index);
    return R"({
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength",
                     "KHR_materials_ior", "KHR_materials_transmission"],
  "scene": 0,
  "scenes": [{"nodes": [0, 2, 3, 4, 5]}],
  "nodes": [
    {"name": "Floor", "mesh": 0, "translation": [0, 2, 0], "children": [1]},
    {"name": "Child", "mesh": 1, "translation": [1, 0, 0], "scale": [2, 2, 2]},
    {"name": "Lamp", "translation": [0, 3, 0],
     "extensions": {"KHR_lights_punctual": {"light": 0}}},
    {"name": "Spot", "rotation": [-0.70710678, 0, 0, 0.70710678],
     "extensions": {"KHR_lights_punctual": {"light": 1}}},
    {"name": "Sun", "extensions": {"KHR_lights_punctual": {"light": 2}}},
    {"name": "Cam", "camera": 0, "translation": [0, 1, 5]}
  ],
  "cameras": [{"type": "perspective",
               "perspective": {"yfov": 0.5, "aspectRatio": 1.5, "znear": 0.1, "zfar": 100}}],
  "extensions": {"KHR_lights_punctual": {"lights": [
    {"name": "Lamp", "type": "point", "color": [1, 0.5, 0.25], "intensity": 100},
    {"type": "spot", "intensity": 683, "spot": {"innerConeAngle": 0.25, "outerConeAngle": 0.5}},
    {"type": "directional", "intensity": 683}]}},
  "materials": [{"name": "Red",
    "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 0.125, 1], "metallicFactor": 0.3,
                             "roughnessFactor": 0.6, "baseColorTexture": {"index": 0}},
    "emissiveFactor": [1, 0.5, 0],
    "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4},
                   "KHR_materials_ior": {"ior": 1.33},
                   "KHR_materials_transmission": {"transmissionFactor": 0.2}}}],
  "textures": [{"source": 0}],
  "images": [{"uri": "data:image/png;base64,)" +
           image_base64 + R"("}],
  "meshes": [
    {"name": "Quad", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                     "indices": 3, "material": 0}]},
    {"name": "Tri", "primitives": [{"attributes": {"POSITION": 4}},
                                   {"attributes": {"POSITION": 4}, "mode": 1}]}
  ],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
    {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
    {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
    {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"},
    {"bufferView": 4, "componentType": 5126, "count": 3, "type": "VEC3"}
  ],
  "bufferViews": [
    {"buffer": 0, "byteOffset": 0, "byteLength": 48},
    {"buffer": 0, "byteOffset": 48, "byteLength": 48},
    {"buffer": 0, "byteOffset": 96, "byteLength": 32},
    {"buffer": 0, "byteOffset": 128, "byteLength": 12},
    {"buffer": 0, "byteOffset": 140, "byteLength": 36}
  ],
  "buffers": [{"byteLength": 176, "uri": "data:application/octet-stream;base64,)" +
           base64(buffer) + R"("}]
})";
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
    const size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return text;
}

using testing::LogCapture;

void expect_near(const vec3& actual, const vec3& expected, float tolerance = kTolerance) {
    EXPECT_NEAR(actual.x, expected.x, tolerance);
    EXPECT_NEAR(actual.y, expected.y, tolerance);
    EXPECT_NEAR(actual.z, expected.z, tolerance);
}

// Loads `json` from a file and expects an IoError whose message contains the path and `needle`.
void expect_io_error(const std::string& name, const std::string& json, const std::string& needle) {
    const std::string path = test_file_path("gltf", name);
    write_file(path, json);
    testing::expect_error<IoError>([&] { load_gltf(path); }, {path, needle});
}

class GltfLoaderTest : public ::testing::Test {
  protected:
    void SetUp() override {
        path_ = test_file_path("gltf", "gltf_loader_scene.gltf");
        write_file(path_, scene_json());
        scene_ = load_gltf(path_);
    }
    std::string path_;
    Scene scene_;
    LogCapture log_;
};

TEST_F(GltfLoaderTest, MeshesAreConvertedToZUp) {
    ASSERT_EQ(scene_.meshes().size(), 2u);  // the LINES primitive is skipped
    const Mesh& quad = scene_.meshes()[0];
    ASSERT_EQ(quad.positions.size(), 4u);
    ASSERT_EQ(quad.triangles.size(), 2u);
    // glTF (x, y, z) -> Blender (x, -z, y): the floor quad lies in z = 0 facing +Z.
    expect_near(quad.positions[0], vec3(-1, -1, 0));
    expect_near(quad.positions[2], vec3(1, 1, 0));
    ASSERT_EQ(quad.normals.size(), 4u);
    expect_near(quad.normals[0], vec3(0, 0, 1));
    EXPECT_EQ(quad.triangles[1], uvec3(0, 2, 3));
    const Mesh& triangle = scene_.meshes()[1];
    EXPECT_EQ(triangle.triangles.size(), 1u);  // non-indexed
    EXPECT_TRUE(triangle.normals.empty());
}

TEST_F(GltfLoaderTest, UvsAreFlippedToBlendersOrigin) {
    const Mesh& quad = scene_.meshes()[0];
    ASSERT_EQ(quad.uv_sets.size(), 1u);
    EXPECT_EQ(quad.uv_sets[0].name, "UVMap");
    ASSERT_EQ(quad.uv_sets[0].coords.size(), 4u);
    EXPECT_EQ(quad.uv_sets[0].coords[0], vec2(0, 1));  // glTF (0, 0) = top-left
    EXPECT_EQ(quad.uv_sets[0].coords[2], vec2(1, 0));  // glTF (1, 1) = bottom-right
}

TEST_F(GltfLoaderTest, NodeHierarchyGivesWorldTransforms) {
    ASSERT_EQ(scene_.instances().size(), 2u);
    const Instance& floor = scene_.instances()[0];
    EXPECT_EQ(floor.name, "Floor");
    const vec3 corner = vec3(floor.world_from_object * vec4(scene_.meshes()[0].positions[2], 1));
    expect_near(corner, vec3(1, 1, 2));  // glTF translation y = 2 is Blender z = 2
    // Child: T(0,2,0) T(1,0,0) S(2) applied to glTF (1,0,0) = (3,2,0) glTF = (3,0,2) Blender.
    const Instance& child = scene_.instances()[1];
    const vec3 p = vec3(child.world_from_object * vec4(scene_.meshes()[1].positions[1], 1));
    expect_near(p, vec3(3, 0, 2));
}

TEST_F(GltfLoaderTest, RayHitsTheConvertedFloor) {
    scene_.commit();
    Ray ray;
    ray.origin = vec3(0.25f, 0.25f, 10.0f);
    ray.direction = vec3(0, 0, -1);
    const Hit hit = scene_.intersect(ray);
    ASSERT_TRUE(hit.valid());
    EXPECT_EQ(hit.instance_id, 0u);
    EXPECT_NEAR(hit.t, 8.0f, 1e-4f);
}

TEST_F(GltfLoaderTest, MaterialValuesAndExtensions) {
    ASSERT_EQ(scene_.materials().size(), 2u);  // "Red" and the default for the triangle
    const Material& red = scene_.materials()[0];
    EXPECT_EQ(red.name, "Red");
    expect_near(red.base_color, vec3(0.5f, 0.25f, 0.125f));
    EXPECT_FLOAT_EQ(red.metallic, 0.3f);
    EXPECT_FLOAT_EQ(red.roughness, 0.6f);
    expect_near(red.emission_color, vec3(1, 0.5f, 0));
    EXPECT_FLOAT_EQ(red.emission_strength, 4.0f);
    EXPECT_FLOAT_EQ(red.ior, 1.33f);
    EXPECT_FLOAT_EQ(red.transmission, 0.2f);
    EXPECT_EQ(red.base_color_uv_set, "UVMap");
    ASSERT_EQ(scene_.meshes()[1].material_indices.size(), 1u);
    EXPECT_EQ(scene_.meshes()[1].material_indices[0], 1u);
    EXPECT_EQ(scene_.materials()[1].name, Material{}.name);
}

TEST_F(GltfLoaderTest, BaseColorTextureIsLinearWithBottomRowFirst) {
    ASSERT_EQ(scene_.textures().size(), 1u);
    ASSERT_EQ(scene_.materials()[0].base_color_texture, 0);
    const Texture& texture = scene_.textures()[0];
    ASSERT_EQ(texture.width, 2u);
    ASSERT_EQ(texture.height, 2u);
    // Row 0 is the PNG's bottom row: blue, then grey 128 (sRGB) with alpha 128 (linear).
    EXPECT_EQ(texture.texels[0], vec4(0, 0, 1, 1));
    const float grey = std::pow((128.0f / 255.0f + 0.055f) / 1.055f, 2.4f);
    EXPECT_NEAR(texture.texels[1].x, grey, kTolerance);
    EXPECT_NEAR(texture.texels[1].w, 128.0f / 255.0f, kTolerance);
    EXPECT_EQ(texture.texels[2], vec4(1, 0, 0, 1));
    EXPECT_EQ(texture.texels[3], vec4(0, 1, 0, 1));
}

// normalTexture: the same image as data (no sRGB decoding, a texture of its own), scale as the
// Strength, and tangents along +U computed from the UV set (the quad's V runs down Blender's -Y,
// so the bitangent sign is -1).
TEST(GltfLoader, NormalTextureIsDataWithComputedTangents) {
    const std::string path = test_file_path("gltf", "normal_texture.gltf");
    write_file(path, replaced(scene_json(), R"("emissiveFactor")",
                              R"("normalTexture": {"index": 0, "scale": 0.5}, "emissiveFactor")"));
    const Scene scene = load_gltf(path);
    const Material& red = scene.materials()[0];
    ASSERT_EQ(red.normal_texture, 1);
    EXPECT_EQ(red.normal_uv_set, "UVMap");
    EXPECT_FLOAT_EQ(red.normal_strength, 0.5f);
    EXPECT_NEAR(scene.textures()[1].texels[1].x, 128.0f / 255.0f, kTolerance) << "not decoded";
    const Mesh& quad = scene.meshes()[0];
    ASSERT_EQ(quad.tangents.size(), quad.positions.size());
    for (const vec4& tangent : quad.tangents) {
        expect_near(vec3(tangent), vec3(1, 0, 0));
        EXPECT_EQ(tangent.w, -1.0f);
    }
    EXPECT_TRUE(scene.meshes()[1].tangents.empty()) << "no normal map, no tangents";
}

TEST(GltfLoaderErrors, TangentCountMustMatchTheVertices) {
    std::string json = replaced(scene_json(), R"("emissiveFactor")",
                                R"("normalTexture": {"index": 0}, "emissiveFactor")");
    json = replaced(json, R"("TEXCOORD_0": 2})", R"("TEXCOORD_0": 2, "TANGENT": 2})");
    expect_io_error("tangent_count.gltf", json, "TANGENT");
}

TEST_F(GltfLoaderTest, PunctualLightsUseBlendersUnits) {
    ASSERT_EQ(scene_.lights().size(), 3u);
    const Light& point = scene_.lights()[0];
    EXPECT_EQ(point.type, LightType::Point);
    EXPECT_EQ(point.name, "Lamp");
    EXPECT_NEAR(point.power, 100.0f * 4.0f * kPi / 683.0f, 1e-5f);  // cd -> W
    expect_near(point.color, vec3(1, 0.5f, 0.25f));
    expect_near(point.position(), vec3(0, 0, 3));
    EXPECT_FLOAT_EQ(point.radius, 0.25f);  // Blender's default, which the importer keeps

    const Light& spot = scene_.lights()[1];
    EXPECT_EQ(spot.type, LightType::Spot);
    EXPECT_NEAR(spot.power, 4.0f * kPi, 1e-4f);
    EXPECT_FLOAT_EQ(spot.spot_size, 1.0f);   // 2 * outerConeAngle
    EXPECT_FLOAT_EQ(spot.spot_blend, 0.5f);  // 1 - inner / outer
    expect_near(spot.direction(), vec3(0, 0, -1));  // rotated to glTF -Y, which is Blender -Z

    const Light& sun = scene_.lights()[2];
    EXPECT_EQ(sun.type, LightType::Sun);
    EXPECT_NEAR(sun.strength, 1.0f, 1e-6f);       // 683 lux -> 1 W/m^2
    expect_near(sun.direction(), vec3(0, 1, 0));  // glTF -Z is Blender +Y
    EXPECT_NEAR(sun.angle, 0.00918043f, 1e-7f);    // Blender's default 0.526 degrees
}

TEST_F(GltfLoaderTest, CameraLooksAlongConvertedAxes) {
    ASSERT_TRUE(scene_.has_camera());
    const Camera& camera = scene_.camera();
    EXPECT_EQ(camera.type, CameraType::Perspective);
    const mat4& m = camera.world_from_camera;
    expect_near(vec3(m[3]), vec3(0, -5, 1));               // glTF (0, 1, 5)
    expect_near(vec3(m * vec4(0, 0, -1, 0)), vec3(0, 1, 0));  // looks along Blender +Y
    expect_near(vec3(m * vec4(0, 1, 0, 0)), vec3(0, 0, 1));   // with +Z up
    EXPECT_EQ(camera.sensor_fit, SensorFit::Vertical);
    EXPECT_NEAR(camera.lens, 0.5f * camera.sensor_height / std::tan(0.25f), 1e-4f);
    EXPECT_EQ(camera.resolution_x, 720u);
    EXPECT_EQ(camera.resolution_y, 480u);
    EXPECT_FLOAT_EQ(camera.clip_start, 0.1f);
    EXPECT_FLOAT_EQ(camera.clip_end, 100.0f);
    const Ray center = camera.generate_ray(vec2(360.0f, 240.0f));
    expect_near(center.direction, vec3(0, 1, 0), 1e-4f);
}

TEST_F(GltfLoaderTest, NonTrianglePrimitivesAreWarnedAbout) {
    // The fixture's load ran with the capture installed.
    EXPECT_NE(log_.warnings.find("mesh 1 primitive 1"), std::string::npos) << log_.warnings;
}

TEST(GltfLoader, LightingModesFollowBlendersImporter) {
    EXPECT_NEAR(gltf_point_power(683.0f, GltfLightingMode::Spec), 4.0f * kPi, 1e-5f);
    EXPECT_NEAR(gltf_point_power(1.0f, GltfLightingMode::Compat), 4.0f * kPi, 1e-6f);
    EXPECT_FLOAT_EQ(gltf_point_power(7.0f, GltfLightingMode::Raw), 7.0f);
    EXPECT_FLOAT_EQ(gltf_sun_strength(683.0f, GltfLightingMode::Spec), 1.0f);
    EXPECT_FLOAT_EQ(gltf_sun_strength(3.0f, GltfLightingMode::Compat), 3.0f);
}

TEST(GltfLoader, OptionsSkipLightsCameraAndTextures) {
    const std::string path = test_file_path("gltf", "gltf_loader_options.gltf");
    write_file(path, scene_json());
    GltfLoadOptions options;
    options.import_lights = false;
    options.import_camera = false;
    options.import_textures = false;
    const Scene scene = load_gltf(path, options);
    EXPECT_TRUE(scene.lights().empty());
    options.import_lights = true;
    options.light_radius = 0.0f;  // truly punctual
    EXPECT_EQ(load_gltf(path, options).lights()[0].radius, 0.0f);
    EXPECT_FALSE(scene.has_camera());
    EXPECT_TRUE(scene.textures().empty());
    EXPECT_EQ(scene.materials()[0].base_color_texture, kNoTexture);
}

TEST(GltfLoader, UndecodableImageCostsOnlyTheTexture) {
    LogCapture log;
    const std::string path = test_file_path("gltf", "gltf_loader_bad_image.gltf");
    write_file(path, scene_json(3, base64({'n', 'o', 't', ' ', 'a', ' ', 'p', 'n', 'g'})));
    const Scene scene = load_gltf(path);
    EXPECT_TRUE(scene.textures().empty());
    EXPECT_EQ(scene.materials()[0].base_color_texture, kNoTexture);
    EXPECT_NE(log.warnings.find("image 0"), std::string::npos) << log.warnings;
}

TEST(GltfLoader, BinaryGlbWithByteIndices) {
    std::vector<uint8_t> bin;
    append<float>(bin, {0, 0, 0, 1, 0, 0, 0, 0, -1});  // glTF; -Z is Blender +Y
    append<uint8_t>(bin, {0, 1, 2, 0});                 // 3 indices + 1 byte of padding
    std::string json = R"({"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}],
      "nodes": [{"mesh": 0}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
      "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
                    {"bufferView": 1, "componentType": 5121, "count": 3, "type": "SCALAR"}],
      "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                      {"buffer": 0, "byteOffset": 36, "byteLength": 3}],
      "buffers": [{"byteLength": 40}]})";
    while (json.size() % 4 != 0) json += ' ';
    std::vector<uint8_t> glb;
    append<uint32_t>(glb, {0x46546C67u, 2u, uint32_t(12 + 8 + json.size() + 8 + bin.size())});
    append<uint32_t>(glb, {uint32_t(json.size()), 0x4E4F534Au});  // "JSON"
    glb.insert(glb.end(), json.begin(), json.end());
    append<uint32_t>(glb, {uint32_t(bin.size()), 0x004E4942u});   // "BIN\0"
    glb.insert(glb.end(), bin.begin(), bin.end());
    const std::string path = test_file_path("gltf", "gltf_loader_triangle.glb");
    write_file(path, std::string(glb.begin(), glb.end()));

    const Scene scene = load_gltf(path);
    ASSERT_EQ(scene.meshes().size(), 1u);
    EXPECT_EQ(scene.meshes()[0].triangles[0], uvec3(0, 1, 2));
    expect_near(scene.meshes()[0].positions[2], vec3(0, 1, 0));
    EXPECT_EQ(scene.materials().size(), 1u);  // the default material
}

TEST(GltfLoaderErrors, MissingFileNamesThePath) {
    const std::string path = test_file_path("gltf", "no_such_file.gltf");
    testing::expect_error<IoError>([&] { load_gltf(path); }, {path});
}

TEST(GltfLoaderErrors, MalformedJson) {
    expect_io_error("gltf_loader_truncated.gltf", scene_json().substr(0, 200), "glTF");
}

TEST(GltfLoaderErrors, IndexOutOfRangeIsAnErrorNotACrash) {
    expect_io_error("gltf_loader_bad_index.gltf", scene_json(7),
                    "indices[5] = 7, but the primitive has only 4");
}

TEST(GltfLoaderErrors, AccessorPastItsBufferView) {
    const std::string json = replaced(scene_json(), R"("count": 6, "type": "SCALAR")",
                                      R"("count": 600, "type": "SCALAR")");
    expect_io_error("gltf_loader_long_accessor.gltf", json, "accessor 3");
}

TEST(GltfLoaderErrors, MissingAccessor) {
    const std::string json =
        replaced(scene_json(), R"({"POSITION": 4}})", R"({"POSITION": 99}})");
    expect_io_error("gltf_loader_missing_accessor.gltf", json, "99");
}

TEST(GltfLoaderErrors, BufferViewPastItsBuffer) {
    const std::string json = replaced(scene_json(), R"("byteOffset": 140, "byteLength": 36)",
                                      R"("byteOffset": 140, "byteLength": 3600)");
    expect_io_error("gltf_loader_long_view.gltf", json, "buffer");
}

TEST(GltfLoaderErrors, FieldOfViewOutsideZeroToPi) {
    for (const char* yfov : {"3.14159274", "4", "0", "-0.5"})
        expect_io_error("gltf_loader_yfov.gltf",
                        replaced(scene_json(), R"("yfov": 0.5)", std::string("\"yfov\": ") + yfov),
                        "camera 0 has yfov = ");
}

TEST(GltfLoaderErrors, CyclicNodeHierarchy) {
    const std::string json = replaced(scene_json(), R"("scale": [2, 2, 2]})",
                                      R"("scale": [2, 2, 2], "children": [0]})");
    expect_io_error("gltf_loader_cycle.gltf", json, "cycle");
}

TEST(GltfLoaderErrors, DeepHierarchyDoesNotOverflowTheStack) {
    // A chain of nested nodes ending in the floor mesh: the walk must not recurse per level.
    constexpr int kNodes = 100000;
    std::string nodes;
    constexpr int kFirst = 6;  // the fixture's nodes come first
    for (int i = 0; i + 1 < kNodes; ++i) {
        nodes += R"({"translation": [0, 0.0001, 0], "children": [)" +
                 std::to_string(kFirst + i + 1) + "]},";
    }
    nodes += R"({"mesh": 0})";
    std::string json = replaced(scene_json(), R"("scenes": [{"nodes": [0, 2, 3, 4, 5]}],)",
                                R"("scenes": [{"nodes": [6]}],)");
    json = replaced(json, R"({"name": "Cam", "camera": 0, "translation": [0, 1, 5]})",
                    R"({"name": "Cam", "camera": 0, "translation": [0, 1, 5]},)" + nodes);
    const std::string path = test_file_path("gltf", "gltf_loader_deep.gltf");
    write_file(path, json);
    const Scene scene = load_gltf(path);
    ASSERT_EQ(scene.instances().size(), 1u);
    // 99999 translations of 0.0001 up (glTF +Y = Blender +Z), accumulated in float.
    EXPECT_NEAR(scene.instances()[0].world_from_object[3].z, 9.9999f, 1e-2f);
}

TEST(GltfLoaderErrors, UnsupportedRequiredExtension) {
    const std::string json =
        replaced(scene_json(), R"("scene": 0,)",
                 R"("scene": 0, "extensionsRequired": ["KHR_draco_mesh_compression"],)");
    expect_io_error("gltf_loader_draco.gltf", json, "KHR_draco_mesh_compression");
}

}  // namespace
}  // namespace shgi
