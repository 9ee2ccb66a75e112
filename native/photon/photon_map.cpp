#include "photon/photon_map.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

#include <nanoflann.hpp>

#include "util/error.h"
#include "util/parallel.h"

namespace shgi {
namespace {

// nanoflann's view of the photons' positions. It points at the vector's buffer, which a move
// of the vector (and so of the PhotonMap) hands over unchanged.
struct PhotonCloud {
    const Photon* photons = nullptr;
    size_t count = 0;

    size_t kdtree_get_point_count() const { return count; }
    float kdtree_get_pt(uint32_t index, size_t axis) const {
        return photons[index].position[int(axis)];
    }
    template <typename BoundingBox>
    bool kdtree_get_bbox(BoundingBox&) const {
        return false;  // let nanoflann compute it
    }
};

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<float, PhotonCloud, float, uint32_t>, PhotonCloud, 3, uint32_t>;

// Photons per k-d tree leaf. With a leaf's photons adjacent in memory (build_trees), a larger
// leaf than nanoflann's default of 10 means fewer nodes visited for cheap extra distances: a
// k = 50 query in photon_lattice_bench's caustic took 8.4-9.7, 7.2-8.6, 6.1-6.7 and 5.7 us with
// leaves of 10, 16, 32 and 64 photons over 10^6 photons, and 3.3-4.5, 3.3, 3.3 and 3.6-4.3 us
// over 10^5 (in cache), where 64 loses.
constexpr size_t kLeafSize = 32;
// Photons per shard (one nanoflann tree): its build takes ~0.1 s, the longest a cancel waits.
constexpr size_t kShardPhotons = size_t(1) << 18;

// The k nearest photons strictly within a radius, sorted by distance: a nanoflann result set
// whose search radius shrinks to the k-th distance once k are found.
class NearestWithin {
  public:
    using DistanceType = float;
    using IndexType = uint32_t;

    // `expected` (at most capacity) sizes the buffers: a huge k over a small map allocates little.
    NearestWithin(size_t capacity, float radius_squared, size_t expected)
        : capacity_(capacity), radius_squared_(radius_squared) {
        indices_.reserve(expected);
        distances_squared_.reserve(expected);
    }

    // Photon index of the tree's point 0: results are map indices.
    void set_first(uint32_t first) { first_ = first; }
    bool full() const { return indices_.size() == capacity_; }
    float worstDist() const { return full() ? distances_squared_.back() : radius_squared_; }

    bool addPoint(float distance_squared, uint32_t local_index) {
        if (distance_squared >= worstDist()) return true;  // keep searching
        const uint32_t index = first_ + local_index;
        if (full()) {
            indices_.pop_back();
            distances_squared_.pop_back();
        }
        // Insertion sort: k is small (tens to a few hundred).
        size_t i = indices_.size();
        indices_.push_back(index);
        distances_squared_.push_back(distance_squared);
        for (; i > 0 && distances_squared_[i - 1] > distance_squared; --i) {
            indices_[i] = indices_[i - 1];
            distances_squared_[i] = distances_squared_[i - 1];
        }
        indices_[i] = index;
        distances_squared_[i] = distance_squared;
        return true;
    }

    const std::vector<uint32_t>& indices() const { return indices_; }
    const std::vector<float>& distances_squared() const { return distances_squared_; }

  private:
    size_t capacity_;
    float radius_squared_;
    uint32_t first_ = 0;
    std::vector<uint32_t> indices_;
    std::vector<float> distances_squared_;
};

// One nanoflann tree over the photons [first, first + cloud.count) of the map.
struct Shard {
    PhotonCloud cloud;
    uint32_t first = 0;
    std::unique_ptr<KdTree> tree;
};

// The median splits above the shards. A leaf names its shard; an inner node's first child holds
// the photons whose coordinate along `axis` is <= split, its second those >= split.
struct SplitNode {
    int axis = 0;
    float split = 0.0f;
    std::array<uint32_t, 2> children{};
    int32_t shard = -1;
};

}  // namespace

struct PhotonMap::Index {
    std::vector<SplitNode> nodes;  // nodes[0] is the root
    std::vector<Shard> shards;     // not resized once the trees, which refer to clouds, exist

    // Splits photons [begin, end) at the median of their widest axis until the parts fit a
    // shard; returns the node. Polls cancel before each split (one nth_element over 10^7
    // photons takes ~0.1 s).
    uint32_t split(Photon* photons, size_t begin, size_t end, const Progress* progress) {
        throw_if_cancelled(progress);
        const uint32_t node = uint32_t(nodes.size());
        nodes.emplace_back();
        if (end - begin <= kShardPhotons) {
            nodes[node].shard = int32_t(shards.size());
            shards.push_back(Shard{PhotonCloud{photons + begin, end - begin}, uint32_t(begin), {}});
            return node;
        }
        vec3 lo(std::numeric_limits<float>::infinity()), hi(-lo);
        for (size_t i = begin; i < end; ++i) {
            lo = glm::min(lo, photons[i].position);
            hi = glm::max(hi, photons[i].position);
        }
        const vec3 extent = hi - lo;
        const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0
                         : extent.y >= extent.z                      ? 1
                                                                     : 2;
        const size_t middle = begin + (end - begin) / 2;
        std::nth_element(photons + begin, photons + middle, photons + end,
                         [axis](const Photon& a, const Photon& b) {
                             return a.position[axis] < b.position[axis];
                         });
        const float at = photons[middle].position[axis];
        const uint32_t first = split(photons, begin, middle, progress);
        const uint32_t second = split(photons, middle, end, progress);
        SplitNode& inner = nodes[node];  // after the recursion: nodes has grown
        inner.axis = axis;
        inner.split = at;
        inner.children = {first, second};
        return node;
    }

