#pragma once
// The least-squares (PCA) plane of a set of points: the edge's SurfaceMap fits it to the map
// points the cloud answered, the cloud to the map points around a hit (surface normals).
#include <cmath>
#include <optional>
#include <vector>

#include <Eigen/Eigenvalues>

#include "mrvs/geometry/types.h"

namespace mrvs {

struct PlaneFit {
  Vec3d normal = Vec3d::UnitZ();  ///< unit, sign arbitrary
  Vec3d centroid = Vec3d::Zero();
  double rms_m = 0.0;     ///< standard deviation of the points along the normal
  double extent_m = 0.0;  ///< along the second principal axis (small: the points form a line)
  int points = 0;
};

/// Normal: the eigenvector of the smallest eigenvalue of the points' covariance; rms and
/// extent the square roots of the smallest and middle ones. nullopt for fewer than 3 points
/// or non-finite input.
inline std::optional<PlaneFit> fit_plane(const std::vector<Vec3d>& points) {
  if (points.size() < 3) return std::nullopt;
  Vec3d mean = Vec3d::Zero();
  for (const Vec3d& q : points) mean += q;
  mean /= static_cast<double>(points.size());
  Mat3d cov = Mat3d::Zero();
  for (const Vec3d& q : points) cov.noalias() += (q - mean) * (q - mean).transpose();
  cov /= static_cast<double>(points.size());
  if (!cov.allFinite()) return std::nullopt;
  const Eigen::SelfAdjointEigenSolver<Mat3d> eig(cov);
  if (eig.info() != Eigen::Success) return std::nullopt;
  const Vec3d l = eig.eigenvalues().cwiseMax(0.0);  // ascending
  PlaneFit out;
  out.normal = eig.eigenvectors().col(0).normalized();
  out.centroid = mean;
  out.rms_m = std::sqrt(l(0));
  out.extent_m = std::sqrt(l(1));
  out.points = static_cast<int>(points.size());
  return out;
}

}  // namespace mrvs
