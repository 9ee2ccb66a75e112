// PhotonMap: a k-d tree (nanoflann) over stored photons and Jensen's density estimate of
// irradiance (Jensen 2001, "Realistic Image Synthesis Using Photon Mapping", eq. 7.6 with a
// constant kernel): gather the k nearest photons within max_radius (whatever their normal);
// E(p, n) = the power of those whose stored normal faces n (dot > 0) divided by pi r^2, r the
// distance to the k-th nearest (max_radius when fewer than k lie within it), i.e. the disk the
// photons were gathered from. Used for caustics (the caustic map) and in tests.
//
// `power_scale` multiplies every photon's power (1 / passes when several passes are merged).
#pragma once

#include <memory>
#include <vector>

#include "photon/photon.h"
#include "util/math.h"

namespace shgi {

class PhotonMap {
  public:
    PhotonMap();
    // Builds the k-d tree. Throws InvalidArgument for a negative or non-finite power_scale or a
    // non-finite photon position.
    explicit PhotonMap(std::vector<Photon> photons, float power_scale = 1.0f);
    ~PhotonMap();
    PhotonMap(PhotonMap&&) noexcept;
    PhotonMap& operator=(PhotonMap&&) noexcept;

    size_t size() const { return photons_.size(); }
    const std::vector<Photon>& photons() const { return photons_; }

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
