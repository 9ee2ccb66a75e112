// validate_mesh: every kind of bad mesh is rejected with its own message, degenerate triangles
// are dropped (with their material indices), zero normals are repaired.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "scene/mesh.h"
#include "scene/scene_test_meshes.h"
#include "support/expect_error.h"
#include "util/error.h"

namespace shgi {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

using testing::expect_contains;

// test::unit_quad ("Quad") with its two triangles on materials 0 and 1.
Mesh two_material_quad() {
    Mesh mesh = test::unit_quad();
    mesh.material_indices = {0, 1};
    return mesh;
}

// Runs validate_mesh on a copy and returns the InvalidArgument message ("" when nothing was
// thrown).
std::string rejection(Mesh mesh, uint32_t material_count = 2) {
    return testing::rejection([&] { validate_mesh(mesh, material_count); });
}

TEST(MeshValidation, AcceptsAValidQuadUnchanged) {
    Mesh mesh = two_material_quad();
    const MeshReport report = validate_mesh(mesh, 2);
    EXPECT_EQ(report.dropped_degenerate, 0u);
    EXPECT_EQ(report.fixed_normals, 0u);
    EXPECT_EQ(mesh.triangles.size(), 2u);
}

TEST(MeshValidation, RejectsNaNPositionNamingMeshArrayIndexAndValue) {
    Mesh mesh = two_material_quad();
    mesh.positions[2] = vec3(kNaN, 0, 1);
    expect_contains(rejection(mesh), "mesh 'Quad': positions[2] = (nan, 0, 1) is not finite");
}

TEST(MeshValidation, RejectsInfNormal) {
    Mesh mesh = two_material_quad();
    mesh.normals[3] = vec3(0, kInf, 0);
    expect_contains(rejection(mesh), "mesh 'Quad': normals[3] = (0, inf, 0) is not finite");
}

TEST(MeshValidation, RejectsNaNUv) {
    Mesh mesh = two_material_quad();
    mesh.uv_sets[0].coords[1] = vec2(kNaN, 0);
    expect_contains(rejection(mesh), "uv set 'UVMap'[1] = (nan, 0) is not finite");
}

TEST(MeshValidation, RejectsHugeCoordinates) {
    Mesh mesh = two_material_quad();
    mesh.positions[1] = vec3(2e12f, 0, 0);
    const std::string message = rejection(mesh);
    expect_contains(message, "positions[1]");
    expect_contains(message, "exceeds 1e+12 m");
}

TEST(MeshValidation, RejectsOutOfRangeVertexIndexWithBothValues) {
    Mesh mesh = two_material_quad();
    mesh.triangles[1] = uvec3(0, 2, 9);
    expect_contains(rejection(mesh),
                    "triangles[1] = (0, 2, 9) indexes vertex 9 but the mesh has 4 vertices");
}

TEST(MeshValidation, RejectsNormalCountMismatch) {
    Mesh mesh = two_material_quad();
    mesh.normals.pop_back();
    expect_contains(rejection(mesh), "normals has 3 elements but positions has 4");
}

TEST(MeshValidation, RejectsUvCountMismatch) {
    Mesh mesh = two_material_quad();
    mesh.uv_sets[0].coords.push_back(vec2(0));
    expect_contains(rejection(mesh), "uv set 'UVMap' has 5 elements but positions has 4");
}

TEST(MeshValidation, RejectsMaterialIndexCountMismatch) {
    Mesh mesh = two_material_quad();
    mesh.material_indices = {0};
    expect_contains(rejection(mesh), "material_indices has 1 elements but triangles has 2");
}

TEST(MeshValidation, RejectsMaterialIndexOutOfRange) {
    Mesh mesh = two_material_quad();
    mesh.material_indices = {0, 5};
    expect_contains(rejection(mesh, 2), "material_indices[1] = 5 but the scene has 2 materials");
}

TEST(MeshValidation, UnnamedMeshIsLabelledAsSuch) {
    Mesh mesh = two_material_quad();
    mesh.name.clear();
    mesh.positions[0].x = kNaN;
    expect_contains(rejection(mesh), "mesh (unnamed): positions[0]");
}

TEST(MeshValidation, DropsDegenerateTrianglesAndKeepsMaterialsInSync) {
    Mesh mesh = two_material_quad();
    mesh.positions.push_back(vec3(2, 0, 0));  // collinear with vertices 0 and 1
    mesh.normals.push_back(vec3(0, 0, 1));
    mesh.uv_sets[0].coords.push_back(vec2(0));
    // repeated index, zero-area (collinear), valid, valid
    mesh.triangles = {{0, 0, 1}, {0, 1, 4}, {0, 1, 2}, {0, 2, 3}};
    mesh.material_indices = {1, 1, 0, 1};
    const MeshReport report = validate_mesh(mesh, 2);
    EXPECT_EQ(report.dropped_degenerate, 2u);
    ASSERT_EQ(mesh.triangles.size(), 2u);
    EXPECT_EQ(mesh.triangles[0], uvec3(0, 1, 2));
    EXPECT_EQ(mesh.triangles[1], uvec3(0, 2, 3));
    EXPECT_EQ(mesh.material_indices, (std::vector<uint32_t>{0, 1}));
}

TEST(MeshValidation, DropsNearZeroAreaSliver) {
    Mesh mesh = two_material_quad();
    mesh.positions[3] = vec3(0.5f, 1e-9f, 0);  // height 1e-9 over the edge from 0 to 1
    mesh.triangles[1] = uvec3(0, 1, 3);
    const MeshReport report = validate_mesh(mesh, 2);
    EXPECT_EQ(report.dropped_degenerate, 1u);
    EXPECT_EQ(mesh.triangles.size(), 1u);
}

TEST(MeshValidation, FixesZeroLengthNormalsFromAdjacentFaces) {
    Mesh mesh = two_material_quad();
    mesh.normals[1] = vec3(0);
    const MeshReport report = validate_mesh(mesh, 2);
    EXPECT_EQ(report.fixed_normals, 1u);
    EXPECT_NEAR(mesh.normals[1].z, 1.0f, 1e-6f);
    EXPECT_NEAR(glm::length(mesh.normals[1]), 1.0f, 1e-6f);
}

TEST(MeshValidation, TriangleAreaIsHalfTheCrossProduct) {
    Mesh mesh = two_material_quad();
    mesh.positions[2] = vec3(3, 2, 0);
    EXPECT_FLOAT_EQ(triangle_area(mesh, 0), 1.0f);  // base 1 along x, height 2
    EXPECT_THROW(triangle_area(mesh, 2), InvalidArgument);
}

}  // namespace
}  // namespace shgi
