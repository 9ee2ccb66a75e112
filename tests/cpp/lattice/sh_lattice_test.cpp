// ShLattice geometry, blur and sampling against closed forms: clipped areas are interval
// overlaps of axis-aligned rectangles with the cell grid, a triangle's pieces sum to its area,
// the blur keeps Σ A_c L(c) and uniform fields, trilinear weights reproduce linear fields, the
// cubic weights are the smoothstep w(d) of the header, D_c(n) hides cells facing elsewhere, and
// the samplers' shortcuts leave them equal to the plain weighted sum.
#include "lattice/sh_lattice.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtx/string_cast.hpp>
#include <tbb/global_control.h>

#include "lattice/lattice_test_scenes.h"
#include "render/render_test_scenes.h"
#include "support/expect_error.h"
#include "util/rng.h"
#include "util/sampling.h"

namespace shgi {
namespace {

// Clipping runs in float on coordinates of a few cells: areas agree with the double-precision
// overlaps to ~1e-6 of a cell face; 1e-5 leaves room.
constexpr double kAreaTolerance = 1e-5;
// Sums and weight normalisations of O(10) floats of magnitude ~1.
constexpr float kFloatTolerance = 1e-5f;
// The interpolation and blur tests below check the weights' formulas on planes that part the
// cells (stacked floors, a wall through a floor): without the visibility masks, which would
// rightly keep the cells of different floors apart (sh_lattice_visibility_test.cpp tests them).
constexpr bool kNoVisibility = false;

const vec3 kUp(0.0f, 0.0f, 1.0f);

// ----- construction -------------------------------------------------------------------------

TEST(ShLattice, DimsCoverTheGrownBoundsWithCubicCells) {
    const ShLattice lattice(Bounds3{vec3(-1.0f, 0.0f, 2.0f), vec3(3.0f, 1.0f, 3.0f)}, 8, 2);
    EXPECT_EQ(lattice.dims(), ivec3(8, 2, 2));
    EXPECT_EQ(lattice.num_coefficients(), 9);
    EXPECT_EQ(lattice.cell_count(), 32u);
    EXPECT_EQ(lattice.coefficients().size(), 32u * 9u * 3u);
    EXPECT_GE(lattice.memory_bytes(), lattice.coefficients().size() * sizeof(float));
    // The margin puts the bounds' own faces strictly inside.
    EXPECT_LT(lattice.origin().x, -1.0f);
    EXPECT_NEAR(lattice.cell_size(), 0.5f, 1e-3f);
    EXPECT_GT(float(lattice.dims().x) * lattice.cell_size() + lattice.origin().x, 3.0f);
    EXPECT_EQ(lattice.cell_of(vec3(-1.0f, 0.0f, 2.0f)), ivec3(0, 0, 0));
    EXPECT_EQ(lattice.cell_of(vec3(3.0f, 1.0f, 3.0f)), ivec3(7, 1, 1));
    EXPECT_EQ(lattice.cell_of(vec3(0.1f, 0.6f, 2.4f)), ivec3(2, 1, 0));
    EXPECT_EQ(lattice.cell_of(vec3(3.5f, 0.5f, 2.5f)), ivec3(-1));
    EXPECT_EQ(lattice.cell_of(vec3(NAN, 0.5f, 2.5f)), ivec3(-1));
    // A single point still makes one cell, around it.
    const ShLattice point(Bounds3{vec3(1.0f), vec3(1.0f)}, 4, 1);
    EXPECT_EQ(point.dims(), ivec3(1));
    EXPECT_EQ(point.cell_of(vec3(1.0f)), ivec3(0));
}

// A default-constructed lattice has no cells: every operation is a no-op that returns zero.
TEST(ShLattice, DefaultConstructedLatticeIsEmpty) {
    ShLattice lattice;
    EXPECT_EQ(lattice.cell_count(), 0u);
    lattice.measure_surfaces(test::committed_scene({test::inward_box(1.0f)}));
    std::vector<Photon> photons(10);
    EXPECT_EQ(lattice.inject(photons, 1.0f), 0u);
    lattice.blur(2);
    EXPECT_EQ(lattice.cell_of(vec3(0.0f)), ivec3(-1));
    for (const ShRgb& sampled : {lattice.sample_trilinear(vec3(0.0f), kUp, 0.5f),
                                 lattice.sample_cubic(vec3(0.0f), kUp, 0.5f)}) {
        EXPECT_EQ(sampled.order, 1);
        EXPECT_EQ(sampled[0], vec3(0.0f));
    }
}

TEST(ShLattice, BadArgumentsThrowNamingThem) {
    const Bounds3 unit{vec3(0.0f), vec3(1.0f)};
    testing::expect_invalid_argument([&] { ShLattice(unit, 0, 1); }, "resolution = 0");
    testing::expect_invalid_argument([&] { ShLattice(unit, 1025, 1); }, "resolution = 1025");
    testing::expect_invalid_argument([&] { ShLattice(unit, 4, 0); }, "order = 0");
    testing::expect_invalid_argument([&] { ShLattice(unit, 4, 3); }, "order = 3");
    testing::expect_invalid_argument([&] { ShLattice(Bounds3{}, 4, 1); }, "bounds are empty");
    testing::expect_invalid_argument(
        [&] { ShLattice(Bounds3{vec3(0.0f), vec3(1.0f, INFINITY, 1.0f)}, 4, 1); }, "not finite");
    testing::expect_invalid_argument([&] { ShLattice(unit, 1024, 1); }, "cells, more than");

    ShLattice lattice(unit, 2, 1);
    Scene uncommitted;
    uncommitted.add_instance(uncommitted.add_mesh(test::plane(0.5f)), mat4(1.0f));
    testing::expect_invalid_argument([&] { lattice.measure_surfaces(uncommitted); }, "commit()");
    testing::expect_invalid_argument([&] { lattice.inject({}, NAN); }, "scale = nan");
    testing::expect_invalid_argument([&] { lattice.scale(INFINITY); }, "factor = inf");
    testing::expect_invalid_argument([&] { lattice.blur(-1); }, "passes = -1");
    testing::expect_invalid_argument([&] { lattice.cell_radiance(8); }, "cell = 8");
    testing::expect_invalid_argument([&] { lattice.surface_area(9); }, "cell = 9");
    testing::expect_invalid_argument([&] { lattice.projected_area(8, kUp); }, "cell = 8");
    testing::expect_invalid_argument([&] { lattice.set_cell_radiance(0, ShRgb(2)); },
                                     "radiance.order = 2");
    testing::expect_invalid_argument([&] { lattice.set_cell_radiance(8, ShRgb(1)); }, "cell = 8");
}

// An explicit grid (the propagation cascades' levels): the layout given, bad grids named.
TEST(ShLattice, ExplicitGridKeepsItsLayoutAndRefusesBadOnes) {
    const ShLattice lattice(vec3(-1.0f, 2.0f, 0.5f), 0.25f, ivec3(3, 4, 5), 2);
    EXPECT_EQ(lattice.origin(), vec3(-1.0f, 2.0f, 0.5f));
    EXPECT_EQ(lattice.cell_size(), 0.25f);
    EXPECT_EQ(lattice.dims(), ivec3(3, 4, 5));
    EXPECT_EQ(lattice.order(), 2);
    EXPECT_EQ(lattice.cell_of(vec3(-0.9f, 2.3f, 1.6f)), ivec3(0, 1, 4));
    testing::expect_invalid_argument(
        [&] { ShLattice(vec3(0.0f), 0.0f, ivec3(2), 1); }, "cell size 0");
    testing::expect_invalid_argument(
        [&] { ShLattice(vec3(NAN, 0.0f, 0.0f), 1.0f, ivec3(2), 1); }, "must be finite");
    testing::expect_invalid_argument([&] { ShLattice(vec3(0.0f), 1.0f, ivec3(2, 0, 2), 1); },
                                     "at least 1 per axis");
    testing::expect_invalid_argument([&] { ShLattice(vec3(0.0f), 1.0f, ivec3(2), 3); },
                                     "order = 3");
    testing::expect_invalid_argument([&] { ShLattice(vec3(0.0f), 1.0f, ivec3(1024), 1); },
                                     "cells, more than");
}

// ----- measure_surfaces ---------------------------------------------------------------------

// A horizontal rectangle split across cells: each cell gets the overlap of the rectangle with
// its x and y intervals, in the z layer holding the rectangle; a rectangle reaching beyond the
// lattice keeps only what is inside.
TEST(ShLattice, ClipsARectangleToTheExactCellAreas) {
    ShLattice lattice(Bounds3{vec3(0.0f), vec3(2.0f)}, 4, 1);
    const vec3 lo(0.3f, 0.2f, 0.9f), hi(1.7f, 1.3f, 0.9f);
    const vec3 far_lo(-5.0f, -5.0f, 1.6f), far_hi(5.0f, 5.0f, 1.6f);
    lattice.measure_surfaces(test::committed_scene(
        {test::quad(lo, vec3(hi.x - lo.x, 0, 0), vec3(0, hi.y - lo.y, 0)),
         test::quad(far_lo, vec3(far_hi.x - far_lo.x, 0, 0), vec3(0, far_hi.y - far_lo.y, 0))}));
    const int layer = lattice.cell_of(lo).z, far_layer = lattice.cell_of(vec3(1.0f, 1.0f, 1.6f)).z;
    ASSERT_NE(layer, far_layer);
    const double lattice_hi_x = test::cell_lower(lattice, 0, lattice.dims().x);
    const double lattice_hi_y = test::cell_lower(lattice, 1, lattice.dims().y);
    for (int k = 0; k < lattice.dims().z; ++k)
        for (int j = 0; j < lattice.dims().y; ++j)
            for (int i = 0; i < lattice.dims().x; ++i) {
                const double x0 = test::cell_lower(lattice, 0, i), x1 = x0 + lattice.cell_size();
                const double y0 = test::cell_lower(lattice, 1, j), y1 = y0 + lattice.cell_size();
                double expected = 0.0;
                if (k == layer)
                    expected =
                        test::overlap(lo.x, hi.x, x0, x1) * test::overlap(lo.y, hi.y, y0, y1);
                if (k == far_layer)
                    expected = test::overlap(far_lo.x, lattice_hi_x, x0, x1) *
                               test::overlap(far_lo.y, lattice_hi_y, y0, y1);
                const size_t cell = lattice.cell_index(ivec3(i, j, k));
                EXPECT_NEAR(lattice.surface_area(cell), expected, kAreaTolerance)
                    << "cell " << i << " " << j << " " << k;
                // One horizontal orientation: D_c(ω) = A |ω_z|.
                const vec3 dir = glm::normalize(vec3(0.3f, -0.5f, 0.8f));
                EXPECT_NEAR(lattice.projected_area(cell, dir), expected * dir.z, kAreaTolerance);
                EXPECT_NEAR(lattice.projected_area(cell, vec3(1, 0, 0)), 0.0, kAreaTolerance);
            }
}

// The six walls of a closed box lie in the boundary cells (the margin keeps them inside); a
// corner cell holds three orientations, each seen only along its own axis.
TEST(ShLattice, PutsTheWallsOfABoxInTheirCells) {
    const Scene scene = test::committed_scene({test::inward_box(1.0f)});
    ShLattice lattice(scene.bounds(), 4, 2);
    lattice.measure_surfaces(scene);
    const ivec3 dims = lattice.dims();
    ASSERT_EQ(dims, ivec3(4));
    double total = 0.0;
    for (int k = 0; k < dims.z; ++k)
        for (int j = 0; j < dims.y; ++j)
            for (int i = 0; i < dims.x; ++i) {
                const ivec3 cell(i, j, k);
                const size_t index = lattice.cell_index(cell);
                double expected = 0.0;
                for (int axis = 0; axis < 3; ++axis) {
                    if (cell[axis] != 0 && cell[axis] != dims[axis] - 1) continue;
                    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
                    const double lu = test::cell_lower(lattice, u, cell[u]);
                    const double lv = test::cell_lower(lattice, v, cell[v]);
                    const double face = test::overlap(-1.0, 1.0, lu, lu + lattice.cell_size()) *
                                        test::overlap(-1.0, 1.0, lv, lv + lattice.cell_size());
                    expected += face;
                    vec3 axis_dir(0.0f);
                    axis_dir[axis] = 1.0f;
                    EXPECT_NEAR(lattice.projected_area(index, axis_dir), face, kAreaTolerance)
                        << "cell " << i << " " << j << " " << k << " axis " << axis;
                }
                EXPECT_NEAR(lattice.surface_area(index), expected, kAreaTolerance);
                total += lattice.surface_area(index);
            }
    EXPECT_NEAR(total, 24.0, 24.0 * kAreaTolerance);
}

// A tilted triangle crossing many cells, instanced twice (once rotated, scaled and moved):
// its pieces add up to its world-space area, and Σ_c D_c(ω) = A |n · ω| for one triangle.
TEST(ShLattice, TiltedTrianglePiecesSumToItsArea) {
    const vec3 p0(0.1f, 0.2f, 0.3f), p1(3.7f, 1.1f, 0.9f), p2(1.3f, 3.2f, 3.6f);
    const vec3 twice_area_normal = glm::cross(p1 - p0, p2 - p0);
    const double area = 0.5 * glm::length(glm::dvec3(twice_area_normal));
    const vec3 normal = glm::normalize(twice_area_normal);
    {
        const Scene scene = test::committed_scene({test::triangle(p0, p1, p2)});
        ShLattice lattice(scene.bounds(), 16, 1);
        lattice.measure_surfaces(scene);
        Pcg32 rng(5, 0);
        for (int trial = 0; trial < 5; ++trial) {
            const vec3 dir = sample_uniform_sphere(rng.next_vec2());
            double sum_area = 0.0, sum_projected = 0.0;
            for (size_t c = 0; c < lattice.cell_count(); ++c) {
                sum_area += lattice.surface_area(c);
                sum_projected += lattice.projected_area(c, dir);
            }
            EXPECT_NEAR(sum_area, area, area * kAreaTolerance);
            EXPECT_NEAR(sum_projected, area * std::fabs(glm::dot(normal, dir)),
                        area * kAreaTolerance);
        }
    }
    Scene scene;
    const uint32_t mesh = scene.add_mesh(test::triangle(p0, p1, p2));
    const mat4 moved = glm::scale(
        glm::rotate(glm::translate(mat4(1.0f), vec3(4.0f, -1.0f, 0.5f)), 0.7f, vec3(1, 2, 3)),
        vec3(1.5f, 0.5f, 2.0f));
    scene.add_instance(mesh, mat4(1.0f));
    scene.add_instance(mesh, moved);
    scene.commit();
    const auto world = [&](const vec3& p) { return glm::dvec3(vec3(moved * vec4(p, 1.0f))); };
    const double moved_area =
        0.5 * glm::length(glm::cross(world(p1) - world(p0), world(p2) - world(p0)));
    ShLattice lattice(scene.bounds(), 24, 1);
    lattice.measure_surfaces(scene);
    double sum = 0.0;
    for (size_t c = 0; c < lattice.cell_count(); ++c) sum += lattice.surface_area(c);
    EXPECT_NEAR(sum, area + moved_area, (area + moved_area) * kAreaTolerance);
}

// A rectangle lying exactly on a plane between two layers of cells is counted once.
TEST(ShLattice, SurfaceOnACellFaceIsCountedOnce) {
    ShLattice lattice(Bounds3{vec3(0.0f), vec3(2.0f)}, 4, 1);
    const float z = lattice.origin().z + 2.0f * lattice.cell_size();
    lattice.measure_surfaces(test::committed_scene(
        {test::quad(vec3(0.25f, 0.25f, z), vec3(1.5f, 0, 0), vec3(0, 1.5f, 0))}));
    double total = 0.0;
    int layers_with_surface = 0;
    for (int k = 0; k < lattice.dims().z; ++k) {
        double layer = 0.0;
        for (int j = 0; j < lattice.dims().y; ++j)
            for (int i = 0; i < lattice.dims().x; ++i)
                layer += lattice.surface_area(lattice.cell_index(ivec3(i, j, k)));
        layers_with_surface += layer > 0.0;
        total += layer;
    }
    EXPECT_NEAR(total, 1.5 * 1.5, kAreaTolerance);
    EXPECT_EQ(layers_with_surface, 1);
}

// Areas and D_c along a few directions, per cell.
std::vector<float> surface_signature(const ShLattice& lattice) {
    std::vector<float> signature;
    for (size_t c = 0; c < lattice.cell_count(); ++c) {
        signature.push_back(lattice.surface_area(c));
        for (const vec3& dir : {vec3(1, 0, 0), vec3(0, 1, 0), glm::normalize(vec3(1, 2, 3))})
            signature.push_back(lattice.projected_area(c, dir));
    }
    return signature;
}

// Many triangles (several chunks), several of them in most cells: same sums in the same order.
TEST(ShLattice, MeasureSurfacesIsIndependentOfThreadCount) {
    const Scene scene = test::committed_scene(
        {test::uv_sphere(1.3f, 96, 192), test::inward_box(2.0f), test::plane(1.9f)});
    const auto measure = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        ShLattice lattice(scene.bounds(), 12, 1);
        lattice.measure_surfaces(scene);
        return surface_signature(lattice);
    };
    EXPECT_EQ(measure(1), measure(2));
}

TEST(ShLattice, MeasureAndInjectReportProgressAndStopWhenCancelled) {
    const Scene box = test::committed_scene({test::inward_box(1.0f)});
    ShLattice lattice(box.bounds(), 4, 1);
    Progress progress;
    lattice.measure_surfaces(box, &progress);
    EXPECT_EQ(progress.fraction(), 1.0f);
    const float corner_area = lattice.surface_area(0);
    ASSERT_GT(corner_area, 0.0f);

    Progress cancelled;
    cancelled.cancel();
    EXPECT_THROW(lattice.measure_surfaces(test::committed_scene({test::plane(0.5f)}), &cancelled),
                 Cancelled);
    EXPECT_EQ(lattice.surface_area(0), corner_area);  // the previous surfaces are kept
    std::vector<Photon> photons(100);
    for (Photon& photon : photons) photon.position = vec3(-0.99f);
    EXPECT_THROW(lattice.inject(photons, 1.0f, &cancelled), Cancelled);
    EXPECT_EQ(lattice.inject(photons, 1.0f, &progress), 100u);
}

// ----- blur -----------------------------------------------------------------------------------

// Radiance uniform in [-1, 1) per coefficient and channel in cells with surface, zero elsewhere.
void fill_random(ShLattice& lattice, uint64_t seed) {
    Pcg32 rng(seed, 2);
    for (size_t c = 0; c < lattice.cell_count(); ++c) {
        ShRgb radiance(lattice.order());
        if (lattice.surface_area(c) > 0.0f)
            for (int i = 0; i < radiance.num_coefficients(); ++i)
                radiance[i] = 2.0f * vec3(rng.next_float(), rng.next_float(), rng.next_float()) -
                              1.0f;
        lattice.set_cell_radiance(c, radiance);
    }
}

// Σ_c A_c L(c), per coefficient and channel, in double.
std::vector<double> received_energy(const ShLattice& lattice) {
    const size_t stride = size_t(lattice.num_coefficients()) * 3;
    std::vector<double> sum(stride, 0.0);
    for (size_t c = 0; c < lattice.cell_count(); ++c)
        for (size_t i = 0; i < stride; ++i)
            sum[i] += double(lattice.surface_area(c)) * lattice.coefficients()[c * stride + i];
    return sum;
}

TEST(ShLattice, BlurKeepsReceivedEnergyAndUniformFields) {
    const Scene scene = test::committed_scene(
        {test::uv_sphere(0.7f, 12, 24), test::inward_box(1.0f),
         test::triangle(vec3(-0.9f, -0.8f, -0.2f), vec3(0.8f, 0.1f, 0.9f),
                        vec3(0.2f, 0.9f, -0.9f))});
    ShLattice lattice(scene.bounds(), 7, 2);
    lattice.measure_surfaces(scene);
    fill_random(lattice, 11);
    double magnitude = 0.0;
    for (size_t c = 0; c < lattice.cell_count(); ++c) magnitude += lattice.surface_area(c);
    const std::vector<double> before = received_energy(lattice);
    lattice.blur(3);
    const std::vector<double> after = received_energy(lattice);
    for (size_t i = 0; i < before.size(); ++i)
        EXPECT_NEAR(after[i], before[i], 1e-5 * magnitude) << "coefficient/channel " << i;
    size_t empty_cells = 0;
    for (size_t c = 0; c < lattice.cell_count(); ++c)
        if (lattice.surface_area(c) == 0.0f) {
            ++empty_cells;
            for (int i = 0; i < lattice.num_coefficients(); ++i)
                EXPECT_EQ(lattice.cell_radiance(c)[i], vec3(0.0f)) << "empty cell " << c;
        }
    EXPECT_GT(empty_cells, 0u);

    ShRgb uniform(2);
    for (int i = 0; i < 9; ++i) uniform[i] = vec3(0.5f * float(i) - 1.0f, 1.0f, 2.0f);
    for (size_t c = 0; c < lattice.cell_count(); ++c)
        lattice.set_cell_radiance(c, lattice.surface_area(c) > 0.0f ? uniform : ShRgb(2));
    lattice.blur(2);
    for (size_t c = 0; c < lattice.cell_count(); ++c) {
        if (lattice.surface_area(c) == 0.0f) continue;
        const ShRgb blurred = lattice.cell_radiance(c);
        for (int i = 0; i < 9; ++i)
            for (int ch = 0; ch < 3; ++ch)
                EXPECT_NEAR(blurred[i][ch], uniform[i][ch], kFloatTolerance) << "cell " << c;
    }
}

// The cells' areas come from float clipping (the planes' diagonals cross them) and agree to
// ~1e-7; the centre's own weight 1 − Σ_26 P_cn is a difference of numbers near 1, so it (and
// the kernel) is exact to a few 1e-6 relative.
constexpr float kKernelTolerance = 3e-5f;

// Every cell holds the same surface: one pass spreads a unit impulse evenly over its 3x3x3
// block (the seed's uniform kernel).
TEST(ShLattice, BlurIsTheUniform27KernelInAFullyCoveredInterior) {
    ShLattice lattice(Bounds3{vec3(0.0f), vec3(5.0f)}, 5, 1);
    lattice.measure_surfaces(test::layered_planes(lattice), nullptr, kNoVisibility);
    const ivec3 centre(2, 2, 2);
    ShRgb impulse(1);
    impulse[0] = vec3(27.0f, 0.0f, 54.0f);
    lattice.set_cell_radiance(lattice.cell_index(centre), impulse);
    lattice.blur(1);
    for (int k = 0; k < 5; ++k)
        for (int j = 0; j < 5; ++j)
            for (int i = 0; i < 5; ++i) {
                const ivec3 cell(i, j, k);
                const bool in_block =
                    glm::all(glm::lessThanEqual(glm::abs(cell - centre), ivec3(1)));
                const vec3 l0 = lattice.cell_radiance(lattice.cell_index(cell))[0];
                EXPECT_NEAR(l0.x, in_block ? 1.0f : 0.0f, kKernelTolerance);
                EXPECT_NEAR(l0.z, in_block ? 2.0f : 0.0f, 2.0f * kKernelTolerance);
            }
}

// ----- sampling -------------------------------------------------------------------------------

// Coefficient i, channel ch of a field linear in the position: a + b · p.
float linear_field(int i, int ch, const vec3& p) {
    const float a = 0.1f * float(i) - 0.2f * float(ch);
    const vec3 b(0.3f - 0.05f * float(i), 0.2f * float(ch) - 0.1f, 0.04f * float(i + ch));
    return a + glm::dot(b, p);
}

vec3 cell_centre(const ShLattice& lattice, const ivec3& cell) {
    return lattice.origin() + (vec3(cell) + 0.5f) * lattice.cell_size();
}

void fill_linear(ShLattice& lattice) {
    const ivec3 dims = lattice.dims();
    for (int k = 0; k < dims.z; ++k)
        for (int j = 0; j < dims.y; ++j)
            for (int i = 0; i < dims.x; ++i) {
                ShRgb radiance(lattice.order());
                const vec3 centre = cell_centre(lattice, ivec3(i, j, k));
                for (int c = 0; c < radiance.num_coefficients(); ++c)
                    for (int ch = 0; ch < 3; ++ch) radiance[c][ch] = linear_field(c, ch, centre);
                lattice.set_cell_radiance(lattice.cell_index(ivec3(i, j, k)), radiance);
            }
}

// With equal D_c everywhere, trilinear weights reproduce a linear field exactly between the
// first and last cell centres, and the normal offset moves the sample point along n.
TEST(ShLattice, TrilinearIsExactOnLinearFields) {
    ShLattice lattice(Bounds3{vec3(0.0f), vec3(4.0f)}, 4, 2);
    lattice.measure_surfaces(test::layered_planes(lattice), nullptr, kNoVisibility);
    fill_linear(lattice);
    const vec3 first = cell_centre(lattice, ivec3(0)), last = cell_centre(lattice, ivec3(3));
    Pcg32 rng(9, 0);
    for (int trial = 0; trial < 200; ++trial) {
        const vec3 u(rng.next_float(), rng.next_float(), rng.next_float());
        const vec3 p = first + u * (last - first);
        const float offset = trial % 2 ? 0.0f : 0.4f * (u.x - 0.5f);
        const vec3 n = trial % 4 < 2 ? kUp : -kUp;
        const vec3 q = glm::clamp(p + offset * lattice.cell_size() * n, first, last);
        const vec3 p_shifted = q - offset * lattice.cell_size() * n;
        const ShRgb sampled = lattice.sample_trilinear(p_shifted, n, offset);
        ASSERT_EQ(sampled.order, 2);
        for (int c = 0; c < 9; ++c)
            for (int ch = 0; ch < 3; ++ch)
                ASSERT_NEAR(sampled[c][ch], linear_field(c, ch, q), kFloatTolerance)
                    << "trial " << trial << " coefficient " << c << " channel " << ch;
    }
}

// w(d) = 2d³/r³ − 3d²/r² + 1, r = 1.75 cells: the test's own transcription of the header.
double smoothstep_weight(double d) {
    const double r = 1.75;
    return d >= r ? 0.0 : 2.0 * d * d * d / (r * r * r) - 3.0 * d * d / (r * r) + 1.0;
}

// An impulse in one cell comes back with weight w(d_impulse) / Σ_27 w(d); a constant field is
// reproduced exactly, also next to the lattice's boundary.
TEST(ShLattice, CubicWeightsFollowTheSmoothstepAndKeepConstants) {
    ShLattice lattice(Bounds3{vec3(0.0f), vec3(5.0f)}, 5, 1);
    lattice.measure_surfaces(test::layered_planes(lattice), nullptr, kNoVisibility);
    const ivec3 impulse_cell(2, 2, 2);
    ShRgb impulse(1);
    impulse[0] = vec3(1.0f, 0.0f, 0.0f);
    lattice.set_cell_radiance(lattice.cell_index(impulse_cell), impulse);
    const float s = lattice.cell_size();
    Pcg32 rng(4, 0);
    for (int trial = 0; trial < 100; ++trial) {
        const vec3 p = lattice.origin() +
                       (vec3(1.0f) + 3.0f * vec3(rng.next_float(), rng.next_float(),
                                                 rng.next_float())) * s;
        const vec3 cells = (p - lattice.origin()) / s;
        const ivec3 centre_cell(glm::floor(cells));
        double total = 0.0, impulse_weight = 0.0;
        for (int z = -1; z <= 1; ++z)
            for (int y = -1; y <= 1; ++y)
                for (int x = -1; x <= 1; ++x) {
                    const ivec3 cell = centre_cell + ivec3(x, y, z);
                    const glm::dvec3 to_centre = glm::dvec3(cells) - (glm::dvec3(cell) + 0.5);
                    const double w = smoothstep_weight(glm::length(to_centre));
                    total += w;
                    if (cell == impulse_cell) impulse_weight = w;
                }
        EXPECT_NEAR(lattice.sample_cubic(p, kUp, 0.0f)[0].x, impulse_weight / total,
                    kFloatTolerance)
            << "trial " << trial;
    }

    ShRgb constant(1);
    for (int i = 0; i < 4; ++i) constant[i] = vec3(1.0f + float(i), -2.0f, 0.25f);
    for (size_t c = 0; c < lattice.cell_count(); ++c) lattice.set_cell_radiance(c, constant);
    for (int trial = 0; trial < 100; ++trial) {
        const vec3 p = lattice.origin() +
                       5.0f * s * vec3(rng.next_float(), rng.next_float(), rng.next_float());
        for (const ShRgb& sampled : {lattice.sample_cubic(p, kUp, 0.4f),
                                     lattice.sample_trilinear(p, kUp, 0.4f)})
            for (int i = 0; i < 4; ++i)
                for (int ch = 0; ch < 3; ++ch)
                    ASSERT_NEAR(sampled[i][ch], constant[i][ch], kFloatTolerance);
    }
}

// A 5^3 lattice of SH `order` whose surface is a floor through its z = 2 layer and a wall
// through its x = 3 layer (each quad reaching past the lattice on every side).
ShLattice floor_and_wall_lattice(int order) {
    ShLattice lattice(Bounds3{vec3(0.0f), vec3(5.0f)}, 5, order);
    const float s = lattice.cell_size();
    const vec3 o = lattice.origin();
    lattice.measure_surfaces(test::committed_scene(
        {test::quad(o + vec3(-1.0f, -1.0f, 2.5f * s), vec3(5.0f * s + 2.0f, 0, 0),
                    vec3(0, 5.0f * s + 2.0f, 0)),
         test::quad(o + vec3(3.5f * s, -1.0f, -1.0f), vec3(0, 5.0f * s + 2.0f, 0),
                    vec3(0, 0, 5.0f * s + 2.0f))}), nullptr, kNoVisibility);
    return lattice;
}

// The queries of the bit-for-bit sample tests below: an L2 floor-and-wall lattice of random
// coefficients in [-0.5, 1.5), normals along and across the floor and the wall, points in and up
// to two cells around the lattice (every eighth query up to ten cells out, where the coordinates
// are clamped), with and without a normal offset.
struct SumQueries {
    static constexpr int kFloats = 27;
    static constexpr int kTrials = 3000;
    struct Query {
        vec3 p, n;
        float normal_offset;
    };

