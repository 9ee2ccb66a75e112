#include "render/light_tree.h"

#include <emmintrin.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "util/sampling.h"

namespace shgi {
namespace {

// Below this length the cross product of two cone axes gives no rotation axis (they are
// parallel or opposite): the union is then made omnidirectional, which is always conservative.
constexpr float kMinRotationAxis = 1e-6f;
// Importance divides by at least this squared distance (m^2): a point on an emitter's box gets
// a large but finite weight.
constexpr float kMinDistanceSquared = 1e-8f;

float safe_acos(float x) { return std::acos(std::clamp(x, -1.0f, 1.0f)); }

// The smallest cone holding cones a and b (Conty Estevez and Kulla 2018, Algorithm 1).
void cone_union(const LightBounds& a_in, const LightBounds& b_in, LightBounds* out) {
    const LightBounds* a = &a_in;
    const LightBounds* b = &b_in;
    if (b->theta_o > a->theta_o) std::swap(a, b);
    out->theta_e = std::max(a->theta_e, b->theta_e);
    const float theta_d = safe_acos(glm::dot(a->axis, b->axis));
    if (std::min(theta_d + b->theta_o, kPi) <= a->theta_o) {
        out->axis = a->axis;
        out->theta_o = a->theta_o;
        return;
    }
    const float theta_o = 0.5f * (a->theta_o + theta_d + b->theta_o);
    const vec3 rotation_axis = glm::cross(a->axis, b->axis);
    if (theta_o >= kPi || glm::length(rotation_axis) < kMinRotationAxis) {
        out->axis = a->axis;
        out->theta_o = kPi;
        return;
    }
    // Rotate a's axis towards b's by theta_o - a.theta_o (Rodrigues; the rotation axis is
    // perpendicular to it).
    const float theta_r = theta_o - a->theta_o;
    const vec3 k = glm::normalize(rotation_axis);
    out->axis = glm::normalize(a->axis * std::cos(theta_r) + glm::cross(k, a->axis) * std::sin(theta_r));
    out->theta_o = theta_o;
}

LightBounds bounds_union(const LightBounds& a, const LightBounds& b) {
    LightBounds out;
    out.bounds = a.bounds;
    out.bounds.extend(b.bounds.lower);
    out.bounds.extend(b.bounds.upper);
    cone_union(a, b, &out);
    out.energy = a.energy + b.energy;
    return out;
}

vec3 centroid(const LightBounds& light) { return 0.5f * (light.bounds.lower + light.bounds.upper); }

int widest_axis(const Bounds3& box) {
    const vec3 extent = box.upper - box.lower;
    if (extent.x >= extent.y && extent.x >= extent.z) return 0;
    return extent.y >= extent.z ? 1 : 2;
}

}  // namespace

LightTree::LightTree(const std::vector<LightBounds>& emitters) {
    if (emitters.empty()) return;
    std::vector<uint32_t> order(emitters.size());
    std::iota(order.begin(), order.end(), 0u);
    leaf_of_.assign(emitters.size(), 0);
    nodes_.reserve(2 * emitters.size() - 1);
    build(order, 0, order.size(), 0, emitters);
    finish_nodes();
}

void LightTree::finish_nodes() {
    for (Node& node : nodes_) {
        const LightBounds& b = node.bounds;
        node.centre = 0.5f * (b.bounds.lower + b.bounds.upper);
        node.radius = 0.5f * glm::length(b.bounds.upper - b.bounds.lower);
        node.cos_theta_o = std::cos(b.theta_o);
        node.sin_theta_o = std::sin(b.theta_o);
        node.cos_theta_e = std::cos(b.theta_e);
    }
}

// The subtree over order[begin, end): a leaf for one emitter, else a split at the median of
// the centroids along their widest axis (ties kept in emitter order). Returns its node.
uint32_t LightTree::build(std::vector<uint32_t>& order, size_t begin, size_t end,
                          uint32_t parent, const std::vector<LightBounds>& emitters) {
    const uint32_t index = uint32_t(nodes_.size());
    nodes_.emplace_back();
    nodes_[index].parent = parent;
    if (end - begin == 1) {
        nodes_[index].leaf = true;
        nodes_[index].emitter = order[begin];
        nodes_[index].bounds = emitters[order[begin]];
        leaf_of_[order[begin]] = index;
        return index;
    }
    Bounds3 centroids;
    for (size_t i = begin; i < end; ++i) centroids.extend(centroid(emitters[order[i]]));
    const int axis = widest_axis(centroids);
    std::stable_sort(order.begin() + std::ptrdiff_t(begin), order.begin() + std::ptrdiff_t(end),
                     [&](uint32_t a, uint32_t b) {
                         return centroid(emitters[a])[axis] < centroid(emitters[b])[axis];
                     });
    const size_t middle = begin + (end - begin) / 2;
    const uint32_t left = build(order, begin, middle, index, emitters);
    const uint32_t right = build(order, middle, end, index, emitters);
    nodes_[index].left = left;
    nodes_[index].right = right;
    nodes_[index].bounds = bounds_union(nodes_[left].bounds, nodes_[right].bounds);
    return index;
}

namespace {

// cos(max(0, a - b)) and sin(max(0, a - b)) from the cosines and sines of angles a, b in [0, pi].
void cos_sin_of_clamped_difference(float cos_a, float sin_a, float cos_b, float sin_b,
                                   float* cos_out, float* sin_out) {
    if (cos_a >= cos_b) {  // a <= b
        *cos_out = 1.0f;
        *sin_out = 0.0f;
        return;
    }
    *cos_out = cos_a * cos_b + sin_a * sin_b;
    *sin_out = sin_a * cos_b - cos_a * sin_b;
}

}  // namespace

// The header's formula with its angles as cosines and sines: theta - theta_o - theta_u is taken
// as two clamped differences, and theta' > theta_e as cos(theta') < cos(theta_e).
float LightTree::node_importance(const Node& node, const vec3& p) const {
    const LightBounds& b = node.bounds;
    const vec3 to_p = p - node.centre;
    const float distance_squared = glm::dot(to_p, to_p);
    const float radius_squared = node.radius * node.radius;
    // Inside the box every direction is possible: only the energy and the box's size count.
    if (distance_squared <= radius_squared)
        return b.energy / std::max(radius_squared, kMinDistanceSquared);
    const float distance = std::sqrt(distance_squared);
    const float cos_theta = std::clamp(glm::dot(b.axis, to_p) / distance, -1.0f, 1.0f);
    const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
    const float sin_theta_u = node.radius / distance;  // < 1 outside the box
    const float cos_theta_u = std::sqrt(std::max(0.0f, 1.0f - sin_theta_u * sin_theta_u));
    float cos_x, sin_x, cos_prime, sin_prime;
    cos_sin_of_clamped_difference(cos_theta, sin_theta, node.cos_theta_o, node.sin_theta_o,
                                  &cos_x, &sin_x);
    cos_sin_of_clamped_difference(cos_x, sin_x, cos_theta_u, sin_theta_u, &cos_prime,
                                  &sin_prime);
    // Strictly beyond: a spot's cone has theta_e = 0 and lights p at theta' = 0 (cos 1).
    if (cos_prime < node.cos_theta_e) return 0.0f;
    return b.energy * cos_prime / std::max(distance_squared, kMinDistanceSquared);
}

void LightTree::child_probabilities(uint32_t index, const vec3& p, float* left,
                                    float* right) const {
    const float il = node_importance(nodes_[nodes_[index].left], p);
    const float ir = node_importance(nodes_[nodes_[index].right], p);
    const float sum = il + ir;
    *left = sum > 0.0f ? il / sum : 0.0f;
    *right = sum > 0.0f ? ir / sum : 0.0f;
}

float LightTree::importance(const vec3& p) const {
    return empty() ? 0.0f : node_importance(nodes_[0], p);
}

uint32_t LightTree::only_emitter() const {
    return nodes_.size() == 1 ? nodes_[0].emitter : kInvalidId;
}

// node_importance(nodes_[0], p) on four lanes: each lane runs its operations in its order
// (no FMA; std::max(a, b) is `a < b ? b : a` and std::clamp std::min(std::max(v, lo), hi),
// which maxps / minps give with their operands in this order, NaN included), and the branches
// become selections.
void LightTree::importance4(const float x[4], const float y[4], const float z[4],
                            float out[4]) const {
    if (empty()) {
        for (int k = 0; k < 4; ++k) out[k] = 0.0f;
        return;
    }
    const Node& node = nodes_[0];
    const LightBounds& b = node.bounds;
    const __m128 tx = _mm_sub_ps(_mm_loadu_ps(x), _mm_set1_ps(node.centre.x));
    const __m128 ty = _mm_sub_ps(_mm_loadu_ps(y), _mm_set1_ps(node.centre.y));
    const __m128 tz = _mm_sub_ps(_mm_loadu_ps(z), _mm_set1_ps(node.centre.z));
    const __m128 distance_squared = _mm_add_ps(
        _mm_add_ps(_mm_mul_ps(tx, tx), _mm_mul_ps(ty, ty)), _mm_mul_ps(tz, tz));
    const float radius_squared = node.radius * node.radius;
    const __m128 inside = _mm_cmple_ps(distance_squared, _mm_set1_ps(radius_squared));
    const __m128 inside_value =
        _mm_set1_ps(b.energy / std::max(radius_squared, kMinDistanceSquared));
    const __m128 one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps();
    const __m128 distance = _mm_sqrt_ps(distance_squared);
    // glm::dot(b.axis, to_p): (ax tx + ay ty) + az tz.
    const __m128 axis_dot = _mm_add_ps(
        _mm_add_ps(_mm_mul_ps(_mm_set1_ps(b.axis.x), tx), _mm_mul_ps(_mm_set1_ps(b.axis.y), ty)),
        _mm_mul_ps(_mm_set1_ps(b.axis.z), tz));
    const __m128 cos_theta = _mm_min_ps(
        one, _mm_max_ps(_mm_set1_ps(-1.0f), _mm_div_ps(axis_dot, distance)));
    const __m128 sin_theta =
        _mm_sqrt_ps(_mm_max_ps(_mm_sub_ps(one, _mm_mul_ps(cos_theta, cos_theta)), zero));
    const __m128 sin_theta_u = _mm_div_ps(_mm_set1_ps(node.radius), distance);
    const __m128 cos_theta_u =
        _mm_sqrt_ps(_mm_max_ps(_mm_sub_ps(one, _mm_mul_ps(sin_theta_u, sin_theta_u)), zero));
    const auto select = [](__m128 mask, __m128 a, __m128 b_) {
        return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b_));
    };
    // cos_sin_of_clamped_difference, twice.
    const __m128 cos_o = _mm_set1_ps(node.cos_theta_o), sin_o = _mm_set1_ps(node.sin_theta_o);
    const __m128 within_o = _mm_cmpge_ps(cos_theta, cos_o);
    const __m128 cos_x =
        select(within_o, one,
               _mm_add_ps(_mm_mul_ps(cos_theta, cos_o), _mm_mul_ps(sin_theta, sin_o)));
    const __m128 sin_x =
        select(within_o, zero,
               _mm_sub_ps(_mm_mul_ps(sin_theta, cos_o), _mm_mul_ps(cos_theta, sin_o)));
    const __m128 within_u = _mm_cmpge_ps(cos_x, cos_theta_u);
    const __m128 cos_prime =
        select(within_u, one,
               _mm_add_ps(_mm_mul_ps(cos_x, cos_theta_u), _mm_mul_ps(sin_x, sin_theta_u)));
    const __m128 beyond = _mm_cmplt_ps(cos_prime, _mm_set1_ps(node.cos_theta_e));
    const __m128 value =
        _mm_div_ps(_mm_mul_ps(_mm_set1_ps(b.energy), cos_prime),
                   _mm_max_ps(_mm_set1_ps(kMinDistanceSquared), distance_squared));
    _mm_storeu_ps(out, select(inside, inside_value, select(beyond, zero, value)));
}

