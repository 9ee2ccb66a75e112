// QuadGlossy (render/quad_glossy.h) gives each slot the bits FieldLookup::glossy gives its query:
// over random SH, normals, views and roughnesses, with and without the horizon flag, for SH
// orders 0 to 2 (the lanes) and 3 and Monte Carlo gathers (the scalar fallback), for 1 to 4
// slots, with and without a band-factor memo; and at the horizon's edge cases: views from
// below the surface, grazing views, roughness 0 and 1, and a dominant direction of (near) zero
// length, which falls back to the normal. The same queries' albedo reads are burley_albedo's and
// ggx_albedo's (render/bsdf.h) bit for bit.
#include "render/quad_glossy.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "sh/ggx_zh.h"
#include "util/rng.h"
#include "util/sampling.h"

namespace shgi {
namespace {

bool same_bits(const vec3& a, const vec3& b) { return std::memcmp(&a, &b, sizeof(vec3)) == 0; }

struct Query {
    vec3 n, wo;
    float roughness;
};

FieldLookup random_lookup(Pcg32& rng, int order, bool horizon) {
    FieldLookup lookup{ShRgb(order), vec3(0.0f)};
    for (int i = 0; i < lookup.radiance.num_coefficients(); ++i)
        lookup.radiance[i] = vec3(rng.next_float(), rng.next_float(), rng.next_float()) * 2.0f -
                             vec3(i == 0 ? 0.0f : 1.0f);
    lookup.horizon = horizon;
    return lookup;
}

// Checks the albedo reads of every slot of `quad`, filled with `queries` as expect_lookup_bits
// does, against burley_albedo and ggx_albedo (render/bsdf.h).
void expect_albedo_bits(QuadGlossy& quad, const std::vector<Query>& queries) {
    for (size_t k = 0; k < queries.size(); ++k) {
        const Query& q = queries[k];
        const float cos_nv = glm::dot(q.n, q.wo);
        const float burley = burley_albedo(cos_nv, 1.0f - q.roughness);
        const vec2 ggx = ggx_albedo(cos_nv, q.roughness);
        const float lane_burley = quad.burley_albedo(int(k));
        const vec2 lane_ggx = quad.ggx_albedo(int(k));
        EXPECT_EQ(std::memcmp(&lane_burley, &burley, sizeof(float)), 0)
            << "slot " << k << " cos " << cos_nv << ": " << lane_burley << " against " << burley;
        EXPECT_EQ(std::memcmp(&lane_ggx, &ggx, sizeof(vec2)), 0)
            << "slot " << k << " cos " << cos_nv << " roughness " << q.roughness << ": ("
            << lane_ggx.x << ", " << lane_ggx.y << ") against (" << ggx.x << ", " << ggx.y << ")";
    }
}

// Checks every slot of a QuadGlossy filled with `queries` (at most four) against
// FieldLookup::glossy, with a memo (as the preview) and without.
void expect_lookup_bits(const FieldLookup& lookup, const std::vector<Query>& queries) {
    for (bool with_memo : {true, false}) {
        GgxZhMemo memo, reference_memo;
        QuadGlossy quad;
        quad.clear();
        std::vector<int> slots;
        // The albedo tables' query: cos(N.V) as the path's local view gives it, and a diffuse
        // roughness other than the glossy one.
        for (const Query& q : queries)
            slots.push_back(
                quad.add(q.n, q.wo, q.roughness, glm::dot(q.n, q.wo), 1.0f - q.roughness));
        // The albedos read before the radiance in one pass, after it in the other.
        if (!with_memo) expect_albedo_bits(quad, queries);
        for (size_t k = 0; k < queries.size(); ++k) {
            const Query& q = queries[k];
            ASSERT_EQ(slots[k], int(k));
            const vec3 lanes = quad.radiance(slots[k], lookup, with_memo ? &memo : nullptr);
            const vec3 scalar = lookup.glossy(q.n, q.wo, q.roughness,
                                              with_memo ? &reference_memo : nullptr);
            EXPECT_TRUE(same_bits(lanes, scalar))
                << "order " << lookup.radiance.order << " horizon " << lookup.horizon
                << " slot " << k << " roughness " << q.roughness << ": lanes (" << lanes.x
                << ", " << lanes.y << ", " << lanes.z << ") against (" << scalar.x << ", "
                << scalar.y << ", " << scalar.z << ")";
        }
        if (with_memo) expect_albedo_bits(quad, queries);
    }
}

// A roughness whose dominant-direction lean, (1 - a)(sqrt(1 - a) + a) with a = roughness^2,
// is within 1e-7 of 1/2 (found by bisection: the lean falls from 1 to 0 over [0, 1]), so that a
// view from straight below n gives a dominant direction of length below 1e-6.
float roughness_of_half_lean() {
    float lo = 0.0f, hi = 1.0f;
    for (int i = 0; i < 60; ++i) {
        const float mid = 0.5f * (lo + hi);
        const float alpha = mid * mid;
        const float lean = (1.0f - alpha) * (std::sqrt(1.0f - alpha) + alpha);
        (lean > 0.5f ? lo : hi) = mid;
    }
    return lo;
}

TEST(QuadGlossy, LanesAreFieldLookupGlossyBitForBit) {
    Pcg32 rng(47, 16);
    for (int trial = 0; trial < 4000; ++trial) {
        const int order = int(rng.next_u32(4));  // 0..2 in lanes, 3 scalar
        const FieldLookup lookup = random_lookup(rng, order, trial % 2 == 0);
        const int count = 1 + int(rng.next_u32(4));
        std::vector<Query> queries;
        for (int k = 0; k < count; ++k) {
            const vec3 n = sample_uniform_sphere(rng.next_vec2());
            // Mostly views above the surface, as a camera's; some from below and grazing.
            vec3 wo = sample_uniform_sphere(rng.next_vec2());
            if (rng.next_float() < 0.8f && glm::dot(wo, n) < 0.0f) wo = -wo;
            if (rng.next_float() < 0.1f) wo = glm::normalize(glm::cross(n, wo));  // grazing
            const float pick = rng.next_float();
            const float roughness = pick < 0.1f ? 0.0f : pick < 0.2f ? 1.0f : rng.next_float();
            queries.push_back({n, wo, roughness});
        }
        expect_lookup_bits(lookup, queries);
        if (HasFailure()) return;
    }
}

TEST(QuadGlossy, HorizonEdgeCasesAreFieldLookupGlossyBitForBit) {
    Pcg32 rng(47, 17);
    const float half_lean = roughness_of_half_lean();
    const vec3 axes[3] = {vec3(1.0f, 0.0f, 0.0f), vec3(0.0f, -1.0f, 0.0f), vec3(0.0f, 0.0f, 1.0f)};
    for (int order = 0; order <= 3; ++order)
        for (bool horizon : {true, false}) {
            const FieldLookup lookup = random_lookup(rng, order, horizon);
            for (const vec3& n : axes) {
                // Straight from below at the half lean: the dominant direction is ~0 long
                // (checked below), so it is n.
                const vec3 below = -n;
                const vec3 grazing = vec3(n.y, n.z, n.x);  // perpendicular to the axis n
                expect_lookup_bits(lookup, {{n, below, half_lean},
                                            {n, grazing, 0.0f},
                                            {n, n, 1.0f},
                                            {n, below, 0.0f}});
                expect_lookup_bits(lookup, {{n, grazing, half_lean}, {n, below, 1.0f}});
            }
        }
    const float alpha = half_lean * half_lean;
    const float lean = (1.0f - alpha) * (std::sqrt(1.0f - alpha) + alpha);
    EXPECT_LT((1.0f - 2.0f * lean) * (1.0f - 2.0f * lean), 1e-12f);
}

TEST(QuadGlossy, GathersGoThroughFieldLookupGlossy) {
    Pcg32 rng(47, 18);
    FieldLookup lookup = random_lookup(rng, 2, true);
    lookup.glossy_rays = 8;
    lookup.gather_key = 1234;
    const vec3 n(0.0f, 0.0f, 1.0f);
    expect_lookup_bits(lookup, {{n, glm::normalize(vec3(0.3f, 0.1f, 0.9f)), 0.4f},
                                {n, glm::normalize(vec3(-0.5f, 0.2f, 0.4f)), 0.7f}});
}

TEST(QuadGlossy, AFifthQueryFindsNoSlot) {
    QuadGlossy quad;
    quad.clear();
    const vec3 n(0.0f, 0.0f, 1.0f);
    for (int k = 0; k < QuadGlossy::kSlots; ++k) EXPECT_EQ(quad.add(n, n, 0.5f, 1.0f, 0.5f), k);
    EXPECT_EQ(quad.add(n, n, 0.5f, 1.0f, 0.5f), -1);
}

}  // namespace
}  // namespace shgi
