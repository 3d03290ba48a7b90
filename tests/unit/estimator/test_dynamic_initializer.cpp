// Dynamic initialisation on generated data: IMU pre-integration (bias Jacobians against
// numeric derivatives, the mean against the RK4 propagator, the noise model against the
// simulator's truth), then the initializer on V1_01_easy-shaped motion from the simulator
// with features projected (not rendered) from random 3-D points: accuracy against the
// ground truth, robustness to outlier tracks and a camera time offset, and the refusals.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "mrvs/edge/dynamic_initializer.h"
#include "mrvs/edge/preintegration.h"
#include "mrvs/geometry/quaternion.h"
#include "mrvs/geometry/so3.h"
#include "mrvs/sim/generator.h"
#include "mrvs/sim/simulator_options.h"
#include "mrvs/test/numeric_jacobian.h"
#include "mrvs/test/shared_data.h"

namespace mrvs::edge {
namespace {

// ------------------------------------------------------------------------------------------
// Worlds and synthetic feature tracks

struct WorldKey {
  double static_prefix_s = 0.0;  ///< > 0: the window starts with this much exact rest
  double time_offset_ms = 0.0;   ///< camera-IMU offset t_d of the simulation
  auto tie() const { return std::make_tuple(static_prefix_s, time_offset_ms); }
  bool operator<(const WorldKey& o) const { return tie() < o.tie(); }
};

/// V1_01_easy from 20 s (moving), 2.5 s, or a window that starts at rest. Built once.
const sim::World& world(const WorldKey& key) {
  static std::map<WorldKey, std::unique_ptr<sim::World>> cache;
  auto it = cache.find(key);
  if (it != cache.end()) return *it->second;
  sim::GeneratorRequest r;
  r.profile = sim::SceneProfile::kIndoor;
  r.preset = "easy";
  r.options = sim::default_options(r.profile);
  EXPECT_TRUE(sim::apply_preset(r.preset, r.profile, r.options).ok());
  r.trajectory = mrvs::test::euroc_groundtruth_file("V1_01_easy.txt");
  r.options.trajectory.window_start_s = key.static_prefix_s > 0.0 ? 0.0 : 20.0;  // V1_01 moves at 20 s
  r.options.trajectory.static_prefix_s = key.static_prefix_s;
  r.options.trajectory.window_duration_s = 2.5;
  r.options.time_offset_ms = key.time_offset_ms;
  r.options.map.spacing_near_m = r.options.map.spacing_far_m = 0.2;  // the map is not used here
  StatusOr<sim::World> w = sim::build_world(r);
  EXPECT_TRUE(w.ok()) << w.status();
  auto owned = std::make_unique<sim::World>(w.ok() ? std::move(*w) : sim::World{});
  // The rig calibration does not carry the simulated offset: it is what the estimator is told.
  for (auto& cam : owned->calibration.cameras) cam.time_offset_ns = std::llround(key.time_offset_ms * 1e6);
  return *cache.emplace(key, std::move(owned)).first->second;
}

struct TrackOptions {
  std::size_t first = 0;          ///< first frame of the world used
  std::size_t count = 31;         ///< frames (20 Hz: 31 frames = 1.5 s)
  int points = 300;               ///< random points, 1-6 m in front of five frames
  double sigma_px = 0.5;          ///< pixel noise
  double outlier_fraction = 0.0;  ///< tracks that jump 8-30 px halfway through
  std::uint64_t seed = 7;
  double min_depth_m = 1.0;  ///< the points' depth range in front of the frames, m
  double max_depth_m = 6.0;
};

/// Points min_depth_m - max_depth_m in front of cam0 at five frames spread over the window.
std::vector<Vec3d> random_points(const sim::World& w, const TrackOptions& o, std::mt19937_64* rng) {
  const config::CameraCalibration& cam = w.calibration.cameras[0];
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3d> out;
  for (int i = 0; i < o.points; ++i) {
    const std::size_t k = o.first + (static_cast<std::size_t>(i % 5) * (o.count - 1)) / 4;
    const Vec2d uv(u(*rng) * (cam.model->width() - 1), u(*rng) * (cam.model->height() - 1));
    const Vec3d bearing = *cam.model->unproject(uv);
    const double depth = o.min_depth_m + (o.max_depth_m - o.min_depth_m) * u(*rng);
    out.push_back(w.frame_pose(k) * cam.T_b_c * Vec3d(bearing / bearing.z() * depth));
  }
  return out;
}

/// The noisy observation of p_w in camera c at frame k, if it is in the image.
std::optional<std::pair<Vec2d, Vec2d>> observe(const sim::World& w, int c, std::size_t k, const Vec3d& p_w,
                                               const Vec2d& noise) {
  const config::CameraCalibration& cam = w.calibration.cameras[static_cast<std::size_t>(c)];
  const Vec3d p_c = (w.frame_pose(k) * cam.T_b_c).inverse() * p_w;
  if (p_c.z() < 0.2) return std::nullopt;
  const auto uv = cam.model->project(p_c);
  if (!uv || !cam.model->in_image(*uv, 2.0)) return std::nullopt;
  const Vec2d uv_noisy = *uv + noise;
  const auto xn = cam.model->undistort(uv_noisy);
  if (!xn.ok()) return std::nullopt;
  return std::make_pair(uv_noisy, *xn);
}

/// Feature frames (camera clock) of the points seen from frames first .. first + count - 1.
std::vector<FeatureFrame> make_frames(const sim::World& w, const TrackOptions& o) {
  std::mt19937_64 rng(o.seed);
  const std::vector<Vec3d> points = random_points(w, o, &rng);
  std::normal_distribution<double> n(0.0, o.sigma_px);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec2d> jump(points.size(), Vec2d::Zero());
  for (Vec2d& j : jump) {
    const double angle = 2.0 * M_PI * u(rng), size = 8.0 + 22.0 * u(rng);
    if (u(rng) < o.outlier_fraction) j = size * Vec2d(std::cos(angle), std::sin(angle));
  }
  std::vector<FeatureFrame> frames;
  std::vector<int> length(points.size(), 0);
  for (std::size_t k = o.first; k < o.first + o.count; ++k) {
    FeatureFrame f;
    f.t_ns = w.grid.camera_stamp_ns[k];
    const Vec2d offset_scale = k >= o.first + o.count / 2 ? Vec2d::Ones() : Vec2d::Zero();
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Vec2d bad = jump[i].cwiseProduct(offset_scale);
      const auto left = observe(w, 0, k, points[i], Vec2d(n(rng), n(rng)) + bad);
      const auto right = observe(w, 1, k, points[i], Vec2d(n(rng), n(rng)) + bad);
      if (!left) continue;
      FeatureObservation obs;
      obs.id = 1000 + i;
      obs.uv_left = left->first;
      obs.xn_left = left->second;
      obs.stereo = right.has_value();
      if (right) {
        obs.uv_right = right->first;
        obs.xn_right = right->second;
      }
      obs.track_length = ++length[i];
      f.features.push_back(obs);
    }
    frames.push_back(std::move(f));
  }
  return frames;
}

std::vector<io::ImuSample> measured_imu(const sim::World& w) {
  std::vector<io::ImuSample> out;
  for (const auto& s : w.imu) out.push_back(s.measured);
  return out;
}

ImuNoise noise_of(const config::StereoRigCalibration& rig) {
  return {rig.imu.gyroscope_noise_density, rig.imu.accelerometer_noise_density, rig.imu.gyroscope_random_walk,
          rig.imu.accelerometer_random_walk};
}

constexpr double kGravity = 9.81;  ///< the simulator's default

DynamicInitOptions test_options() {
  DynamicInitOptions o;
  o.max_solver_time_s = 30.0;  // deterministic: the iteration limit ends the solve, not the clock
  return o;
}

ImuState truth_at(const sim::World& w, std::size_t frame) {
  const io::GroundTruthState& s = w.states[w.grid.camera_imu_index[frame]];
  ImuState x;
  x.t_ns = s.t_ns;
  x.q_w_b = s.T_w_b.quaternion();
  x.p_w_b = s.T_w_b.translation();
  x.v_w_b = s.v_w_b;
  x.bg = s.bias_gyro;
  x.ba = s.bias_accel;
  return x;
}

struct Errors {
  double gravity_deg = 0.0;  ///< gravity direction in the body frame
  double velocity = 0.0;     ///< body-frame velocity, m/s
  double gyro_bias = 0.0;    ///< rad/s
  double accel_bias = 0.0;   ///< m/s^2
};

Errors errors_of(const InitializationResult& r, const ImuState& truth) {
  Errors e;
  const Vec3d up(0.0, 0.0, 1.0);
  const Vec3d g_est = r.imu.q_w_b.conjugate() * up, g_true = truth.q_w_b.conjugate() * up;
  e.gravity_deg = std::acos(std::clamp(g_est.dot(g_true), -1.0, 1.0)) * 180.0 / M_PI;
  e.velocity = (r.imu.q_w_b.conjugate() * r.imu.v_w_b - truth.q_w_b.conjugate() * truth.v_w_b).norm();
  e.gyro_bias = (r.imu.bg - truth.bg).norm();
  e.accel_bias = (r.imu.ba - truth.ba).norm();
  std::cout << "[ result   ] gravity " << e.gravity_deg << " deg, velocity " << e.velocity
            << " m/s, gyro bias " << e.gyro_bias << " rad/s, accel bias " << e.accel_bias
            << " m/s^2\n[ detail   ] " << r.detail << "\n";
  return e;
}

void expect_spd(const Mat15d& P) {
  EXPECT_TRUE(P.allFinite());
  EXPECT_LE((P - P.transpose()).cwiseAbs().maxCoeff(), 1e-12 * P.cwiseAbs().maxCoeff());
  EXPECT_EQ(Eigen::LLT<Mat15d>(P).info(), Eigen::Success);
  const Eigen::SelfAdjointEigenSolver<Mat15d> eig(P);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
}

/// Normalised squared error of the observable part [tilt (2), bg, ba] against the
/// covariance without the inflation: tilt = the gravity direction error in the body frame.
double nees(const InitializationResult& r, const ImuState& truth, const DynamicInitOptions& o) {
  Vec15d unscale = Vec15d::Ones();
  unscale.segment<3>(0).setConstant(1.0 / std::sqrt(o.inflate_orientation));
  unscale.segment<3>(6).setConstant(1.0 / std::sqrt(o.inflate_velocity));
  unscale.segment<3>(9).setConstant(1.0 / std::sqrt(o.inflate_gyro_bias));
  unscale.segment<3>(12).setConstant(1.0 / std::sqrt(o.inflate_accel_bias));
  const Mat15d P = unscale.asDiagonal() * r.P * unscale.asDiagonal();
  // R_est = R_true Exp(theta) (up to yaw) moves the body-frame up vector by u x theta.
  const Vec3d up(0.0, 0.0, 1.0);
  const Vec3d u_est = r.imu.q_w_b.conjugate() * up, u_true = truth.q_w_b.conjugate() * up;
  const Vec3d e1 = u_true.unitOrthogonal(), e2 = u_true.cross(e1);
  const Vec3d tilt = u_est.cross(u_true);
  Eigen::Matrix<double, 8, 15> S = Eigen::Matrix<double, 8, 15>::Zero();
  S.block<1, 3>(0, 0) = e1.transpose();
  S.block<1, 3>(1, 0) = e2.transpose();
  S.block<6, 6>(2, 9).setIdentity();
  Eigen::Matrix<double, 8, 1> e;
  e << e1.dot(tilt), e2.dot(tilt), r.imu.bg - truth.bg, r.imu.ba - truth.ba;
  const Eigen::Matrix<double, 8, 8> Ps = S * P * S.transpose();
  return e.dot(Ps.ldlt().solve(e));
}

// ------------------------------------------------------------------------------------------
// Pre-integration

/// The simulator's IMU between two frames 6 apart (0.3 s) of the moving world.
struct Interval {
  const sim::World* w;
  std::vector<io::ImuSample> imu;
  std::size_t i, j;
};

Interval interval(std::size_t i) {
  const sim::World& w = world({});
  return {&w, measured_imu(w), i, i + 6};
}

TEST(DynamicInitPreintegration, BiasJacobiansMatchNumericDerivatives) {
  const Interval iv = interval(4);
  const ImuState xi = truth_at(*iv.w, iv.i);
  const TimestampNs t0 = xi.t_ns, t1 = truth_at(*iv.w, iv.j).t_ns;
  const ImuNoise noise = noise_of(iv.w->calibration);
  const auto pre = preintegrate(iv.imu, t0, t1, xi.bg, xi.ba, noise);
  ASSERT_TRUE(pre.ok()) << pre.status();
  const auto f = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
    const auto p =
        preintegrate(iv.imu, t0, t1, Vec3d(xi.bg + d.head<3>()), Vec3d(xi.ba + d.tail<3>()), noise);
    Eigen::VectorXd out(9);
    out << quat::minus_right(p->dq, pre->dq), p->dp - pre->dp, p->dv - pre->dv;
    return out;
  };
  const Eigen::MatrixXd num = mrvs::test::numeric_jacobian<double>(f, 6, 1e-5);
  Eigen::Matrix<double, 9, 6> J = Eigen::Matrix<double, 9, 6>::Zero();
  J.block<3, 3>(0, 0) = pre->dR_dbg;
  J.block<3, 3>(3, 0) = pre->dp_dbg;
  J.block<3, 3>(3, 3) = pre->dp_dba;
  J.block<3, 3>(6, 0) = pre->dv_dbg;
  J.block<3, 3>(6, 3) = pre->dv_dba;
  EXPECT_TRUE(mrvs::test::matrices_near(J, num, 1e-7));
  // The first-order correction predicts a re-integration at other biases.
  const Vec3d bg = xi.bg + Vec3d(0.004, -0.003, 0.005), ba = xi.ba + Vec3d(0.05, 0.04, -0.06);
  const auto again = preintegrate(iv.imu, t0, t1, bg, ba, noise);
  ASSERT_TRUE(again.ok());
  // The first-order correction predicts a re-integration at other biases to within 1 % of
  // the change (the rest is second order).
  EXPECT_LT(quat::angular_distance(pre->dq_at(bg), again->dq),
            1e-2 * quat::angular_distance(pre->dq, again->dq));
  EXPECT_LT((pre->dp_at(bg, ba) - again->dp).norm(), 1e-2 * (pre->dp - again->dp).norm());
  EXPECT_LT((pre->dv_at(bg, ba) - again->dv).norm(), 1e-2 * (pre->dv - again->dv).norm());
}

