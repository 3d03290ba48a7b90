#pragma once
// The fine stage: 4-DoF point-to-plane ICP (x, y, z, yaw; gravity known, so roll and pitch
// stay the edge's) of the submap against a MapSurface, by Gauss-Newton with Huber weights and
// a shrinking correspondence distance. PCL's ICP variants estimate 6 DoF (its rigid warps are
// 6-D or planar 3-D), which would let the map's local tilt fight the IMU's gravity; this one
// also returns the information matrix the answer's covariance comes from.
//
// Pose: a submap point p (gravity-aligned, relative to the anchor) lies at
//   x = R_z(yaw) p + anchor   (map-local),
// and the error [d_anchor (3); d_yaw] perturbs it as x + d_anchor + d_yaw z x (x - anchor).
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "map_surface.h"

namespace mrvs::localise {

struct FineOptions {
  int iterations = 20;            ///< at most; fewer once a step moves less than the tolerances
  int ramp_iterations = 10;       ///< the correspondence distance shrinks over these ...
  double start_distance_m = 0.3;  ///< ... from this (the first iteration's) ...
  double end_distance_m = 0.1;    ///< ... to this, kept until the end
  double converged_m = 1e-4;      ///< after the ramp, a step shorter than this ...
  double converged_rad = 1e-5;    ///< ... and turning less than this ends the iterations
  double huber_m = 0.03;          ///< residuals beyond are down-weighted
  double inlier_m = 0.05;         ///< a point this close to the map's surface is on it
  double voxel_m = 0.03;          ///< the map level's voxel: its points are this sparse on a surface
};

struct FineResult {
  double yaw = 0.0;
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();
  /// Share of the points on the map's surface: within inlier_m of the plane of their nearest
  /// map point (within inlier_m of the point itself where the map has no plane there), that
  /// point at most inlier_m + voxel_m away.
  double fitness = 0.0;
  /// The same count weighted by how much each inlier fixes the horizontal pose, |n_xy| of its
  /// map normal (1 on walls, 0 on floors), per point: what tells two placements apart.
  double structure = 0.0;
  double rmse_m = 0.0;  ///< point-to-plane rms of the inliers with a normal
  /// sum of J^T J over the inliers with a normal (unit weights), order [anchor; yaw]
  Eigen::Matrix4d information = Eigen::Matrix4d::Zero();
  int inliers = 0;
  int iterations = 0;
  /// Per point, in order: its share of `structure` (|n_xy| when an inlier with a normal, else
  /// 0). Two placements are told apart by the points that fit one and not the other.
  std::vector<float> evidence;
  /// Per point, in order: its nearest map point (MapSurface index) when it is an inlier, else -1
  /// (the appearance check compares the submap's brightness with the map's intensity there).
  std::vector<std::int32_t> matched;
};

/// Refines (yaw, anchor) from the given start.
FineResult refine_pose(const MapSurface& surface, const std::vector<Eigen::Vector3d>& points, double yaw,
                       const Eigen::Vector3d& anchor, const FineOptions& options);

/// The map-local position of point p at (yaw, anchor).
inline Eigen::Vector3d place(const Eigen::Vector3d& p, double yaw, const Eigen::Vector3d& anchor) {
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * p + anchor;
}

}  // namespace mrvs::localise