bool LightTree::sample(const vec3& p, float u, uint32_t* emitter, float* pmf) const {
    if (empty()) return false;
    return sample_below(0, p, u, emitter, pmf);
}

bool LightTree::sample_below(uint32_t node, const vec3& p, float u, uint32_t* emitter,
                             float* pmf) const {
    uint32_t index = node;
    float probability = 1.0f;
    while (!nodes_[index].leaf) {
        float p_left, p_right;
        child_probabilities(index, p, &p_left, &p_right);
        if (!(p_left + p_right > 0.0f)) return false;
        // u is rescaled to the chosen child's share and reused below it.
        if (u < p_left) {
            u = std::min(u / p_left, kOneMinusEpsilon);
            probability *= p_left;
            index = nodes_[index].left;
        } else {
            u = std::min((u - p_left) / p_right, kOneMinusEpsilon);
            probability *= p_right;
            index = nodes_[index].right;
        }
    }
    *emitter = nodes_[index].emitter;
    *pmf = probability;
    return probability > 0.0f;
}

bool LightTree::should_split(const Node& node, const vec3& p) const {
    if (node.leaf) return false;
    const float distance = glm::length(p - node.centre);
    return distance <= node.radius || node.radius > kSplitRadiusRatio * distance;
}

int LightTree::cut(const vec3& p, int max_samples, uint32_t* nodes) const {
    if (empty() || !(node_importance(nodes_[0], p) > 0.0f)) return 0;
    const int limit = std::clamp(max_samples, 1, kMaxLightSplits);
    int count = 1;
    nodes[0] = 0;
    // Each node in turn is replaced by its children (those that can light p) while it should
    // split and the cut has room; a replaced slot is looked at again.
    for (int i = 0; i < count;) {
        const Node& node = nodes_[nodes[i]];
        if (count >= limit || !should_split(node, p)) {
            ++i;
            continue;
        }
        const bool left = node_importance(nodes_[node.left], p) > 0.0f;
        const bool right = node_importance(nodes_[node.right], p) > 0.0f;
        nodes[i] = left ? node.left : node.right;  // the root's importance > 0: one of them is
        if (left && right) nodes[count++] = node.right;
    }
    return count;
}