    explicit SumQueries(uint64_t seed) : lattice(floor_and_wall_lattice(2)), rng(seed, 0) {
        for (size_t c = 0; c < lattice.cell_count(); ++c) {
            ShRgb radiance(2);
            for (int i = 0; i < kFloats; ++i) radiance.data()[i] = 2.0f * rng.next_float() - 0.5f;
            lattice.set_cell_radiance(c, radiance);
        }
    }

    // The trial-th query; call with trial 0, 1, 2, ... in turn (the points come from rng).
    Query query(int trial) {
        static const vec3 normals[] = {kUp, -kUp, vec3(1, 0, 0), vec3(-1, 0, 0),
                                       glm::normalize(vec3(0.3f, -0.2f, 0.9f)), vec3(0, 1, 0)};
        const float s = lattice.cell_size();
        const float reach = trial % 8 == 0 ? 10.0f : 2.0f;
        const vec3 u(rng.next_float(), rng.next_float(), rng.next_float());
        return {lattice.origin() + s * (-reach + (5.0f + 2.0f * reach) * u), normals[trial % 6],
                trial % 2 == 0 ? 0.0f : 0.25f};
    }

    ShLattice lattice;
    Pcg32 rng;
};

// A sample against the reference's weighted sum, normalised as the samples do (Σ w L · (1 / Σ w),
// zero without weight), bit for bit.
void expect_normalised_sum(const ShRgb& sampled, const std::array<float, SumQueries::kFloats>& sum,
                           float total, int trial, const vec3& cells, const vec3& n) {
    std::array<float, SumQueries::kFloats> expected{};
    if (total > 0.0f)
        for (size_t i = 0; i < expected.size(); ++i) expected[i] = sum[i] * (1.0f / total);
    ASSERT_EQ(sampled.order, 2);
    ASSERT_EQ(std::memcmp(sampled.data(), expected.data(), sizeof(expected)), 0)
        << "trial " << trial << " at cells " << glm::to_string(cells) << ", n "
        << glm::to_string(n) << ": " << sampled[0].x << " against " << expected[0];
}

// A cubic sample is, bit for bit, the scalar weighted sum the header describes, in block-bit
// order: per cell of the block inside the lattice with D_c(n) > 0 and d² < r², w = w(√d²) D_c(n),
// Σ w L(c) · (1 / Σ w), each operation in float as the walk does it (its cells and D_c(n) come
// from the per-thread memo, its sums from the blend's vector registers), so that a faster walk or
// blend is checked against the plain sum. An L2 lattice (27 floats a cell) of random coefficients,
// a floor and a wall (cells without surface, cells facing away), normals along and across them,
// points in and around the lattice (up to ten cells out), with and without a normal offset.
TEST(ShLattice, CubicSampleIsTheScalarWeightedSumBitForBit) {
    SumQueries queries(11);
    const ShLattice& lattice = queries.lattice;
    const float s = lattice.cell_size();
    const vec3 o = lattice.origin();
    const ivec3 dims = lattice.dims();
    constexpr int kFloats = SumQueries::kFloats;
    for (int trial = 0; trial < SumQueries::kTrials; ++trial) {
        const auto [p, n, normal_offset] = queries.query(trial);
        const vec3 cells = glm::clamp((p + (normal_offset * s) * n - o) / s, vec3(-4.0f),
                                      vec3(dims) + 4.0f);
        const ivec3 centre(glm::floor(cells));
        std::array<float, kFloats> sum{};
        float total = 0.0f;
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const ivec3 cell = centre + ivec3(dx, dy, dz);
                    if (glm::any(glm::lessThan(cell, ivec3(0))) ||
                        glm::any(glm::greaterThanEqual(cell, dims)))
                        continue;
                    const size_t index = lattice.cell_index(cell);
                    const float density = lattice.projected_area(index, n);
                    if (!(density > 0.0f)) continue;
                    vec3 d;
                    for (int a = 0; a < 3; ++a) d[a] = cells[a] - (float(cell[a]) + 0.5f);
                    const float d2 = d.x * d.x + (d.y * d.y + d.z * d.z);
                    if (d2 >= kCubicRadiusCells * kCubicRadiusCells) continue;
                    const float w = cubic_falloff(std::sqrt(d2)) * density;
                    if (!(w > 0.0f)) continue;
                    const float* coefficients = lattice.coefficients().data() + index * kFloats;
                    for (int i = 0; i < kFloats; ++i) sum[size_t(i)] += w * coefficients[i];
                    total += w;
                }
        expect_normalised_sum(lattice.sample_cubic(p, n, normal_offset), sum, total, trial, cells, n);
    }
}

