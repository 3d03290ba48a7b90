#pragma once
// Helpers shared by the simulator tests: the real EuRoC ground truth, midpoint strapdown.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mrvs/geometry/angles.h"
#include "mrvs/geometry/quaternion.h"
#include "mrvs/geometry/se3.h"
#include "mrvs/io/trajectory_io.h"
#include "mrvs/sim/spline_trajectory.h"
#include "mrvs/test/shared_data.h"

namespace mrvs::sim::test {

using mrvs::kRadToDeg;

/// The real EuRoC ground truth `name` (e.g. "V1_01_easy.txt"); empty (and a test failure)
/// when it cannot be read.
inline io::Trajectory load_euroc_gt(const std::string& name) {
  auto traj = io::read_trajectory(mrvs::test::euroc_groundtruth_file(name));
  EXPECT_TRUE(traj.ok()) << traj.status();
  return traj.ok() ? *traj : io::Trajectory{};
}

/// Navigation state for strapdown integration.
struct NavState {
  Quatd q_w_b = Quatd::Identity();
  Vec3d p_w = Vec3d::Zero();  ///< m
  Vec3d v_w = Vec3d::Zero();  ///< m/s
};

/// Midpoint strapdown integration of bias-free samples gyro[k], accel[k] (k = first .. last,
/// period dt) from `state` at sample `first` to sample `last`:
///   R_{k+1} = R_k exp((w_k + w_{k+1}) / 2 dt),  a = (R_k f_k + R_{k+1} f_{k+1}) / 2 + g,
///   p += v dt + a dt^2 / 2,  v += a dt.
inline NavState integrate_midpoint(NavState state, const std::vector<Vec3d>& gyro,
                                   const std::vector<Vec3d>& accel, std::size_t first, std::size_t last,
                                   double dt, double gravity) {
  const Vec3d g_w(0.0, 0.0, -gravity);
  for (std::size_t k = first; k < last; ++k) {
    const Quatd q1 = (state.q_w_b * so3::exp_quat<double>(0.5 * (gyro[k] + gyro[k + 1]) * dt)).normalized();
    const Vec3d a = 0.5 * (state.q_w_b * accel[k] + q1 * accel[k + 1]) + g_w;
    state.p_w += state.v_w * dt + 0.5 * a * dt * dt;
    state.v_w += a * dt;
    state.q_w_b = q1;
  }
  return state;
}

}  // namespace mrvs::sim::test