int LightTree::sample_split(const vec3& p, float u, int max_samples, uint32_t* emitters,
                            float* pmfs) const {
    if (nodes_.size() == 1) {
        // One emitter (a room lit by one lamp): what cut() and sample_below() give for a lone
        // leaf, the emitter with pmf 1 where it can light p, without their loops (~40% of the
        // light selection of such a scene).
        if (!(node_importance(nodes_[0], p) > 0.0f)) return 0;
        emitters[0] = nodes_[0].emitter;
        pmfs[0] = 1.0f;
        return 1;
    }
    uint32_t nodes[kMaxLightSplits];
    const int count = cut(p, max_samples, nodes);
    int written = 0;
    for (int i = 0; i < count; ++i)
        if (sample_below(nodes[i], p, u, &emitters[written], &pmfs[written])) ++written;
    return written;
}

float LightTree::pmf(const vec3& p, uint32_t emitter, int max_samples) const {
    if (emitter >= leaf_of_.size()) return 0.0f;
    uint32_t nodes[kMaxLightSplits];
    const int count = max_samples <= 1 ? (empty() ? 0 : 1) : cut(p, max_samples, nodes);
    if (max_samples <= 1) nodes[0] = 0;  // no cut: the root (pmf() of the one-emitter choice)
    const auto in_cut = [&](uint32_t index) {
        return std::find(nodes, nodes + count, index) != nodes + count;
    };
    // The factors sample_below() multiplies on the way down from the cut node, from the leaf up.
    float probability = 1.0f;
    uint32_t index = leaf_of_[emitter];
    while (!in_cut(index)) {
        if (index == 0) return 0.0f;  // the root, and no node of the cut above the emitter
        const uint32_t parent = nodes_[index].parent;
        float p_left, p_right;
        child_probabilities(parent, p, &p_left, &p_right);
        probability *= index == nodes_[parent].left ? p_left : p_right;
        index = parent;
    }
    return probability;
}

}  // namespace shgi
