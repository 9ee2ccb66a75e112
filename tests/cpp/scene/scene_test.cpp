// Scene on Embree: hits on known geometry (exact t, barycentrics, normals) through instance
// transforms, batch == single, every bad input rejected with its own message, memory budget,
// empty scenes, emissive triangles, cancel, meshes replaced by set_mesh.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <random>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "scene/embree_scene.h"
#include "scene/scene.h"
#include "scene/scene_test_meshes.h"
#include "support/expect_error.h"
#include "util/error.h"
#include "util/log.h"

namespace shgi {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// Embree's robust watertight intersection is accurate to a few float ulps at unit scale.
constexpr float kTolerance = 1e-5f;

using test::unit_quad;
using testing::expect_contains;
using testing::rejection;

// Closed unit cube [0,1]^3, outward-facing, 12 triangles.
Mesh unit_cube() {
    Mesh mesh;
    mesh.name = "Cube";
    for (int i = 0; i < 8; ++i) mesh.positions.push_back(vec3(i & 1, (i >> 1) & 1, (i >> 2) & 1));
    mesh.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                      {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    return mesh;
}

// A grid of n x n quads (2 n^2 triangles) in the XY plane.
Mesh grid(int n) {
    Mesh mesh;
    mesh.name = "Grid";
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x) mesh.positions.push_back(vec3(x, y, 0) / float(n));
    const auto v = [n](int x, int y) { return static_cast<uint32_t>(y * (n + 1) + x); };
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            mesh.triangles.push_back(uvec3(v(x, y), v(x + 1, y), v(x + 1, y + 1)));
            mesh.triangles.push_back(uvec3(v(x, y), v(x + 1, y + 1), v(x, y + 1)));
        }
    return mesh;
}

Ray make_ray(vec3 origin, vec3 direction, float tmin = 0.0f, float tmax = kInfinity) {
    Ray ray;
    ray.origin = origin;
    ray.direction = direction;
    ray.tmin = tmin;
    ray.tmax = tmax;
    return ray;
}

void expect_near(const vec3& actual, const vec3& expected, float tolerance = kTolerance) {
    EXPECT_NEAR(actual.x, expected.x, tolerance);
    EXPECT_NEAR(actual.y, expected.y, tolerance);
    EXPECT_NEAR(actual.z, expected.z, tolerance);
}

Scene quad_scene(const mat4& world_from_object = mat4(1.0f)) {
    Scene scene;
    scene.add_instance(scene.add_mesh(unit_quad()), world_from_object, "QuadObject");
    scene.commit();
    return scene;
}

TEST(SceneIntersect, HitsUnitQuadWithExactTBarycentricsAndNormal) {
    const Scene scene = quad_scene();
    const Hit hit = scene.intersect(make_ray(vec3(0.75f, 0.25f, 1.0f), vec3(0, 0, -1)));
    ASSERT_TRUE(hit.valid());
    EXPECT_NEAR(hit.t, 1.0f, kTolerance);
    EXPECT_EQ(hit.instance_id, 0u);
    EXPECT_EQ(hit.triangle_id, 0u);
    // p = (0.75, 0.25) = b1 (1,0) + b2 (1,1): b2 = 0.25, b1 = 0.5.
    EXPECT_NEAR(hit.barycentrics.x, 0.5f, kTolerance);
    EXPECT_NEAR(hit.barycentrics.y, 0.25f, kTolerance);
    // Unnormalised: twice the triangle's area (1) along +Z.
    expect_near(hit.geometric_normal, vec3(0, 0, 1));

    const Hit other = scene.intersect(make_ray(vec3(0.25f, 0.75f, 2.0f), vec3(0, 0, -2)));
    EXPECT_EQ(other.triangle_id, 1u);
    EXPECT_NEAR(other.t, 1.0f, kTolerance);  // t is in units of |direction|
}

TEST(SceneIntersect, MissesBesideBehindAndBeyondTmax) {
    const Scene scene = quad_scene();
    EXPECT_FALSE(scene.intersect(make_ray(vec3(2, 2, 1), vec3(0, 0, -1))).valid());
    EXPECT_FALSE(scene.intersect(make_ray(vec3(0.5f, 0.5f, 1), vec3(0, 0, 1))).valid());
    EXPECT_FALSE(scene.intersect(make_ray(vec3(0.5f, 0.5f, 1), vec3(0, 0, -1), 0, 0.99f)).valid());
    EXPECT_FALSE(scene.intersect(make_ray(vec3(0.5f, 0.5f, 1), vec3(0, 0, -1), 1.01f)).valid());
}

TEST(SceneOccluded, RespectsTheRaySegment) {
    const Scene scene = quad_scene();
    EXPECT_TRUE(scene.occluded(make_ray(vec3(0.5f, 0.5f, 1), vec3(0, 0, -1))));
    EXPECT_FALSE(scene.occluded(make_ray(vec3(0.5f, 0.5f, 1), vec3(0, 0, -1), 0, 0.5f)));
    EXPECT_FALSE(scene.occluded(make_ray(vec3(3, 0.5f, 1), vec3(0, 0, -1))));
}

TEST(SceneIntersect, InstanceWithScaleRotationAndTranslation) {
    // Object (x, y, 0) -> world (2x, 0, 2y + 5): rotated +90 degrees about X, scaled by 2.
    const mat4 world_from_object = glm::translate(mat4(1.0f), vec3(0, 0, 5)) *
                                   glm::rotate(mat4(1.0f), 0.5f * kPi, vec3(1, 0, 0)) *
                                   glm::scale(mat4(1.0f), vec3(2.0f));
    const Scene scene = quad_scene(world_from_object);
    const Ray ray = make_ray(vec3(1.5f, -3.0f, 5.5f), vec3(0, 1, 0));
    const Hit hit = scene.intersect(ray);
    ASSERT_TRUE(hit.valid());
    EXPECT_NEAR(hit.t, 3.0f, kTolerance);
    EXPECT_EQ(hit.triangle_id, 0u);  // object point (0.75, 0.25)
    EXPECT_NEAR(hit.barycentrics.x, 0.5f, kTolerance);
    EXPECT_NEAR(hit.barycentrics.y, 0.25f, kTolerance);
    // +Z rotates to -Y; length = twice the world-space area = 2 * 0.5 * 2 * 2.
    expect_near(hit.geometric_normal, vec3(0, -4, 0));

    const SurfacePoint point = scene.surface_point(ray, hit);
    expect_near(point.position, vec3(1.5f, 0.0f, 5.5f));
    expect_near(point.geometric_normal, vec3(0, -1, 0));
    expect_near(point.shading_normal, vec3(0, -1, 0));
    EXPECT_NEAR(point.uv.x, 0.75f, kTolerance);
    EXPECT_NEAR(point.uv.y, 0.25f, kTolerance);
}

TEST(SceneIntersect, NonUniformScaleTransformsNormalsByInverseTranspose) {
    // A quad tilted 45 degrees about Y, then squashed along X: the world normal is not the
    // transformed object normal but the inverse-transpose one.
    Mesh tilted = unit_quad("Tilted");
    for (vec3& p : tilted.positions) p.z = p.x;  // plane z = x, normal (-1, 0, 1) / sqrt 2
    for (vec3& n : tilted.normals) n = glm::normalize(vec3(-1, 0, 1));
    Scene scene;
    const mat4 world_from_object = glm::scale(mat4(1.0f), vec3(0.5f, 1.0f, 1.0f));
    scene.add_instance(scene.add_mesh(tilted), world_from_object);
    scene.commit();
    // World plane: z = 2x, normal (-2, 0, 1) / sqrt 5.
    const Ray ray = make_ray(vec3(0.25f, 0.5f, 3.0f), vec3(0, 0, -1));
    const Hit hit = scene.intersect(ray);
    ASSERT_TRUE(hit.valid());
    EXPECT_NEAR(hit.t, 2.5f, kTolerance);
    const SurfacePoint point = scene.surface_point(ray, hit);
    expect_near(point.geometric_normal, glm::normalize(vec3(-2, 0, 1)));
    expect_near(point.shading_normal, glm::normalize(vec3(-2, 0, 1)));
}

