// The scene layer against raw Embree, and what edits cost before the next frame.
//
// Rooms: bench_scenes.h's Cornell-like room (a single-use room box, one block mesh used twice)
// and the same room holding a 502k-triangle UV sphere (used once). For each, Scene committed
// with single-use and small shared meshes flattened (the default) and with every mesh
// instanced (the layout before flattening), and raw Embree on a flattened one-level scene of the same triangles
// (scene/embree_reference.h), on the same rays in the same run, all threads:
//  - incoherent closest-hit and occlusion rays (random origins in the room, random directions);
//  - coherent rays: one 640 x 360 frame's camera rays in 16 x 16 tiles as 16-wide packets and one
//    shadow ray per first hit to the area light, best of kFrames frames;
// as rates and as Scene's time over raw Embree's (1.00 = no cost over Embree).
// Then, on the flattened scene, the wall time of the commit after an edit (what a viewport
// waits for before its next frame can start), best of kEditRuns: a light's power, a material's
// colour; the first move of an object (the scene then instances every mesh: the per-mesh BVHs
// are built once) and later moves of the shared block, the room box and the sphere (the top
// level only).
// A plain main printing figures: benchmarks are not tests.
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

#include "bench_scenes.h"

using namespace shgi;

namespace {

constexpr int kFrames = 20;
constexpr int kEditRuns = 5;

void print_rates(const char* what, const bench::RayRates& rates, const char* unit) {
    std::printf("    %-44s Scene %9.3g %s, raw Embree %9.3g %s: Scene/raw time %.2f\n", what,
                rates.scene, unit, rates.embree, unit, rates.embree / rates.scene);
}

void queries(const char* layout, Scene& scene, bool flatten) {
    CommitSettings settings;
    settings.flatten_single_use_meshes = flatten;
    scene.commit(settings);
    const EmbreeReference embree(scene);
    std::printf("  %s (%llu of %llu instances flattened):\n", layout,
                (unsigned long long)scene.stats().flattened_instances,
                (unsigned long long)scene.stats().instances);
    print_rates("incoherent closest-hit (rtcIntersect1)",
                bench::incoherent_ray_rates(scene, embree, false), "rays/s");
    print_rates("incoherent occlusion (rtcOccluded1)",
                bench::incoherent_ray_rates(scene, embree, true), "rays/s");
    const bench::FrameRays frame = bench::frame_rays(scene);
    const bench::RayRates frames = bench::coherent_frame_rates(scene, embree, frame, kFrames);
    print_rates("coherent camera + shadow (rtc*16)",
                {frames.scene * frame.count, frames.embree * frame.count}, "rays/s");
    std::printf("    %-44s Scene %.2f ms, raw Embree %.2f ms\n", "  one frame's rays:",
                1e3 / frames.scene, 1e3 / frames.embree);
}

// Best-of-kEditRuns wall time of edit() followed by commit().
template <typename Edit>
double edit_seconds(Scene& scene, Edit&& edit) {
    double best = 1e30;
    for (int run = 0; run < kEditRuns; ++run) {
        edit(run);
        const auto start = now();
        scene.commit();
        best = std::min(best, seconds_since(start));
    }
    return best;
}

void edits(Scene& scene) {
    scene.commit();
    const uint64_t builds = scene.stats().bvh_builds;
    const double light_seconds = edit_seconds(scene, [&](int run) {
        Light light = scene.lights()[0];
        light.power = bench::kLightPower * float(run + 2);
        scene.set_light(0, light);
    });
    const double material_seconds = edit_seconds(scene, [&](int run) {
        Material material = scene.materials()[0];
        material.base_color = vec3(0.5f + 0.05f * float(run));
        scene.set_material(0, material);
    });
    std::printf("  commit after a light power edit %.2f ms, a material colour edit %.2f ms "
                "(BVH builds: %llu)\n",
                light_seconds * 1e3, material_seconds * 1e3,
                (unsigned long long)(scene.stats().bvh_builds - builds));
    // The first move switches the scene to instancing every mesh (scene.h): one build of the
    // per-mesh BVHs; later moves rebuild only the top level.
    const mat4 room = scene.instances()[0].world_from_object;
    scene.set_instance_transform(0, glm::translate(mat4(1.0f), vec3(0.001f)) * room);
    const auto first = now();
    scene.commit();
    const double first_move = seconds_since(first);
    const auto move = [&](uint32_t instance) {
        const mat4 start = scene.instances()[instance].world_from_object;
        return edit_seconds(scene, [&, start](int run) {
            scene.set_instance_transform(
                instance, glm::translate(mat4(1.0f), vec3(0.001f * float(run + 1))) * start);
        });
    };
    std::printf("  commit after the first move (the room box) %.2f ms; then moving the shared "
                "block %.2f ms, the room box %.2f ms",
                first_move * 1e3, move(1) * 1e3, move(0) * 1e3);
    if (scene.instances().size() > 3) std::printf(", the sphere %.2f ms", move(3) * 1e3);
    std::printf(" (%llu of %llu instances flattened)\n",
                (unsigned long long)scene.stats().flattened_instances,
                (unsigned long long)scene.stats().instances);
}

void run(const char* name, Scene scene) {
    std::printf("%s: %llu triangles\n", name,
                (unsigned long long)scene.stats().instanced_triangles);
    queries("single-use and small shared meshes flattened", scene, true);
    queries("every mesh instanced", scene, false);
    edits(scene);
}

}  // namespace

int main() {
    run("cornell box", bench::cornell_box(640, 360));
    run("cornell box + dense sphere", bench::cornell_box_with_dense_sphere(640, 360));
    return 0;
}