    // One tree per shard, in parallel (each is built from its own photons only, so the trees do
    // not depend on the thread count). Then each shard's photons are put in its tree's order, so
    // that a leaf's photons are adjacent in memory: nanoflann reaches points through an index
    // array, and over a map larger than the caches each point of a leaf was a cache miss (a
    // k = 50 query over 10^6 photons took ~15 us, twice as long as with the photons in order).
    // The index array becomes the identity; the tree's nodes hold ranges of it and split values,
    // which the permutation leaves valid.
    void build_trees(Photon* photons, Progress* progress) {
        parallel_for(0, shards.size(), 1, [&](uint64_t begin, uint64_t end) {
            std::vector<Photon> ordered;
            for (uint64_t s = begin; s < end; ++s) {
                Shard& shard = shards[s];
                shard.tree = std::make_unique<KdTree>(
                    3, shard.cloud, nanoflann::KDTreeSingleIndexAdaptorParams(kLeafSize));
                std::vector<uint32_t>& order = shard.tree->vAcc;
                Photon* own = photons + shard.first;
                ordered.resize(order.size());
                for (size_t i = 0; i < order.size(); ++i) ordered[i] = own[order[i]];
                std::copy(ordered.begin(), ordered.end(), own);
                std::iota(order.begin(), order.end(), uint32_t(0));
            }
        }, progress);
    }

    // Adds to `nearest` the photons of node's subtree that are closer than its current worst
    // distance: the near side first, the far side only when its half-space is closer than that.
    template <typename ResultSet>
    void search(uint32_t node, const float query[3], ResultSet& nearest) const {
        const SplitNode& at = nodes[node];
        if (at.shard >= 0) {
            const Shard& shard = shards[size_t(at.shard)];
            nearest.set_first(shard.first);
            shard.tree->findNeighbors(nearest, query, nanoflann::SearchParams());
            return;
        }
        const float offset = query[at.axis] - at.split;
        const int near = offset < 0.0f ? 0 : 1;
        search(at.children[near], query, nearest);
        if (offset * offset < nearest.worstDist()) search(at.children[1 - near], query, nearest);
    }
};

PhotonMap::PhotonMap() = default;
PhotonMap::~PhotonMap() = default;
PhotonMap::PhotonMap(PhotonMap&&) noexcept = default;
PhotonMap& PhotonMap::operator=(PhotonMap&&) noexcept = default;

PhotonMap::PhotonMap(std::vector<Photon> photons, float power_scale, Progress* progress)
    : photons_(std::move(photons)), power_scale_(power_scale) {
    if (!std::isfinite(power_scale) || power_scale < 0.0f)
        throw InvalidArgument(format_message("PhotonMap: power_scale is ", power_scale,
                                             "; it must be finite and >= 0"));
    if (photons_.size() >= size_t(std::numeric_limits<uint32_t>::max()))
        throw InvalidArgument(format_message("PhotonMap: ", photons_.size(),
                                             " photons; at most 2^32 - 2 fit one map"));
    for (size_t i = 0; i < photons_.size(); ++i) {
        const vec3& p = photons_[i].position;
        if (!is_finite(p))
            throw InvalidArgument(format_message("PhotonMap: photons[", i, "].position is (", p.x,
                                                 ", ", p.y, ", ", p.z, "); it must be finite"));
    }
    if (photons_.empty()) return;
    auto index = std::make_unique<Index>();
    index->split(photons_.data(), 0, photons_.size(), progress);
    index->build_trees(photons_.data(), progress);
    index_ = std::move(index);
}

size_t PhotonMap::shard_count() const { return index_ ? index_->shards.size() : 0; }

vec3 PhotonMap::irradiance(const vec3& p, const vec3& n, int k, float max_radius) const {
    if (k < 1)
        throw InvalidArgument(
            format_message("PhotonMap::irradiance: k is ", k, "; it must be >= 1"));
    if (!(std::isfinite(max_radius) && max_radius > 0.0f))
        throw InvalidArgument(format_message("PhotonMap::irradiance: max_radius is ", max_radius,
                                             "; it must be finite and > 0"));
    if (!index_) return vec3(0.0f);
    NearestWithin nearest(size_t(k), max_radius * max_radius,
                          std::min(size_t(k), photons_.size()));
    const float query[3] = {p.x, p.y, p.z};
    index_->search(0, query, nearest);
    vec3 power(0.0f);
    for (uint32_t index : nearest.indices()) {
        const Photon& photon = photons_[index];
        if (glm::dot(photon.normal, n) > 0.0f) power += photon.power;
    }
    // The disk the photons were gathered from: the k-th nearest's distance, or the whole search
    // radius when fewer than k lie within it.
    const float radius_squared =
        nearest.full() ? nearest.distances_squared().back() : max_radius * max_radius;
    if (!(radius_squared > 0.0f)) return vec3(0.0f);  // k photons at p itself: no disk
    return power * (power_scale_ / (kPi * radius_squared));
}

}  // namespace shgi