TEST(SceneIntersect, MirroringTransformKeepsTheFrontSide) {
    // Mirrored in X: the world winding flips, but the object's front (+Z) stays the front.
    const Scene scene = quad_scene(glm::scale(mat4(1.0f), vec3(-1, 1, 1)));
    const Ray ray = make_ray(vec3(-0.75f, 0.25f, 1.0f), vec3(0, 0, -1));
    const Hit hit = scene.intersect(ray);
    ASSERT_TRUE(hit.valid());
    expect_near(hit.geometric_normal, vec3(0, 0, 1));
    const SurfacePoint point = scene.surface_point(ray, hit);
    expect_near(point.geometric_normal, vec3(0, 0, 1));
    expect_near(point.shading_normal, vec3(0, 0, 1));
}

// Mesh 0, a unit quad, instanced twice: "Low" at z = 0 and "High" at z = 2; committed.
Scene two_quad_instances() {
    Scene scene;
    const uint32_t mesh = scene.add_mesh(unit_quad());
    scene.add_instance(mesh, mat4(1.0f), "Low");
    scene.add_instance(mesh, glm::translate(mat4(1.0f), vec3(0, 0, 2)), "High");
    scene.commit();
    return scene;
}

TEST(SceneIntersect, TwoInstancesOfOneMeshAndTransformUpdate) {
    Scene scene = two_quad_instances();
    const Ray down = make_ray(vec3(0.75f, 0.25f, 10), vec3(0, 0, -1));
    Hit hit = scene.intersect(down);
    EXPECT_EQ(hit.instance_id, 1u);
    EXPECT_NEAR(hit.t, 8.0f, kTolerance);
    EXPECT_EQ(scene.stats().triangles, 2u);
    EXPECT_EQ(scene.stats().instanced_triangles, 4u);

    scene.set_instance_transform(0, glm::translate(mat4(1.0f), vec3(0, 0, 4)));
    expect_contains(rejection<InvalidArgument>([&] { scene.intersect(down); }),
                    "call commit() first");
    scene.commit();
    hit = scene.intersect(down);
    EXPECT_EQ(hit.instance_id, 0u);
    EXPECT_NEAR(hit.t, 6.0f, kTolerance);
}

TEST(SceneIntersect, BatchMatchesSingleRays) {
    Scene scene;
    const uint32_t cube = scene.add_mesh(unit_cube());
    scene.add_instance(cube, mat4(1.0f));
    scene.add_instance(cube, glm::translate(mat4(1.0f), vec3(2, 0, 0)) *
                                 glm::rotate(mat4(1.0f), 0.3f, vec3(0, 0, 1)));
    scene.commit();
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    std::vector<Ray> rays;
    for (int i = 0; i < 10000; ++i) {  // several chunks and a partial one
        const vec3 target(1.5f + 1.5f * uniform(rng), 0.5f + uniform(rng), 0.5f + uniform(rng));
        const vec3 origin(1.5f + 4 * uniform(rng), 4 * uniform(rng), 3.0f + uniform(rng));
        rays.push_back(make_ray(origin, target - origin, 0.0f, i % 3 == 0 ? 0.7f : kInfinity));
    }
    // Both traversals: Embree ray streams (incoherent) and 16-wide packets (coherent), the
    // latter with a partial last packet (10000 = 625 x 16, so drop one ray).
    for (RayCoherence coherence : {RayCoherence::Incoherent, RayCoherence::Coherent}) {
        SCOPED_TRACE(coherence == RayCoherence::Coherent ? "coherent" : "incoherent");
        const std::vector<Ray> batch(rays.begin(), rays.end() - 1);
        std::vector<Hit> hits;
        std::vector<uint8_t> occluded;
        scene.intersect(batch, hits, nullptr, coherence);
        scene.occluded(batch, occluded, nullptr, coherence);
        ASSERT_EQ(hits.size(), batch.size());
        ASSERT_EQ(occluded.size(), batch.size());
        int hit_count = 0;
        for (size_t i = 0; i < batch.size(); ++i) {
            const Hit single = scene.intersect(batch[i]);
            ASSERT_EQ(hits[i].instance_id, single.instance_id) << "ray " << i;
            EXPECT_EQ(hits[i].triangle_id, single.triangle_id);
            EXPECT_EQ(hits[i].t, single.t);
            EXPECT_EQ(hits[i].barycentrics, single.barycentrics);
            EXPECT_EQ(hits[i].geometric_normal, single.geometric_normal);
            EXPECT_EQ(occluded[i] != 0, scene.occluded(batch[i]));
            EXPECT_EQ(occluded[i] != 0, single.valid());
            hit_count += single.valid();
        }
        EXPECT_GT(hit_count, 1000);  // the test would be vacuous if every ray missed
        EXPECT_LT(hit_count, 9000);
    }
}

TEST(SceneIntersect, SurfacePointGivesMaterialAndInterpolatedNormal) {
    Mesh mesh = unit_quad();
    mesh.material_indices = {1, 0};
    mesh.normals[2] = glm::normalize(vec3(1, 0, 1));
    Scene scene;
    scene.add_material(Material{});
    scene.add_material(Material{});
    scene.add_instance(scene.add_mesh(mesh), mat4(1.0f));
    scene.commit();
    const Ray ray = make_ray(vec3(0.75f, 0.25f, 1), vec3(0, 0, -1));
    const SurfacePoint point = scene.surface_point(ray, scene.intersect(ray));
    EXPECT_EQ(point.material_id, 1u);
    // b = (0.25, 0.5, 0.25) over normals (0,0,1), (0,0,1), (1,0,1)/sqrt 2.
    const vec3 n = 0.75f * vec3(0, 0, 1) + 0.25f * glm::normalize(vec3(1, 0, 1));
    expect_near(point.shading_normal, glm::normalize(n));
    expect_contains(rejection<InvalidArgument>([&] { scene.surface_point(ray, Hit{}); }),
                    "the hit is a miss");
}

// A TriangleNormalMemo changes no bit of a surface point: hits in runs on the same triangle
// (the memo's hits) and jumps between triangles and instances (its misses), through a rotated
// and a non-uniformly scaled instance of one mesh.
TEST(SceneIntersect, SurfacePointWithATriangleNormalMemoIsBitForBit) {
    Scene scene;
    const uint32_t cube = scene.add_mesh(unit_cube());
    scene.add_instance(cube, mat4(1.0f));
    scene.add_instance(cube, glm::translate(mat4(1.0f), vec3(2, 0, 0)) *
                                 glm::rotate(mat4(1.0f), 0.3f, vec3(0, 0, 1)) *
                                 glm::scale(mat4(1.0f), vec3(0.7f, 1.3f, 1.0f)));
    scene.commit();
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    TriangleNormalMemo memo;
    int hits = 0, repeated = 0;
    for (int i = 0; i < 4000; ++i) {
        // Runs of four rays towards nearby targets mostly meet one triangle in turn.
        std::mt19937 run_rng{uint32_t(i / 4)};
        const vec3 target(1.5f + 1.5f * uniform(run_rng), 0.5f + 0.5f * uniform(run_rng),
                          0.5f + 0.5f * uniform(run_rng));
        const vec3 origin(1.5f + 4 * uniform(rng), 4 * uniform(rng), 3.0f + uniform(rng));
        const Ray ray = make_ray(origin, target + 0.01f * vec3(uniform(rng)) - origin);
        const Hit hit = scene.intersect(ray);
        if (!hit.valid()) continue;
        ++hits;
        repeated += memo.instance_id == hit.instance_id && memo.triangle_id == hit.triangle_id;
        const SurfacePoint expected = scene.surface_point(ray, hit);
        const SurfacePoint point = scene.surface_point(ray, hit, &memo);
        ASSERT_EQ(std::memcmp(&point.geometric_normal, &expected.geometric_normal, sizeof(vec3)),
                  0)
            << "ray " << i;
        EXPECT_EQ(std::memcmp(&point.shading_normal, &expected.shading_normal, sizeof(vec3)), 0);
        EXPECT_EQ(std::memcmp(&point.position, &expected.position, sizeof(vec3)), 0);
        EXPECT_EQ(memo.instance_id, hit.instance_id);
        EXPECT_EQ(memo.triangle_id, hit.triangle_id);
    }
    // Both paths of the memo ran.
    EXPECT_GT(hits, 1000);
    EXPECT_GT(repeated, 300);
    EXPECT_LT(repeated, hits - 300);
}