// A trilinear sample is, bit for bit, the scalar weighted sum of the 8 cells around its point,
// in z, y, x order: per cell inside the lattice with D_c(n) > 0, w = (trilinear weight along x x
// (along y x along z)) D_c(n), Σ w L(c) · (1 / Σ w), with the coordinates and their floor
// computed axis by axis in float (sample_coordinates, which runs in SSE lanes where the build
// has them, is checked against it). The lattice, coefficients, normals and points of the cubic
// test above (no visibility: every cell of the block may be read).
TEST(ShLattice, TrilinearSampleIsTheScalarWeightedSumBitForBit) {
    SumQueries queries(12);
    const ShLattice& lattice = queries.lattice;
    const float s = lattice.cell_size();
    const vec3 o = lattice.origin();
    const ivec3 dims = lattice.dims();
    constexpr int kFloats = SumQueries::kFloats;
    for (int trial = 0; trial < SumQueries::kTrials; ++trial) {
        const auto [p, n, normal_offset] = queries.query(trial);
        vec3 cells;
        for (int a = 0; a < 3; ++a)
            cells[a] = std::min(std::max((p[a] + (normal_offset * s) * n[a] - o[a]) / s, -4.0f),
                                float(dims[a]) + 4.0f);
        const vec3 f = cells - 0.5f;
        const ivec3 base(int(std::floor(f.x)), int(std::floor(f.y)), int(std::floor(f.z)));
        const vec3 t = f - vec3(base);
        std::array<float, kFloats> sum{};
        float total = 0.0f;
        for (int z = base.z; z <= base.z + 1; ++z)
            for (int y = base.y; y <= base.y + 1; ++y)
                for (int x = base.x; x <= base.x + 1; ++x) {
                    const ivec3 cell(x, y, z);
                    if (glm::any(glm::lessThan(cell, ivec3(0))) ||
                        glm::any(glm::greaterThanEqual(cell, dims)))
                        continue;
                    const size_t index = lattice.cell_index(cell);
                    const float density = lattice.projected_area(index, n);
                    if (!(density > 0.0f)) continue;
                    const float wz = z == base.z ? 1.0f - t.z : t.z;
                    const float wyz = (y == base.y ? 1.0f - t.y : t.y) * wz;
                    const float w = (x == base.x ? 1.0f - t.x : t.x) * wyz * density;
                    if (!(w > 0.0f)) continue;
                    const float* coefficients = lattice.coefficients().data() + index * kFloats;
                    for (int i = 0; i < kFloats; ++i) sum[size_t(i)] += w * coefficients[i];
                    total += w;
                }
        expect_normalised_sum(lattice.sample_trilinear(p, n, normal_offset), sum, total, trial, cells, n);
    }
}

