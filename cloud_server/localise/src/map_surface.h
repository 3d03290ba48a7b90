#pragma once
// The fine stage's target: the points of one map level with their surface normals (the
// least-squares plane of each point's k nearest neighbours) and a k-d tree (nanoflann) for
// nearest-neighbour look-ups. Map-local coordinates (as stored in the map), float.
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

namespace mrvs::localise {

struct Neighbour {
  std::uint32_t index = 0;
  float distance_m = 0.0f;
};

class MapSurface {
 public:
  /// Normals from the `knn` nearest points; a point whose neighbourhood is rougher than
  /// `max_rms_m` (a corner, an edge, clutter) gets a zero normal. `intensity` (one per point,
  /// or empty): the map's intensity, kept as the mean over the same neighbourhood (the
  /// appearance the edge's image brightness is compared with, at a similar footprint).
  static MapSurface build(std::vector<Eigen::Vector3f> points, int knn, double max_rms_m,
                          const std::vector<float>& intensity = {});

  MapSurface();
  ~MapSurface();
  MapSurface(MapSurface&&) noexcept;
  MapSurface& operator=(MapSurface&&) noexcept;

  /// The nearest point within max_distance_m of q, if any.
  std::optional<Neighbour> nearest(const Eigen::Vector3f& q, float max_distance_m) const;

  const Eigen::Vector3f& point(std::uint32_t i) const { return points_[i]; }
  /// Unit normal, or zero where the map is not a plane.
  const Eigen::Vector3f& normal(std::uint32_t i) const { return normals_[i]; }
  /// The neighbourhood's mean intensity; NaN when the map has none.
  float intensity(std::uint32_t i) const { return i < intensity_.size() ? intensity_[i] : NAN; }
  std::size_t size() const { return points_.size(); }
  /// Share of the points with a normal.
  double planar_fraction() const;

 private:
  struct Index;
  std::vector<Eigen::Vector3f> points_;
  std::vector<Eigen::Vector3f> normals_;
  std::vector<float> intensity_;  ///< smoothed, one per point, or empty
  std::unique_ptr<Index> index_;
};

}  // namespace mrvs::localise
