// Scenes and timing helpers shared by the benchmarks.
#pragma once

#include <algorithm>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "scene/camera.h"
#include "scene/embree_reference.h"
#include "scene/scene.h"
#include "util/parallel.h"
#include "util/rng.h"
#include "util/sampling.h"
#include "util/timer.h"

namespace shgi::bench {

inline constexpr float kHalf = 1.0f;  // box half size (m)
// The rooms' area light: a square of this side (m) and power (W), facing down just under the
// ceiling.
inline constexpr float kLightSide = 0.5f;
inline constexpr float kLightPower = 100.0f;
inline constexpr float kLightHeight = kHalf - 0.01f;

// A uniformly random point of the area light.
inline vec3 point_on_light(Pcg32& rng) {
    const float x = kLightSide * (rng.next_float() - 0.5f);
    const float y = kLightSide * (rng.next_float() - 0.5f);
    return vec3(x, y, kLightHeight);
}

inline Mesh box(float half, bool inward) {
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

// A Cornell-like room (2 m closed box, red and green side walls, two inner blocks, a 0.5 m square
// area light under the ceiling), the camera inside looking at the back wall; not committed.
inline Scene cornell_box(uint32_t width = 128, uint32_t height = 128) {
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
    light.size_x = kLightSide;
    light.power = kLightPower;
    light.world_from_light = glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, kLightHeight));
    scene.add_light(light);
    World world;
    world.strength = 0.0f;
    scene.set_world(world);
    Camera camera;  // inside the box, looking along +Y at the back wall
    camera.world_from_camera =
        glm::inverse(glm::lookAt(vec3(0.0f, -0.95f, 0.0f), vec3(0.0f, 1.0f, 0.0f), vec3(0, 0, 1)));
    camera.lens = 18.0f;
    camera.resolution_x = width;
    camera.resolution_y = height;
    camera.clip_start = 0.01f;
    scene.set_camera(camera);
    return scene;
}

inline Mesh uv_sphere(float radius, int rings, int segments) {
    Mesh mesh;
    for (int r = 0; r <= rings; ++r) {
        const float theta = kPi * float(r) / float(rings);
        for (int s = 0; s < segments; ++s) {
            const float phi = kTwoPi * float(s) / float(segments);
            mesh.positions.push_back(radius * vec3(std::sin(theta) * std::cos(phi),
                                                   std::sin(theta) * std::sin(phi),
                                                   std::cos(theta)));
        }
    }
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            const uint32_t a = uint32_t(r * segments + s);
            const uint32_t b = uint32_t(r * segments + (s + 1) % segments);
            const uint32_t c = a + uint32_t(segments), d = b + uint32_t(segments);
            if (r > 0) mesh.triangles.push_back(uvec3(a, c, b));
            if (r + 1 < rings) mesh.triangles.push_back(uvec3(b, c, d));
        }
    return mesh;
}

// The Cornell-like room holding an orange UV sphere of 502,636 triangles (r = 0.3 m).
inline Scene cornell_box_with_dense_sphere(uint32_t width, uint32_t height) {
    Scene scene = cornell_box(width, height);
    Material material;
    material.base_color = vec3(0.8f, 0.6f, 0.3f);
    const uint32_t material_id = scene.add_material(material);
    Mesh sphere = uv_sphere(0.3f, 360, 700);
    sphere.material_indices.assign(sphere.triangles.size(), material_id);
    scene.add_instance(scene.add_mesh(sphere), glm::translate(mat4(1.0f), vec3(0.3f, 0.4f, 0.2f)));
    return scene;
}

// Scene's ray queries against raw Embree (scene/embree_reference.h: every instance flattened into
// one one-level BVH, no validation) on the same rays, the same threads and the same chunks, in
// the same run. Rays per second (or seconds per frame), the best of kRawRuns timed passes that
// alternate between the two, so both see the same machine (the solvers' figures are
// best-of-three too, so their ratios to these do not swing with one noisy pass).
inline constexpr int kRawRuns = 3;

struct RayRates {
    double scene = 0.0;   // through Scene's batch queries
    double embree = 0.0;  // raw Embree
};

// Random origins inside the box, uniformly random directions: incoherent rays.
inline std::vector<Ray> incoherent_rays(size_t count) {
    std::vector<Ray> rays(count);
    Pcg32 rng(1, 0);
    for (Ray& ray : rays) {
        ray.origin = (2.0f * vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 1.0f) *
                     (0.99f * kHalf);
        ray.direction = sample_uniform_sphere(rng.next_vec2());
    }
    return rays;
}

// Best-of-`runs` rates of scene_pass() and embree_pass(), each tracing `count` rays.
template <typename ScenePass, typename EmbreePass>
RayRates best_rates(double count, int runs, ScenePass&& scene_pass, EmbreePass&& embree_pass) {
    scene_pass();  // warm-up
    embree_pass();
    RayRates best;
    for (int run = 0; run < runs; ++run) {
        auto start = now();
        scene_pass();
        best.scene = std::max(best.scene, count / seconds_since(start));
        start = now();
        embree_pass();
        best.embree = std::max(best.embree, count / seconds_since(start));
    }
    return best;
}

