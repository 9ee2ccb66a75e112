// Tests for io/obj_loader: an OBJ + MTL pair written by the test (two shapes, two materials),
// checked against the axis change and Blender's MTL mapping stated in obj_loader.h.
#include "io/obj_loader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "support/expect_error.h"
#include "support/log_capture.h"
#include "support/test_folder.h"
#include "util/error.h"
#include "util/log.h"

namespace shgi {
namespace {

constexpr float kTolerance = 1e-6f;

using testing::test_file_path;
using testing::write_file;

// A floor quad (OBJ y = 1 plane, facing +Y) and an emissive triangle, Y-up as OBJ files are.
constexpr const char* kObj = R"(# test scene
mtllib obj_loader_two.mtl
v -1 1 1
v 1 1 1
v 1 1 -1
v -1 1 -1
v 0 0 0
v 1 0 0
v 0 2 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 1 0
o Floor
usemtl Red
f 1/1/1 2/2/1 3/3/1 4/4/1
o Glow
usemtl Glow
f 5 6 7
)";

constexpr const char* kMtl = R"(newmtl Red
Kd 0.8 0.1 0.1
Ks 0.5 0.5 0.5
Ns 250
Ni 1.5
illum 2

newmtl Glow
Ka 0.2 0.2 0.2
Kd 0 0 0
Ke 2 2 2
Pr 0.3
Pm 0.7
d 0.5
illum 3
)";

void expect_near(const vec3& actual, const vec3& expected) {
    EXPECT_NEAR(actual.x, expected.x, kTolerance);
    EXPECT_NEAR(actual.y, expected.y, kTolerance);
    EXPECT_NEAR(actual.z, expected.z, kTolerance);
}

using testing::LogCapture;

class ObjLoaderTest : public ::testing::Test {
  protected:
    void SetUp() override {
        write_file(test_file_path("obj", "obj_loader_two.mtl"), kMtl);
        write_file(test_file_path("obj", "obj_loader_two.obj"), kObj);
        scene_ = load_obj(test_file_path("obj", "obj_loader_two.obj"));
    }
    Scene scene_;
};

TEST_F(ObjLoaderTest, OneMeshAndInstancePerShape) {
    ASSERT_EQ(scene_.meshes().size(), 2u);
    ASSERT_EQ(scene_.instances().size(), 2u);
    EXPECT_EQ(scene_.meshes()[0].name, "Floor");
    EXPECT_EQ(scene_.instances()[1].name, "Glow");
    EXPECT_EQ(scene_.instances()[0].world_from_object, mat4(1.0f));
    EXPECT_EQ(scene_.meshes()[0].triangles.size(), 2u);  // the quad, triangulated
    EXPECT_EQ(scene_.meshes()[1].triangles.size(), 1u);
}

TEST_F(ObjLoaderTest, PositionsAndNormalsAreConvertedToZUp) {
    const Mesh& floor = scene_.meshes()[0];
    ASSERT_EQ(floor.positions.size(), 4u);
    expect_near(floor.positions[0], vec3(-1, -1, 1));  // OBJ (x, y, z) -> (x, -z, y)
    expect_near(floor.positions[2], vec3(1, 1, 1));
    ASSERT_EQ(floor.normals.size(), 4u);
    expect_near(floor.normals[0], vec3(0, 0, 1));
    EXPECT_TRUE(scene_.meshes()[1].normals.empty());  // "f 5 6 7" has no vn
}

TEST_F(ObjLoaderTest, UvsKeepTheirOrigin) {
    const Mesh& floor = scene_.meshes()[0];
    ASSERT_EQ(floor.uv_sets.size(), 1u);
    EXPECT_EQ(floor.uv_sets[0].name, "UVMap");
    EXPECT_EQ(floor.uv_sets[0].coords[0], vec2(0, 0));
    EXPECT_EQ(floor.uv_sets[0].coords[2], vec2(1, 1));
    EXPECT_TRUE(scene_.meshes()[1].uv_sets.empty());
}

TEST_F(ObjLoaderTest, MtlMapsLikeBlendersImporter) {
    ASSERT_EQ(scene_.materials().size(), 2u);
    const Material& red = scene_.materials()[0];
    EXPECT_EQ(red.name, "Red");
    expect_near(red.base_color, vec3(0.8f, 0.1f, 0.1f));
    EXPECT_NEAR(red.roughness, 0.5f, kTolerance);  // 1 - sqrt(250 / 1000)
    EXPECT_FLOAT_EQ(red.specular, 0.5f);
    EXPECT_FLOAT_EQ(red.metallic, 0.0f);  // illum 2 is not reflective
    EXPECT_FLOAT_EQ(red.ior, 1.5f);
    EXPECT_FALSE(red.is_emissive());

    const Material& glow = scene_.materials()[1];
    expect_near(glow.emission(), vec3(2.0f));
    EXPECT_FLOAT_EQ(glow.roughness, 0.3f);  // Pr overrides the Ns fallback
    EXPECT_FLOAT_EQ(glow.metallic, 0.7f);   // Pm overrides Ka
    EXPECT_FLOAT_EQ(glow.transmission, 0.0f);  // d is ignored
    EXPECT_EQ(scene_.meshes()[1].material_indices[0], 1u);
}