// surface_point_lanes gives surface_point's points bit for bit: four hits on one instance of a
// flat mesh (the SSE2 lanes) through an identity, a rotated and non-uniformly scaled and a
// translated instance, at random and edge barycentrics (0, 1, -0, subnormal, b1 + b2 > 1); and
// the one-by-one fallback for mixed instances, a mesh with normals and UVs, and misses (whose
// points are left as they were). The memo ends on the last valid hit's triangle.
TEST(SceneIntersect, SurfacePointLanesAreSurfacePointBitForBit) {
    Scene scene;
    scene.add_material(Material{});
    scene.add_material(Material{});
    Mesh cube = unit_cube();
    for (size_t t = 0; t < cube.triangles.size(); ++t)
        cube.material_indices.push_back(uint32_t(t % 3 == 0));
    const uint32_t cube_id = scene.add_mesh(cube);
    scene.add_instance(cube_id, mat4(1.0f));
    scene.add_instance(cube_id, glm::translate(mat4(1.0f), vec3(2, 0.1f, -3)) *
                                    glm::rotate(mat4(1.0f), 0.3f, vec3(0.2f, 0.5f, 1)) *
                                    glm::scale(mat4(1.0f), vec3(0.7f, 1.3f, 2.1f)));
    scene.add_instance(scene.add_mesh(unit_quad()), glm::translate(mat4(1.0f), vec3(0, 0, 5)));
    scene.add_instance(cube_id, glm::translate(mat4(1.0f), vec3(-1e3f, 7.5f, 1e-3f)));
    scene.commit();
    const uint32_t instances = 4, quad = 2;
    const float edges[] = {0.0f, 1.0f, -0.0f, 0.5f, 1e-40f, 0.9999999f, 1.0e-7f, 0.75f};
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    const auto barycentric = [&] {
        return rng() % 4 == 0 ? edges[rng() % std::size(edges)] : uniform(rng);
    };
    TriangleNormalMemo memo, reference_memo;
    int lane_groups = 0;
    for (int group = 0; group < 3000; ++group) {
        Hit hits[4];
        const uint32_t shared = rng() % instances;
        const int kind = int(rng() % 4);  // 0, 1: one instance; 2: mixed; 3: with a miss
        for (int j = 0; j < 4; ++j) {
            if (kind == 3 && rng() % 2 == 0) continue;  // a miss
            Hit& hit = hits[j];
            hit.instance_id = kind == 2 ? rng() % instances : shared;
            hit.triangle_id = rng() % (hit.instance_id == quad ? 2 : 12);
            hit.barycentrics = vec2(barycentric(), barycentric());
            hit.t = 1.0f;
        }
        lane_groups += kind < 2 && shared != quad;
        SurfacePoint points[4], before[4];
        for (int j = 0; j < 4; ++j) points[j].material_id = before[j].material_id = 77;
        scene.surface_point_lanes(hits, points, &memo);
        const Hit* last = nullptr;
        for (int j = 0; j < 4; ++j) {
            const SurfacePoint& expected =
                hits[j].valid() ? scene.surface_point(Ray{}, hits[j], &reference_memo) : before[j];
            ASSERT_EQ(std::memcmp(&points[j], &expected, sizeof(SurfacePoint)), 0)
                << "group " << group << " lane " << j << " instance " << hits[j].instance_id
                << " triangle " << hits[j].triangle_id << " b " << hits[j].barycentrics.x
                << ", " << hits[j].barycentrics.y;
            if (hits[j].valid()) last = &hits[j];
        }
        if (last != nullptr) {
            EXPECT_EQ(memo.instance_id, last->instance_id);
            EXPECT_EQ(memo.triangle_id, last->triangle_id);
        }
    }
    EXPECT_GT(lane_groups, 1000);  // the lanes ran
}

// A texture reads the UV set its material names; without a name, or with an unknown one, the first.
TEST(SceneIntersect, SurfacePointUsesTheMaterialsUvSet) {
    Mesh mesh = unit_quad();
    mesh.uv_sets = {{"UVMap", {{0, 0}, {1, 0}, {1, 1}, {0, 1}}},
                    {"Detail", {{0, 0}, {4, 0}, {4, 4}, {0, 4}}}};
    const Ray ray = make_ray(vec3(0.75f, 0.25f, 1), vec3(0, 0, -1));
    for (const auto& [uv_set, expected] :
         {std::pair<std::string, vec2>{"", {0.75f, 0.25f}}, {"Detail", {3.0f, 1.0f}},
          {"Missing", {0.75f, 0.25f}}}) {
        Material material;
        material.base_color_uv_set = uv_set;
        Scene scene;
        scene.add_material(material);
        scene.add_instance(scene.add_mesh(mesh), mat4(1.0f));
        scene.commit();
        const SurfacePoint point = scene.surface_point(ray, scene.intersect(ray));
        EXPECT_NEAR(point.uv.x, expected.x, 1e-5f) << uv_set;
        EXPECT_NEAR(point.uv.y, expected.y, 1e-5f) << uv_set;
    }
}

TEST(SceneValidation, EachBadInputHasItsOwnMessage) {
    Scene scene;
    Mesh nan_mesh = unit_quad();
    nan_mesh.positions[1].y = kNaN;
    expect_contains(rejection<InvalidArgument>([&] { scene.add_mesh(nan_mesh); }),
                    "mesh 'Quad': positions[1] = (1, nan, 0) is not finite");
    const uint32_t mesh = scene.add_mesh(unit_quad());
    expect_contains(rejection<InvalidArgument>([&] { scene.add_instance(7, mat4(1.0f)); }),
                    "mesh_id = 7 but the scene has 1 meshes");
    expect_contains(rejection<InvalidArgument>([&] {
                        scene.add_instance(mesh, glm::scale(mat4(1.0f), vec3(1, 0, 1)), "Flat");
                    }),
                    "instance 'Flat': world_from_object is singular");
    mat4 nan_transform(1.0f);
    nan_transform[3].y = kNaN;
    expect_contains(rejection<InvalidArgument>([&] { scene.add_instance(mesh, nan_transform); }),
                    "world_from_object has a non-finite (NaN or Inf) entry");
    expect_contains(rejection<InvalidArgument>([&] {
                        scene.set_instance_transform(3, mat4(1.0f));
                    }),
                    "instance_id = 3 but the scene has 0 instances");
    expect_contains(rejection<InvalidArgument>([&] { scene.camera(); }), "has no camera");
    Camera camera;
    camera.lens = -1.0f;
    expect_contains(rejection<InvalidArgument>([&] { scene.set_camera(camera); }),
                    "camera: lens = -1 must be > 0");
    Light light;
    light.name = "Fill";
    light.power = kNaN;
    expect_contains(rejection<InvalidArgument>([&] { scene.add_light(light); }),
                    "light 'Fill': power = nan is not finite");
}

