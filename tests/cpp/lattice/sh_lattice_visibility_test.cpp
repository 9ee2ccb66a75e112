// ShLattice's visibility masks against closed forms: a floor split by a wall 0.1 cells thick, lit
// only on one side. Lookups and the blur on the unlit side read exactly zero (before the masks,
// the cubic weights read the lit cells through the wall); a wall-less floor, the same photons,
// reads them there (the fixture would leak). Not covered by the masks (docs/methods.md, Limits):
// two surfaces closer than a quarter cell, or both inside one cell.
#include "lattice/sh_lattice.h"

#include <gtest/gtest.h>

#include <glm/gtx/component_wise.hpp>

#include "lattice/lattice_test_scenes.h"
#include "render/render_test_scenes.h"

namespace shgi {
namespace {

const vec3 kUp(0.0f, 0.0f, 1.0f);

struct SplitFloor {
    ShLattice lattice;
    float wall_x = 0.0f;  // the wall's middle: a cell boundary
    float half_thickness = 0.0f;
    std::vector<Photon> photons;  // a uniform radiance 1 on the floor left of the wall
};

// A 4 x 4 x 4 lattice of ~1 m cells; the floor in the middle of the bottom layer; with `wall`, a
// wall 0.1 cells thick centred on the boundary between cells x = 1 and x = 2 (two quads facing
// out, reaching past the lattice), so the wall's faces lie in different cells.
SplitFloor split_floor(bool wall) {
    SplitFloor f{ShLattice(Bounds3{vec3(0.0f), vec3(4.0f)}, 4, 2)};
    const float s = f.lattice.cell_size();
    const vec3 o = f.lattice.origin();
    f.wall_x = o.x + 2.0f * s;
    f.half_thickness = 0.05f * s;
    const float floor_z = o.z + 0.5f * s;
    std::vector<Mesh> meshes = {
        test::quad(vec3(o.x - 1.0f, o.y - 1.0f, floor_z), vec3(4.0f * s + 2.0f, 0, 0),
                   vec3(0, 4.0f * s + 2.0f, 0))};  // faces +z
    if (wall) {
        const float y0 = o.y - 1.0f, z0 = o.z - 1.0f, span = 4.0f * s + 2.0f;
        meshes.push_back(test::quad(vec3(f.wall_x - f.half_thickness, y0, z0), vec3(0, 0, span),
                                    vec3(0, span, 0)));  // faces -x, towards the lit side
        meshes.push_back(test::quad(vec3(f.wall_x + f.half_thickness, y0, z0), vec3(0, span, 0),
                                    vec3(0, 0, span)));  // faces +x
    }
    f.lattice.measure_surfaces(test::committed_scene(std::move(meshes)));
    const vec3 corner(o.x, o.y, floor_z);
    f.photons = test::uniform_field_photons(
        corner, vec3(f.wall_x - f.half_thickness - o.x, 0, 0), vec3(0, 4.0f * s, 0), kUp,
        vec3(1.0f), 20000, 3);
    f.lattice.inject(f.photons, 1.0f);
    return f;
}

// Largest |coefficient| over samples on the floor at x in [x0, x1] (both samplers).
float largest_sample(const ShLattice& lattice, float x0, float x1) {
    const float s = lattice.cell_size();
    const vec3 o = lattice.origin();
    float largest = 0.0f;
    for (int i = 0; i <= 20; ++i)
        for (int j = 0; j <= 8; ++j) {
            const vec3 p(x0 + (x1 - x0) * float(i) / 20.0f, o.y + 4.0f * s * float(j) / 8.0f,
                         o.z + 0.5f * s);
            for (const ShRgb& sh : {lattice.sample_cubic(p, kUp, 0.25f),
                                    lattice.sample_trilinear(p, kUp, 0.25f)})
                for (int c = 0; c < sh.num_coefficients(); ++c)
                    largest = std::max(largest, glm::compMax(glm::abs(sh[c])));
        }
    return largest;
}

TEST(ShLatticeVisibility, NoLightCrossesAWallThinnerThanACell) {
    SplitFloor split = split_floor(true);
    const float s = split.lattice.cell_size();
    const vec3 o = split.lattice.origin();
    const float lit_side = largest_sample(split.lattice, o.x, split.wall_x - split.half_thickness);
    const float unlit_side =
        largest_sample(split.lattice, split.wall_x + split.half_thickness, o.x + 4.0f * s);
    EXPECT_GT(lit_side, 0.5f);       // L00 of a uniform radiance 1 over the upper hemisphere
    EXPECT_EQ(unlit_side, 0.0f);     // exactly: no cell beyond the wall is read
    split.lattice.blur(2);
    EXPECT_EQ(largest_sample(split.lattice, split.wall_x + split.half_thickness, o.x + 4.0f * s),
              0.0f);

    // The same photons on a floor without the wall: the unlit half near x = wall_x reads them.
    const SplitFloor open = split_floor(false);
    EXPECT_GT(largest_sample(open.lattice, split.wall_x + split.half_thickness, o.x + 4.0f * s),
              0.1f);
}

// The wall's lit cell and its unlit neighbour do not see each other, every other pair of
// neighbours on one side does: the masks follow the wall and nothing else.
TEST(ShLatticeVisibility, CellsAcrossTheWallAreNotBlurredTogether) {
    SplitFloor split = split_floor(true);
    // Cell (1, j, 0) holds the lit floor; blurring with its unlit neighbour (2, j, 0) would move
    // radiance into it. The lit side's total Σ A_c L00 is kept by the blur (it stays on its side).
    const auto total = [&](int x_begin, int x_end) {
        double sum = 0.0;
        for (int x = x_begin; x < x_end; ++x)
            for (int y = 0; y < 4; ++y)
                for (int z = 0; z < 4; ++z) {
                    const size_t cell = split.lattice.cell_index(ivec3(x, y, z));
                    sum += double(split.lattice.surface_area(cell)) *
                           double(split.lattice.cell_radiance(cell)[0].x);
                }
        return sum;
    };
    const double lit_before = total(0, 2);
    split.lattice.blur(3);
    EXPECT_NEAR(total(0, 2), lit_before, 1e-5 * lit_before);
    EXPECT_EQ(total(2, 4), 0.0);
}

}  // namespace
}  // namespace shgi