// Incoherent closest-hit rays (occluded = false) or shadow queries (true), all threads, in
// Scene's chunks of Scene::kRaysPerChunk.
inline RayRates incoherent_ray_rates(const Scene& scene, const EmbreeReference& embree,
                                     bool occluded = false, size_t count = size_t(1) << 21) {
    const std::vector<Ray> rays = incoherent_rays(count);
    std::vector<Hit> hits(count);
    std::vector<uint8_t> blocked(count);
    const auto embree_pass = [&] {
        parallel_for(0, count, Scene::kRaysPerChunk, [&](uint64_t begin, uint64_t end) {
            if (occluded)
                embree.occluded(&rays[begin], &blocked[begin], end - begin,
                                RayCoherence::Incoherent);
            else
                embree.intersect(&rays[begin], &hits[begin], end - begin,
                                 RayCoherence::Incoherent);
        });
    };
    const auto scene_pass = [&] {
        if (occluded)
            scene.occluded(rays, blocked);
        else
            scene.intersect(rays, hits);
    };
    return best_rates(double(count), kRawRuns, scene_pass, embree_pass);
}

// The raw Embree incoherent closest-hit rate the figures are measured against.
inline double incoherent_ray_rate(const Scene& scene, size_t count = size_t(1) << 21) {
    const EmbreeReference embree(scene);
    return incoherent_ray_rates(scene, embree, false, count).embree;
}

// A frame's coherent rays, per 16 x 16 tile: one camera ray per pixel (16-wide packets, as the
// renderer casts them) and one shadow ray from each first hit to a random point of the bench
// rooms' area light.
struct FrameRays {
    std::vector<std::vector<Ray>> camera, shadow;  // per tile
    double count = 0.0;
};

inline FrameRays frame_rays(const Scene& scene) {
    const Camera& camera = scene.camera();
    const CameraRayGenerator generator(camera);
    const int width = int(camera.resolution_x), height = int(camera.resolution_y);
    constexpr int kTile = 16;
    const int columns = (width + kTile - 1) / kTile, rows = (height + kTile - 1) / kTile;
    FrameRays frame;
    frame.camera.resize(size_t(columns) * size_t(rows));
    frame.shadow.resize(frame.camera.size());
    std::vector<Hit> hits;
    for (size_t t = 0; t < frame.camera.size(); ++t) {
        const int x0 = int(t % size_t(columns)) * kTile, y0 = int(t / size_t(columns)) * kTile;
        Pcg32 rng(0, t);
        std::vector<Ray>& rays = frame.camera[t];
        for (int y = y0; y < std::min(y0 + kTile, height); ++y)
            for (int x = x0; x < std::min(x0 + kTile, width); ++x)
                rays.push_back(generator.generate_ray(vec2(float(x), float(y)) + rng.next_vec2()));
        scene.intersect(rays, hits, nullptr, RayCoherence::Coherent);
        for (size_t i = 0; i < rays.size(); ++i) {
            if (!hits[i].valid()) continue;
            const vec3 p = rays[i].origin + hits[i].t * rays[i].direction;
            const vec3 to_light = point_on_light(rng) - p;
            const float distance = glm::length(to_light);
            if (!(distance > 1e-3f)) continue;
            Ray shadow;
            shadow.direction = to_light / distance;
            shadow.origin = p + 1e-4f * shadow.direction;
            shadow.tmax = 0.999f * distance;
            frame.shadow[t].push_back(shadow);
        }
        frame.count += double(rays.size() + frame.shadow[t].size());
    }
    return frame;
}

// Frames per second for `frame`'s rays, a few tiles per task on all threads, best of `runs`.
inline RayRates coherent_frame_rates(const Scene& scene, const EmbreeReference& embree,
                                     const FrameRays& frame, int runs) {
    const auto pass = [&](auto&& trace) {
        parallel_for(0, frame.camera.size(), 4, [&](uint64_t begin, uint64_t end) {
            std::vector<Hit> hits;
            std::vector<uint8_t> occluded;
            for (uint64_t t = begin; t < end; ++t) trace(frame.camera[t], frame.shadow[t], hits,
                                                         occluded);
        });
    };
    const auto scene_pass = [&] {
        pass([&](const std::vector<Ray>& camera, const std::vector<Ray>& shadow,
                 std::vector<Hit>& hits, std::vector<uint8_t>& occluded) {
            scene.intersect(camera, hits, nullptr, RayCoherence::Coherent);
            scene.occluded(shadow, occluded, nullptr, RayCoherence::Coherent);
        });
    };
    const auto embree_pass = [&] {
        pass([&](const std::vector<Ray>& camera, const std::vector<Ray>& shadow,
                 std::vector<Hit>& hits, std::vector<uint8_t>& occluded) {
            hits.resize(camera.size());
            occluded.resize(shadow.size());
            embree.intersect(camera.data(), hits.data(), camera.size(), RayCoherence::Coherent);
            embree.occluded(shadow.data(), occluded.data(), shadow.size(),
                            RayCoherence::Coherent);
        });
    };
    return best_rates(1.0, runs, scene_pass, embree_pass);
}

}  // namespace shgi::bench