// Cubic samples over a lattice where only some cells hold surface (a floor through the z = 2
// layer, a wall through the x = 3 layer): an impulse in a floor cell comes back with weight
// w(d_impulse) / Σ w(d) over the floor cells of the block, for upward normals (wall cells face
// sideways, D_c(up) = 0, and cells without surface weigh nothing). One impulse lies inside (red),
// one on the lattice's x = 0 face (green). Sample points reach two cells beyond the lattice in x
// and y, so each of the 27 neighbours is tried in and out of the lattice, also from block
// centres just outside it.
TEST(ShLattice, CubicSamplesWeighOnlyTheCellsWithSurface) {
    ShLattice lattice = floor_and_wall_lattice(1);
    const float s = lattice.cell_size();
    const vec3 o = lattice.origin();
    const ivec3 impulse_cells[2] = {ivec3(2, 2, 2), ivec3(0, 2, 2)};
    for (int i = 0; i < 2; ++i) {
        ShRgb impulse(1);
        impulse[0][i] = 1.0f;
        lattice.set_cell_radiance(lattice.cell_index(impulse_cells[i]), impulse);
    }
    Pcg32 rng(7, 0);
    int nonzero[2] = {0, 0};
    for (int trial = 0; trial < 1200; ++trial) {
        const vec3 cells = vec3(-1.5f + 8.0f * rng.next_float(), -1.5f + 8.0f * rng.next_float(),
                                5.0f * rng.next_float());
        const ivec3 centre_cell(glm::floor(cells));
        double total = 0.0, impulse_weight[2] = {0.0, 0.0};
        for (int y = -1; y <= 1; ++y)
            for (int x = -1; x <= 1; ++x) {
                const ivec3 cell = ivec3(centre_cell.x + x, centre_cell.y + y, 2);
                if (std::abs(centre_cell.z - 2) > 1 || glm::any(glm::lessThan(cell, ivec3(0))) ||
                    glm::any(glm::greaterThanEqual(cell, lattice.dims())))
                    continue;
                const glm::dvec3 to_centre = glm::dvec3(cells) - (glm::dvec3(cell) + 0.5);
                const double w = smoothstep_weight(glm::length(to_centre));
                total += w;
                for (int i = 0; i < 2; ++i)
                    if (cell == impulse_cells[i]) impulse_weight[i] = w;
            }
        const vec3 sampled = lattice.sample_cubic(o + cells * s, kUp, 0.0f)[0];
        for (int i = 0; i < 2; ++i) {
            const float expected = total > 0.0 ? float(impulse_weight[i] / total) : 0.0f;
            nonzero[i] += expected > 0.0f;
            EXPECT_NEAR(sampled[i], expected, kFloatTolerance)
                << "impulse " << i << ", trial " << trial << " at cells "
                << glm::to_string(cells);
        }
    }
    EXPECT_GT(nonzero[0], 50);
    EXPECT_GT(nonzero[1], 50);
}

