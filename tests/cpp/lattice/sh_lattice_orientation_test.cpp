// Receiving sides of ShLattice cells (lattice/sh_lattice.h, "Density estimate"): the sides of a
// cell's orientation bins that photons arrive on, the projected area D_c(ω) they give, and the
// sampling weights D_c(n) they give, against the closed forms of axis-aligned walls.
#include "lattice/sh_lattice.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <tbb/global_control.h>

#include "lattice/lattice_test_scenes.h"
#include "render/render_test_scenes.h"
#include "util/rng.h"
#include "util/sampling.h"

namespace shgi {
namespace {

// Clipped areas agree with the closed forms to ~1e-6 of a cell face (sh_lattice_test.cpp).
constexpr double kAreaTolerance = 1e-5;
// Normalised blends of O(10) floats of magnitude ~1.
constexpr float kFloatTolerance = 1e-5f;

constexpr uint8_t kPlusX = ShLattice::side_bit(0, true), kMinusX = ShLattice::side_bit(0, false);
constexpr uint8_t kPlusY = ShLattice::side_bit(1, true), kMinusY = ShLattice::side_bit(1, false);
constexpr uint8_t kPlusZ = ShLattice::side_bit(2, true), kMinusZ = ShLattice::side_bit(2, false);

// Photons on the rectangle corner + [0,1] edge_u + [0,1] edge_v arriving on the side with
// outward normal `normal`.
std::vector<Photon> photons_on(const vec3& corner, const vec3& edge_u, const vec3& edge_v,
                               const vec3& normal, uint64_t seed) {
    return test::uniform_field_photons(corner, edge_u, edge_v, normal, vec3(1.0f), 4096, seed);
}

// The box [-1, 1]^3 (walls facing inwards) at resolution 4, each wall's inner side receiving
// photons: boundary cells mark the inner sides of the walls they hold, and D_c counts those
// sides only. Before any photon, and after clear(), every side counts.
TEST(ShLatticeOrientation, ClosedBoxMarksTheInnerSidesOfItsWalls) {
    const Scene scene = test::committed_scene({test::inward_box(1.0f)});
    ShLattice lattice(scene.bounds(), 4, 1);
    lattice.measure_surfaces(scene);
    const size_t corner = lattice.cell_index(ivec3(0, 0, 0));
    const size_t far_corner = lattice.cell_index(ivec3(3, 3, 3));
    const size_t edge = lattice.cell_index(ivec3(0, 0, 2));  // walls x = -1 and y = -1
    const size_t face = lattice.cell_index(ivec3(1, 2, 3));  // wall z = +1
    const size_t inside = lattice.cell_index(ivec3(1, 1, 2));
    const float corner_area = lattice.surface_area(corner);
    const float wall_piece = corner_area / 3.0f;  // each wall's share of the corner cell
    const float face_area = lattice.surface_area(face);
    ASSERT_NEAR(wall_piece, 0.25, 1e-3);
    const vec3 diagonal = glm::normalize(vec3(1.0f, 1.0f, 1.0f));
    const vec3 mirrored = glm::normalize(vec3(-1.0f, 1.0f, 1.0f));

    EXPECT_EQ(lattice.receiving_sides(corner), 0u);
    EXPECT_NEAR(lattice.projected_area(corner, mirrored), 3.0f * wall_piece * diagonal.x,
                kAreaTolerance);

    for (int axis = 0; axis < 3; ++axis)
        for (float side : {-1.0f, 1.0f}) {
            vec3 u(0.0f), v(0.0f), inward(0.0f);
            u[(axis + 1) % 3] = 2.0f;
            v[(axis + 2) % 3] = 2.0f;
            inward[axis] = -side;
            lattice.inject(photons_on(-inward - 0.5f * (u + v), u, v, inward,
                                      uint64_t(2 * axis) + (side > 0.0f)),
                           1.0f);
        }
    EXPECT_EQ(lattice.receiving_sides(corner), kPlusX | kPlusY | kPlusZ);
    EXPECT_EQ(lattice.receiving_sides(far_corner), kMinusX | kMinusY | kMinusZ);
    EXPECT_EQ(lattice.receiving_sides(edge), kPlusX | kPlusY);
    EXPECT_EQ(lattice.receiving_sides(face), kMinusZ);
    EXPECT_EQ(lattice.receiving_sides(inside), 0u);
    // D_c(ω) = Σ A max(0, n_inner · ω): from the mirrored diagonal the x = -1 wall's inner side
    // faces away, and a photon arriving from there could not have reached it.
    EXPECT_NEAR(lattice.projected_area(corner, diagonal), 3.0f * wall_piece * diagonal.x,
                kAreaTolerance);
    EXPECT_NEAR(lattice.projected_area(corner, mirrored), 2.0f * wall_piece * diagonal.x,
                kAreaTolerance);
    EXPECT_NEAR(lattice.projected_area(corner, -diagonal), 0.0f, kAreaTolerance);
    EXPECT_NEAR(lattice.projected_area(face, vec3(0, 0, -1)), face_area, kAreaTolerance);
    EXPECT_NEAR(lattice.projected_area(face, vec3(0, 0, 1)), 0.0f, kAreaTolerance);
    EXPECT_EQ(lattice.surface_area(corner), corner_area);  // areas do not change

    lattice.clear();
    EXPECT_EQ(lattice.receiving_sides(corner), 0u);
    EXPECT_NEAR(lattice.projected_area(corner, mirrored), 3.0f * wall_piece * diagonal.x,
                kAreaTolerance);
}

// Marks accumulate across inject() calls (interactive passes), are the same for any thread
// count, and a panel reached on both sides counts both.
TEST(ShLatticeOrientation, MarksAccumulateAcrossCallsAndDoNotDependOnThreadCount) {
    ShLattice lattice(Bounds3{vec3(0.0f), vec3(1.0f)}, 1, 1);
    const vec3 corner(0.1f, 0.1f, 0.5f), edge_u(0.8f, 0, 0), edge_v(0, 0.8f, 0), up(0, 0, 1);
    lattice.measure_surfaces(test::committed_scene({test::quad(corner, edge_u, edge_v)}));
    lattice.inject(photons_on(corner, edge_u, edge_v, up, 1), 1.0f);
    EXPECT_EQ(lattice.receiving_sides(0), kPlusZ);
    EXPECT_NEAR(lattice.projected_area(0, -up), 0.0f, kAreaTolerance);
    lattice.inject(photons_on(corner, edge_u, edge_v, -up, 2), 1.0f);
    EXPECT_EQ(lattice.receiving_sides(0), kPlusZ | kMinusZ);
    EXPECT_NEAR(lattice.projected_area(0, -up), 0.64f, kAreaTolerance);

    // Photons with random normals all over a box with a sphere inside.
    const Scene scene = test::committed_scene({test::inward_box(1.0f), test::uv_sphere(0.6f)});
    Pcg32 rng(8, 0);
    std::vector<Photon> photons(200000);
    for (Photon& photon : photons) {
        photon.position = 2.0f * vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 1.0f;
        photon.power = vec3(1.0f);
        photon.normal = sample_uniform_sphere(rng.next_vec2());
        photon.direction = photon.normal;
    }
    const auto marks = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        ShLattice marked(scene.bounds(), 6, 1);
        marked.measure_surfaces(scene);
        marked.inject(photons, 1.0f);
        std::vector<uint8_t> sides(marked.cell_count());
        for (size_t c = 0; c < sides.size(); ++c) sides[c] = marked.receiving_sides(c);
        return sides;
    };
    EXPECT_EQ(marks(1), marks(2));
}

// A photon marks the bin whose mean normal is closest to its own, not the bin of its normal's
// largest component: on a ramp at nearly 45° (normal ∝ (-1, -0.999, 0), in bin X), a photon
// whose normal leans slightly the other way (rounding) marks the ramp's bin, not that of the
// wall (Y) sharing the cell.
TEST(ShLatticeOrientation, PhotonsMarkTheBinClosestToTheirNormal) {
    ShLattice lattice(Bounds3{vec3(0.0f), vec3(1.0f)}, 1, 1);
    const vec3 ramp_corner(0.1f, 0.9f, 0.1f), ramp_u(0.7992f, -0.8f, 0.0f), ramp_v(0, 0, 0.8f);
    const vec3 wall_corner(0.1f, 0.2f, 0.1f), wall_u(0, 0, 0.8f), wall_v(0.3f, 0, 0);
    lattice.measure_surfaces(test::committed_scene(
        {test::quad(ramp_corner, ramp_u, ramp_v), test::quad(wall_corner, wall_u, wall_v)}));
    Photon photon;
    photon.position = vec3(0.5f, 0.5f, 0.5f);
    photon.power = vec3(1.0f);
    photon.normal = glm::normalize(vec3(-1.0f, -1.001f, 0.0f));
    photon.direction = photon.normal;
    ASSERT_EQ(lattice.inject({photon}, 1.0f), 1u);
    EXPECT_EQ(lattice.receiving_sides(0), kMinusX);
}

// A floor (its photons arriving from above) and a ceiling (from below) across a 2 x 2 x 2
// lattice: the floor in the bottom layer of cells, the ceiling in the top one.
struct FloorUnderCeiling {
    ShLattice lattice{Bounds3{vec3(0.0f), vec3(2.0f)}, 2, 1};
    float s = lattice.cell_size();
    vec3 o = lattice.origin();
    vec3 across_u{3.0f * s, 0, 0}, across_v{0, 3.0f * s, 0}, up{0, 0, 1};
    vec3 floor_corner = o + vec3(-0.5f * s, -0.5f * s, 0.3f * s);
    vec3 ceiling_corner = o + vec3(-0.5f * s, -0.5f * s, 1.7f * s);

