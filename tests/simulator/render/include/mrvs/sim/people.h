#pragma once
// Moving people (issue 31): walking figures in the images but not in the prior map. Each is
// an upright box (width x depth x height, feet on floor_z) that walks back and forth along
// a straight path at a constant speed, facing where it goes, with a textured body (a
// shirt, trousers and a head of their own albedo times a value-noise pattern of 4 cm cells,
// so that a tracker finds corners on it). Rays test them after the static scene; the
// nearer hit wins.
//
// Frames: world w (z up, metres); a person's frame p: origin at the box centre, x along the
// walking direction, z up.
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "mrvs/core/time.h"
#include "mrvs/geometry/types.h"

namespace mrvs::sim {

struct Walker {
  Eigen::Vector2d a = Eigen::Vector2d::Zero();   ///< one end of the path, world xy, m
  Eigen::Vector2d b = Eigen::Vector2d::UnitX();  ///< the other end
  double floor_z = 0.0;                          ///< feet, m
  double speed_mps = 1.3;
  TimestampNs at_a_ns = 0;  ///< a time at which the person is at `a`, walking to `b`
  double width_m = 0.5, depth_m = 0.3, height_m = 1.75;
  std::uint64_t texture_seed = 0;

  /// Box centre at time t (world), and the unit walking direction (xy).
  Vec3d centre(TimestampNs t_ns, Eigen::Vector2d* heading = nullptr) const;
};

/// One person at one instant, in floats for the pixel loops.
struct PersonBox {
  Eigen::Matrix3f R_p_w = Eigen::Matrix3f::Identity();  ///< world -> person; a turn about z (upright)
  Eigen::Vector3f centre_w = Eigen::Vector3f::Zero();
  Eigen::Vector3f half = Eigen::Vector3f::Ones();  ///< half sizes along the person's x, y, z
  std::uint64_t texture_seed = 0;
  int index = 0;  ///< in the crowd

  /// Nearest entry of the ray origin + t d (t in (0, max_t]); nullopt when missed or when
  /// the origin is inside the box.
  std::optional<float> intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& d, float max_t) const;
  /// Albedo in [0.03, 0.97] of the surface point p (world) of the box.
  float albedo(const Eigen::Vector3f& p_w) const;
};

/// The crowd at time t.
std::vector<PersonBox> people_at(const std::vector<Walker>& walkers, TimestampNs t_ns);

}  // namespace mrvs::sim