TEST(DynamicInitPreintegration, MeanAgreesWithTheRk4Propagator) {
  const Interval iv = interval(10);
  const ImuState xi = truth_at(*iv.w, iv.i);
  const TimestampNs t1 = truth_at(*iv.w, iv.j).t_ns + 1'234'567;  // ends between two samples
  const Vec3d g_w(0.0, 0.0, -kGravity);
  const auto pre = preintegrate(iv.imu, xi.t_ns + 2'000'000, t1, xi.bg, xi.ba, ImuNoise{});
  ImuState x0 = xi;
  x0.t_ns = xi.t_ns + 2'000'000;  // starts between two samples
  const auto prop = propagate(x0, iv.imu, t1, g_w, ImuNoise{});
  ASSERT_TRUE(pre.ok() && prop.ok());
  const Vec9d r = preintegration_residual(*pre, x0, prop->state, g_w);
  EXPECT_LT(r.segment<3>(0).norm(), 1e-6);  // rad (the propagator adds a commutator term)
  EXPECT_LT(r.segment<3>(3).norm(), 2e-5);  // m over 0.3 s
  EXPECT_LT(r.segment<3>(6).norm(), 1e-4);  // m/s
}

TEST(DynamicInitPreintegration, TrueStatesFitWithinTheNoiseModel) {
  const sim::World& w = world({});
  const std::vector<io::ImuSample> imu = measured_imu(w);
  const ImuNoise noise = noise_of(w.calibration);
  const Vec3d g_w(0.0, 0.0, -kGravity);
  double chi2 = 0.0;
  int n = 0;
  for (std::size_t i = 0; i + 6 < w.grid.camera_imu_index.size(); i += 6, ++n) {
    const ImuState xi = truth_at(w, i), xj = truth_at(w, i + 6);
    const auto pre = preintegrate(imu, xi.t_ns, xj.t_ns, xi.bg, xi.ba, noise);
    ASSERT_TRUE(pre.ok()) << pre.status();
    const Vec9d r = preintegration_residual(*pre, xi, xj, g_w);
    chi2 += r.dot(pre->cov.ldlt().solve(r));
  }
  ASSERT_GT(n, 5);
  // 9 degrees of freedom per interval; the sampled-signal model adds a little on top.
  EXPECT_LT(chi2 / n, 2.0 * 9.0) << "mean chi2 " << chi2 / n << " over " << n << " intervals";
  EXPECT_GT(chi2 / n, 0.2 * 9.0) << "mean chi2 " << chi2 / n << " (noise model too pessimistic)";
}

