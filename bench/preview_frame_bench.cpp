// The viewport's progressive preview frame against a raw camera + shadow floor
// (docs/frame-pipeline.md): 640 x 360 Combined-only 1-spp frames of PreviewRenderer with a
// photon lattice field and with a probe grid field, on the two rooms of bench_scenes.h.
//
// The floor is what no renderer built on Embree can beat for the same first-hit work: a
// flattened one-level Embree scene (every instance's triangles transformed into world space, one
// RTCScene), the frame's camera rays (the same CameraRayGenerator, one ray through each pixel's
// centre, where the renderer's are jittered) traced as 16-wide packets of a row with
// rtcIntersect16, and one shadow ray per first hit towards a point of the room's area light
// traced with rtcOccluded16, over the same 16 x 16 tiles and threads the renderer uses. No
// shading, no field, no film. Its scene has Embree's default traversal unless asked for the
// robust one that Scene's BVH uses (RTC_SCENE_FLAG_ROBUST: 1.43-1.47x Embree's work on these rays).
//
// Prints, best of kFrames: the frame's wall time, its stages' times, the floor's time and their
// ratio; then the same in CPU time (all threads' together), the figures to compare on a loaded
// machine. A plain main printing figures: benchmarks are not tests. Embree is included here
// directly (the library includes it only in scene/embree_*): the floor must not go through
// Scene's ray streams, whose cost is part of what the ratio measures.
#include <embree3/rtcore.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <vector>

#include "bench_scenes.h"
#include "lattice/photon_lattice.h"
#include "probes/probe_grid.h"
#include "render/preview_renderer.h"
#include "util/parallel.h"
#include "util/rng.h"
#include "util/timer.h"

using namespace shgi;

namespace {

constexpr uint32_t kWidth = 640, kHeight = 360;
constexpr int kFrames = 20;  // frames of each kind, unless a third argument says otherwise
int g_frames = kFrames;
constexpr int kTile = 16;     // the renderer's default tile side
constexpr int kPacket = 16;   // rays per rtcIntersect16 / rtcOccluded16 call

// One RTCScene holding every instance's triangles in world space (no instancing level).
// `robust`: with RTC_SCENE_FLAG_ROBUST, as Scene builds its own BVH (scene/embree_scene.cpp),
// so that the floor's Embree does the same traversal work as the renderer's.
class FlatEmbreeScene {
  public:
    FlatEmbreeScene(const Scene& scene, bool robust) {
        device_ = rtcNewDevice(nullptr);
        scene_ = rtcNewScene(device_);
        for (const Instance& instance : scene.instances()) {
            const Mesh& mesh = scene.meshes()[instance.mesh_id];
            RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
            auto* vertices = static_cast<float*>(
                rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                        3 * sizeof(float), mesh.positions.size()));
            for (size_t v = 0; v < mesh.positions.size(); ++v) {
                const vec3 p = vec3(instance.world_from_object * vec4(mesh.positions[v], 1.0f));
                vertices[3 * v] = p.x;
                vertices[3 * v + 1] = p.y;
                vertices[3 * v + 2] = p.z;
            }
            auto* indices = static_cast<unsigned*>(
                rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                        3 * sizeof(unsigned), mesh.triangles.size()));
            for (size_t t = 0; t < mesh.triangles.size(); ++t)
                for (int k = 0; k < 3; ++k) indices[3 * t + k] = mesh.triangles[t][k];
            rtcCommitGeometry(geometry);
            rtcAttachGeometry(scene_, geometry);
            rtcReleaseGeometry(geometry);
        }
        if (robust) rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
        rtcCommitScene(scene_);
    }
    ~FlatEmbreeScene() {
        rtcReleaseScene(scene_);
        rtcReleaseDevice(device_);
    }
    FlatEmbreeScene(const FlatEmbreeScene&) = delete;
    FlatEmbreeScene& operator=(const FlatEmbreeScene&) = delete;
    RTCScene get() const { return scene_; }

  private:
    RTCDevice device_ = nullptr;
    RTCScene scene_ = nullptr;
};