    // ceiling_faces_down: the ceiling quad's winding faces the floor (else it faces up too).
    explicit FloorUnderCeiling(bool ceiling_faces_down) {
        lattice.measure_surfaces(test::committed_scene(
            {test::quad(floor_corner, across_u, across_v),
             ceiling_faces_down ? test::quad(ceiling_corner, across_v, across_u)
                                : test::quad(ceiling_corner, across_u, across_v)}));
    }
    void inject_photons() {
        lattice.inject(photons_on(floor_corner, across_u, across_v, up, 3), 1.0f);
        lattice.inject(photons_on(ceiling_corner, across_u, across_v, -up, 4), 1.0f);
    }
    // Radiance 1 in the floor's cells, 5 in the ceiling's.
    static void set_radiance(ShLattice& target) {
        for (int k = 0; k < 2; ++k)
            for (int j = 0; j < 2; ++j)
                for (int i = 0; i < 2; ++i) {
                    ShRgb radiance(1);
                    radiance[0] = vec3(k == 0 ? 1.0f : 5.0f);
                    target.set_cell_radiance(target.cell_index(ivec3(i, j, k)), radiance);
                }
    }
};

// Sampling counts the receiving sides that face like the shading normal: a floor lit from
// above (radiance 1 in its cells) under a ceiling lit from below (radiance 5). Upward normals
// see only floor cells, downward normals only ceiling cells, wherever the point lies between
// them. Counting both sides of every surface, both would blend to 3 in the middle.
TEST(ShLatticeOrientation, SamplingWeighsOnlySidesThatFaceTheNormal) {
    FloorUnderCeiling room(false);
    room.inject_photons();
    ShLattice& lattice = room.lattice;
    const float s = room.s;
    const vec3 o = room.o, up = room.up;
    for (int k = 0; k < 2; ++k)
        for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i)
                ASSERT_EQ(lattice.receiving_sides(lattice.cell_index(ivec3(i, j, k))),
                          k == 0 ? kPlusZ : kMinusZ);
    FloorUnderCeiling::set_radiance(lattice);
    for (const vec3& p : {o + vec3(s), o + vec3(0.7f * s, 1.2f * s, 0.6f * s),
                          o + vec3(1.3f * s, 0.6f * s, 1.4f * s)}) {
        EXPECT_NEAR(lattice.sample_cubic(p, up, 0.0f)[0].x, 1.0f, kFloatTolerance);
        EXPECT_NEAR(lattice.sample_trilinear(p, up, 0.0f)[0].x, 1.0f, kFloatTolerance);
        EXPECT_NEAR(lattice.sample_cubic(p, -up, 0.0f)[0].x, 5.0f, kFloatTolerance);
        EXPECT_NEAR(lattice.sample_trilinear(p, -up, 0.0f)[0].x, 5.0f, kFloatTolerance);
    }
    // A sideways normal faces neither side: no weight, zero radiance.
    EXPECT_EQ(lattice.sample_cubic(o + vec3(s), vec3(1, 0, 0), 0.0f)[0], vec3(0.0f));
}

