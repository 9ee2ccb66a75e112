// The smallest complete use of the SHGI core: build a scene, commit it, trace rays.
//
// A unit quad in the XY plane is instanced twice (at z = 0 and, rotated to face down, at z = 2);
// a ray shot up from below hits the first, a ray shot down from above hits the second, and a
// ray with a NaN direction is rejected with an error instead of reaching Embree.
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

#include "scene/scene.h"
#include "util/error.h"

int main() {
    using namespace shgi;
    Scene scene;
    scene.add_material(Material{});

    Mesh quad;
    quad.name = "quad";
    quad.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    quad.triangles = {{0, 1, 2}, {0, 2, 3}};
    const uint32_t mesh_id = scene.add_mesh(quad);

    scene.add_instance(mesh_id, mat4(1.0f), "floor");
    const mat4 ceiling = glm::rotate(glm::translate(mat4(1.0f), vec3(0, 0, 2)), kPi, vec3(1, 0, 0));
    scene.add_instance(mesh_id, ceiling, "ceiling");
    scene.commit();

    const SceneStats stats = scene.stats();
    std::printf("scene: %llu mesh, %llu instances, %llu triangles instanced, BVH %.1f KiB\n",
                static_cast<unsigned long long>(stats.meshes),
                static_cast<unsigned long long>(stats.instances),
                static_cast<unsigned long long>(stats.instanced_triangles),
                static_cast<double>(stats.bvh_bytes) / 1024.0);

    for (const Ray& ray : {Ray{{0.2f, 0.3f, -1.0f}, {0, 0, 1}}, Ray{{0.2f, 0.3f, 3.0f}, {0, 0, -1}}}) {
        const Hit hit = scene.intersect(ray);
        const SurfacePoint point = scene.surface_point(ray, hit);
        std::printf("ray from z=%+.1f hits '%s' at t=%.3f, normal (%.0f, %.0f, %.0f)\n",
                    ray.origin.z, scene.instances()[hit.instance_id].name.c_str(), hit.t,
                    point.shading_normal.x, point.shading_normal.y, point.shading_normal.z);
    }

    try {
        scene.intersect(Ray{{0, 0, -1}, {0, 0, std::nanf("")}});
    } catch (const InvalidArgument& error) {
        std::printf("rejected: %s\n", error.what());
    }
    return 0;
}