TEST(DynamicInitPreintegration, RefusesAnIntervalTheSamplesDoNotCover) {
  const std::vector<io::ImuSample> imu = {{0, Vec3d::Zero(), Vec3d(0, 0, 9.81)},
                                          {5000, Vec3d::Zero(), Vec3d(0, 0, 9.81)}};
  EXPECT_EQ(preintegrate(imu, 1000, 9000, Vec3d::Zero(), Vec3d::Zero(), ImuNoise{}).status().code(),
            absl::StatusCode::kOutOfRange);
  EXPECT_EQ(preintegrate(imu, 3000, 3000, Vec3d::Zero(), Vec3d::Zero(), ImuNoise{}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_TRUE(preintegrate(imu, 1000, 5000, Vec3d::Zero(), Vec3d::Zero(), ImuNoise{}).ok());
}

// ------------------------------------------------------------------------------------------
// The initializer

TEST(DynamicInit, RecoversTheStateOfAMovingWindow) {
  const sim::World& w = world({});
  const TrackOptions tracks;
  const std::vector<FeatureFrame> frames = make_frames(w, tracks);
  const auto r = dynamic_initialize(frames, measured_imu(w), w.calibration, noise_of(w.calibration), kGravity,
                                    test_options());
  ASSERT_TRUE(r.ok()) << r.status();
  const std::size_t last = tracks.first + tracks.count - 1;
  const ImuState truth = truth_at(w, last);
  EXPECT_EQ(r->imu.t_ns, truth.t_ns);
  EXPECT_EQ(r->method, "dynamic");
  EXPECT_EQ(r->imu.p_w_b, Vec3d::Zero());
  const Errors e = errors_of(*r, truth);
  EXPECT_LT(e.gravity_deg, 1.0);
  EXPECT_LT(e.velocity, 0.05);
  EXPECT_LT(e.gyro_bias, 2e-3);
  EXPECT_LT(e.accel_bias, 0.1);
  expect_spd(r->P);
  // The (inflated) covariance covers the errors it describes.
  EXPECT_LT(e.gyro_bias, 3.0 * std::sqrt(r->P.block<3, 3>(9, 9).trace()));
  EXPECT_LT(e.velocity, 3.0 * std::sqrt(r->P.block<3, 3>(6, 6).trace()));
}

TEST(DynamicInit, IsRobustToOutlierTracksAndUsesTheTimeOffset) {
  const sim::World& w = world({0.0, 5.0});  // t_imu = t_cam + 5 ms
  TrackOptions tracks;
  tracks.first = 8;
  tracks.sigma_px = 1.0;
  tracks.outlier_fraction = 0.1;
  tracks.seed = 21;
  const std::vector<FeatureFrame> frames = make_frames(w, tracks);
  const auto r = dynamic_initialize(frames, measured_imu(w), w.calibration, noise_of(w.calibration), kGravity,
                                    test_options());
  ASSERT_TRUE(r.ok()) << r.status();
  const ImuState truth = truth_at(w, tracks.first + tracks.count - 1);
  EXPECT_EQ(r->imu.t_ns, truth.t_ns);
  EXPECT_EQ(r->imu.t_ns, frames.back().t_ns + 5'000'000);
  const Errors e = errors_of(*r, truth);
  EXPECT_LT(e.gravity_deg, 1.0);
  EXPECT_LT(e.velocity, 0.05);
  EXPECT_LT(e.gyro_bias, 2e-3);
  EXPECT_LT(e.accel_bias, 0.1);
  expect_spd(r->P);
}

TEST(DynamicInit, IsAccurateAndConsistentOverWindowsAndSeeds) {
  const sim::World& w = world({});
  const auto imu = measured_imu(w);
  const DynamicInitOptions o = test_options();
  double sum_nees = 0.0;
  int runs = 0;
  for (const std::size_t first : {0, 6, 12, 16}) {
    for (const std::uint64_t seed : {1, 2}) {
      TrackOptions tracks;
      tracks.first = first;
      tracks.seed = seed;
      tracks.sigma_px = 1.0;
      const auto r = dynamic_initialize(make_frames(w, tracks), imu, w.calibration, noise_of(w.calibration),
                                        kGravity, o);
      ASSERT_TRUE(r.ok()) << "first frame " << first << ", seed " << seed << ": " << r.status();
      const ImuState truth = truth_at(w, first + tracks.count - 1);
      const Errors e = errors_of(*r, truth);
      EXPECT_LT(e.gravity_deg, 1.0);
      EXPECT_LT(e.velocity, 0.05);
      EXPECT_LT(e.gyro_bias, 2e-3);
      EXPECT_LT(e.accel_bias, 0.15);  // 1 px: the weakest direction has sigma ~0.06 m/s^2
      sum_nees += nees(*r, truth, o);
      ++runs;
    }
  }
  // 8 degrees of freedom: the uninflated covariance is about right (8 runs: +-50 %).
  EXPECT_LT(sum_nees / runs, 2.0 * 8.0);
  EXPECT_GT(sum_nees / runs, 0.25 * 8.0);
  std::cout << "[ result   ] mean NEES of [tilt, bg, ba] " << sum_nees / runs << " (8 dof)\n";
}

TEST(DynamicInit, IsDeterministic) {
  const sim::World& w = world({});
  const std::vector<FeatureFrame> frames = make_frames(w, TrackOptions{});
  const auto imu = measured_imu(w);
  const auto a =
      dynamic_initialize(frames, imu, w.calibration, noise_of(w.calibration), kGravity, test_options());
  const auto b =
      dynamic_initialize(frames, imu, w.calibration, noise_of(w.calibration), kGravity, test_options());
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->imu.q_w_b.coeffs(), b->imu.q_w_b.coeffs());
  EXPECT_EQ(a->imu.v_w_b, b->imu.v_w_b);
  EXPECT_EQ(a->P, b->P);
}

TEST(DynamicInit, RefusesAWindowWithoutRotation) {
  const sim::World& w = world({3.0, 0.0});  // the first 3 s are at rest
  const std::vector<FeatureFrame> frames = make_frames(w, TrackOptions{});
  const auto r = dynamic_initialize(frames, measured_imu(w), w.calibration, noise_of(w.calibration), kGravity,
                                    test_options());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(r.status().message().find("not enough rotation"), std::string::npos) << r.status();
  EXPECT_NE(r.status().message().find("min_rotation_deg"), std::string::npos) << r.status();
}

// The stereo points come from the caller's triangulation bounds: a street's points lie far
// beyond the default's 40 baselines (here 0.11 m: 4.4 m), where the estimator's own options
// (config/kaist.yaml: 200 baselines) still take them.
TEST(DynamicInit, TakesFarPointsWithTheEstimatorsTriangulationOptions) {
  const sim::World& w = world({});
  TrackOptions tracks;
  tracks.min_depth_m = 6.0;
  tracks.max_depth_m = 12.0;
  tracks.sigma_px = 0.2;
  const std::vector<FeatureFrame> frames = make_frames(w, tracks);
  const auto refused = dynamic_initialize(frames, measured_imu(w), w.calibration, noise_of(w.calibration),
                                          kGravity, test_options());
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("too few features"), std::string::npos) << refused.status();
  TriangulationOptions far;
  far.max_baseline_ratio = 200.0;
  far.max_cond = 1e6;
  const auto r = dynamic_initialize(frames, measured_imu(w), w.calibration, noise_of(w.calibration), kGravity,
                                    test_options(), far);
  ASSERT_TRUE(r.ok()) << r.status();
  const Errors e = errors_of(*r, truth_at(w, tracks.first + tracks.count - 1));
  EXPECT_LT(e.gravity_deg, 1.0);
  EXPECT_LT(e.velocity, 0.1);
}

