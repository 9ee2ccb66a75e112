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
// Energy is in units that make importance an irradiance estimate (W/m^2): intensity (W/sr) for
// local emitters, irradiance for the distant ones LightSampler weighs against the tree.
// Determinism: building depends only on the emitters' order; sampling only on p and u.
#pragma once

#include <cstdint>
#include <vector>

#include "scene/scene.h"
#include "util/math.h"

namespace shgi {

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
    // Chooses an emitter for p with u in [0, 1): its index and probability. False when no
    // emitter can light p.
    bool sample(const vec3& p, float u, uint32_t* emitter, float* pmf) const;
    // The probability that sample() chooses `emitter` at p.
    float pmf(const vec3& p, uint32_t emitter) const;

  private:
    struct Node {
        LightBounds bounds;
        uint32_t left = 0, right = 0;  // interior: the children
        uint32_t emitter = 0;          // leaf: the emitter
        uint32_t parent = 0;
        bool leaf = false;
    };
    uint32_t build(std::vector<uint32_t>& order, size_t begin, size_t end, uint32_t parent,
                   const std::vector<LightBounds>& emitters);
    float node_importance(const Node& node, const vec3& p) const;
    // Probabilities of descending from interior node `index` to its left and right child.
    void child_probabilities(uint32_t index, const vec3& p, float* left, float* right) const;

    std::vector<Node> nodes_;          // nodes_[0] is the root
    std::vector<uint32_t> leaf_of_;    // emitter -> its leaf node
};

}  // namespace shgi