TEST(SceneValidation, CommitChecksCrossReferences) {
    Scene scene;
    Mesh mesh = unit_quad();
    mesh.material_indices = {0, 2};
    scene.add_instance(scene.add_mesh(mesh), mat4(1.0f));
    scene.add_material(Material{});
    expect_contains(rejection<InvalidArgument>([&] { scene.commit(); }),
                    "mesh 'Quad': material_indices[1] = 2 but the scene has 1 materials");

    Scene textured;
    Material material;
    material.name = "Bricks";
    material.base_color_texture = 0;
    textured.add_material(material);  // the texture may still come
    expect_contains(rejection<InvalidArgument>([&] { textured.commit(); }),
                    "material 'Bricks': base_color_texture = 0 but the scene has 0 textures");
    Texture texture;
    texture.width = texture.height = 1;
    texture.texels = {vec4(1)};
    textured.add_texture(texture);
    EXPECT_NO_THROW(textured.commit());
    EXPECT_TRUE(textured.committed());
}

// What the BSDF takes from a material alone (MaterialTerms), against the closure weights of
// render/bsdf.h's header comment and the meaning of Principled's Specular (F0 = 0.08 specular).
TEST(SceneMaterials, MaterialTermsFollowThePrincipledParameters) {
    for (float metallic : {0.0f, 0.3f, 1.0f})
        for (float transmission : {0.0f, 0.6f, 1.0f})
            for (float specular : {0.0f, 0.5f, 1.0f}) {
                Material material;
                material.metallic = metallic;
                material.transmission = transmission;
                material.specular = specular;
                material.roughness = 0.4f;
                material.ior = 1.33f;
                const MaterialTerms terms = material_terms(material);
                const std::string name = "metallic " + std::to_string(metallic) +
                                         " transmission " + std::to_string(transmission) +
                                         " specular " + std::to_string(specular);
                const float dielectric = (1.0f - metallic) * (1.0f - transmission);
                EXPECT_EQ(terms.metallic, metallic) << name;
                EXPECT_FLOAT_EQ(terms.transmission, (1.0f - metallic) * transmission) << name;
                EXPECT_FLOAT_EQ(terms.diffuse_scale, dielectric) << name;
                // The dielectric layer exists only with a non-zero Specular.
                EXPECT_FLOAT_EQ(terms.dielectric_weight, specular > 0.0f ? dielectric : 0.0f)
                    << name;
                EXPECT_FLOAT_EQ(terms.alpha, 0.16f) << name;
                EXPECT_FLOAT_EQ(terms.specular_f0, 0.08f * specular) << name;
                // specular_ior is the ior whose Fresnel reflectance at normal incidence,
                // ((n - 1) / (n + 1))^2, is F0.
                const float n = terms.specular_ior;
                EXPECT_NEAR((n - 1.0f) * (n - 1.0f) / ((n + 1.0f) * (n + 1.0f)),
                            terms.specular_f0, 1e-6f) << name;
                EXPECT_NEAR(terms.inv_one_minus_f0 * (1.0f - terms.specular_f0), 1.0f, 1e-6f)
                    << name;
                EXPECT_NEAR(terms.inv_ior * material.ior, 1.0f, 1e-6f) << name;
                EXPECT_EQ(terms.specular, specular > 0.0f || metallic > 0.0f) << name;
            }
}

// The old PrincipledBsdf(material, ...) constructor takes materials no scene validated: their
// terms use the clamped parameters, so no lobe gets a negative weight.
TEST(SceneMaterials, MaterialTermsClampOutOfRangeParameters) {
    Material material;
    material.metallic = -0.5f;
    material.transmission = 1.5f;
    material.specular = 0.5f;
    const MaterialTerms terms = material_terms(material);
    EXPECT_EQ(terms.metallic, 0.0f);
    EXPECT_FLOAT_EQ(terms.transmission, 1.0f);
    EXPECT_EQ(terms.diffuse_scale, 0.0f);
    EXPECT_EQ(terms.dielectric_weight, 0.0f);
    material.transmission = -1.0f;
    const MaterialTerms opaque = material_terms(material);
    EXPECT_EQ(opaque.transmission, 0.0f);
    EXPECT_EQ(opaque.diffuse_scale, 1.0f);
    EXPECT_EQ(opaque.dielectric_weight, 1.0f);
}

TEST(SceneMaterials, CommitKeepsEachMaterialsTerms) {
    Scene scene;
    scene.add_instance(scene.add_mesh(unit_quad()), mat4(1.0f));
    scene.commit();  // no material: commit adds the default one
    ASSERT_EQ(scene.materials().size(), 1u);
    ASSERT_EQ(scene.material_terms().size(), 1u);
    Material metal;
    metal.metallic = 1.0f;
    metal.roughness = 0.3f;
    scene.add_material(metal);
    scene.commit();
    ASSERT_EQ(scene.material_terms().size(), 2u);
    for (size_t i = 0; i < 2; ++i) {
        const MaterialTerms expected = material_terms(scene.materials()[i]);
        const MaterialTerms& kept = scene.material_terms()[i];
        EXPECT_EQ(kept.metallic, expected.metallic) << i;
        EXPECT_EQ(kept.alpha, expected.alpha) << i;
        EXPECT_EQ(kept.specular_ior, expected.specular_ior) << i;
        EXPECT_EQ(kept.inv_ior, expected.inv_ior) << i;
    }
    EXPECT_EQ(scene.material_terms()[1].metallic, 1.0f);
    EXPECT_FLOAT_EQ(scene.material_terms()[1].alpha, 0.09f);
    EXPECT_EQ(scene.material_terms()[1].diffuse_scale, 0.0f);
}

TEST(SceneValidation, InstanceBeyondEmbreeRangeIsRejectedAtCommit) {
    Scene scene;
    scene.add_instance(scene.add_mesh(unit_quad()), glm::scale(mat4(1.0f), vec3(1e16f)), "Huge");
    expect_contains(rejection<InvalidArgument>([&] { scene.commit(); }),
                    "instance 0 'Huge': world-space bounds");
}

// The largest scene kMaxCoordinate allows still intersects right: Embree's triangle test
// multiplies three lengths in float, and in a box of half-side 5e12 m most hits came back at
// t = inf (scene/ray.h). Rays from inside a closed cube of half-side kMaxCoordinate all hit it,
// within the cube's diagonal.
TEST(SceneIntersect, TheLargestSceneAllowedHitsAtFiniteDistances) {
    Scene scene;
    scene.add_instance(scene.add_mesh(unit_cube()),
                       glm::translate(mat4(1.0f), vec3(-kMaxCoordinate)) *
                           glm::scale(mat4(1.0f), vec3(2.0f * kMaxCoordinate)));
    scene.commit();
    std::mt19937 random(7);
    std::uniform_real_distribution<float> inside(-0.99f, 0.99f);
    std::normal_distribution<float> normal;
    std::vector<Ray> rays(4096);
    for (Ray& ray : rays) {
        ray.origin = kMaxCoordinate * vec3(inside(random), inside(random), inside(random));
        ray.direction = vec3(normal(random), normal(random), normal(random));
    }
    std::vector<Hit> hits;
    scene.intersect(rays, hits);
    for (size_t i = 0; i < rays.size(); ++i) {
        ASSERT_TRUE(hits[i].valid()) << i;
        ASSERT_TRUE(std::isfinite(hits[i].t)) << i;
        ASSERT_LE(hits[i].t * glm::length(rays[i].direction), 3.5f * kMaxCoordinate) << i;
    }
}

// A closed cube of half-side `half` around the origin, in its own coordinates.
Mesh cube_of_half_side(float half) {
    Mesh mesh = unit_cube();
    for (vec3& p : mesh.positions) p = (2.0f * p - 1.0f) * half;
    return mesh;
}

