// PhotonMap: a k-d tree (nanoflann) over stored photons and Jensen's density estimate of
// irradiance (Jensen 2001, "Realistic Image Synthesis Using Photon Mapping", eq. 7.6 with a
// constant kernel): gather the k nearest photons within max_radius (whatever their normal);
// E(p, n) = the power of those whose stored normal faces n (dot > 0) divided by pi r^2, r the
// distance to the k-th nearest (max_radius when fewer than k lie within it), i.e. the disk the
// photons were gathered from. Used for caustics (the caustic map) and in tests.
//
// `power_scale` multiplies every photon's power (1 / passes when several passes are merged).
//
// Large maps (the caustic map gathers every pass's photons, 10^7 and more) are built in shards:
// a median split along the widest axis, repeated until each part holds at most 2^18 photons,
// then one nanoflann tree per part, built in parallel. A build polls cancel between the splits
// and the shards (nanoflann's own build cannot be interrupted: one tree of 10^7 photons takes ~5 s
// on one core), and a query visits the parts nearest first, skipping those farther than the k-th
// photon found so far.
#pragma once

#include <memory>
#include <vector>

#include "photon/photon.h"
#include "util/math.h"
#include "util/progress.h"

namespace shgi {

class PhotonMap {
  public:
    PhotonMap();
    // Builds the k-d tree (the photons are reordered by it). Throws InvalidArgument for a
    // negative or non-finite power_scale or a non-finite photon position; Cancelled when
    // `progress` is cancelled while it builds.
    explicit PhotonMap(std::vector<Photon> photons, float power_scale = 1.0f,
                       Progress* progress = nullptr);
    ~PhotonMap();
    PhotonMap(PhotonMap&&) noexcept;
    PhotonMap& operator=(PhotonMap&&) noexcept;

    size_t size() const { return photons_.size(); }
    size_t shard_count() const;  // nanoflann trees the map is split into (0 when empty)
    const std::vector<Photon>& photons() const { return photons_; }
    float power_scale() const { return power_scale_; }

    // Irradiance (W/m^2) at p on a surface with unit normal n from the k nearest photons.
    // Thread-safe. Throws InvalidArgument for k < 1 or max_radius not finite and > 0.
    vec3 irradiance(const vec3& p, const vec3& n, int k, float max_radius) const;

  private:
    struct Index;
    std::vector<Photon> photons_;
    float power_scale_ = 1.0f;
    std::unique_ptr<Index> index_;
};

}  // namespace shgi