// A room corner: floor in the z = 0 layer, wall in the x = 0 layer. Wall cells hold radiance
// 1, floor-only cells 5. A wall-facing query sees only cells with wall (D_c(+x) = 0 for floor);
// a floor-facing query sees only cells with floor; a query among empty cells returns zero.
TEST(ShLattice, SamplingWeightsCellsByHowMuchOfThemFacesTheNormal) {
    ShLattice lattice(Bounds3{vec3(0.0f), vec3(2.0f)}, 2, 1);
    const float s = lattice.cell_size();
    const vec3 o = lattice.origin();
    lattice.measure_surfaces(test::committed_scene(
        {test::quad(o + vec3(0.0f, 0.0f, 0.25f * s), vec3(2.0f * s, 0, 0), vec3(0, 2.0f * s, 0)),
         test::quad(o + vec3(0.25f * s, 0.0f, 0.0f), vec3(0, 2.0f * s, 0),
                    vec3(0, 0, 2.0f * s))}));
    ShRgb wall(1), floor_only(1);
    wall[0] = vec3(1.0f);
    floor_only[0] = vec3(5.0f);
    for (int k = 0; k < 2; ++k)
        for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i) {
                const size_t cell = lattice.cell_index(ivec3(i, j, k));
                if (i == 0) lattice.set_cell_radiance(cell, wall);
                else if (k == 0) lattice.set_cell_radiance(cell, floor_only);
            }
    const vec3 x(1, 0, 0), z(0, 0, 1);
    const vec3 middle = o + vec3(s);
    EXPECT_NEAR(lattice.sample_trilinear(middle, x, 0.0f)[0].x, 1.0f, kFloatTolerance);
    EXPECT_NEAR(lattice.sample_cubic(middle, x, 0.0f)[0].x, 1.0f, kFloatTolerance);
    // Floor-facing at the centre: the four floor cells, two with wall (1) and two without (5).
    EXPECT_NEAR(lattice.sample_trilinear(middle, z, 0.0f)[0].x, 3.0f, kFloatTolerance);
    // Near the floor-only cells the wall query still returns only wall cells.
    EXPECT_NEAR(lattice.sample_cubic(o + vec3(1.6f * s, 0.4f * s, 0.3f * s), x, 0.0f)[0].x, 1.0f,
                kFloatTolerance);
    EXPECT_NEAR(lattice.sample_trilinear(o + vec3(0.9f * s, 0.4f * s, 0.3f * s), -x, 0.0f)[0].x,
                1.0f, kFloatTolerance);
    // Between empty cells only, outside the lattice, at a non-finite point: zero.
    const vec3 empty = o + vec3(1.8f * s, 1.0f * s, 1.8f * s);
    EXPECT_EQ(lattice.sample_trilinear(empty, z, 0.0f)[0], vec3(0.0f));
    EXPECT_EQ(lattice.sample_cubic(o + vec3(10.0f * s), z, 0.0f)[0], vec3(0.0f));
    EXPECT_EQ(lattice.sample_cubic(vec3(NAN), z, 0.0f)[0], vec3(0.0f));
}

