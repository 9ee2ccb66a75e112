// The lookup sharing stage on hand-made G-buffers: the lead rotates with the sample index and
// skips pixels without a surface; pixels within the reuse distance whose normals agree follow,
// a pixel beyond the distance or ~20 degrees off does not.
#include "render/lookup_sharing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "render/path_integrator.h"

namespace shgi {
namespace {

constexpr float kReuse = 0.1f;  // m

// A 2 x 2 G-buffer whose four pixels lie on the plane z = 0, 1 cm apart, normals +Z.
GBuffer flat_quad() {
    GBuffer g(2, 2);
    for (uint32_t i = 0; i < 4; ++i) {
        g.position[i] = vec3(0.01f * float(i % 2), 0.01f * float(i / 2), 0.0f);
        g.shading_normal[i] = vec3(0.0f, 0.0f, 1.0f);
        g.object_id[i] = 0;
        g.material_id[i] = 0;
    }
    return g;
}

const uint32_t kQuad[4] = {0, 1, 2, 3};

TEST(LookupSharing, LeadRotatesWithTheSampleIndexAndTheOthersFollow) {
    const GBuffer g = flat_quad();
    for (uint64_t s = 0; s < 8; ++s) {
        const QuadLookupSharing sharing = share_quad_lookup(g, kQuad, 4, s, kReuse);
        EXPECT_EQ(sharing.lead, uint32_t(s % 4));
        EXPECT_EQ(sharing.followers, 0xFu & ~(1u << (s % 4))) << "sample " << s;
    }
}

TEST(LookupSharing, LeadSkipsMissesAndNoSurfaceMeansNoLead) {
    GBuffer g = flat_quad();
    g.object_id[1] = GBuffer::kNoSurface;
    const QuadLookupSharing sharing = share_quad_lookup(g, kQuad, 4, 1, kReuse);
    EXPECT_EQ(sharing.lead, 2u);                            // pixel 1 missed: the next one leads
    EXPECT_EQ(sharing.followers, (1u << 0) | (1u << 3));   // the miss follows nobody
    for (uint32_t i = 0; i < 4; ++i) g.object_id[i] = GBuffer::kNoSurface;
    EXPECT_EQ(share_quad_lookup(g, kQuad, 4, 0, kReuse).lead, QuadLookupSharing::kNoLead);
}

// The lead is the first pixel with a surface from (sample + k) mod size on, for every quad size
// (border quads have 1 to 3 pixels) and for sample indices far beyond 2^32, with any pixels missed.
TEST(LookupSharing, LeadStartsAtTheSampleIndexModTheQuadSize) {
    GBuffer g = flat_quad();
    for (uint32_t missed = 0; missed < 16; ++missed) {
        for (uint32_t i = 0; i < 4; ++i)
            g.object_id[i] = (missed >> i) & 1 ? GBuffer::kNoSurface : 0;
        for (uint32_t size = 1; size <= 4; ++size)
            for (const uint64_t base : {uint64_t(0), uint64_t(1) << 33, ~uint64_t(0) - 64})
                for (uint64_t s = base; s < base + 24; ++s) {
                    uint32_t expected = QuadLookupSharing::kNoLead;
                    for (uint32_t k = 0; k < size; ++k) {
                        const uint32_t candidate = uint32_t((s + k) % size);
                        if (g.has_surface(kQuad[candidate])) {
                            expected = candidate;
                            break;
                        }
                    }
                    EXPECT_EQ(share_quad_lookup(g, kQuad, size, s, kReuse).lead, expected)
                        << "size " << size << ", sample " << s << ", missed " << missed;
                }
    }
}

TEST(LookupSharing, FarOrTurnedPixelsMakeTheirOwnLookup) {
    GBuffer g = flat_quad();
    g.position[1].z = 2.0f * kReuse;  // a depth jump
    const float angle = 20.0f * kPi / 180.0f;  // past kReuseMinCosine's ~11 degrees
    g.shading_normal[2] = vec3(std::sin(angle), 0.0f, std::cos(angle));
    const QuadLookupSharing sharing = share_quad_lookup(g, kQuad, 4, 0, kReuse);
    EXPECT_EQ(sharing.lead, 0u);
    EXPECT_EQ(sharing.followers, 1u << 3);
    // A border quad of two pixels (size 2) uses only its own pixels.
    const uint32_t pair[2] = {2, 3};
    const QuadLookupSharing border = share_quad_lookup(g, pair, 2, 1, kReuse);
    EXPECT_EQ(border.lead, 1u);
    EXPECT_EQ(border.followers, 0u);  // pixel 2's normal is turned away from pixel 3's
}

// The irradiance the paths of a quad share (IrradianceMemo) is the one the lookup gives, bit for
// bit: for a repeated normal, for a new one, for a normal that differs only in the sign of a zero,
// and, after reset(), for another lookup at the same normal.
TEST(LookupSharing, IrradianceMemoGivesTheLookupsOwnIrradiance) {
    FieldLookup lookup{ShRgb(2), vec3(0.0f)};
    for (int i = 0; i < 9; ++i)
        lookup.radiance[i] = vec3(0.3f + 0.1f * float(i), -0.05f * float(i), 0.2f);
    const auto same_bits = [](const vec3& a, const vec3& b) {
        return std::memcmp(&a, &b, sizeof(vec3)) == 0;
    };
    const vec3 up(0.0f, 0.0f, 1.0f), minus_zero(-0.0f, 0.0f, 1.0f);
    const vec3 tilted = glm::normalize(vec3(1.0f, 0.0f, 1.0f));
    IrradianceMemo memo;
    EXPECT_TRUE(same_bits(memo.irradiance(lookup, up), lookup.irradiance(up)));
    EXPECT_TRUE(same_bits(memo.irradiance(lookup, up), lookup.irradiance(up)));
    EXPECT_TRUE(same_bits(memo.irradiance(lookup, tilted), lookup.irradiance(tilted)));
    EXPECT_TRUE(same_bits(memo.irradiance(lookup, minus_zero), lookup.irradiance(minus_zero)));
    EXPECT_TRUE(same_bits(memo.irradiance(lookup, tilted), lookup.irradiance(tilted)));
    FieldLookup brighter = lookup;
    brighter.radiance[0] *= 2.0f;
    ASSERT_FALSE(same_bits(brighter.irradiance(tilted), lookup.irradiance(tilted)));
    memo.reset();
    EXPECT_TRUE(same_bits(memo.irradiance(brighter, tilted), brighter.irradiance(tilted)));
}

}  // namespace
}  // namespace shgi