// Rays at the limits a scene sets from its triangles still intersect right, where Embree's
// triangle test in float overflowed before (scene/ray.h, RayLimits): from origins just inside
// the origin limit, with directions just inside the direction limits (longest and shortest) and
// of length 1, aimed at points inside a closed cube, every ray hits it at a finite distance no
// farther than its target; origins and directions just past the limits are refused, naming the
// cause. Before, the cube of half-side 1e12 m hit at t = inf from 1e17 m, and the shrunk one
// from 1e9 m; and a direction of 1e-38 missed a triangle 5 m away.
TEST(SceneIntersect, RaysAtTheTriangleTestLimitsHitAtFiniteDistances) {
    struct Case {
        float half;          // the mesh's, in its own coordinates
        float scale;         // the instance's
        float far_origin;    // traced as hits at t = inf before
    };
    for (const Case& c : {Case{1e12f, 1.0f, 1e17f}, Case{9e11f, 1e-7f, 1e9f}}) {
        SCOPED_TRACE(c.half);
        Scene scene;
        scene.add_instance(scene.add_mesh(cube_of_half_side(c.half)),
                           glm::scale(mat4(1.0f), vec3(c.scale)), "Cube");
        scene.commit();
        const RayLimits limits = scene.ray_limits();
        const float world_half = c.half * c.scale;
        EXPECT_GE(limits.origin, world_half);
        EXPECT_GE(limits.direction, 1.0f);
        EXPECT_LT(limits.origin, c.far_origin);
        const std::string far = rejection<InvalidArgument>([&] {
            scene.intersect(make_ray(vec3(-c.far_origin, 0, 0), vec3(1, 0, 0)));
        });
        expect_contains(far, "ray: origin exceeds the scene's ray range");
        expect_contains(far, "instance 0 'Cube''s mesh has triangle edges up to");
        expect_contains(rejection<InvalidArgument>([&] {
                            scene.intersect(make_ray(vec3(0.0f),
                                                     vec3(0, 0, 1.01f * limits.direction)));
                        }),
                        "ray: direction exceeds the scene's ray range");
        expect_contains(rejection<InvalidArgument>([&] {
                            scene.intersect(make_ray(vec3(0.0f),
                                                     vec3(0, 0, 0.5f * limits.min_direction)));
                        }),
                        "ray: direction is shorter than the scene's ray range");
        std::mt19937 random(11);
        std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
        std::vector<Ray> rays;
        std::vector<vec3> targets;
        for (int i = 0; i < 3000; ++i) {
            // An origin on the faces of the box the origin limit allows, outside the cube.
            vec3 origin(unit(random), unit(random), unit(random));
            origin[i % 3] = (i & 8) ? 1.0f : -1.0f;
            origin *= 0.999f * limits.origin;
            const vec3 target = 0.9f * world_half * vec3(unit(random), unit(random), unit(random));
            const vec3 towards = target - origin;
            const float length = i % 3 == 0   ? 0.999f * limits.direction
                                 : i % 3 == 1 ? 1.001f * limits.min_direction
                                              : 1.0f;  // largest component
            rays.push_back(make_ray(origin, towards * (length / max_abs_component(towards))));
            targets.push_back(target);
        }
        std::vector<Hit> hits;
        scene.intersect(rays, hits);
        for (size_t i = 0; i < rays.size(); ++i) {
            ASSERT_TRUE(hits[i].valid()) << i;
            ASSERT_TRUE(std::isfinite(hits[i].t)) << i;
            const double reached = double(hits[i].t) * glm::length(glm::dvec3(rays[i].direction));
            ASSERT_LE(reached, 1.0001 * glm::length(glm::dvec3(targets[i] - rays[i].origin)))
                << i;
        }
    }
}

// Embree checks a ray again in each instance's own coordinates (and Debian's Embree aborts past
// 1.8e18 there): an instance that shrinks its mesh lowers the range the scene traces, and one
// that would put rays from the scene's own surfaces out of range is refused at commit.
TEST(SceneValidation, ShrunkInstanceLowersTheRayRange) {
    Scene small;
    small.add_instance(small.add_mesh(unit_quad()), glm::scale(mat4(1.0f), vec3(0.1f)), "Small");
    small.commit();
    EXPECT_NEAR(small.ray_limits().origin, 1e17f, 1e12f);
    EXPECT_NEAR(small.ray_limits().direction, 1e17f, 1e12f);
    // Within the lowered range: traced (9e17 in the mesh's coordinates).
    EXPECT_FALSE(small.intersect(make_ray(vec3(9e16f, 0.05f, 0.05f), vec3(0, 0, 1))).valid());
    expect_contains(rejection<InvalidArgument>([&] {
                        small.intersect(make_ray(vec3(5e17f, 0, 0), vec3(-1, 0, 0)));
                    }),
                    "ray: origin exceeds the scene's ray range");
    const std::vector<Ray> rays(3, make_ray(vec3(0.05f, 0.05f, 1), vec3(0, 2e17f, -1)));
    std::vector<Hit> hits;
    expect_contains(rejection<InvalidArgument>([&] { small.intersect(rays, hits); }),
                    "rays[0]: direction exceeds the scene's ray range");
    expect_contains(rejection<InvalidArgument>([&] { small.intersect(rays, hits); }),
                    "instance 0 'Small' shrinks its mesh by up to 10x");
    // The translation counts too: origins are moved by it before the inverse scale.
    Scene moved;
    const mat4 transform =
        glm::scale(glm::translate(mat4(1.0f), vec3(0, 0, 1e12f)), vec3(1e-5f));
    moved.add_instance(moved.add_mesh(unit_quad()), transform);
    moved.commit();
    EXPECT_NEAR(moved.ray_limits().origin, 1e13f - 1e12f, 1e8f);
    EXPECT_NEAR(moved.ray_limits().direction, 1e13f, 1e8f);
    // Scaling up, or a mesh without triangles, leaves Embree's own range.
    Scene large;
    large.add_instance(large.add_mesh(unit_quad()), glm::scale(mat4(1.0f), vec3(10.0f)));
    large.add_instance(large.add_mesh(Mesh{}), glm::scale(mat4(1.0f), vec3(1e-30f)));
    large.commit();
    EXPECT_EQ(large.ray_limits().origin, kMaxRayComponent);
    EXPECT_EQ(large.ray_limits().direction, kMaxRayComponent);
    // One axis scaled by 1e-20 (its determinant is not "singular" relative to its columns):
    // a ray from anywhere in the scene would leave Embree's range in the mesh's coordinates.
    Scene flat;
    flat.add_instance(flat.add_mesh(unit_quad()), glm::scale(mat4(1.0f), vec3(1, 1, 1e-20f)),
                      "Flat");
    const std::string message = rejection<InvalidArgument>([&] { flat.commit(); });
    expect_contains(message, "instance 0 'Flat': its transform shrinks the mesh by up to 1e+20x");
    expect_contains(message, "Apply Scale");
    EXPECT_FALSE(flat.committed());
}

