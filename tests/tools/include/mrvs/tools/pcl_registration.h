#pragma once
// PCL's registration on the localisation service's problem, for the comparison issue 30 asks
// for (tests/tools/localise_compare.cpp): the expected starting point was PCL (features plus
// sample consensus for the global step; GICP, NDT or point-to-plane ICP for the fine one), and
// the service's own code (cloud_server/localise/) stands only where a measurement shows it is
// better. Measurement code, not part of the two processes.
//
// Frames: the submap as PCL registers it is the request's points rotated so that the request's
// gravity is -z (R_g) and relative to the anchor ("aligned"); a registration returns M, the
// transform of aligned points into the map's local frame (map frame minus VoxelMap::origin).
// T_map_odom follows: R = M_R R_g, t = M_t + origin - R anchor_o.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mrvs/core/status.h"
#include "mrvs/geometry/se3.h"
#include "mrvs/localisation/types.h"
#include "mrvs/map/voxel_map.h"

namespace mrvs::tools {

enum class PclMethod {
  kGicp,          ///< pcl::GeneralizedIterativeClosestPoint
  kNdt,           ///< pcl::NormalDistributionsTransform
  kPointToPlane,  ///< pcl::IterativeClosestPointWithNormals (point-to-plane objective)
  kFpfhSac,       ///< FPFH + pcl::SampleConsensusPrerejective, then GICP (global)
};

const char* pcl_method_name(PclMethod m);
std::optional<PclMethod> pcl_method_from_name(const std::string& name);

struct PclOptions {
  double map_level_m = 0.03;          ///< the map level registered to (the localiser's fine level)
  double voxel_m = 0.05;              ///< the submap (and the FPFH map) thinned to this cell, m
  int max_points = 2000;              ///< submap points registered (the localiser's fine_max_points)
  double normal_radius_m = 0.1;       ///< normals' neighbourhood, m
  double fpfh_radius_m = 0.25;        ///< FPFH neighbourhood, m
  int sac_iterations = 50000;         ///< sample-consensus iterations
  int sac_randomness = 5;             ///< feature neighbours a sample is drawn from
  double sac_similarity = 0.9;        ///< polygonal edge-length similarity of a sample
  double sac_inlier_fraction = 0.25;  ///< a pose needs this share of inliers
  double max_correspondence_m = 0.3;  ///< fine methods' correspondence distance, m
  int iterations = 50;                ///< fine methods' iterations
  double ndt_resolution_m = 1.0;      ///< NDT cell, m (PCL's example; 0.25-0.5 m stop short here)
  double ndt_step_m = 0.1;            ///< NDT line-search step, m
  double inlier_m = 0.05;             ///< fitness: the share of the submap this close to the map, m
};

/// An outcome: M (aligned submap -> map-local), the fitness at M, the time (one thread).
struct PclResult {
  bool converged = false;
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  double fitness = 0.0;
  double ms = 0.0;
};

/// The request's submap as PCL registers it.
struct AlignedSubmap {
  Eigen::Matrix3d R_g = Eigen::Matrix3d::Identity();  ///< odometry frame -> gravity along -z
  std::vector<Eigen::Vector3d> points;                ///< R_g * point, thinned to voxel_m, at most max_points
  Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();  ///< mean camera centre, aligned (normals face it)
};
AlignedSubmap align_submap(const localisation::Request& q, const PclOptions& o);

SE3d T_m_o_from(const Eigen::Matrix4d& M, const AlignedSubmap& s, const localisation::Request& q,
                const Vec3d& map_origin);
Eigen::Matrix4d M_from(const SE3d& T_m_o, const AlignedSubmap& s, const localisation::Request& q,
                       const Vec3d& map_origin);

/// One map's targets: its level's points, their normals, the GICP covariances, the NDT grid
/// and (with features) the FPFH descriptors of the thinned level, built once (setup_s).
/// Not thread-safe (PCL's registration objects keep state between calls).
class PclMap {
 public:
  static StatusOr<PclMap> build(const map::VoxelMap& map, const PclOptions& o, bool with_features);

  /// A fine method (kGicp, kNdt, kPointToPlane) from `start`.
  PclResult register_fine(PclMethod m, const AlignedSubmap& s, const Eigen::Matrix4d& start);
  /// FPFH + sample consensus over the whole map, then GICP from its pose (needs features).
  PclResult register_global(const AlignedSubmap& s);

  double setup_s() const;
  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace mrvs::tools
