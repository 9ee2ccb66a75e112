// Scenes and photon sets with closed-form answers for the SH lattice tests: rectangles
// (test::quad, render_test_scenes.h) placed against a lattice's own cell grid, committed scenes
// of a few meshes, the photons a uniform radiance field would leave on a rectangle, and the bias
// the density estimate's grazing floor may leave on such a field.
#pragma once

#include <algorithm>
#include <utility>
#include <vector>

#include "lattice/sh_lattice.h"
#include "photon/photon.h"
#include "render/render_test_scenes.h"
#include "scene/scene.h"
#include "util/rng.h"
#include "util/sampling.h"

namespace shgi::test {

// Relative bias the grazing floor f A_c of the density estimate (sh_lattice.h) may leave on the
// irradiance π L of a uniform radiance L at L2: at most f / 4 for one plane (the first test of
// sh_lattice_injection_test.cpp); by quadrature 0.5% for one plane, 0.6% for two or three
// perpendicular planes of equal area.
constexpr double kFloorBias = kMinProjectedFraction / 4.0;

// Every mesh instanced once (identity transform), committed.
inline Scene committed_scene(std::vector<Mesh> meshes) {
    Scene scene;
    for (Mesh& mesh : meshes) scene.add_instance(scene.add_mesh(std::move(mesh)), mat4(1.0f));
    scene.commit();
    return scene;
}

// Lower corner of cell index `i` along `axis`, in metres.
inline double cell_lower(const ShLattice& lattice, int axis, int i) {
    return double(lattice.origin()[axis]) + double(i) * double(lattice.cell_size());
}

// Length of [a0, a1] ∩ [b0, b1].
inline double overlap(double a0, double a1, double b0, double b1) {
    return std::max(0.0, std::min(a1, b1) - std::max(a0, b0));
}

// A horizontal plane through the centre of every z layer of the lattice, reaching beyond it in
// x and y: every cell holds exactly one cell_size² of surface facing +Z.
inline Scene layered_planes(const ShLattice& lattice) {
    std::vector<Mesh> planes;
    const float s = lattice.cell_size();
    const vec3 o = lattice.origin();
    const vec3 size = vec3(lattice.dims()) * s + 2.0f;
    for (int k = 0; k < lattice.dims().z; ++k)
        planes.push_back(quad(vec3(o.x - 1.0f, o.y - 1.0f, o.z + (float(k) + 0.5f) * s),
                              vec3(size.x, 0, 0), vec3(0, size.y, 0)));
    return committed_scene(std::move(planes));
}

// The photons a uniform radiance `radiance` arriving from the whole hemisphere around the unit
// `normal` leaves on the rectangle corner + [0,1] edge_u + [0,1] edge_v: irradiance π L over area
// A, i.e. flux π L A, split over `count` photons with cosine-distributed directions (the
// distribution of the flux a Lambertian receiver collects), positions uniform on the rectangle.
inline std::vector<Photon> uniform_field_photons(const vec3& corner, const vec3& edge_u,
                                                 const vec3& edge_v, const vec3& normal,
                                                 const vec3& radiance, int count, uint64_t seed) {
    const float area = glm::length(glm::cross(edge_u, edge_v));
    const Frame frame = Frame::from_z(normal);
    Pcg32 rng(seed, 1);
    std::vector<Photon> photons(static_cast<size_t>(count));
    for (Photon& photon : photons) {
        const vec2 u = rng.next_vec2();
        photon.position = corner + u.x * edge_u + u.y * edge_v;
        photon.power = kPi * radiance * area / float(count);
        photon.normal = normal;
        const vec3 local = sample_cosine_hemisphere(rng.next_vec2());
        photon.direction = glm::normalize(frame.to_world(local));
    }
    return photons;
}

}  // namespace shgi::test
