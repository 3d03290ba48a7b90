#pragma once
// A small hand-made window for the updater tests: a stereo rig looking along the body's x
// axis, six clones along a sideways path, and tracks of points seen by every clone.
#include <random>
#include <vector>

#include "mrvs/edge/feature_database.h"
#include "mrvs/edge/state.h"
#include "mrvs/edge/state_helper.h"
#include "mrvs/geometry/so3.h"

namespace mrvs::edge::test {

inline config::StereoRigCalibration scene_rig() {
  camera::Params p;
  p << 458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05;
  config::StereoRigCalibration r;
  for (int c = 0; c < 2; ++c) {
    r.cameras[c].model = std::shared_ptr<const camera::CameraModel>(
        std::move(*camera::make_camera(camera::DistortionModel::kRadTan, 752, 480, p)));
    // Cameras looking along the body's x axis, 11 cm apart.
    Mat3d R_b_c;  // columns: the camera's x, y, z axes in the body frame (z along body x)
    R_b_c << 0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, -1.0, 0.0;
    r.cameras[c].T_b_c = SE3d(R_b_c, Vec3d(0.0, 0.055 - 0.11 * c, 0.0));
  }
  return r;
}

/// A state with 6 clones along a sideways path and a track of a point seen by all of them.
struct Scene {
  State state{StateOptions{}, scene_rig()};
  FeatureTrack track;
  Vec3d p_w{4.0, 0.3, 0.2};
};

inline Scene make_scene(double pixel_noise = 0.0) {
  Scene s;
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0.0, pixel_noise);
  for (int k = 0; k < 6; ++k) {
    s.state.imu.p_w_b = Vec3d(0.0, 0.1 * k, 0.02 * k);
    s.state.imu.q_w_b = so3::exp_quat<double>(Vec3d(0.0, 0.0, 0.02 * k));
    EXPECT_TRUE(augment_clone(s.state, 1000 * (k + 1), Vec3d::Zero()).ok());
    for (int c = 0; c < 2; ++c) {
      const CameraState& cam = s.state.cams[static_cast<std::size_t>(c)];
      const Vec3d p_c = (s.state.clones.at(1000 * (k + 1)).T_w_b * cam.T_b_c).inverse() * s.p_w;
      const Vec2d uv = *cam.model->project(p_c) + (pixel_noise > 0 ? Vec2d(n(rng), n(rng)) : Vec2d::Zero());
      s.track.obs.push_back({1000 * (k + 1), c, uv, *cam.model->undistort(uv)});
    }
  }
  s.state.P = Eigen::MatrixXd::Identity(s.state.dim(), s.state.dim()) * 1e-4;
  return s;
}

/// `state` moved by `d` over `vars` (d holds their errors in that order), the clones' first
/// estimates reset to the moved poses (numeric Jacobians).
inline State moved_state(const State& state, const std::vector<Slot>& vars, const Eigen::VectorXd& d) {
  State moved = state;
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(moved.dim());
  int c = 0;
  for (const Slot& v : vars) dx.segment(v.offset, v.size) = d.segment(c, v.size), c += v.size;
  moved.apply_correction(dx);
  for (auto& [t, clone] : moved.clones) clone.fej = clone.T_w_b;
  return moved;
}

/// The points `points`, observed in stereo by every clone with pixel noise, added to `db`
/// with ids 1..size.
inline void add_observed_points(const State& state, const std::vector<Vec3d>& points, double pixel_noise,
                                unsigned seed, FeatureDatabase* db) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, pixel_noise);
  const auto noise = [&] { return pixel_noise > 0 ? Vec2d(n(rng), n(rng)) : Vec2d::Zero(); };
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3d& p_w = points[i];
    for (const auto& [t, clone] : state.clones) {
      FeatureFrame f;
      f.t_ns = t;
      FeatureObservation o;
      o.id = static_cast<FeatureId>(i + 1);
      const auto& cams = state.cams;
      o.uv_left = *cams[0].model->project((clone.T_w_b * cams[0].T_b_c).inverse() * p_w) + noise();
      o.xn_left = *cams[0].model->undistort(o.uv_left);
      o.stereo = true;
      o.uv_right = *cams[1].model->project((clone.T_w_b * cams[1].T_b_c).inverse() * p_w) + noise();
      o.xn_right = *cams[1].model->undistort(o.uv_right);
      f.features.push_back(o);
      db->add(f);
    }
  }
}

/// `count` points in front of the clones (x 3..5 m), observed in stereo by every clone with
/// pixel noise, added to `db` with ids 1..count; their positions.
inline std::vector<Vec3d> add_points(const State& state, int count, double pixel_noise, unsigned seed,
                                     FeatureDatabase* db) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec3d> points;
  for (int i = 0; i < count; ++i) {
    const double x = 4.0 + u(rng), y = 1.5 * u(rng), z = u(rng);
    points.emplace_back(x, y, z);
  }
  add_observed_points(state, points, pixel_noise, seed + 1, db);
  return points;
}

}  // namespace mrvs::edge::test