TEST(SceneValidation, EachBadRayHasItsOwnMessage) {
    const Scene scene = quad_scene();
    const auto bad = [&](const Ray& ray) {
        return rejection<InvalidArgument>([&] { scene.intersect(ray); });
    };
    expect_contains(bad(make_ray(vec3(kNaN, 0, 0), vec3(0, 0, -1))),
                    "ray: origin is not finite (origin (nan, 0, 0), direction (0, 0, -1)");
    expect_contains(bad(make_ray(vec3(0), vec3(0, kInfinity, 0))), "ray: direction is not finite");
    expect_contains(bad(make_ray(vec3(0), vec3(0))), "ray: direction is zero");
    // Finite but beyond Embree's FLT_LARGE: Debian's Embree asserts on these and aborts.
    expect_contains(bad(make_ray(vec3(2e18f, 0, 1), vec3(0, 0, -1))),
                    "ray: origin exceeds the scene's ray range");
    expect_contains(bad(make_ray(vec3(2e18f, 0, 1), vec3(0, 0, -1))),
                    "; this scene traces origins up to 1e+18 and directions up to 1e+18 per "
                    "component");
    expect_contains(bad(make_ray(vec3(0, 0, 1), vec3(0, -3e18f, 0))),
                    "ray: direction exceeds the scene's ray range");
    expect_contains(bad(make_ray(vec3(0), vec3(0, 0, 1), -1.0f)),
                    "ray: tmin must be finite and >= 0");
    expect_contains(bad(make_ray(vec3(0), vec3(0, 0, 1), 2.0f, 1.0f)),
                    "ray: tmax is less than tmin (origin (0, 0, 0), direction (0, 0, 1), tmin 2, "
                    "tmax 1)");
    expect_contains(bad(make_ray(vec3(0), vec3(0, 0, 1), 0.0f, kNaN)), "ray: tmax is NaN");
    expect_contains(rejection<InvalidArgument>([&] {
                        scene.occluded(make_ray(vec3(0), vec3(0)));
                    }),
                    "ray: direction is zero");
    // Batches name the first bad ray by index.
    std::vector<Ray> rays(10, make_ray(vec3(0.5f, 0.5f, 1), vec3(0, 0, -1)));
    rays[6].direction.z = kNaN;
    rays[8].origin.x = kNaN;
    std::vector<Hit> hits;
    std::vector<uint8_t> occluded;
    expect_contains(rejection<InvalidArgument>([&] { scene.intersect(rays, hits); }),
                    "rays[6]: direction is not finite");
    expect_contains(rejection<InvalidArgument>([&] { scene.occluded(rays, occluded); }),
                    "rays[6]: direction is not finite");
}

// is_valid_ray (branch-free, on every traced ray) and ray_problem (the message) are two codings
// of one rule: they must agree on every ray, here every combination of edge values per field.
TEST(SceneValidation, FastRayTestAgreesWithTheNamedProblem) {
    const float max = std::numeric_limits<float>::max();
    const float denormal = std::numeric_limits<float>::denorm_min();
    const std::vector<float> values = {0.0f, -0.0f, denormal, -1.0f, 1.0f, 1e18f, -1e18f,
                                       std::nextafter(1e18f, max), -2e18f, max, kInfinity,
                                       -kInfinity, kNaN};
    size_t checked = 0, valid = 0;
    const auto agree = [&](const Ray& ray) {
        const bool fast = is_valid_ray(ray);
        EXPECT_EQ(fast, ray_problem(ray) == nullptr)
            << "origin " << ray.origin.x << "," << ray.origin.y << "," << ray.origin.z
            << " direction " << ray.direction.x << "," << ray.direction.y << ","
            << ray.direction.z << " tmin " << ray.tmin << " tmax " << ray.tmax;
        ++checked;
        valid += fast ? 1 : 0;
    };
    const RayLimits lowered{1e3f, 10.0f, 1e-3f};
    const auto agree_lowered = [&](const Ray& ray) {
        EXPECT_EQ(is_valid_ray(ray, lowered), ray_problem(ray, lowered) == nullptr)
            << "origin " << ray.origin.x << " direction " << ray.direction.y;
    };
    for (float a : {999.0f, 1e3f, 1001.0f, 9.0f, 10.0f, 11.0f, kNaN})
        for (float b : {0.0f, 1.0f, -1e3f, -1e4f}) {
            agree_lowered(make_ray(vec3(a, b, 0.0f), vec3(0, 0, 1)));
            agree_lowered(make_ray(vec3(0.0f), vec3(b, a, 1.0f)));
        }
    // The shortest direction: its largest |component| must exceed min_direction.
    for (float a : {0.0f, 1e-4f, -1e-3f, 1e-3f, std::nextafter(1e-3f, 1.0f), -2e-3f, kNaN})
        for (float b : {0.0f, 5e-4f, -1e-2f}) agree_lowered(make_ray(vec3(0.0f), vec3(a, b, b)));
    for (float a : values)
        for (float b : values) {
            agree(make_ray(vec3(a, 1.0f, b), vec3(0, 0, 1)));      // origin
            agree(make_ray(vec3(0.5f), vec3(a, b, 0.0f)));         // direction, incl. zero
            agree(make_ray(vec3(0.5f), vec3(1, 0, 0), a, b));      // tmin, tmax
            agree(make_ray(vec3(b, 0.0f, 0.0f), vec3(0, a, 0)));   // one of each
        }
    EXPECT_EQ(checked, 4 * values.size() * values.size());
    EXPECT_GT(valid, 0u);
    EXPECT_LT(valid, checked);
}

// first_invalid_ray tests four rays at a time: it must name the same ray as is_valid_ray
// checked one by one, wherever the bad ray sits in its group of four and in a batch's
// remainder, for every field's edge values and for lowered limits.
TEST(SceneValidation, FirstInvalidRayIsTheFirstThatIsValidRayRejects) {
    const float max = std::numeric_limits<float>::max();
    const std::vector<float> values = {0.0f, -0.0f, 1e-4f, -1.0f, 1.0f, 1e18f, -1e18f,
                                       std::nextafter(1e18f, max), max, kInfinity,
                                       -kInfinity, kNaN};
    std::vector<Ray> odd;  // valid and invalid rays, one edge value at a time per field
    for (float a : values) {
        odd.push_back(make_ray(vec3(a, 1.0f, 0.5f), vec3(0, 0, 1)));
        odd.push_back(make_ray(vec3(0.5f, a, 0.5f), vec3(0, 0, 1)));
        odd.push_back(make_ray(vec3(0.5f, 0.5f, a), vec3(0, 0, 1)));
        odd.push_back(make_ray(vec3(0.5f), vec3(a, 0, 0)));
        odd.push_back(make_ray(vec3(0.5f), vec3(0, a, 0)));
        odd.push_back(make_ray(vec3(0.5f), vec3(0, 0, a)));
        odd.push_back(make_ray(vec3(0.5f), vec3(1, 0, 0), a, 1.0f));
        odd.push_back(make_ray(vec3(0.5f), vec3(1, 0, 0), 0.0f, a));
    }
    const Ray good = make_ray(vec3(0.5f), vec3(0, 0, -1));
    const auto scalar_first = [](const std::vector<Ray>& rays, const RayLimits& limits) {
        size_t i = 0;
        while (i < rays.size() && is_valid_ray(rays[i], limits)) ++i;
        return i;
    };
    size_t batches = 0, found = 0;
    for (const RayLimits& limits : {RayLimits{}, RayLimits{1e3f, 10.0f, 1e-3f}})
        for (const Ray& ray : odd)
            for (size_t size = 1; size <= 9; ++size)
                for (size_t at = 0; at < size; ++at) {
                    std::vector<Ray> rays(size, good);
                    rays[at] = ray;
                    const size_t expected = scalar_first(rays, limits);
                    ASSERT_EQ(first_invalid_ray(rays.data(), rays.size(), limits), expected)
                        << "ray " << (&ray - odd.data()) << " at " << at << " of " << size;
                    ++batches;
                    found += expected < size ? 1 : 0;
                }
    EXPECT_GT(found, 0u);          // some edge values are rejected...
    EXPECT_LT(found, batches);     // ...and some accepted
    EXPECT_EQ(first_invalid_ray(nullptr, 0), 0u);
}

