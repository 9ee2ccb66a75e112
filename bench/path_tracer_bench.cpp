// Path tracer throughput against the raw Embree ray rate, measured in the same run.
//
// Scene: a Cornell-box-like room (2 m closed box, red and green side walls, two inner blocks,
// a 0.5 m square area light under the ceiling), 128 x 128 pixels, perspective camera inside.
// Printed figures:
//  - path samples per second of PathTracer::render (all threads, default settings: 12 bounces
//    with Cycles' per-type limits, NEE + MIS, Russian roulette);
//  - incoherent rays per second: random origins inside the box and uniformly random directions,
//    traced through Scene::intersect's batch interface (Embree ray streams, all threads);
//  - their ratio: the cost of one path sample in raw closest-hit rays (it folds in shadow
//    rays, shading and BSDF/light sampling, so it is not a count of rays traced).
// A plain main printing figures (DESIGN.md: benchmarks are not tests).
#include <chrono>
#include <cstdio>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "render/path_tracer.h"
#include "util/rng.h"
#include "util/sampling.h"

namespace {

using namespace shgi;

constexpr uint32_t kResolution = 128;
constexpr uint32_t kSamples = 16;
constexpr size_t kRayCount = size_t(1) << 21;  // ~2M rays: long enough to time reliably
constexpr float kHalf = 1.0f;                   // box half size (m)

Mesh box(float half, bool inward) {
    Mesh mesh;
    for (int i = 0; i < 8; ++i)
        mesh.positions.push_back(vec3(i & 1 ? half : -half, i & 2 ? half : -half,
                                      i & 4 ? half : -half));
    const uvec3 faces[12] = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                             {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
    for (uvec3 f : faces) mesh.triangles.push_back(inward ? f : uvec3(f.x, f.z, f.y));
    // Faces 8-9 are x = -half (red), 10-11 x = +half (green), the rest white.
    mesh.material_indices.assign(12, 0);
    mesh.material_indices[8] = mesh.material_indices[9] = 1;
    mesh.material_indices[10] = mesh.material_indices[11] = 2;
    return mesh;
}

Scene cornell_box() {
    Scene scene;
    const vec3 colors[3] = {vec3(0.73f), vec3(0.65f, 0.05f, 0.05f), vec3(0.12f, 0.45f, 0.15f)};
    for (const vec3& c : colors) {
        Material material;
        material.base_color = c;
        material.roughness = 0.8f;
        scene.add_material(material);
    }
    scene.add_instance(scene.add_mesh(box(kHalf, true)), mat4(1.0f));
    const uint32_t block = scene.add_mesh(box(0.3f, false));
    scene.add_instance(block, glm::translate(mat4(1.0f), vec3(-0.35f, 0.3f, -0.7f)));
    scene.add_instance(block, glm::scale(glm::translate(mat4(1.0f), vec3(0.4f, -0.3f, -0.4f)),
                                         vec3(1.0f, 1.0f, 2.0f)));
    Light light;
    light.type = LightType::Area;
    light.size_x = 0.5f;
    light.power = 100.0f;
    light.world_from_light = glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, kHalf - 0.01f));
    scene.add_light(light);
    World world;
    world.strength = 0.0f;
    scene.set_world(world);
    Camera camera;  // inside the box, looking along +Y at the back wall
    camera.world_from_camera =
        glm::inverse(glm::lookAt(vec3(0.0f, -0.95f, 0.0f), vec3(0.0f, 1.0f, 0.0f), vec3(0, 0, 1)));
    camera.lens = 18.0f;
    camera.resolution_x = camera.resolution_y = kResolution;
    camera.clip_start = 0.01f;
    scene.set_camera(camera);
    scene.commit();
    return scene;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main() {
    const Scene scene = cornell_box();

    PathTracerSettings settings;
    settings.samples = kSamples;
    PathTracer tracer(scene, settings);
    tracer.render(1);  // warm-up
    auto start = std::chrono::steady_clock::now();
    tracer.render(kSamples);
    const double path_seconds = seconds_since(start);
    const double paths = double(kResolution) * kResolution * kSamples;
    const double paths_per_second = paths / path_seconds;

    std::vector<Ray> rays(kRayCount);
    Pcg32 rng(1, 0);
    for (Ray& ray : rays) {
        ray.origin = (2.0f * vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 1.0f) *
                     (0.99f * kHalf);
        ray.direction = sample_uniform_sphere(rng.next_vec2());
    }
    std::vector<Hit> hits;
    scene.intersect(rays, hits);  // warm-up
    start = std::chrono::steady_clock::now();
    scene.intersect(rays, hits);
    const double ray_seconds = seconds_since(start);
    const double rays_per_second = double(kRayCount) / ray_seconds;

    std::printf("path tracer: %u x %u px, %u spp in %.3f s: %.3g path samples/s\n", kResolution,
                kResolution, kSamples, path_seconds, paths_per_second);
    std::printf("embree incoherent closest-hit (Scene::intersect batch, all threads): "
                "%zu rays in %.3f s: %.3g rays/s\n",
                kRayCount, ray_seconds, rays_per_second);
    std::printf("ratio: one path sample costs %.2f raw rays\n", rays_per_second / paths_per_second);
    return 0;
}
