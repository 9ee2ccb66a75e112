// Small scenes with closed-form answers for the render tests: a closed box seen from inside
// (furnace), a UV sphere, a large plane under an orthographic camera looking straight down; and
// the pieces they are built from (rectangles, triangles, Lambert and mirror materials, point
// lights), shared with the photon and lattice tests.
#pragma once

#include <cmath>
#include <optional>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "render/path_tracer.h"
#include "scene/scene.h"

namespace shgi::test {

// Axis-aligned cube [-half, half]^3 with its triangles facing inwards.
inline Mesh inward_box(float half) {
    Mesh mesh;
    mesh.name = "box";
    for (int i = 0; i < 8; ++i)
        mesh.positions.push_back(vec3(i & 1 ? half : -half, i & 2 ? half : -half,
                                      i & 4 ? half : -half));
    // Each face as two triangles wound counter-clockwise seen from inside.
    const uvec3 faces[12] = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                             {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
    mesh.triangles.assign(faces, faces + 12);
    return mesh;
}

// UV sphere of the given radius, outward facing, with smooth normals.
inline Mesh uv_sphere(float radius, int rings = 24, int segments = 48) {
    Mesh mesh;
    mesh.name = "sphere";
    for (int r = 0; r <= rings; ++r) {
        const float theta = kPi * float(r) / float(rings);
        for (int s = 0; s <= segments; ++s) {
            const float phi = kTwoPi * float(s) / float(segments);
            const vec3 n = spherical_direction(std::sin(theta), std::cos(theta), phi);
            mesh.positions.push_back(radius * n);
            mesh.normals.push_back(n);
        }
    }
    const uint32_t row = uint32_t(segments) + 1;
    for (uint32_t r = 0; r < uint32_t(rings); ++r)
        for (uint32_t s = 0; s < uint32_t(segments); ++s) {
            const uint32_t a = r * row + s, b = a + row;
            mesh.triangles.push_back({a, b, b + 1});
            mesh.triangles.push_back({a, b + 1, a + 1});
        }
    return mesh;
}

// The rectangle corner + [0,1] edge_u + [0,1] edge_v as two triangles, facing edge_u x edge_v.
inline Mesh quad(const vec3& corner, const vec3& edge_u, const vec3& edge_v) {
    Mesh mesh;
    mesh.name = "quad";
    mesh.positions = {corner, corner + edge_u, corner + edge_u + edge_v, corner + edge_v};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    return mesh;
}

inline Mesh triangle(const vec3& p0, const vec3& p1, const vec3& p2) {
    Mesh mesh;
    mesh.name = "triangle";
    mesh.positions = {p0, p1, p2};
    mesh.triangles = {{0, 1, 2}};
    return mesh;
}

// Square in the z = 0 plane, facing +Z.
// Two 1 x 2 m quads facing +Z, one at x in [-1, 0] and one 50 m away, whose LightmapUV halves
// meet at u = 0.5: two UV charts side by side in UV space, far apart in the world (what a
// filter must not mix: their texels are neighbours only in the lightmap).
inline Mesh two_charts() {
    Mesh two = quad(vec3(-1, -1, 0), vec3(1, 0, 0), vec3(0, 2, 0));
    const Mesh far = quad(vec3(50, -1, 0), vec3(1, 0, 0), vec3(0, 2, 0));
    for (const vec3& p : far.positions) two.positions.push_back(p);
    two.triangles.push_back({4, 5, 6});
    two.triangles.push_back({4, 6, 7});
    two.uv_sets = {{"LightmapUV",
                    {{0, 0}, {0.5f, 0}, {0.5f, 1}, {0, 1}, {0.5f, 0}, {1, 0}, {1, 1}, {0.5f, 1}}}};
    return two;
}

inline Mesh plane(float half) {
    Mesh mesh;
    mesh.name = "plane";
    mesh.positions = {{-half, -half, 0}, {half, -half, 0}, {half, half, 0}, {-half, half, 0}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    return mesh;
}

inline Material lambert(float albedo) {
    Material material;
    material.name = "lambert";
    material.base_color = vec3(albedo);
    material.specular = 0.0f;  // no specular lobe: a pure diffuse closure
    material.roughness = 1.0f;
    material.diffuse_model = DiffuseModel::Lambert;
    return material;
}

// A smooth metal mirror: metallic, roughness 0, base colour `reflectance`.
inline Material mirror(float reflectance) {
    Material material;
    material.name = "mirror";
    material.base_color = vec3(reflectance);
    material.metallic = 1.0f;
    material.roughness = 0.0f;
    return material;
}

// Point light of `power` watts at `position`.
inline Light point_light(const vec3& position, float power) {
    Light light;
    light.type = LightType::Point;
    light.power = power;
    light.world_from_light = glm::translate(mat4(1.0f), position);
    return light;
}

// Orthographic camera at `position` looking down -Z, covering `scale` metres.
inline Camera ortho_camera_down(const vec3& position, float scale, uint32_t resolution) {
    Camera camera;
    camera.type = CameraType::Orthographic;
    camera.world_from_camera = glm::translate(mat4(1.0f), position);
    camera.ortho_scale = scale;
    camera.resolution_x = camera.resolution_y = resolution;
    camera.clip_start = 1e-3f;
    return camera;
}

inline World black_world() {
    World world;
    world.strength = 0.0f;
    return world;
}

// A metal mirror of reflectance 0.8 facing up at z = 0 (material 0) under a Lambert ceiling of
// albedo 0.6 at z = 1 (material 1), both 5 m planes; a black world. No light or camera.
inline void add_mirror_under_ceiling(Scene* scene) {
    scene->add_material(mirror(0.8f));
    scene->add_material(lambert(0.6f));
    scene->add_instance(scene->add_mesh(plane(5.0f)), mat4(1.0f));
    Mesh ceiling = plane(5.0f);
    ceiling.material_indices.assign(ceiling.triangles.size(), 1);
    scene->add_instance(scene->add_mesh(ceiling), glm::translate(mat4(1.0f), vec3(0, 0, 1.0f)));
    scene->set_world(black_world());
}

// Closed box [-1, 1]^3 seen from inside, every inner face emitting emission_color x
// emission_strength with Lambert albedo `albedo`, black world, `camera` if given; committed.
inline Scene emissive_furnace(float albedo, const vec3& emission_color, float emission_strength,
                              const std::optional<Camera>& camera = std::nullopt) {
    Scene scene;
    Material material = lambert(albedo);
    material.emission_color = emission_color;
    material.emission_strength = emission_strength;
    scene.add_material(material);
    scene.add_instance(scene.add_mesh(inward_box(1.0f)), mat4(1.0f));
    scene.set_world(black_world());
    if (camera) scene.set_camera(*camera);
    scene.commit();
    return scene;
}

// Plane of Lambert albedo `albedo` at z = 0 seen from above through a narrow orthographic view.
inline Scene plane_scene(float albedo, uint32_t resolution = 4) {
    Scene scene;
    scene.add_material(lambert(albedo));
    scene.add_instance(scene.add_mesh(plane(50.0f)), mat4(1.0f));
    scene.set_world(black_world());
    scene.set_camera(ortho_camera_down(vec3(0.0f, 0.0f, 0.5f), 0.01f, resolution));
    return scene;
}

inline PathTracerSettings settings_with_samples(uint32_t samples) {
    PathTracerSettings settings;
    settings.samples = samples;
    return settings;
}

// Mean and standard error of the mean over pixels of one channel of a pass.
struct PixelStats {
    double mean = 0.0, standard_error = 0.0;
};

inline PixelStats pixel_stats(const Film& film, Pass pass, int channel = 0) {
    const std::vector<float> pixels = film.pixels(pass);
    const size_t channels = pass_suffixes(pass).size();
    const size_t n = pixels.size() / channels;
    double sum = 0.0, sum2 = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double v = pixels[i * channels + size_t(channel)];
        sum += v;
        sum2 += v * v;
    }
    PixelStats stats;
    stats.mean = sum / double(n);
    const double variance = std::max(0.0, sum2 / double(n) - stats.mean * stats.mean);
    stats.standard_error = std::sqrt(variance / double(n - 1));
    return stats;
}

}  // namespace shgi::test