// One packet of up to 16 pixels of row y from x0: camera rays, then shadow rays from the hits.
void trace_packet(RTCScene scene, const CameraRayGenerator& rays, int x0, int x1, int y,
                  uint64_t seed) {
    alignas(64) int valid[kPacket];
    alignas(64) RTCRayHit16 rayhit;
    for (int k = 0; k < kPacket; ++k) {
        const int x = x0 + k;
        valid[k] = x < x1 ? -1 : 0;
        const Ray ray = rays.generate_ray(vec2(float(std::min(x, x1 - 1)) + 0.5f, float(y) + 0.5f));
        rayhit.ray.org_x[k] = ray.origin.x;
        rayhit.ray.org_y[k] = ray.origin.y;
        rayhit.ray.org_z[k] = ray.origin.z;
        rayhit.ray.dir_x[k] = ray.direction.x;
        rayhit.ray.dir_y[k] = ray.direction.y;
        rayhit.ray.dir_z[k] = ray.direction.z;
        rayhit.ray.tnear[k] = ray.tmin;
        rayhit.ray.tfar[k] = ray.tmax;
        rayhit.ray.time[k] = 0.0f;
        rayhit.ray.mask[k] = 0xFFFFFFFFu;
        rayhit.ray.id[k] = unsigned(k);
        rayhit.ray.flags[k] = 0;
        rayhit.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
    }
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rtcIntersect16(valid, scene, &context, &rayhit);
    alignas(64) RTCRay16 shadow;
    Pcg32 rng(seed, uint64_t(y) * kWidth + uint64_t(x0));
    for (int k = 0; k < kPacket; ++k) {
        const bool hit = valid[k] != 0 && rayhit.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
        valid[k] = hit ? -1 : 0;
        const float t = rayhit.ray.tfar[k];
        const vec3 p = vec3(rayhit.ray.org_x[k], rayhit.ray.org_y[k], rayhit.ray.org_z[k]) +
                       t * vec3(rayhit.ray.dir_x[k], rayhit.ray.dir_y[k], rayhit.ray.dir_z[k]);
        const vec3 to_light = bench::point_on_light(rng) - p;
        shadow.org_x[k] = p.x;
        shadow.org_y[k] = p.y;
        shadow.org_z[k] = p.z;
        shadow.dir_x[k] = to_light.x;
        shadow.dir_y[k] = to_light.y;
        shadow.dir_z[k] = to_light.z;
        shadow.tnear[k] = 1e-4f;
        shadow.tfar[k] = 0.999f;
        shadow.time[k] = 0.0f;
        shadow.mask[k] = 0xFFFFFFFFu;
        shadow.id[k] = unsigned(k);
        shadow.flags[k] = 0;
    }
    rtcOccluded16(valid, scene, &context, &shadow);
}

// Seconds of one floor frame: every 16 x 16 tile on the thread pool, rows as 16-wide packets.
double floor_frame(const FlatEmbreeScene& flat, const CameraRayGenerator& rays, uint64_t seed) {
    const int columns = (int(kWidth) + kTile - 1) / kTile;
    const int rows = (int(kHeight) + kTile - 1) / kTile;
    const TimePoint start = now();
    parallel_for(0, uint64_t(columns) * uint64_t(rows), 4, [&](uint64_t begin, uint64_t end) {
        for (uint64_t t = begin; t < end; ++t) {
            const int x0 = int(t % uint64_t(columns)) * kTile;
            const int y0 = int(t / uint64_t(columns)) * kTile;
            const int x1 = std::min(x0 + kTile, int(kWidth));
            for (int y = y0; y < std::min(y0 + kTile, int(kHeight)); ++y)
                for (int x = x0; x < x1; x += kPacket)
                    trace_packet(flat.get(), rays, x, std::min(x + kPacket, x1), y, seed);
        }
    });
    return seconds_since(start);
}