// sample_cubic keeps each thread's last block's D_c(n) for the next sample with the same normal
// (lattice/sh_lattice.cpp, FacingMemo): a sample right after the sides change (inject, clear),
// or of a copy holding the old sides, reads the sides it has, and a sample from the memo is the
// same bits as one that computes D_c(n) afresh.
TEST(ShLatticeOrientation, CubicSamplesFollowTheSidesAsTheyChange) {
    FloorUnderCeiling room(true);  // facing down: the floor sees it before photons mark sides
    ShLattice& lattice = room.lattice;
    const float s = room.s;
    const vec3 o = room.o, up = room.up;
    const auto set_radiance = FloorUnderCeiling::set_radiance;
    set_radiance(lattice);
    const vec3 p = o + vec3(0.7f * s, 1.2f * s, 0.6f * s);
    const vec3 q = o + vec3(0.8f * s, 1.1f * s, 0.7f * s);  // in p's cell: the same block
    const vec3 far = o + vec3(1.6f * s, 1.6f * s, 1.6f * s);  // another block: evicts the memo
    // No photon yet: every side counts, so an upward normal reads the ceiling too.
    const float unmarked = lattice.sample_cubic(p, up, 0.0f)[0].x;
    EXPECT_GT(unmarked, 1.1f);
    const ShLattice unmarked_copy = lattice;
    room.inject_photons();
    set_radiance(lattice);
    EXPECT_NEAR(lattice.sample_cubic(p, up, 0.0f)[0].x, 1.0f, kFloatTolerance);
    EXPECT_EQ(unmarked_copy.sample_cubic(p, up, 0.0f)[0].x, unmarked);
    EXPECT_NEAR(lattice.sample_cubic(p, up, 0.0f)[0].x, 1.0f, kFloatTolerance);
    // From the memo (q after p, same block and normal) and afresh (after a sample elsewhere).
    (void)lattice.sample_cubic(p, up, 0.0f);
    const ShRgb memo = lattice.sample_cubic(q, up, 0.0f);
    (void)lattice.sample_cubic(far, -up, 0.0f);
    const ShRgb fresh = lattice.sample_cubic(q, up, 0.0f);
    for (int i = 0; i < memo.num_coefficients(); ++i) EXPECT_EQ(memo[i], fresh[i]);
    lattice.clear();
    set_radiance(lattice);
    EXPECT_EQ(lattice.sample_cubic(p, up, 0.0f)[0].x, unmarked);
}

