// QuadGlossy: the glossy field light of the pixels of a 2 x 2 quad that share one field lookup
// (render/lookup_sharing.h), evaluated for the quad's pixels together.
//
// Each pixel of a quad reads the same SH toward its own direction: FieldLookup::glossy's closed
// form (seed 002 §4.2.2: the fitted GGX ZH lobe about the reflected direction, or about its
// dominant direction divided by the upper hemisphere's read for a horizon field) is, per pixel,
// a dependent chain of a square root, divisions and nine-term sums that leaves the CPU waiting.
// Here the quad's pixels are the four lanes of SSE2 vectors: each lane takes the scalar code's
// IEEE operations in its order (no FMA: the build has none, and -ffp-contract=off), so each
// pixel's radiance is the bits FieldLookup::glossy gives it (tests/cpp/render/
// quad_glossy_test.cpp compares them over random inputs and the horizon's edge cases). Lookups
// that the lanes do not cover (Monte Carlo gathers, SH orders 3 and 4, builds without SSE2) go
// through FieldLookup::glossy one pixel at a time.
//
// The quad's pixels also read their field lobes' albedo tables here (burley_albedo, ggx_albedo:
// render/bsdf.h), four views at once in the same lanes (field_albedo_lanes), the same bits.
//
// Use: clear() when the quad's lookup changes, add() each pixel's query before the first
// radiance() (which evaluates every query at once, against the lookup it is given: the same one
// for every slot) or the first albedo read (which reads every query's).
#pragma once

#include "render/bsdf.h"
#include "render/indirect_field.h"

namespace shgi {

class QuadGlossy {
  public:
    static constexpr int kSlots = 4;

    void clear() {
        count_ = 0;
        evaluated_ = false;
        albedos_read_ = false;
    }
    // A pixel's query: its shading normal n, the unit direction towards the viewer wo (world
    // space) and the glossy lobe's roughness; for the albedo tables, cos(N.V) (the local view's
    // z) and the diffuse lobe's roughness. Returns the pixel's slot, or -1 when all are taken.
    // Not after the first radiance() or albedo read since clear().
    int add(const vec3& n, const vec3& wo, float roughness, float cos_nv,
            float diffuse_roughness) {
        if (count_ == kSlots) return -1;
        for (int c = 0; c < 3; ++c) {
            n_[c][count_] = n[c];
            wo_[c][count_] = wo[c];
        }
        roughness_[count_] = roughness;
        cos_nv_[count_] = cos_nv;
        diffuse_roughness_[count_] = diffuse_roughness;
        return count_++;
    }
    float roughness(int slot) const { return roughness_[slot]; }
    vec3 wo(int slot) const { return vec3(wo_[0][slot], wo_[1][slot], wo_[2][slot]); }
    // lookup.glossy(n, wo, roughness, zh) of the slot's query, bit for bit; the first call
    // evaluates every slot.
    vec3 radiance(int slot, const FieldLookup& lookup, GgxZhMemo* zh) {
        if (!evaluated_) evaluate(lookup, zh);
        return vec3(radiance_[0][slot], radiance_[1][slot], radiance_[2][slot]);
    }

    // burley_albedo(cos_nv, diffuse_roughness) and ggx_albedo(cos_nv, roughness) of the slot's
    // query, bit for bit; the first read reads every slot's.
    float burley_albedo(int slot) {
        if (!albedos_read_) read_albedos();
        return albedos_.burley[slot];
    }
    vec2 ggx_albedo(int slot) {
        if (!albedos_read_) read_albedos();
        return vec2(albedos_.ggx[0][slot], albedos_.ggx[1][slot]);
    }

  private:
    void evaluate(const FieldLookup& lookup, GgxZhMemo* zh);
    void read_albedos();

    int count_ = 0;
    bool evaluated_ = false;
    // The queries and their radiance by component, one lane per slot (the lanes' layout).
    alignas(16) float n_[3][kSlots] = {}, wo_[3][kSlots] = {};
    alignas(16) float roughness_[kSlots] = {};
    alignas(16) float radiance_[3][kSlots] = {};
    alignas(16) float cos_nv_[kSlots] = {}, diffuse_roughness_[kSlots] = {};
    bool albedos_read_ = false;
    FieldAlbedoLanes albedos_;
};

}  // namespace shgi
