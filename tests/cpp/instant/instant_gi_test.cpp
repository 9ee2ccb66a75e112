// InstantGi (seed 004): one VPL's L2 SH against the analytic kernel, the settings' refusals, a
// preview sample's view of the field.
#include "instant/instant_gi.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "render/render_test_scenes.h"
#include "sh/sh_irradiance.h"
#include "util/error.h"

namespace shgi {
namespace {

// One VPL projected into L2 SH and dotted with the Lambert (clamped-cosine) lobe gives
// E0 (3/32 + mu/2 + 15 mu^2/32), mu the cosine between the normal and the VPL's direction
// (the L2 truncation of E0 max(0, mu): band factors pi, 2 pi / 3, pi / 4).
TEST(InstantGi, OneVplAgainstTheAnalyticKernel) {
    const vec3 p(0.2f, -0.1f, 0.3f);
    const vec3 to_vpl = glm::normalize(vec3(0.3f, 0.4f, 1.0f));
    const float d = 1.7f;
    InstantVpl vpl;
    vpl.position = p + d * to_vpl;
    const vec3 vpl_normal = glm::normalize(vec3(-0.2f, 0.1f, -1.0f));
    vpl.normal = vpl_normal;
    vpl.power = vec3(2.0f, 1.0f, 0.5f);
    const float cos_vpl = -glm::dot(vpl_normal, to_vpl);
    ASSERT_GT(cos_vpl, 0.0f);
    const vec3 e0 = vpl.power * cos_vpl / (kPi * d * d);
    ShRgb sh(2);
    ASSERT_TRUE(add_vpl_sh(sh, p, vec3(0.0f, 0.0f, 1.0f), vpl, 1.0f, 0.0f));
    // Normals over the whole sphere: mu from -1 to 1.
    for (int i = 0; i <= 40; ++i)
        for (int j = 0; j < 8; ++j) {
            const float theta = kPi * float(i) / 40.0f, phi = 2.0f * kPi * float(j) / 8.0f;
            const vec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                         std::cos(theta));
            const float mu = glm::dot(n, to_vpl);
            const float kernel = 3.0f / 32.0f + mu / 2.0f + 15.0f * mu * mu / 32.0f;
            const vec3 e = sh_irradiance(sh, n);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(e[c] / e0[c], kernel, 1e-5f) << "mu " << mu << " channel " << c;
        }
}

TEST(InstantGi, ClampAndFacing) {
    InstantVpl vpl;
    vpl.position = vec3(0.0f, 0.0f, 0.01f);
    vpl.normal = vec3(0.0f, 0.0f, -1.0f);
    vpl.power = vec3(1.0f);
    ShRgb near(2), clamped(2);
    const vec3 ng(0.0f, 0.0f, 1.0f);
    ASSERT_TRUE(add_vpl_sh(near, vec3(0.0f), ng, vpl, 1.0f, 0.0f));
    ASSERT_TRUE(add_vpl_sh(clamped, vec3(0.0f), ng, vpl, 1.0f, 0.1f));
    // 1/d^2 with d = 0.01 against d clamped to 0.1: 100x.
    EXPECT_NEAR(near[0].x / clamped[0].x, 100.0f, 1e-2f);
    ShRgb none(2);
    EXPECT_FALSE(add_vpl_sh(none, vec3(0.0f), -ng, vpl, 1.0f, 0.0f));  // below the surface
    vpl.normal = -vpl.normal;
    EXPECT_FALSE(add_vpl_sh(none, vec3(0.0f), ng, vpl, 1.0f, 0.0f));   // faces away
    EXPECT_EQ(none[0], vec3(0.0f));
}

// A closed 1 m box, Lambert 0.7 inside, lit by a 100 W point light off its centre, committed.
void build_lit_box(Scene& scene) {
    scene.add_material(test::lambert(0.7f));
    scene.add_instance(scene.add_mesh(test::inward_box(1.0f)), mat4(1.0f));
    scene.add_light(test::point_light(vec3(0.3f, 0.2f, 0.5f), 100.0f));
    scene.set_world(test::black_world());
    scene.commit();
}

// A preview sample's view (sample_view) reads that sample's passes alone: over a field of 8
// passes at 4 per sample, sample 0's lookups are those of the field of the first 4 passes (the
// same VPLs, the same scale, summed in the same order: the same bits), and sample 1's read the
// other 4; the view reads a quarter of the VPLs a lookup of the whole field reads.
TEST(InstantGi, SampleViewLooksUpTheSamplesPassesAlone) {
    Scene scene;
    build_lit_box(scene);
    InstantGiSettings settings;
    settings.seed = 7;
    settings.passes_per_sample = 4;
    InstantGi solver(scene, settings);
    for (int i = 0; i < 4; ++i) solver.refine();
    const std::shared_ptr<const InstantGiField> four = solver.field();
    for (int i = 0; i < 4; ++i) solver.refine();
    const std::shared_ptr<const InstantGiField> eight = solver.field();
    ASSERT_EQ(eight->sample_passes(1), (std::vector<uint64_t>{4, 5, 6, 7}));
    const vec3 p(0.1f, -0.2f, -0.99f), n(0.0f, 0.0f, 1.0f);  // on the floor, facing the room
    const std::unique_ptr<const IndirectField> first = eight->sample_view(0);
    ASSERT_NE(first, nullptr);
    EXPECT_TRUE(first->shades_first_surfaces());
    const ShRgb view = first->radiance_sh(p, n), expected = four->radiance_sh(p, n);
    ASSERT_GT(expected[0].x, 0.0f);
    for (int i = 0; i < 9; ++i) EXPECT_EQ(view[i], expected[i]) << "coefficient " << i;
    const InstantGiLookupCounts counts = eight->lookup_counts();
    EXPECT_EQ(counts.lookups, 1u);  // the view's; four's are its own
    EXPECT_EQ(counts.vpls, four->vpl_count());
    const ShRgb second = eight->sample_view(1)->radiance_sh(p, n);
    EXPECT_NE(second[0], view[0]);  // other VPLs ...
    EXPECT_NEAR(second[0].x / view[0].x, 1.0f, 0.5f);  // ... of the same light
    EXPECT_EQ(eight->lookup_counts().vpls, eight->vpl_count() - four->vpl_count());
}

// Where a final gather ray lands (gather_lookup) one set is read, scaled by the sets: over the
// sets (u at the middle of each's share) the lookups average to the lookup of every set, for
// the field and for a sample's view of it (that sample's passes), and each reads one set's VPLs.
// With gather_near_radius the view reads the VPLs within it from every set and the rest from
// the one set: the same average, and a lookup reads the set's far VPLs and every near one.
TEST(InstantGi, GatherLookupsOfEverySetAverageToTheWholeLookup) {
    Scene scene;
    build_lit_box(scene);
    const vec3 p(-0.2f, 0.3f, -0.99f), n(0.0f, 0.0f, 1.0f), wo(0.0f, 0.6f, 0.8f);
    for (const float radius : {0.0f, 0.5f}) {
        SCOPED_TRACE(radius);
        InstantGiSettings settings;
        settings.seed = 3;
        settings.passes_per_sample = 2;
        settings.gather_near_radius = radius;
        InstantGi solver(scene, settings);
        for (int i = 0; i < 4; ++i) solver.refine();
        const std::shared_ptr<const InstantGiField> field = solver.field();
        const std::unique_ptr<const IndirectField> view = field->sample_view(1);  // passes 2, 3
        const size_t sets = field->sets().size();
        ASSERT_EQ(sets, 16u);
        for (const IndirectField* whole : {static_cast<const IndirectField*>(field.get()),
                                           view.get()}) {
            const ShRgb expected = whole->radiance_sh(p, n);
            ASSERT_GT(expected[0].x, 0.0f);
            ShRgb mean(2);
            std::vector<float> dc;
            for (size_t k = 0; k < sets; ++k) {
                const FieldLookup one =
                    whole->gather_lookup(p, n, wo, (float(k) + 0.5f) / 16.0f);
                for (int i = 0; i < 9; ++i) mean[i] += one.radiance[i] / float(sets);
                dc.push_back(one.radiance[0].x);
            }
            for (int i = 0; i < 9; ++i)
                for (int c = 0; c < 3; ++c)
                    EXPECT_NEAR(mean[i][c], expected[i][c], 1e-5f * std::abs(expected[0][c]))
                        << "coefficient " << i << " channel " << c;
            // Different sets, so different answers (each of about the whole's size).
            EXPECT_NE(*std::min_element(dc.begin(), dc.end()),
                      *std::max_element(dc.begin(), dc.end()));
        }
        // Set 0's VPLs of the sample's passes (passes 2 and 3) beyond the radius, and every
        // set's within it.
        uint64_t expected_vpls = 0;
        for (size_t s = 0; s < sets; ++s) {
            const std::vector<uint64_t>& ends = field->pass_ends()[s];
            for (uint64_t v = ends[1]; v < ends[3]; ++v) {
                const vec3 d = field->sets()[s][v].position - p;
                const bool near = glm::dot(d, d) < radius * radius;
                if (near || s == 0) ++expected_vpls;
            }
        }
        const std::unique_ptr<const IndirectField> counted = field->sample_view(1);  // reset
        counted->gather_lookup(p, n, wo, 0.0f);
        const InstantGiLookupCounts counts = field->lookup_counts();
        EXPECT_EQ(counts.lookups, 1u);
        EXPECT_EQ(counts.vpls, expected_vpls);
        if (radius == 0.0f) {  // one set alone: a sixteenth of the view's whole lookup
            const std::vector<uint64_t>& ends = field->pass_ends()[0];
            EXPECT_EQ(counts.vpls, ends[3] - ends[1]);
        } else {  // the near VPLs of other sets too
            EXPECT_GT(counts.vpls, field->pass_ends()[0][3] - field->pass_ends()[0][1]);
        }
    }
}

TEST(InstantGi, SettingsRefusalsNameTheField) {
    auto refused = [](auto edit, const char* field) {
        InstantGiSettings s;
        edit(s);
        try {
            validate_instant_gi_settings(s);
            ADD_FAILURE() << field << " accepted";
        } catch (const InvalidArgument& e) {
            EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
        }
    };
    validate_instant_gi_settings(InstantGiSettings{});
    refused([](InstantGiSettings& s) { s.sets_x = 0; }, "sets_x");
    refused([](InstantGiSettings& s) { s.sets_y = 17; }, "sets_y");
    refused([](InstantGiSettings& s) { s.photons_per_set = 0; }, "photons_per_set");
    refused([](InstantGiSettings& s) { s.vpl_bounces = 0; }, "vpl_bounces");
    refused([](InstantGiSettings& s) { s.glossy_bounces = -1; }, "glossy_bounces");
    refused([](InstantGiSettings& s) { s.glossy_bounces = 65; }, "glossy_bounces");
    refused([](InstantGiSettings& s) { s.clamp_distance = NAN; }, "clamp_distance");
    refused([](InstantGiSettings& s) { s.depth_threshold = -1.0f; }, "depth_threshold");
    refused([](InstantGiSettings& s) { s.normal_threshold = 2.0f; }, "normal_threshold");
    refused([](InstantGiSettings& s) { s.near_field_reach = NAN; }, "near_field_reach");
    refused([](InstantGiSettings& s) { s.near_field_reach = 65.0f; }, "near_field_reach");
    refused([](InstantGiSettings& s) { s.gather_near_radius = -1.0f; }, "gather_near_radius");
}

}  // namespace
}  // namespace shgi
