#pragma once
// Synthetic scenes for the localisation tests: a room (floor, ceiling, four walls) with
// optional boxes standing on the floor, sampled densely on its surfaces, voxelised into a
// multi-level map (one point per voxel, the first sample that falls in it), and submaps as an
// edge would send them: the surface points within a range of a viewpoint, noisy, in an
// odometry frame turned and shifted against the map.
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "mrvs/geometry/se3.h"
#include "mrvs/localisation/types.h"
#include "mrvs/map/voxel_map.h"

namespace mrvs::localise::test {

struct Box {
  Eigen::Vector3d centre;
  Eigen::Vector3d half;
  double yaw = 0.0;
};

struct Scene {
  Eigen::Vector3d room_min = Eigen::Vector3d(0, 0, 0);
  Eigen::Vector3d room_max = Eigen::Vector3d(8, 6, 3);
  std::vector<Box> boxes;
  /// Surface samples (map frame), spacing ~ `spacing`.
  std::vector<Eigen::Vector3d> sample(double spacing) const;
};

/// A room with `boxes` random boxes (fixed seed), none overlapping the room's walls.
Scene cluttered_room(int boxes, std::uint64_t seed);

/// A surface texture: albedo in [0.1, 0.9] at a point, trilinear value noise on a 0.15 m
/// lattice (fixed seed), the same nowhere twice (so no turn of a room maps it onto itself).
float blob_albedo(const Eigen::Vector3d& p);

/// One point per voxel of every resolution, map origin `origin` (positions stored relative to it),
/// intensity 0.5 everywhere, or `albedo` of the point when given.
std::shared_ptr<map::VoxelMap> voxelise(const std::vector<Eigen::Vector3d>& points,
                                        const std::vector<double>& resolutions,
                                        const Eigen::Vector3d& origin = Eigen::Vector3d::Zero(),
                                        float (*albedo)(const Eigen::Vector3d&) = nullptr);

/// A submap: the scene's samples within `range` of `viewpoint` (map frame), thinned to about
/// `max_points`, with isotropic noise `sigma`, expressed in the odometry frame T_o_m; the
/// anchor is the viewpoint.
localisation::Request submap_request(const std::vector<Eigen::Vector3d>& samples,
                                     const Eigen::Vector3d& viewpoint, double range, int max_points,
                                     double sigma, const SE3d& T_o_m, std::uint64_t seed);

/// The request's brightness as a camera would see `albedo` at each point: a response unlike the
/// map's (20 + 200 albedo^0.6) plus noise of sd 3 grey levels; the points are undone from T_o_m.
void add_brightness(localisation::Request* q, const SE3d& T_o_m, float (*albedo)(const Eigen::Vector3d&),
                    std::uint64_t seed);

/// A gravity-aligned pose: yaw (rad) about +z and a translation.
SE3d yaw_pose(double yaw, const Eigen::Vector3d& t);

}  // namespace mrvs::localise::test