// transform_normal (every hit's normal into world space) is glm's mat3 * vec3 in SSE2: the
// same bits on random matrices and normals, and on signed zeros, infinities and NaN.
TEST(SceneIntersect, TransformNormalIsGlmBitForBit) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> uniform(-3.0f, 3.0f);
    const std::vector<float> edges = {0.0f, -0.0f, 1.0f, -1.0f, 1e-40f, 3e38f, kInfinity,
                                      -kInfinity, kNaN};
    int checked = 0;
    for (int i = 0; i < 2000; ++i) {
        mat3 m;
        for (int c = 0; c < 3; ++c)
            for (int r = 0; r < 3; ++r) m[c][r] = i % 4 == 0 ? float(r == c) : uniform(rng);
        vec3 n(uniform(rng), uniform(rng), uniform(rng));
        if (i % 3 == 0) n[i % 2] = edges[size_t(i / 3) % edges.size()];
        const vec3 expected = m * n, got = transform_normal(m, n);
        ASSERT_EQ(std::memcmp(&expected, &got, sizeof(vec3)), 0)
            << "matrix " << i << ": " << expected.x << " " << got.x;
        ++checked;
    }
    EXPECT_EQ(checked, 2000);
}

TEST(SceneValidation, QueriesBeforeCommitAreRejected) {
    Scene scene;
    scene.add_instance(scene.add_mesh(unit_quad()), mat4(1.0f));
    const Ray ray = make_ray(vec3(0.5f, 0.5f, 1), vec3(0, 0, -1));
    std::vector<Hit> hits;
    expect_contains(rejection<InvalidArgument>([&] { scene.intersect(ray); }),
                    "Scene::intersect: the scene was edited or never committed; call commit() "
                    "first");
    expect_contains(rejection<InvalidArgument>([&] { scene.occluded(ray); }),
                    "Scene::occluded");
    expect_contains(rejection<InvalidArgument>([&] { scene.intersect({ray}, hits); }),
                    "call commit() first");
    scene.commit();
    EXPECT_TRUE(scene.occluded(ray));
    scene.add_material(Material{});  // any edit un-commits
    EXPECT_FALSE(scene.committed());
}

TEST(SceneSetMesh, ReplacesTheMeshOfEveryInstanceAtTheNextCommit) {
    // Two instances of a unit quad, at z = 0 and z = 2; the quad is then replaced by one moved
    // to x in [2, 3] with a degenerate triangle, as a relaid-out mesh would be put back.
    Scene scene = two_quad_instances();
    const uint32_t mesh = 0;
    const Ray old_place = make_ray(vec3(0.75f, 0.25f, 10), vec3(0, 0, -1));
    const Ray new_place = make_ray(vec3(2.75f, 0.25f, 10), vec3(0, 0, -1));
    EXPECT_TRUE(scene.intersect(old_place).valid());
    EXPECT_FALSE(scene.intersect(new_place).valid());
    const uint64_t revision = scene.revision();

    Mesh moved = unit_quad("Moved");
    for (vec3& p : moved.positions) p.x += 2.0f;
    moved.triangles.push_back(uvec3(0, 0, 1));
    scene.set_mesh(mesh, moved);
    EXPECT_FALSE(scene.committed());
    EXPECT_GT(scene.revision(), revision);
    expect_contains(rejection<InvalidArgument>([&] { scene.intersect(new_place); }),
                    "call commit() first");
    EXPECT_EQ(scene.meshes()[mesh].name, "Moved");
    EXPECT_EQ(scene.mesh_reports()[mesh].dropped_degenerate, 1u);
    EXPECT_EQ(scene.meshes()[mesh].triangles.size(), 2u);

    scene.commit();
    EXPECT_FALSE(scene.intersect(old_place).valid());
    const Hit hit = scene.intersect(new_place);
    ASSERT_TRUE(hit.valid());
    EXPECT_EQ(hit.instance_id, 1u);  // the z = 2 instance moved with its mesh
    EXPECT_NEAR(hit.t, 8.0f, kTolerance);
    EXPECT_EQ(scene.stats().meshes, 1u);
    EXPECT_EQ(scene.stats().dropped_degenerate, 1u);
    EXPECT_EQ(scene.stats().instanced_triangles, 4u);
}

TEST(SceneSetMesh, BadIdOrMeshIsRejectedAndLeavesTheSceneCommitted) {
    Scene scene;
    scene.add_instance(scene.add_mesh(unit_quad()), mat4(1.0f));
    scene.commit();
    const std::string message = rejection<InvalidArgument>([&] { scene.set_mesh(3, unit_quad()); });
    expect_contains(message, "mesh_id = 3");
    expect_contains(message, "the scene has 1 meshes");
    Mesh nan_mesh = unit_quad("Broken");
    nan_mesh.positions[2].y = kNaN;
    expect_contains(rejection<InvalidArgument>([&] { scene.set_mesh(0, nan_mesh); }),
                    "mesh 'Broken': positions[2] = (1, nan, 0) is not finite");
    EXPECT_TRUE(scene.committed());
    EXPECT_EQ(scene.meshes()[0].name, "Quad");
    EXPECT_TRUE(scene.intersect(make_ray(vec3(0.5f, 0.5f, 1), vec3(0, 0, -1))).valid());
}

TEST(SceneStats, CountsDroppedDegenerateTriangles) {
    Mesh mesh = unit_quad();
    mesh.triangles.push_back(uvec3(1, 1, 2));
    mesh.triangles.push_back(uvec3(0, 1, 1));
    Scene scene;
    scene.add_instance(scene.add_mesh(mesh), mat4(1.0f));
    scene.commit();
    EXPECT_EQ(scene.stats().dropped_degenerate, 2u);
    EXPECT_EQ(scene.mesh_reports()[0].dropped_degenerate, 2u);
    EXPECT_EQ(scene.stats().triangles, 2u);
    EXPECT_GT(scene.stats().bvh_bytes, 0u);
}

TEST(SceneMemory, TinyBudgetFailsUpFrontWithOutOfMemory) {
    Scene scene;
    scene.add_instance(scene.add_mesh(grid(16)), mat4(1.0f));
    CommitSettings settings;
    settings.memory_budget_bytes = 1024;
    const std::string message = rejection<OutOfMemory>([&] { scene.commit(settings); });
    expect_contains(message, "needs at least");
    expect_contains(message, "the memory budget is 1024 bytes");
    EXPECT_FALSE(scene.committed());
}

TEST(SceneMemory, MonitorRefusesAllocationsBeyondTheBudget) {
    Scene scene;
    scene.add_instance(scene.add_mesh(grid(100)), mat4(1.0f));
    // Above the up-front estimate, so the build starts and the memory monitor must stop it.
    CommitSettings settings;
    settings.memory_budget_bytes = estimate_bvh_bytes(scene.meshes(), scene.instances()) + 1;
    const std::string message = rejection<OutOfMemory>([&] { scene.commit(settings); });
    expect_contains(message, "building the BVH of mesh 'Grid' exceeded the memory budget: budget " +
                                 std::to_string(settings.memory_budget_bytes) + " bytes");
    expect_contains(message, "more bytes requested");
    EXPECT_FALSE(scene.committed());
    // The failed build released everything: the same scene commits with the default budget.
    scene.commit();
    EXPECT_TRUE(scene.occluded(make_ray(vec3(0.5f, 0.5f, 1), vec3(0, 0, -1))));
    EXPECT_GT(scene.stats().bvh_bytes, settings.memory_budget_bytes);
}