TEST_F(ObjLoaderTest, RayHitsTheFloor) {
    scene_.commit();
    Ray ray;
    ray.origin = vec3(0.5f, -0.5f, 5.0f);
    ray.direction = vec3(0, 0, -1);
    const Hit hit = scene_.intersect(ray);
    ASSERT_TRUE(hit.valid());
    EXPECT_EQ(hit.instance_id, 0u);
    EXPECT_NEAR(hit.t, 4.0f, 1e-5f);
}

TEST(ObjLoader, RoughnessFromSpecularExponent) {
    EXPECT_FLOAT_EQ(obj_roughness_from_exponent(0.0f), 1.0f);
    EXPECT_FLOAT_EQ(obj_roughness_from_exponent(1000.0f), 0.0f);
    EXPECT_FLOAT_EQ(obj_roughness_from_exponent(5000.0f), 0.0f);  // clamped
    EXPECT_NEAR(obj_roughness_from_exponent(90.0f), 1.0f - std::sqrt(0.09f), kTolerance);
}

TEST(ObjLoader, ZUpOptionKeepsCoordinates) {
    write_file(test_file_path("obj", "obj_loader_zup.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    ObjLoadOptions options;
    options.up_axis = ObjUpAxis::Z;
    const Scene scene = load_obj(test_file_path("obj", "obj_loader_zup.obj"), options);
    ASSERT_EQ(scene.meshes().size(), 1u);
    expect_near(scene.meshes()[0].positions[2], vec3(0, 1, 0));
    EXPECT_EQ(scene.materials().size(), 1u);  // default material for faces without usemtl
}

TEST(ObjLoader, MissingMtlIsAWarning) {
    LogCapture log;
    write_file(test_file_path("obj", "obj_loader_no_mtl.obj"),
               "mtllib obj_loader_absent.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl X\nf 1 2 3\n");
    const Scene scene = load_obj(test_file_path("obj", "obj_loader_no_mtl.obj"));
    EXPECT_EQ(scene.meshes().size(), 1u);
    EXPECT_EQ(scene.materials().size(), 1u);
    EXPECT_NE(log.warnings.find("obj_loader_absent.mtl"), std::string::npos) << log.warnings;
}

// "mtllib /dev/zero" (any path naming a device, FIFO or folder) was read until memory ran out.
TEST(ObjLoader, MtlThatIsNotARegularFileIsAWarningNotARead) {
    LogCapture log;
    std::string up;  // from the test folder to the root, whatever its depth ("/.." is "/")
    for (int i = 0; i < 32; ++i) up += "../";
    write_file(test_file_path("obj", "obj_loader_device_mtl.obj"),
               "mtllib " + up + "dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl X\nf 1 2 3\n");
    const Scene scene = load_obj(test_file_path("obj", "obj_loader_device_mtl.obj"));
    EXPECT_EQ(scene.materials().size(), 1u);
    EXPECT_NE(log.warnings.find("/dev/zero' is not a regular file"), std::string::npos)
        << log.warnings;
}

void expect_io_error(const std::string& name, const std::string& text, const std::string& needle) {
    const std::string path = test_file_path("obj", name);
    write_file(path, text);
    testing::expect_error<IoError>([&] { load_obj(path); }, {path, needle});
}

TEST(ObjLoaderErrors, MissingFile) {
    testing::expect_error<IoError>([] { load_obj(test_file_path("obj", "no_such_file.obj")); },
                                   {"no_such_file.obj"});
}

TEST(ObjLoaderErrors, VertexIndexOutOfRangeIsAnErrorNotACrash) {
    expect_io_error("obj_loader_bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\no Tri\nf 1 2 9\n",
                    "vertex (v) 9");
}

TEST(ObjLoaderErrors, QuadWithOutOfRangeIndexIsNotTriangulatedFirst) {
    expect_io_error("obj_loader_bad_quad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 1000000\n",
                    "1000000");
}

TEST(ObjLoaderErrors, NormalIndexOutOfRange) {
    expect_io_error("obj_loader_bad_normal.obj",
                    "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n", "normal (vn) 2");
}

TEST(ObjLoaderErrors, ZeroIndexIsRefusedWithItsLine) {
    // OBJ counts vertices from 1: 0 names none (checked before tinyobjloader, which also fails).
    expect_io_error("obj_loader_zero_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
                    ":4: index '0' in '0' is not a vertex number");
}

}  // namespace
}  // namespace shgi