// CPU seconds of the whole process so far (every thread's): on a machine shared with other
// work a frame's wall time grows with the load, while the CPU time its threads spend changes
// much less, so the CPU figures are the ones to compare between runs on a busy machine.
double process_cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// Best of kFrames preview frames and floor frames, interleaved so both see the same machine.
// Wall time (best frame) and CPU time (the frame that took the least CPU, its stages split in
// the proportions of its own stage timings) for each.
void compare(const char* room, const char* field_name, const Scene& scene,
             const FlatEmbreeScene& flat, const IndirectField& field) {
    PreviewSettings settings;
    settings.combined_only = true;
    PreviewRenderer preview(scene, settings);
    const CameraRayGenerator rays(scene.camera());
    double best_frame = 1e30, best_floor = 1e30, best_frame_cpu = 1e30, best_floor_cpu = 1e30;
    PreviewTimings best_timings, best_cpu_timings;
    for (int frame = 0; frame < g_frames; ++frame) {
        const double cpu_start = process_cpu_seconds();
        preview.render(&field, 1);
        const double frame_cpu = process_cpu_seconds() - cpu_start;
        if (preview.timings().total < best_frame) {
            best_frame = preview.timings().total;
            best_timings = preview.timings();
        }
        if (frame_cpu < best_frame_cpu) {
            best_frame_cpu = frame_cpu;
            best_cpu_timings = preview.timings();
        }
        const double floor_cpu_start = process_cpu_seconds();
        best_floor = std::min(best_floor, floor_frame(flat, rays, uint64_t(frame)));
        best_floor_cpu = std::min(best_floor_cpu, process_cpu_seconds() - floor_cpu_start);
    }
    std::printf("  %-26s %-14s frame %6.1f ms (primary %5.1f, direct %5.1f, indirect %5.1f) | "
                "floor %5.1f ms | ratio %4.1fx\n",
                room, field_name, best_frame * 1e3, best_timings.primary * 1e3,
                best_timings.direct * 1e3, best_timings.indirect * 1e3, best_floor * 1e3,
                best_frame / best_floor);
    const double stages = best_cpu_timings.primary + best_cpu_timings.direct +
                          best_cpu_timings.indirect + best_cpu_timings.frame_stages;
    const double to_cpu = stages > 0.0 ? best_frame_cpu / stages : 0.0;
    std::printf("  %-26s %-14s   cpu %6.1f ms (primary %5.1f, direct %5.1f, indirect %5.1f) | "
                "floor %5.1f ms | ratio %4.1fx\n",
                "", "", best_frame_cpu * 1e3, best_cpu_timings.primary * to_cpu * 1e3,
                best_cpu_timings.direct * to_cpu * 1e3, best_cpu_timings.indirect * to_cpu * 1e3,
                best_floor_cpu * 1e3, best_frame_cpu / best_floor_cpu);
    std::fflush(stdout);
}

// Which fields to run: both, or only the one named on the command line ("lattice", "probe").
const char* g_field_filter = nullptr;
// The floor's scene built robust, as Scene's (fourth argument "robust").
bool g_robust_floor = false;

bool wanted(const char* filter, const char* name) {
    return filter == nullptr || std::strcmp(filter, "all") == 0 ||
           std::strstr(name, filter) != nullptr;
}

void run(const char* room, Scene& scene) {
    scene.commit();
    const FlatEmbreeScene flat(scene, g_robust_floor);
    if (wanted(g_field_filter, "lattice")) {
        PhotonLattice lattice(scene, PhotonLatticeSettings{});
        lattice.solve();
        compare(room, "photon lattice", scene, flat, lattice);
    }
    if (wanted(g_field_filter, "probe")) {
        ProbeGrid grid(scene, ProbeGridSettings{});
        grid.update();
        compare(room, "probe grid", scene, flat, grid);
    }
}

}  // namespace

// Arguments (optional, for profiling one case): a room ("cornell" or "dense"), a field
// ("lattice" or "probe"; "all" for every room or field), a frame count (20 by default; 2 keeps
// a callgrind run short) and "robust" for a floor scene built with RTC_SCENE_FLAG_ROBUST as
// Scene's BVH is (without it the floor is Embree's default, faster traversal), e.g.
// `preview_frame_bench cornell lattice 2` or `preview_frame_bench all all 20 robust`.
int main(int argc, char** argv) {
    const char* room_filter = argc > 1 && std::strcmp(argv[1], "all") != 0 ? argv[1] : nullptr;
    g_field_filter = argc > 2 ? argv[2] : nullptr;
    if (argc > 3) g_frames = std::max(1, std::atoi(argv[3]));
    g_robust_floor = argc > 4 && std::strcmp(argv[4], "robust") == 0;
    std::printf("preview %ux%u, progressive 1-spp Combined-only frames, best of %d; floor: "
                "flattened Embree scene%s, rtcIntersect16 + rtcOccluded16\n",
                kWidth, kHeight, g_frames, g_robust_floor ? " (robust, as Scene's)" : "");
    if (room_filter == nullptr || std::strcmp(room_filter, "cornell") == 0) {
        Scene cornell = bench::cornell_box(kWidth, kHeight);
        run("cornell box", cornell);
    }
    if (room_filter == nullptr || std::strcmp(room_filter, "dense") == 0) {
        Scene dense = bench::cornell_box_with_dense_sphere(kWidth, kHeight);
        run("cornell box + dense sphere", dense);
    }
    return 0;
}