TEST(SceneEmpty, CommitWarnsRaysMissAndBoundsThrow) {
    std::vector<std::string> warnings;
    const LogSink previous = set_log_sink([&](LogLevel level, const std::string& message) {
        if (level == LogLevel::Warning) warnings.push_back(message);
    });
    Scene scene;
    scene.add_mesh(unit_quad());  // a mesh without an instance renders nothing
    scene.commit();
    set_log_sink(previous);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_EQ(warnings[0], "scene has no triangles: every ray misses");
    EXPECT_TRUE(scene.empty());
    const Ray ray = make_ray(vec3(0.5f, 0.5f, 1), vec3(0, 0, -1));
    EXPECT_FALSE(scene.intersect(ray).valid());
    EXPECT_FALSE(scene.occluded(ray));
    std::vector<Hit> hits;
    scene.intersect({ray, ray}, hits);
    EXPECT_FALSE(hits[1].valid());
    expect_contains(rejection<InvalidArgument>([&] { scene.bounds(); }),
                    "the scene has no triangles");
    // Invalid rays are still rejected in an empty scene.
    EXPECT_THROW(scene.intersect(make_ray(vec3(kNaN), vec3(0, 0, 1))), InvalidArgument);
}

TEST(SceneBounds, AreTheWorldBoundsOfTheInstances) {
    const Scene scene = quad_scene(glm::translate(mat4(1.0f), vec3(1, 2, 3)) *
                                   glm::scale(mat4(1.0f), vec3(2.0f)));
    const Bounds3 bounds = scene.bounds();
    expect_near(bounds.lower, vec3(1, 2, 3));
    expect_near(bounds.upper, vec3(3, 4, 3));
}

TEST(SceneEmissive, GathersWorldSpaceEmissiveTriangles) {
    Scene scene;
    Material lamp;
    lamp.name = "Lamp";
    lamp.emission_color = vec3(1.0f, 0.5f, 0.25f);
    lamp.emission_strength = 4.0f;
    scene.add_material(Material{});
    const uint32_t lamp_id = scene.add_material(lamp);
    Mesh half_lit = unit_quad();
    half_lit.material_indices = {lamp_id, 0};
    scene.add_instance(scene.add_mesh(half_lit),
                       glm::translate(mat4(1.0f), vec3(0, 0, 3)) *
                           glm::scale(mat4(1.0f), vec3(2.0f)));
    scene.add_instance(scene.add_mesh(unit_cube()), mat4(1.0f));  // not emissive
    scene.commit();
    ASSERT_EQ(scene.emissive_triangles().size(), 1u);
    const EmissiveTriangle& emissive = scene.emissive_triangles()[0];
    EXPECT_EQ(emissive.instance_id, 0u);
    EXPECT_EQ(emissive.triangle_id, 0u);
    expect_near(emissive.p0, vec3(0, 0, 3));
    expect_near(emissive.p1, vec3(2, 0, 3));
    expect_near(emissive.p2, vec3(2, 2, 3));
    EXPECT_NEAR(emissive.area, 2.0f, kTolerance);
    expect_near(emissive.radiance, vec3(4.0f, 2.0f, 1.0f));
    EXPECT_EQ(scene.stats().emissive_triangles, 1u);
}

// Float light sampling overflows past ~3e38 W: commit() refuses a scene emitting more than
// kMaxEmittedPower and names its brightest emitter and the field to lower.
TEST(SceneEmissive, PowerBeyondTheLimitIsRefusedNamingTheBrightestEmitter) {
    auto commit_with = [](auto&& edit) {
        Scene scene;
        scene.add_instance(scene.add_mesh(unit_quad()), mat4(1.0f));  // cross-section pi / 2 m^2
        edit(scene);
        return rejection<InvalidArgument>([&] { scene.commit(); });
    };
    auto light = [](const char* name, LightType type, float power, float strength) -> Light {
        Light made;
        made.name = name;
        made.type = type;
        made.power = power;
        made.strength = strength;
        return made;
    };
    expect_contains(commit_with([&](Scene& scene) {
                        scene.add_light(light("Bulb", LightType::Point, 2e36f, 1.0f));
                    }),
                    "the scene emits 2e+36 W, beyond the 1e+36 W");
    expect_contains(commit_with([&](Scene& scene) {
                        scene.add_light(light("Dim", LightType::Point, 4e35f, 1.0f));
                        scene.add_light(light("Bulb", LightType::Spot, 7e35f, 1.0f));
                    }),
                    "the brightest emitter, with 7e+35 W, is light 'Bulb' (power 7e+35 W): "
                    "lower its power");
    // A sun covers the scene's cross-section: 1e36 W/m^2 over pi / 2 m^2.
    expect_contains(commit_with([&](Scene& scene) {
                        scene.add_light(light("Sun", LightType::Sun, 1.0f, 1e36f));
                    }),
                    "light 'Sun' (strength 1e+36 W/m^2 over the scene's cross-section of "
                    "1.5708 m^2): lower its strength");
    expect_contains(commit_with([&](Scene& scene) {
                        World world;
                        world.color = vec3(1.0f);
                        world.strength = 1e35f;  // x 4 pi x pi / 2 m^2
                        scene.set_world(world);
                    }),
                    "is the world (1e+35 W m^-2 sr^-1 around the scene's cross-section");
    expect_contains(commit_with([&](Scene& scene) {
                        Material lamp;
                        lamp.emission_color = vec3(1.0f);
                        lamp.emission_strength = 1e36f;  // x 2 pi x 0.5 m^2
                        scene.add_material(Material{});  // the first quad's
                        Mesh panel = unit_quad();
                        panel.material_indices = {scene.add_material(lamp), 0};
                        scene.add_instance(scene.add_mesh(panel), mat4(1.0f), "Panel");
                    }),
                    "is triangle 0 of instance 1 'Panel' (emission 1e+36 W m^-2 sr^-1 over 0.5 "
                    "m^2): lower its material's emission strength");

    // Within the limit: a real sun, and a sun and lamp as large as scene coordinates go, whose
    // float area (a cross product of 8e23 m^2, squared) would overflow.
    Scene sunny;
    sunny.add_instance(sunny.add_mesh(unit_quad()), mat4(1.0f));
    sunny.add_light(light("Sun", LightType::Sun, 1.0f, 1000.0f));
    EXPECT_NO_THROW(sunny.commit());
    Scene huge;
    Material lamp;
    lamp.emission_color = vec3(1.0f);
    lamp.emission_strength = 1.0f;
    huge.add_material(lamp);
    huge.add_instance(huge.add_mesh(unit_quad()), glm::scale(mat4(1.0f), vec3(9e11f)));
    huge.add_light(light("Sun", LightType::Sun, 1.0f, 1000.0f));
    ASSERT_NO_THROW(huge.commit());
    ASSERT_EQ(huge.emissive_triangles().size(), 2u);
    EXPECT_NEAR(huge.emissive_triangles()[0].area / 4.05e23f, 1.0f, 1e-5f);
}

TEST(SceneProgress, CancelledBatchThrowsCancelled) {
    const Scene scene = quad_scene();
    std::vector<Ray> rays(50000, make_ray(vec3(0.5f, 0.5f, 1), vec3(0, 0, -1)));
    std::vector<Hit> hits;
    Progress progress;
    progress.cancel();
    EXPECT_THROW(scene.intersect(rays, hits, &progress), Cancelled);
    Progress commit_progress;
    commit_progress.cancel();
    Scene other;
    other.add_instance(other.add_mesh(grid(8)), mat4(1.0f));
    EXPECT_THROW(other.commit({}, &commit_progress), Cancelled);
    EXPECT_FALSE(other.committed());
}

TEST(SceneProgress, BatchReportsCompletion) {
    const Scene scene = quad_scene();
    std::vector<Ray> rays(20000, make_ray(vec3(0.5f, 0.5f, 1), vec3(0, 0, -1)));
    std::vector<uint8_t> occluded;
    Progress progress;
    scene.occluded(rays, occluded, &progress);
    EXPECT_FLOAT_EQ(progress.fraction(), 1.0f);
    for (uint8_t o : occluded) ASSERT_EQ(o, 1);
}

}  // namespace
}  // namespace shgi