TEST(DynamicInit, RefusesTooFewFeatures) {
  const sim::World& w = world({});
  TrackOptions tracks;
  tracks.points = 15;
  const auto r = dynamic_initialize(make_frames(w, tracks), measured_imu(w), w.calibration,
                                    noise_of(w.calibration), kGravity, test_options());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(r.status().message().find("too few features"), std::string::npos) << r.status();
  EXPECT_NE(r.status().message().find("min_features"), std::string::npos) << r.status();
}

TEST(DynamicInit, RefusesTooFewFramesOrMissingImu) {
  const sim::World& w = world({});
  std::vector<FeatureFrame> frames = make_frames(w, TrackOptions{});
  const auto imu = measured_imu(w);
  const std::vector<FeatureFrame> three(frames.begin(), frames.begin() + 3);
  const auto few =
      dynamic_initialize(three, imu, w.calibration, noise_of(w.calibration), kGravity, test_options());
  ASSERT_FALSE(few.ok());
  EXPECT_EQ(few.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(few.status().message().find("num_poses"), std::string::npos) << few.status();
  // The IMU ends before the newest frame: wait for it.
  std::vector<io::ImuSample> early;
  for (const auto& s : imu) {
    if (s.t_ns < frames.back().t_ns - 20'000'000) early.push_back(s);
  }
  const auto r =
      dynamic_initialize(frames, early, w.calibration, noise_of(w.calibration), kGravity, test_options());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(r.status().message().find("IMU"), std::string::npos) << r.status();
  // Frames out of order are a caller error.
  std::swap(frames[3], frames[4]);
  const auto bad =
      dynamic_initialize(frames, imu, w.calibration, noise_of(w.calibration), kGravity, test_options());
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace mrvs::edge