// The header's sampling rule summed over every cell of the 3x3x3 block in double, without the
// shortcuts of ShLattice (cells skipped before their filter weight, neighbourhoods without
// radiance skipped as a whole): Σ w_c D_c(n) L(c) / Σ w_c D_c(n), zero when no weight.
ShRgb reference_sample(const ShLattice& lattice, const vec3& p, const vec3& n, float offset,
                       bool cubic) {
    const glm::dvec3 cells =
        (glm::dvec3(p + offset * lattice.cell_size() * n) - glm::dvec3(lattice.origin())) /
        double(lattice.cell_size());
    const ivec3 centre(glm::floor(cells));
    std::vector<glm::dvec3> sum(size_t(lattice.num_coefficients()), glm::dvec3(0.0));
    double total = 0.0;
    for (int z = -1; z <= 1; ++z)
        for (int y = -1; y <= 1; ++y)
            for (int x = -1; x <= 1; ++x) {
                const ivec3 cell = centre + ivec3(x, y, z);
                if (glm::any(glm::lessThan(cell, ivec3(0))) ||
                    glm::any(glm::greaterThanEqual(cell, lattice.dims())))
                    continue;
                const glm::dvec3 to_centre = cells - (glm::dvec3(cell) + 0.5);
                double filter = 1.0;
                if (cubic)
                    filter = smoothstep_weight(glm::length(to_centre));
                else
                    for (int a = 0; a < 3; ++a)
                        filter *= std::max(0.0, 1.0 - std::fabs(to_centre[a]));
                const size_t index = lattice.cell_index(cell);
                const double weight = filter * lattice.projected_area(index, n);
                if (!(weight > 0.0)) continue;
                const ShRgb radiance = lattice.cell_radiance(index);
                for (size_t i = 0; i < sum.size(); ++i)
                    sum[i] += weight * glm::dvec3(radiance[int(i)]);
                total += weight;
            }
    ShRgb result(lattice.order());
    if (total > 0.0)
        for (size_t i = 0; i < sum.size(); ++i) result[int(i)] = vec3(sum[i] / total);
    return result;
}

