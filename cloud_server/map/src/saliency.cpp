// Saliency with PCL's kd-tree (FLANN, exact search) and PCL's plane fit per neighbourhood.
#include "mrvs/map/saliency.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>

#include <fmt/format.h>

#include <pcl/common/centroid.h>
#include <pcl/features/feature.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace mrvs::map {
namespace {

Status check_inputs(const std::vector<Eigen::Vector3f>& positions, const std::vector<float>& intensities,
                    const SaliencyOptions& options) {
  if (positions.size() != intensities.size()) {
    return absl::InvalidArgumentError(
        fmt::format("saliency: {} positions but {} intensities", positions.size(), intensities.size()));
  }
  if (positions.empty()) return absl::InvalidArgumentError("saliency: the cloud has no point");
  if (positions.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    return absl::InvalidArgumentError(
        fmt::format("saliency: {} points exceed the kd-tree's int index range", positions.size()));
  }
  if (options.knn < 1) return absl::InvalidArgumentError(fmt::format("saliency: knn {} < 1", options.knn));
  if (!std::isfinite(options.alpha) || options.alpha < 0.0) {
    return absl::InvalidArgumentError(
        fmt::format("saliency: alpha {} must be finite and >= 0", options.alpha));
  }
  for (std::size_t i = 0; i < positions.size(); ++i) {
    if (!positions[i].allFinite() || !std::isfinite(intensities[i])) {
      return absl::InvalidArgumentError(fmt::format("saliency: point {} is not finite", i));
    }
  }
  return absl::OkStatus();
}

/// Unit normal of the points `indices` (zero vector when degenerate).
Eigen::Vector3f neighbourhood_normal(const pcl::PointCloud<pcl::PointXYZ>& cloud,
                                     const pcl::Indices& indices) {
  Eigen::Matrix3f covariance;
  Eigen::Vector4f centroid;
  if (indices.size() < 3 || pcl::computeMeanAndCovarianceMatrix(cloud, indices, covariance, centroid) == 0) {
    return Eigen::Vector3f::Zero();
  }
  float nx = 0.0f, ny = 0.0f, nz = 0.0f, curvature = 0.0f;
  pcl::solvePlaneParameters(covariance, nx, ny, nz, curvature);
  const Eigen::Vector3f n(nx, ny, nz);
  const float norm = n.norm();
  if (!n.allFinite() || !(norm > 0.5f)) return Eigen::Vector3f::Zero();
  return n / norm;
}

/// S of point i over its neighbourhood (see saliency.h).
float point_saliency(const std::vector<Eigen::Vector3f>& positions, const std::vector<float>& intensities,
                     std::size_t i, const pcl::Indices& neighbours, const Eigen::Vector3f& normal,
                     const SaliencyOptions& options) {
  const Eigen::Vector3d p = positions[i].cast<double>();
  const Eigen::Vector3d n = normal.cast<double>();
  double best = 0.0;
  for (const int j : neighbours) {
    const Eigen::Vector3d d = positions[static_cast<std::size_t>(j)].cast<double>() - p;
    const double dist = d.norm();
    if (!(dist >= options.min_neighbour_distance_m)) continue;
    const double gradient = std::abs(static_cast<double>(intensities[i]) -
                                     static_cast<double>(intensities[static_cast<std::size_t>(j)])) /
                            dist;
    const double s = gradient * (1.0 + options.alpha * std::abs(n.dot(d)) / dist);
    best = std::max(best, s);
  }
  return static_cast<float>(std::min(best, static_cast<double>(std::numeric_limits<float>::max())));
}

}  // namespace

StatusOr<std::vector<float>> compute_saliency(const std::vector<Eigen::Vector3f>& positions,
                                              const std::vector<float>& intensities,
                                              const SaliencyOptions& options) {
  MRVS_RETURN_IF_ERROR(check_inputs(positions, intensities, options));
  std::vector<float> saliency(positions.size(), 0.0f);
  try {
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    cloud->resize(positions.size());
    for (std::size_t i = 0; i < positions.size(); ++i) {
      (*cloud)[i] = pcl::PointXYZ(positions[i].x(), positions[i].y(), positions[i].z());
    }
    pcl::KdTreeFLANN<pcl::PointXYZ> tree(/*sorted=*/true);
    tree.setInputCloud(cloud);
    const int k = options.knn + 1;
    const auto n = static_cast<std::int64_t>(positions.size());
    const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();
#pragma omp parallel num_threads(threads)
    {
      pcl::Indices neighbours;
      std::vector<float> sq_distances;
#pragma omp for schedule(dynamic, 4096)
      for (std::int64_t i = 0; i < n; ++i) {
        const auto u = static_cast<std::size_t>(i);
        if (tree.nearestKSearch((*cloud)[u], k, neighbours, sq_distances) <= 0) continue;
        const Eigen::Vector3f normal = neighbourhood_normal(*cloud, neighbours);
        saliency[u] = point_saliency(positions, intensities, u, neighbours, normal, options);
      }
    }
  } catch (const std::exception& e) {
    return absl::InternalError(fmt::format("saliency: PCL failed: {}", e.what()));
  }
  return saliency;
}

}  // namespace mrvs::map