// The closed box with every wall's inner side marked (face, edge and corner cells have one, two
// and three sides): a field that is uniform within each kind of cell but differs between kinds
// comes out of the blur unchanged, as floors blur with floors only; and a random field keeps
// Σ_c A_c L(c).
TEST(ShLatticeOrientation, BlurMixesOnlyCellsWithTheSameSides) {
    const Scene scene = test::committed_scene({test::inward_box(1.0f)});
    ShLattice lattice(scene.bounds(), 6, 1);
    lattice.measure_surfaces(scene);
    std::vector<Photon> photons;
    for (int axis = 0; axis < 3; ++axis)
        for (float side : {-1.0f, 1.0f}) {
            vec3 u(0.0f), v(0.0f), inward(0.0f);
            u[(axis + 1) % 3] = 2.0f;
            v[(axis + 2) % 3] = 2.0f;
            inward[axis] = -side;
            const std::vector<Photon> wall = photons_on(-inward - 0.5f * (u + v), u, v, inward,
                                                        uint64_t(10 + 2 * axis) + (side > 0.0f));
            photons.insert(photons.end(), wall.begin(), wall.end());
        }
    lattice.inject(photons, 1.0f);

    const auto by_sides = [](uint8_t sides) {  // a radiance per set of sides
        ShRgb radiance(1);
        for (int i = 0; i < 4; ++i)
            radiance[i] = vec3(float(sides), float(i) - 1.5f, 0.1f * float(sides * (i + 1)));
        return radiance;
    };
    for (size_t c = 0; c < lattice.cell_count(); ++c)
        lattice.set_cell_radiance(c, lattice.surface_area(c) > 0.0f
                                         ? by_sides(lattice.receiving_sides(c))
                                         : ShRgb(1));
    const std::vector<float> before = lattice.coefficients();
    lattice.blur(2);
    for (size_t i = 0; i < before.size(); ++i)
        ASSERT_NEAR(lattice.coefficients()[i], before[i], kFloatTolerance * 64.0f) << i;

    Pcg32 rng(12, 0);
    std::vector<double> energy_before(12, 0.0), energy_after(12, 0.0);
    for (size_t c = 0; c < lattice.cell_count(); ++c) {
        ShRgb radiance(1);
        if (lattice.surface_area(c) > 0.0f)
            for (int i = 0; i < 4; ++i)
                radiance[i] = vec3(rng.next_float(), rng.next_float(), rng.next_float());
        lattice.set_cell_radiance(c, radiance);
        for (size_t i = 0; i < 12; ++i)
            energy_before[i] += double(lattice.surface_area(c)) * radiance.data()[i];
    }
    lattice.blur(3);
    for (size_t c = 0; c < lattice.cell_count(); ++c)
        for (size_t i = 0; i < 12; ++i)
            energy_after[i] += double(lattice.surface_area(c)) * lattice.cell_radiance(c).data()[i];
    for (size_t i = 0; i < 12; ++i)
        EXPECT_NEAR(energy_after[i], energy_before[i], 1e-5 * 24.0) << "coefficient/channel " << i;
}

}  // namespace
}  // namespace shgi