// Sparse radiance, as in a caustic lattice: a few lit cells among many empty ones, then blurred,
// scaled, partly overwritten with zeros, and finally photons injected into one corner. At random
// points and normals, both samplers agree with the reference sum, and are exactly zero where no
// cell of the neighbourhood holds radiance.
TEST(ShLattice, SamplesOfSparseRadianceMatchTheFullSum) {
    const Scene scene = test::committed_scene(
        {test::inward_box(1.0f), test::uv_sphere(0.5f, 12, 24),
         test::triangle(vec3(-0.9f, -0.8f, -0.2f), vec3(0.8f, 0.1f, 0.9f),
                        vec3(0.2f, 0.9f, -0.9f))});
    ShLattice lattice(scene.bounds(), 12, 2);
    lattice.measure_surfaces(scene, nullptr, kNoVisibility);
    Pcg32 rng(17, 3);
    for (const ivec3& lit : {ivec3(1, 2, 0), ivec3(9, 9, 9), ivec3(5, 0, 6), ivec3(11, 4, 3)}) {
        ShRgb radiance(2);
        for (int i = 0; i < 9; ++i)
            radiance[i] = vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 0.3f;
        lattice.set_cell_radiance(lattice.cell_index(lit), radiance);
    }
    const auto expect_samples_match = [&](const char* stage) {
        int zero_samples = 0;
        for (int trial = 0; trial < 3000; ++trial) {
            const vec3 p = 2.2f * vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 1.1f;
            const vec3 n = sample_uniform_sphere(rng.next_vec2());
            for (bool cubic : {true, false}) {
                const ShRgb expected = reference_sample(lattice, p, n, 0.25f, cubic);
                const ShRgb sampled = cubic ? lattice.sample_cubic(p, n, 0.25f)
                                            : lattice.sample_trilinear(p, n, 0.25f);
                bool zero = true;
                for (int i = 0; i < 9; ++i)
                    for (int ch = 0; ch < 3; ++ch) {
                        ASSERT_NEAR(sampled[i][ch], expected[i][ch], kFloatTolerance)
                            << stage << ", trial " << trial << (cubic ? " cubic" : " trilinear");
                        zero = zero && expected[i][ch] == 0.0f;
                    }
                zero_samples += zero;
            }
        }
        EXPECT_GT(zero_samples, 100) << stage;  // the zero neighbourhoods were exercised
    };
    expect_samples_match("impulses");
    lattice.blur(1);
    expect_samples_match("blurred");
    lattice.scale(0.5f);
    lattice.set_cell_radiance(lattice.cell_index(ivec3(9, 9, 9)), ShRgb(2));
    expect_samples_match("scaled, one cell cleared");
    lattice.clear();
    std::vector<Photon> photons =
        test::uniform_field_photons(vec3(-1.0f, -1.0f, -1.0f), vec3(0.4f, 0, 0), vec3(0, 0.4f, 0),
                                    vec3(0, 0, 1), vec3(1.0f, 2.0f, 3.0f), 2000, 5);
    lattice.inject(photons, 1.0f);
    expect_samples_match("photons in one corner");
}

TEST(ShLattice, ClearAndScaleActOnEveryCoefficient) {
    ShLattice lattice(Bounds3{vec3(0.0f), vec3(1.0f)}, 3, 1);
    lattice.measure_surfaces(test::layered_planes(lattice), nullptr, kNoVisibility);
    fill_random(lattice, 3);
    const std::vector<float> before = lattice.coefficients();
    lattice.scale(-2.0f);
    for (size_t i = 0; i < before.size(); ++i)
        ASSERT_EQ(lattice.coefficients()[i], -2.0f * before[i]);
    lattice.clear();
    for (float c : lattice.coefficients()) ASSERT_EQ(c, 0.0f);
    EXPECT_GT(lattice.surface_area(0), 0.0f);  // surfaces are kept
}

}  // namespace
}  // namespace shgi
