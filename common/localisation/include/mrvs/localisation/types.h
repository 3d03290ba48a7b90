#pragma once
// The map-based localisation service in plain types (no middleware; the wire form is
// idl/mrvs_link.idl, converted by mrvs::link): the edge sends a local submap in its odometry
// frame `o`, the cloud answers where that frame lies in its map frame `m` (design/localisation.md).
//
// Frames: `o` is the edge's odometry frame (gravity along -z, origin and heading where the
// filter started), `m` the map frame (gravity along -z as well: the prior map is levelled).
// The covariance of an answer is that of the error xi = [rho; phi] (translation first, map
// frame) of a perturbation about the submap's anchor a_m = T_m_o * anchor_o:
//   x_m,true = a_m + rho + Exp(phi) (x_m - a_m)   for every point x_m = T_m_o * x_o,
// so it does not depend on how far the anchor is from the map origin.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mrvs/core/time.h"
#include "mrvs/geometry/se3.h"
#include "mrvs/geometry/types.h"

namespace mrvs::localisation {

/// Where the anchor may be in the map (outdoors: from GNSS). No region: anywhere.
struct PriorRegion {
  Vec3d centre_m = Vec3d::Zero();  ///< map frame, m (absolute, not map-local)
  double radius_m = 0.0;           ///< > 0
};

/// Where a run of consecutive submap points was seen from: the cloud checks that the line of
/// sight from there to each point crosses no surface of the map (free space) under a pose.
struct Viewpoint {
  Eigen::Vector3f position = Eigen::Vector3f::Zero();  ///< camera centre minus anchor_o, odometry frame, m
  std::uint32_t count = 0;                             ///< points seen from it, following the previous runs
};

/// Edge -> cloud: one localisation attempt.
struct Request {
  std::uint64_t seq = 0;                ///< per client, increasing
  TimestampNs stamp_ns = 0;             ///< time of the anchor (IMU clock)
  Vec3d gravity_o = Vec3d(0, 0, -1);    ///< unit direction of gravity in the odometry frame
  Vec3d anchor_o = Vec3d::Zero();       ///< odometry-frame point the submap points are relative to, m
  std::vector<Eigen::Vector3f> points;  ///< submap points minus anchor_o, odometry frame, m
  std::optional<PriorRegion> prior;     ///< where anchor_o lies in the map
  /// The points' viewpoints in point order (counts sum to at most points.size(); points after
  /// them have none). Empty: no free-space check.
  std::vector<Viewpoint> viewpoints;
  /// Per point, in order: the mean image brightness around it (1-255; 0: not known). Empty:
  /// none. The cloud correlates it with the map's intensity under each pose (the appearance
  /// that tells a room's symmetric placements apart).
  std::vector<std::uint8_t> brightness;
};

enum class Status : std::uint8_t {
  kOk,
  kTooLittleStructure,  ///< the submap does not constrain every direction (a wall, a corridor)
  kAmbiguous,           ///< another distinct pose fits almost as well (a symmetric room)
  kOutsideMap,          ///< no pose puts enough of the submap on the map's surfaces
  kBadRequest,          ///< malformed: too few or too many points, non-finite values, bad gravity or prior
  kMapUnavailable,      ///< the cloud has no map to search
  kServerError,
  kBusy,  ///< the cloud has too many requests queued: ask again later
};

/// Short name ("ok", "too little structure", ...).
const char* status_name(Status status);

/// Cloud -> edge: the answer to one request.
struct Result {
  Status status = Status::kServerError;
  std::string detail;                ///< why (human-readable)
  SE3d T_m_o;                        ///< valid for kOk (and the best guess for kAmbiguous)
  Mat6d covariance = Mat6d::Zero();  ///< of [rho; phi] about the anchor (see above)
  double fitness = 0.0;              ///< share of the submap's points on the map's surface at T_m_o, [0, 1]
  double rmse_m = 0.0;               ///< point-to-plane residual of those points, m
  double ambiguity =
      0.0;               ///< the best distinct other pose's structure score / the best's, [0, 1] (1: as good)
  int hypotheses = 0;    ///< distinct poses refined
  double blocked = 0.0;  ///< share of the lines of sight that cross the map's surfaces at T_m_o
  double time_ms = 0.0;  ///< registration time on the cloud
};

}  // namespace mrvs::localisation
