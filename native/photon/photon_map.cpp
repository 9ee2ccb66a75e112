#include "photon/photon_map.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <nanoflann.hpp>

#include "util/error.h"

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

// Photons per k-d tree leaf: nanoflann's default, a good balance of tree depth and leaf scans.
constexpr size_t kLeafSize = 10;

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

    bool full() const { return indices_.size() == capacity_; }
    float worstDist() const { return full() ? distances_squared_.back() : radius_squared_; }

    bool addPoint(float distance_squared, uint32_t index) {
        if (distance_squared >= worstDist()) return true;  // keep searching
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
    std::vector<uint32_t> indices_;
    std::vector<float> distances_squared_;
};

}  // namespace

struct PhotonMap::Index {
    PhotonCloud cloud;  // must outlive the tree, which keeps a reference to it
    KdTree tree;

    explicit Index(const std::vector<Photon>& photons)
        : cloud{photons.data(), photons.size()},
          tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(kLeafSize)) {}
};

PhotonMap::PhotonMap() = default;
PhotonMap::~PhotonMap() = default;
PhotonMap::PhotonMap(PhotonMap&&) noexcept = default;
PhotonMap& PhotonMap::operator=(PhotonMap&&) noexcept = default;

PhotonMap::PhotonMap(std::vector<Photon> photons, float power_scale)
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
    if (!photons_.empty()) index_ = std::make_unique<Index>(photons_);
}

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
    index_->tree.findNeighbors(nearest, query, nanoflann::SearchParams());
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
