// LightTree: many-light selection for next-event estimation by a bounding volume hierarchy over
// the local emitters (point, spot and area lights, emissive triangles), after Conty Estevez and
// Kulla, "Importance Sampling of Many Lights with Adaptive Tree Splitting" (HPG 2018), as
// Cycles 4.0 and later sample lights.
//
// Each node bounds its emitters' positions (an axis-aligned box), their emission directions (an
// orientation cone: axis, theta_o around it that normals span, theta_e beyond that over which
// they emit) and their energy. At a shading point p a node's importance is
//   energy * cos(theta') / d^2,   theta' = max(0, theta - theta_o - theta_u),
// zero when theta' > theta_e: d is the distance from p to the box's centre (clamped to the box's
// half diagonal), theta the angle between the cone's axis and the direction from the centre to
// p, theta_u the half angle the box subtends from p. Descending from the root, a child is chosen
// with probability proportional to its importance; the probability of an emitter is the product
// along its path, computed the same way for sampling and for pdf(), so multiple importance
// sampling stays unbiased. An importance is zero only where no emitter of the node can light p
// (behind every one-sided area light of it, outside every spot cone), never by the shading
// normal: transmissive surfaces receive light from below it.
//
// Splitting (the paper's adaptive tree splitting, section 5): one emitter per next-event estimate
// cannot tell which lights p actually sees. Two rooms split by a wall, a 2000 W lamp in one and a
// 20 W lamp in the other: in the dim room the tree weighs the bright lamp 30-100 times higher,
// so nearly every shadow ray goes to the lamp behind the wall and the lamp that lights the room
// gets a few percent of them. sample_split(p, u, max_samples) therefore samples one emitter from
// each node of a cut of the tree: starting from the root, a node whose bounding sphere is large
// seen from p (radius > kSplitRadiusRatio x distance, or p inside it: where 1/d^2 varies by more
// than ~3x over the node, so its importance says little about its emitters) is replaced by its
// children while the cut holds fewer than max_samples nodes. The cut depends on p and
// max_samples alone, so pmf(p, emitter, max_samples) rebuilds it: an emitter's probability is
// the product of the descent's choices below its cut node, and the estimator (the sum of one
// sample per cut node) stays unbiased with MIS against BSDF sampling. max_samples = 1 is the
// plain one-emitter selection.
//
// Energy is in units that make importance an irradiance estimate (W/m^2): intensity (W/sr) for
// local emitters, irradiance for the distant ones LightSampler weighs against the tree.
// Determinism: building depends only on the emitters' order; sampling only on p and u.
#pragma once

#include <cstdint>
#include <vector>

#include "scene/scene.h"
#include "util/math.h"

namespace shgi {

// Largest cut sample_split() makes (emitters per next-event estimate).
inline constexpr int kMaxLightSplits = 8;
// A node is split when its bounding sphere's radius exceeds this share of its distance from p.
inline constexpr float kSplitRadiusRatio = 0.25f;

// What the tree knows of one emitter.
struct LightBounds {
    Bounds3 bounds;             // its extent (a point light's sphere, an area light's corners)
    vec3 axis{0.0f, 0.0f, 1.0f};
    float theta_o = kPi;        // normals within theta_o of the axis (pi: every direction)
    float theta_e = kPi / 2.0f; // emission beyond the normals (pi/2: a cosine lobe)
    float energy = 0.0f;        // intensity estimate, W/sr (> 0)
};

class LightTree {
  public:
    LightTree() = default;
    // Builds over `emitters` (index i is emitter i in sample() and pmf()).
    explicit LightTree(const std::vector<LightBounds>& emitters);

    bool empty() const { return nodes_.empty(); }
    // The root's importance at p: how much light the whole tree may give p (0: none can).
    float importance(const vec3& p) const;
    // importance() at four points at once, point k = (x[k], y[k], z[k]), bit for bit: the same
    // operations in the same order on four SSE2 lanes (a wave's light stage).
    void importance4(const float x[4], const float y[4], const float z[4], float out[4]) const;
    // The tree's one emitter when it has no other (a room lit by one lamp), else kInvalidId:
    // sample_split() then returns it with pmf 1 wherever importance() is positive.
    uint32_t only_emitter() const;
    // Chooses an emitter for p with u in [0, 1): its index and probability. False when no
    // emitter can light p.
    bool sample(const vec3& p, float u, uint32_t* emitter, float* pmf) const;
    // The probability that sample() chooses `emitter` at p.
    float pmf(const vec3& p, uint32_t emitter) const { return pmf(p, emitter, 1); }

    // One emitter from each node of the cut at p (see the header), each chosen with u as
    // sample() chooses below the root: writes up to max_samples (clamped to [1,
    // kMaxLightSplits]) emitters and their probabilities, returns how many (0: none can light p).
    int sample_split(const vec3& p, float u, int max_samples, uint32_t* emitters,
                     float* pmfs) const;
    // The probability that sample_split(p, ., max_samples) returns `emitter` among its samples.
    float pmf(const vec3& p, uint32_t emitter, int max_samples) const;
    // The cut at p: writes its nodes (at most max_samples, clamped as above) and returns their
    // count; 0 when no emitter can light p.
    int cut(const vec3& p, int max_samples, uint32_t* nodes) const;

  private:
    struct Node {
        LightBounds bounds;
        uint32_t left = 0, right = 0;  // interior: the children
        uint32_t emitter = 0;          // leaf: the emitter
        uint32_t parent = 0;
        bool leaf = false;
        // Of `bounds`, once per tree (finish_nodes): what node_importance() reads at every
        // shading point, so that it needs no trigonometry (pbrt-v4's LightBounds::Importance).
        vec3 centre{0.0f};
        float radius = 0.0f;           // half the box's diagonal
        float cos_theta_o = -1.0f, sin_theta_o = 0.0f, cos_theta_e = 0.0f;
    };
    uint32_t build(std::vector<uint32_t>& order, size_t begin, size_t end, uint32_t parent,
                   const std::vector<LightBounds>& emitters);
    void finish_nodes();
    float node_importance(const Node& node, const vec3& p) const;
    bool should_split(const Node& node, const vec3& p) const;
    // sample() below `node`.
    bool sample_below(uint32_t node, const vec3& p, float u, uint32_t* emitter,
                      float* pmf) const;
    // Probabilities of descending from interior node `index` to its left and right child.
    void child_probabilities(uint32_t index, const vec3& p, float* left, float* right) const;

    std::vector<Node> nodes_;          // nodes_[0] is the root
    std::vector<uint32_t> leaf_of_;    // emitter -> its leaf node
};

}  // namespace shgi
