#include "map_surface.h"

#include <nanoflann.hpp>

#include "mrvs/geometry/plane_fit.h"

namespace mrvs::localise {

/// nanoflann's view of the point vector, and the tree over it.
struct MapSurface::Index {
  /// The points' buffer (it stays where it is when the vector, and the MapSurface, move).
  struct Cloud {
    const Eigen::Vector3f* points = nullptr;
    std::size_t size = 0;
    std::size_t kdtree_get_point_count() const { return size; }
    float kdtree_get_pt(std::size_t i, std::size_t dim) const {
      return points[i][static_cast<Eigen::Index>(dim)];
    }
    template <class Box>
    bool kdtree_get_bbox(Box&) const {
      return false;
    }
  };
  using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Cloud>, Cloud, 3>;

  explicit Index(const std::vector<Eigen::Vector3f>& points)
      : cloud{points.data(), points.size()}, tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10)) {
    tree.buildIndex();
  }
  Cloud cloud;
  Tree tree;
};

MapSurface::MapSurface() = default;
MapSurface::~MapSurface() = default;
MapSurface::MapSurface(MapSurface&&) noexcept = default;
MapSurface& MapSurface::operator=(MapSurface&&) noexcept = default;

MapSurface MapSurface::build(std::vector<Eigen::Vector3f> points, int knn, double max_rms_m,
                             const std::vector<float>& intensity) {
  MapSurface s;
  s.points_ = std::move(points);
  s.normals_.assign(s.points_.size(), Eigen::Vector3f::Zero());
  const bool smooth = intensity.size() == s.points_.size();
  if (smooth) s.intensity_.assign(s.points_.size(), NAN);
  if (s.points_.empty()) return s;
  s.index_ = std::make_unique<Index>(s.points_);
  const std::size_t k = std::min<std::size_t>(static_cast<std::size_t>(std::max(knn, 3)), s.points_.size());
  std::vector<std::uint32_t> idx(k);
  std::vector<float> d2(k);
  std::vector<Vec3d> nb;
  for (std::size_t i = 0; i < s.points_.size(); ++i) {
    const std::size_t n = s.index_->tree.knnSearch(s.points_[i].data(), k, idx.data(), d2.data());
    nb.clear();
    for (std::size_t j = 0; j < n; ++j) nb.push_back(s.points_[idx[j]].cast<double>());
    if (smooth && n > 0) {
      double sum = 0.0;
      for (std::size_t j = 0; j < n; ++j) sum += intensity[idx[j]];
      s.intensity_[i] = static_cast<float>(sum / static_cast<double>(n));
    }
    const std::optional<PlaneFit> fit = fit_plane(nb);
    if (fit && fit->rms_m <= max_rms_m && fit->extent_m > 2.0 * fit->rms_m) {
      s.normals_[i] = fit->normal.cast<float>();
    }
  }
  return s;
}

std::optional<Neighbour> MapSurface::nearest(const Eigen::Vector3f& q, float max_distance_m) const {
  if (!index_) return std::nullopt;
  std::uint32_t i = 0;
  float d2 = 0.0f;
  // The nearest point, searched only within max_distance_m: the bound on the result's
  // distance prunes the tree's cells farther than that (a point far from the map costs a
  // few cells instead of a walk to its distant nearest neighbour).
  nanoflann::KNNResultSet<float, std::uint32_t> result(1);
  result.init(&i, &d2);
  d2 = max_distance_m * max_distance_m;
  index_->tree.findNeighbors(result, q.data(), nanoflann::SearchParams());
  if (result.size() != 1) return std::nullopt;
  return Neighbour{i, std::sqrt(d2)};
}

double MapSurface::planar_fraction() const {
  if (normals_.empty()) return 0.0;
  std::size_t n = 0;
  for (const Eigen::Vector3f& v : normals_) n += v.squaredNorm() > 0.5f;
  return static_cast<double>(n) / static_cast<double>(normals_.size());
}

}  // namespace mrvs::localise
