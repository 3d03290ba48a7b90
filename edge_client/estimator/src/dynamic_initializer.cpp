// Dynamic initialisation (algorithm.md 6.1), in stages:
//   select_window      num_poses frames spread over the input, feature count check
//   relative_pose      stereo points of frame i against the bearings of frame i+1 (robust
//                      Gauss-Newton): metric relative camera poses
//   estimate_gyro_bias pre-integrated rotations against the visual ones, rotation check
//   solve_linear       velocities and gravity (|g| enforced) from the visual positions and
//                      the pre-integration, in the first body frame
//   refine             Ceres MLE of poses, velocities, biases and points (pre-integration,
//                      reprojection and prior factors), outlier rounds, covariance
// Conventions: the world frame w is gravity aligned (g_w = (0, 0, -g)); its yaw is that of
// the minimal rotation taking the first body frame's gravity to -z; the oldest pose of the
// window is held fixed (position, yaw) during the refinement and every position is shifted
// at the end so that the newest IMU position is 0. The biases are one constant pair over
// the window (their random walk over ~2 s is far below what the window determines).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <unordered_map>

#include <ceres/ceres.h>
#include <ceres/normal_prior.h>
#include <ceres/rotation.h>
#include <fmt/format.h>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include "mrvs/edge/dynamic_initializer.h"
#include "mrvs/edge/imu_factor.h"
#include "mrvs/edge/preintegration.h"
#include "mrvs/edge/triangulation.h"
#include "mrvs/geometry/quaternion.h"
#include "mrvs/geometry/so3.h"

namespace mrvs::edge {
namespace {

constexpr int kMinPairPoints = 8;          ///< stereo points needed between two frames
constexpr int kGyroBiasIterations = 3;     ///< re-integrations of the gyro bias solve
constexpr int kPoseIterations = 15;        ///< Gauss-Newton iterations of relative_pose
constexpr double kLinearSigmaPos = 0.01;   ///< m, weight of the visual positions (linear solve)
constexpr double kLinearSigmaVel = 0.003;  ///< m/s, floor of the velocity rows (linear solve)
constexpr double kYawPriorSigma = 1e-4;    ///< rad, gauge of the oldest pose's yaw
constexpr double kPreintFloor = 1e-12;     ///< variance added to the pre-integration covariance
constexpr int kMaxOutlierRounds = 2;       ///< re-solves after dropping outliers

Status fail(const std::string& why) { return absl::FailedPreconditionError(why); }

// ------------------------------------------------------------------------------------------
// Window

struct Window {
  std::vector<const FeatureFrame*> frames;
  std::vector<TimestampNs> t_imu_ns;  ///< frame times on the IMU clock
  std::vector<std::unordered_map<FeatureId, const FeatureObservation*>> by_id;
  std::size_t tracked = 0;  ///< features seen in most frames
};

StatusOr<Window> select_window(const std::vector<FeatureFrame>& frames, DurationNs offset_ns,
                               const DynamicInitOptions& o) {
  const std::size_t n = static_cast<std::size_t>(o.num_poses);
  if (frames.size() < n) return fail(fmt::format("{} frames, need num_poses = {}", frames.size(), n));
  for (std::size_t k = 1; k < frames.size(); ++k) {
    if (frames[k].t_ns <= frames[k - 1].t_ns) {
      return absl::InvalidArgumentError(
          fmt::format("frames not time-ordered at {} ({} ns)", k, frames[k].t_ns));
    }
  }
  Window w;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = (i * (frames.size() - 1) + (n - 1) / 2) / (n - 1);
    w.frames.push_back(&frames[k]);
    w.t_imu_ns.push_back(frames[k].t_ns + offset_ns);
    auto& map = w.by_id.emplace_back();
    for (const FeatureObservation& f : frames[k].features) map.emplace(f.id, &f);
  }
  std::unordered_map<FeatureId, std::size_t> count;
  for (const auto& map : w.by_id) {
    for (const auto& [id, obs] : map) ++count[id];
  }
  for (const auto& [id, c] : count) w.tracked += c > n / 2 ? 1 : 0;
  if (w.tracked < static_cast<std::size_t>(o.min_features)) {
    return fail(
        fmt::format("too few features: {} seen in more than {} of the {} frames, need min_features = {}",
                    w.tracked, n / 2, n, o.min_features));
  }
  return w;
}

StatusOr<std::vector<Preintegration>> preintegrate_window(const Window& w,
                                                          const std::vector<io::ImuSample>& imu,
                                                          const Vec3d& bg, const Vec3d& ba,
                                                          const ImuNoise& noise) {
  std::vector<Preintegration> out;
  for (std::size_t k = 0; k + 1 < w.t_imu_ns.size(); ++k) {
    auto pre = preintegrate(imu, w.t_imu_ns[k], w.t_imu_ns[k + 1], bg, ba, noise);
    if (!pre.ok()) {
      return fail(fmt::format("IMU does not cover the window yet ({})", std::string(pre.status().message())));
    }
    out.push_back(std::move(*pre));
  }
  return out;
}

// ------------------------------------------------------------------------------------------
// Relative camera poses from stereo points

using StereoPoints = std::unordered_map<FeatureId, Vec3d>;  ///< per feature: the point in cam0

/// The stereo-triangulated points of every window frame.
std::vector<StereoPoints> stereo_points(const Window& w, const SE3d& T_c0_c1,
                                        const TriangulationOptions& tri) {
  std::vector<StereoPoints> out(w.frames.size());
  for (std::size_t k = 0; k < w.frames.size(); ++k) {
    for (const FeatureObservation& f : w.frames[k]->features) {
      if (!f.stereo) continue;
      auto p = triangulate({{SE3d(), f.xn_left}, {T_c0_c1, f.xn_right}}, tri);
      if (p.ok()) out[k].emplace(f.id, *p);
    }
  }
  return out;
}

struct PairPoint {
  Vec3d p_ci;                       ///< in cam0 of frame i
  const FeatureObservation* obs_j;  ///< in frame j
};

std::vector<PairPoint> pair_points(const Window& w, std::size_t i, const StereoPoints& points_i) {
  std::vector<PairPoint> out;
  for (const auto& [id, p] : points_i) {
    const auto it = w.by_id[i + 1].find(id);
    if (it != w.by_id[i + 1].end()) out.push_back({p, it->second});
  }
  return out;
}

/// Adds the residual of normalised observation `xn` of q_c (a point in the camera frame) to
/// the normal equations (Huber-weighted); dq / d[dtheta, dt] = M [-[RP]x, I].
void accumulate(const Vec3d& q_c, const Mat3d& M, const Vec3d& RP, const Vec2d& xn, double huber,
                Eigen::Matrix<double, 6, 6>* H, Eigen::Matrix<double, 6, 1>* b) {
  if (q_c.z() < 1e-3) return;
  const double iz = 1.0 / q_c.z();
  const Vec2d r = xn - q_c.head<2>() * iz;
  Eigen::Matrix<double, 2, 3> Jp;
  Jp << iz, 0.0, -q_c.x() * iz * iz, 0.0, iz, -q_c.y() * iz * iz;
  Eigen::Matrix<double, 3, 6> dq;
  dq << -M * skew<double>(RP), M;
  const Eigen::Matrix<double, 2, 6> J = Jp * dq;
  const double e = r.norm();
  const double weight = e <= huber ? 1.0 : huber / e;
  *H += weight * J.transpose() * J;
  *b += weight * J.transpose() * r;
}

/// T_cj_ci of cam0 between window frames i and j = i + 1: the stereo points of frame i
/// against the left and right bearings of frame j, robust Gauss-Newton from `init`.
StatusOr<SE3d> relative_pose(const Window& w, std::size_t i, const StereoPoints& points_i,
                             const config::StereoRigCalibration& rig, SE3d init,
                             const DynamicInitOptions& o) {
  const SE3d T_c1_c0 = rig.T_c0_c1().inverse();
  const std::vector<PairPoint> pts = pair_points(w, i, points_i);
  if (static_cast<int>(pts.size()) < kMinPairPoints) {
    return fail(fmt::format("too few features: {} stereo points shared by window frames {} and {}, need {}",
                            pts.size(), i, i + 1, kMinPairPoints));
  }
  const double f = rig.cameras[0].model->fx();
  const double huber = o.sigma_px / f;
  const Mat3d R_c1_c0 = T_c1_c0.rotation_matrix();
  Mat3d R = init.rotation_matrix();
  Vec3d t = init.translation();
  for (int it = 0; it < kPoseIterations; ++it) {
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    for (const PairPoint& p : pts) {
      const Vec3d RP = R * p.p_ci;
      const Vec3d q = RP + t;
      accumulate(q, Mat3d::Identity(), RP, p.obs_j->xn_left, huber, &H, &b);
      if (p.obs_j->stereo) accumulate(T_c1_c0 * q, R_c1_c0, RP, p.obs_j->xn_right, huber, &H, &b);
    }
    const Eigen::Matrix<double, 6, 1> d = H.ldlt().solve(b);
    if (!d.allFinite()) {
      return fail(fmt::format("relative pose of window frames {} and {} is degenerate", i, i + 1));
    }
    R = so3::exp<double>(Vec3d(d.head<3>())) * R;
    t += d.tail<3>();
    if (d.norm() < 1e-10) break;
  }
  int inliers = 0;
  for (const PairPoint& p : pts) {
    const Vec3d q = R * p.p_ci + t;
    inliers += q.z() > 0.0 && (p.obs_j->xn_left - q.head<2>() / q.z()).norm() * f < o.outlier_px ? 1 : 0;
  }
  if (inliers < kMinPairPoints) {
    return fail(fmt::format("too few features: {} consistent stereo points between window frames {} and {}",
                            inliers, i, i + 1));
  }
  return SE3d(Quatd(R), t);
}

/// Median of the 3-D displacements of points with stereo in both frames (translation guess).
Vec3d median_translation(const StereoPoints& points_i, const StereoPoints& points_j, const Mat3d& R_cj_ci) {
  std::array<std::vector<double>, 3> d;
  for (const auto& [id, p_i] : points_i) {
    const auto it = points_j.find(id);
    if (it == points_j.end()) continue;
    const Vec3d delta = it->second - R_cj_ci * p_i;
    for (int a = 0; a < 3; ++a) d[a].push_back(delta[a]);
  }
  Vec3d out = Vec3d::Zero();
  for (int a = 0; a < 3 && !d[a].empty(); ++a) {
    std::nth_element(d[a].begin(), d[a].begin() + d[a].size() / 2, d[a].end());
    out[a] = d[a][d[a].size() / 2];
  }
  return out;
}

/// T_b0_bk of every window frame from the chained relative camera poses.
StatusOr<std::vector<SE3d>> visual_poses(const Window& w, const std::vector<Preintegration>& pre,
                                         const config::StereoRigCalibration& rig, const DynamicInitOptions& o,
                                         const TriangulationOptions& tri) {
  const SE3d& T_b_c = rig.cameras[0].T_b_c;
  const SE3d T_c_b = T_b_c.inverse();
  const std::vector<StereoPoints> points = stereo_points(w, rig.T_c0_c1(), tri);
  std::vector<SE3d> T_b0_bk = {SE3d()};
  for (std::size_t i = 0; i + 1 < w.frames.size(); ++i) {
    // Rotation guess from the gyroscope: R_cj_ci = R_c_b dR^T R_b_c.
    const Mat3d R_guess = (T_c_b * SE3d(pre[i].dq.conjugate(), Vec3d::Zero()) * T_b_c).rotation_matrix();
    const Vec3d t_guess = median_translation(points[i], points[i + 1], R_guess);
    MRVS_ASSIGN_OR_RETURN(const SE3d T_cj_ci,
                          relative_pose(w, i, points[i], rig, SE3d(Quatd(R_guess), t_guess), o));
    T_b0_bk.push_back(T_b0_bk.back() * T_b_c * T_cj_ci.inverse() * T_c_b);
  }
  return T_b0_bk;
}

// ------------------------------------------------------------------------------------------
// Gyroscope bias and rotation check

/// Gauss-Newton on sum_k |log(dR_k(bg)^T R_vis_k)|^2, re-integrating at every step.
StatusOr<Vec3d> estimate_gyro_bias(const Window& w, const std::vector<io::ImuSample>& imu,
                                   const std::vector<SE3d>& T_b0_bk, const ImuNoise& noise,
                                   std::vector<Preintegration>* pre) {
  Vec3d bg = Vec3d::Zero();
  for (int it = 0; it < kGyroBiasIterations; ++it) {
    Mat3d H = Mat3d::Zero();
    Vec3d b = Vec3d::Zero();
    for (std::size_t k = 0; k < pre->size(); ++k) {
      const Quatd R_vis = (T_b0_bk[k].inverse() * T_b0_bk[k + 1]).quaternion();
      const Vec3d r = quat::minus_right(R_vis, (*pre)[k].dq);
      const Mat3d& J = (*pre)[k].dR_dbg;
      H += J.transpose() * J;
      b += J.transpose() * r;
    }
    bg += H.ldlt().solve(b);
    if (!bg.allFinite()) return fail("gyroscope bias solve is degenerate");
    MRVS_ASSIGN_OR_RETURN(*pre, preintegrate_window(w, imu, bg, Vec3d::Zero(), noise));
  }
  return bg;
}

/// Largest rotation of a window frame from the oldest one (bias-corrected gyroscope), deg.
double window_rotation_deg(const std::vector<Preintegration>& pre) {
  Quatd q = Quatd::Identity();
  double largest = 0.0;
  for (const Preintegration& p : pre) {
    q = q * p.dq;
    largest = std::max(largest, so3::log<double>(q).norm());
  }
  return largest * 180.0 / M_PI;
}

// ------------------------------------------------------------------------------------------
// Linear solve: velocities and gravity in the first body frame

struct LinearSolution {
  std::vector<Vec3d> v_b0;  ///< velocity of every window frame
  Vec3d g_b0 = Vec3d::Zero();
  double free_gravity_norm = 0.0;  ///< |g| of the unconstrained solve (0 when singular)
  double constraint_error = 0.0;   ///< relative | |g| - g | of the constrained solve
};

/// min |A1 x1 + A2 g - b|^2 subject to |g| = g_mag: x1 eliminated, then the secular
/// equation of the 3 x 3 reduced problem (D - lambda I) g = d, lambda below eig_min(D).
StatusOr<LinearSolution> constrained_solve(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, double g_mag) {
  const int n1 = static_cast<int>(A.cols()) - 3;
  const Eigen::MatrixXd A1 = A.leftCols(n1), A2 = A.rightCols(3);
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A1);
  if (qr.rank() < n1) return fail("the velocities are not determined by the linear system");
  const Eigen::MatrixXd M2 = A2 - A1 * qr.solve(A2);  // (I - P1) A2
  const Eigen::VectorXd mb = b - A1 * qr.solve(b);    // (I - P1) b
  const Mat3d D = M2.transpose() * M2;
  const Vec3d d = M2.transpose() * mb;
  const Eigen::SelfAdjointEigenSolver<Mat3d> eig(D);
  const Vec3d s = eig.eigenvalues();
  const Vec3d c = eig.eigenvectors().transpose() * d;
  if (!(s(2) > 0.0) || s(0) < 1e-12 * s(2)) return fail("gravity is not determined by the linear system");
  LinearSolution out;
  out.free_gravity_norm = (eig.eigenvectors() * c.cwiseQuotient(s)).norm();
  const auto g_of = [&](double lambda) -> Vec3d {
    return eig.eigenvectors() * Vec3d(c(0) / (s(0) - lambda), c(1) / (s(1) - lambda), c(2) / (s(2) - lambda));
  };
  double lo = s(0) - c.norm() / g_mag - 1.0, hi = s(0);
  for (int it = 0; it < 200 && hi - lo > 1e-14 * std::max(1.0, std::abs(hi)); ++it) {
    const double mid = 0.5 * (lo + hi);
    (g_of(mid).norm() < g_mag ? lo : hi) = mid;
  }
  out.g_b0 = g_of(lo);
  out.constraint_error = std::abs(out.g_b0.norm() - g_mag) / g_mag;
  const Eigen::VectorXd x1 = qr.solve(b - A2 * out.g_b0);
  for (int k = 0; k < n1 / 3; ++k) out.v_b0.push_back(x1.segment<3>(3 * k));
  return out;
}

/// Rows per interval i -> j (weighted):  v_i dt + 0.5 g dt^2 = p_j - p_i - R_i dp,
///                                       v_j - v_i - g dt = R_i dv.
StatusOr<LinearSolution> solve_linear(const std::vector<SE3d>& T_b0_bk,
                                      const std::vector<Preintegration>& pre, double g_mag,
                                      const DynamicInitOptions& o) {
  const int n = static_cast<int>(T_b0_bk.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(6 * (n - 1), 3 * n + 3);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(6 * (n - 1));
  for (int i = 0; i + 1 < n; ++i) {
    const Preintegration& p = pre[i];
    const Mat3d R_i = T_b0_bk[i].rotation_matrix();
    const double dt = p.dt, wp = 1.0 / kLinearSigmaPos;
    const double wv =
        1.0 / std::sqrt(kLinearSigmaVel * kLinearSigmaVel + p.cov.block<3, 3>(6, 6).trace() / 3.0);
    const Mat3d I = Mat3d::Identity();
    A.block<3, 3>(6 * i, 3 * i) = wp * dt * I;
    A.block<3, 3>(6 * i, 3 * n) = wp * 0.5 * dt * dt * I;
    b.segment<3>(6 * i) = wp * (T_b0_bk[i + 1].translation() - T_b0_bk[i].translation() - R_i * p.dp);
    A.block<3, 3>(6 * i + 3, 3 * (i + 1)) = wv * I;
    A.block<3, 3>(6 * i + 3, 3 * i) = -wv * I;
    A.block<3, 3>(6 * i + 3, 3 * n) = -wv * dt * I;
    b.segment<3>(6 * i + 3) = wv * R_i * p.dv;
  }
  MRVS_ASSIGN_OR_RETURN(LinearSolution sol, constrained_solve(A, b, g_mag));
  if (sol.constraint_error > o.max_gravity_error) {
    return fail(
        fmt::format("gravity residual too large: |g| constraint met to {:.2e}, max_gravity_error = {:.2e}",
                    sol.constraint_error, o.max_gravity_error));
  }
  const double free_error = std::abs(sol.free_gravity_norm - g_mag) / g_mag;
  if (free_error > o.max_free_gravity_error) {
    return fail(
        fmt::format("gravity residual too large: the unconstrained solve gives |g| = {:.3f} m/s^2 "
                    "(relative error {:.3f} > max_free_gravity_error = {:.3f})",
                    sol.free_gravity_norm, free_error, o.max_free_gravity_error));
  }
  return sol;
}

// ------------------------------------------------------------------------------------------
// Ceres factors (quaternions in Eigen storage order x, y, z, w). The pre-integration factor
// is analytic (ImuCostFunction, imu_factor.h); the two small ones below use automatic
// derivatives.

template <typename T>
Vec3<T> log_q(const Quat<T>& q) {
  const T wxyz[4] = {q.w(), q.x(), q.y(), q.z()};
  Vec3<T> phi;
  ceres::QuaternionToAngleAxis(wxyz, phi.data());
  return phi;
}

/// Reprojection of a world point in camera c of a body pose: the normalised-coordinate
/// error mapped to pixels by the distortion Jacobian at the observation, whitened by sigma_px.
struct ReprojectionFactor {
  template <typename T>
  bool operator()(const T* q, const T* p, const T* point, T* residual) const {
    const Eigen::Map<const Quat<T>> q_w_b(q);
    const Eigen::Map<const Vec3<T>> p_w_b(p), p_w(point);
    const Vec3<T> p_c = q_c_b.cast<T>() * Vec3<T>(q_w_b.conjugate() * Vec3<T>(p_w - p_w_b)) + p_c_b.cast<T>();
    if (p_c.z() < T(1e-6)) return false;
    const Vec2<T> e(p_c.x() / p_c.z() - T(xn.x()), p_c.y() / p_c.z() - T(xn.y()));
    Eigen::Map<Vec2<T>> out(residual);
    out = W.cast<T>() * e;
    return true;
  }

  Vec2d xn;
  Quatd q_c_b;
  Vec3d p_c_b;
  Mat2d W;  ///< d uv / d xn at the observation, / sigma_px
};

/// Yaw (rotation about world z) of a pose relative to a reference: the gauge.
struct YawPrior {
  template <typename T>
  bool operator()(const T* q, T* residual) const {
    const Eigen::Map<const Quat<T>> q_w_b(q);
    residual[0] = log_q<T>(Quat<T>(q_w_b * q_ref.conjugate().cast<T>())).z() / T(kYawPriorSigma);
    return true;
  }
  Quatd q_ref;
};

// ------------------------------------------------------------------------------------------
// Refinement

struct Observation {
  std::size_t frame = 0;  ///< window index
  int cam = 0;
  Vec2d xn = Vec2d::Zero();
  Mat2d J = Mat2d::Identity();  ///< d uv / d xn (px) at xn
  bool inlier = true;
};

Observation observation(std::size_t frame, int cam, const Vec2d& xn,
                        const config::StereoRigCalibration& rig) {
  Observation ob{frame, cam, xn, Mat2d::Identity(), true};
  rig.cameras[static_cast<std::size_t>(cam)].model->distort(xn, &ob.J);
  return ob;
}

struct Landmark {
  FeatureId id = 0;
  std::array<double, 3> p_w{};
  std::vector<Observation> obs;
};

/// The refinement's variables (stable addresses for Ceres).
struct Variables {
  std::vector<std::array<double, 4>> q;  ///< q_w_bk, x y z w
  std::vector<std::array<double, 3>> p, v;
  std::array<double, 3> bg{}, ba{};
  std::vector<Landmark> landmarks;

  SE3d T_w_b(std::size_t k) const { return SE3d(Quatd(q[k].data()), Vec3d(p[k].data())); }
};

/// The smallest rotation taking direction a to direction b; a half turn about an axis
/// orthogonal to a when they are opposite. The rotation of Quatd::FromTwoVectors (same
/// arithmetic), without its SVD for the opposite case: that SVD alone took ~10-20 s of this
/// file's -O3 compile time.
Quatd rotation_between(const Vec3d& a, const Vec3d& b) {
  const Vec3d u = a.normalized(), v = b.normalized();
  const double c = u.dot(v);  // cos(angle)
  if (c < -1.0 + 1e-12) {
    const Vec3d n = u.unitOrthogonal();
    return Quatd(0.0, n.x(), n.y(), n.z());
  }
  const double s = std::sqrt((1.0 + c) * 2.0);  // 2 cos(angle / 2); |u x v| = s sin(angle / 2)
  const Vec3d xyz = u.cross(v) * (1.0 / s);
  return Quatd(0.5 * s, xyz.x(), xyz.y(), xyz.z());
}

Variables initial_variables(const std::vector<SE3d>& T_b0_bk, const LinearSolution& lin, const Vec3d& bg) {
  const Quatd q_w_b0 = rotation_between(lin.g_b0.normalized(), Vec3d(0.0, 0.0, -1.0));
  Variables x;
  for (std::size_t k = 0; k < T_b0_bk.size(); ++k) {
    const Quatd q = (q_w_b0 * T_b0_bk[k].quaternion()).normalized();
    const Vec3d p = q_w_b0 * T_b0_bk[k].translation(), v = q_w_b0 * lin.v_b0[k];
    x.q.push_back({q.x(), q.y(), q.z(), q.w()});
    x.p.push_back({p.x(), p.y(), p.z()});
    x.v.push_back({v.x(), v.y(), v.z()});
  }
  x.bg = {bg.x(), bg.y(), bg.z()};
  return x;
}

/// Triangulates the longest tracks (seen in 2 or more window frames) from the initial poses.
void add_landmarks(const Window& w, const config::StereoRigCalibration& rig, const DynamicInitOptions& o,
                   const TriangulationOptions& tri, Variables* x) {
  std::unordered_map<FeatureId, Landmark> tracks;
  for (std::size_t k = 0; k < w.frames.size(); ++k) {
    for (const FeatureObservation& f : w.frames[k]->features) {
      Landmark& l = tracks[f.id];
      l.id = f.id;
      l.obs.push_back(observation(k, 0, f.xn_left, rig));
      if (f.stereo) l.obs.push_back(observation(k, 1, f.xn_right, rig));
    }
  }
  std::vector<Landmark> all;
  for (auto& [id, l] : tracks) {
    if (l.obs.front().frame != l.obs.back().frame) all.push_back(std::move(l));
  }
  std::sort(all.begin(), all.end(), [](const Landmark& a, const Landmark& b) {
    return a.obs.size() != b.obs.size() ? a.obs.size() > b.obs.size() : a.id < b.id;
  });
  for (Landmark& l : all) {
    if (static_cast<int>(x->landmarks.size()) >= o.max_features) break;
    std::vector<BearingObservation> bearings;
    for (const Observation& ob : l.obs)
      bearings.push_back({x->T_w_b(ob.frame) * rig.cameras[ob.cam].T_b_c, ob.xn});
    auto p = triangulate(bearings, tri);
    if (!p.ok()) continue;
    l.p_w = {p->x(), p->y(), p->z()};
    x->landmarks.push_back(std::move(l));
  }
}

ceres::CostFunction* reprojection_cost(const Observation& ob, const config::StereoRigCalibration& rig,
                                       const DynamicInitOptions& o) {
  const SE3d T_c_b = rig.cameras[ob.cam].T_b_c.inverse();
  return new ceres::AutoDiffCostFunction<ReprojectionFactor, 2, 4, 3, 3>(
      new ReprojectionFactor{ob.xn, T_c_b.quaternion(), T_c_b.translation(), ob.J / o.sigma_px});
}

std::unique_ptr<ceres::Problem> build_problem(Variables* x, const std::vector<Preintegration>& pre,
                                              double g_mag, const config::StereoRigCalibration& rig,
                                              const DynamicInitOptions& o, ceres::Manifold* manifold,
                                              ceres::LossFunction* loss) {
  ceres::Problem::Options po;
  po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  auto problem = std::make_unique<ceres::Problem>(po);
  for (std::size_t k = 0; k < x->q.size(); ++k) {
    problem->AddParameterBlock(x->q[k].data(), 4, manifold);
    problem->AddParameterBlock(x->p[k].data(), 3);
    problem->AddParameterBlock(x->v[k].data(), 3);
  }
  problem->SetParameterBlockConstant(x->p[0].data());
  problem->AddResidualBlock(
      new ceres::AutoDiffCostFunction<YawPrior, 1, 4>(new YawPrior{Quatd(x->q[0].data())}), nullptr,
      x->q[0].data());
  const Vec3d g_w(0.0, 0.0, -g_mag);
  for (std::size_t k = 0; k < pre.size(); ++k) {
    problem->AddResidualBlock(new ImuCostFunction(pre[k], g_w, kPreintFloor), nullptr, x->q[k].data(),
                              x->p[k].data(), x->v[k].data(), x->q[k + 1].data(), x->p[k + 1].data(),
                              x->v[k + 1].data(), x->bg.data(), x->ba.data());
  }
  problem->AddResidualBlock(new ceres::NormalPrior(Mat3d::Identity() / o.prior_gyro_bias, Vec3d::Zero()),
                            nullptr, x->bg.data());
  problem->AddResidualBlock(new ceres::NormalPrior(Mat3d::Identity() / o.prior_accel_bias, Vec3d::Zero()),
                            nullptr, x->ba.data());
  for (Landmark& l : x->landmarks) {
    for (const Observation& ob : l.obs) {
      if (!ob.inlier) continue;
      problem->AddResidualBlock(reprojection_cost(ob, rig, o), loss, x->q[ob.frame].data(),
                                x->p[ob.frame].data(), l.p_w.data());
    }
  }
  return problem;
}

/// Reprojection error (px) of one observation at the current variables; +inf behind the camera.
double reprojection_px(const Variables& x, const Landmark& l, const Observation& ob,
                       const config::StereoRigCalibration& rig) {
  const SE3d T_c_w = (x.T_w_b(ob.frame) * rig.cameras[ob.cam].T_b_c).inverse();
  const Vec3d p_c = T_c_w * Vec3d(l.p_w.data());
  if (p_c.z() <= 1e-6) return std::numeric_limits<double>::infinity();
  return (ob.J * (p_c.head<2>() / p_c.z() - ob.xn)).norm();
}

/// Marks observations above `threshold_px` as outliers; returns how many were newly marked.
int mark_outliers(Variables* x, const config::StereoRigCalibration& rig, double threshold_px) {
  int marked = 0;
  for (Landmark& l : x->landmarks) {
    for (Observation& ob : l.obs) {
      if (ob.inlier && !(reprojection_px(*x, l, ob, rig) <= threshold_px)) {
        ob.inlier = false;
        ++marked;
      }
    }
  }
  return marked;
}

/// Drops the landmarks left with inliers in fewer than 2 frames (moves the landmarks: any
/// problem built on them must be rebuilt).
void prune_landmarks(Variables* x) {
  const auto too_few = [](const Landmark& l) {
    std::size_t first = l.obs.size(), last = 0, n = 0;
    for (std::size_t i = 0; i < l.obs.size(); ++i) {
      if (!l.obs[i].inlier) continue;
      ++n;
      first = std::min(first, l.obs[i].frame);
      last = std::max(last, l.obs[i].frame);
    }
    return n < 2 || first == last;
  };
  x->landmarks.erase(std::remove_if(x->landmarks.begin(), x->landmarks.end(), too_few), x->landmarks.end());
}

struct Refinement {
  std::unique_ptr<ceres::Problem> problem;
  ceres::Solver::Summary summary;
  int outliers = 0;
  int observations = 0;
  int iterations = 0;         ///< over every round
  double initial_cost = 0.0;  ///< of the first round
};

StatusOr<Refinement> refine(const Window& w, const std::vector<io::ImuSample>& imu, const ImuNoise& noise,
                            double g_mag, const config::StereoRigCalibration& rig,
                            const DynamicInitOptions& o, ceres::Manifold* manifold, ceres::LossFunction* loss,
                            Variables* x) {
  // Gross outliers against the initial poses (points behind a camera, far-off tracks).
  Refinement out;
  out.outliers = mark_outliers(x, rig, 10.0 * o.outlier_px);
  prune_landmarks(x);
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_SCHUR;
  so.max_num_iterations = o.max_iterations;
  so.max_solver_time_in_seconds = o.max_solver_time_s;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  for (int round = 0; round <= kMaxOutlierRounds; ++round) {
    if (static_cast<int>(x->landmarks.size()) < o.min_features) {
      return fail(
          fmt::format("too few features: {} usable landmarks after outlier removal, need min_features = {}",
                      x->landmarks.size(), o.min_features));
    }
    // Re-linearise the pre-integration at the current biases.
    MRVS_ASSIGN_OR_RETURN(const std::vector<Preintegration> pre,
                          preintegrate_window(w, imu, Vec3d(x->bg.data()), Vec3d(x->ba.data()), noise));
    out.problem = build_problem(x, pre, g_mag, rig, o, manifold, loss);
    ceres::Solve(so, out.problem.get(), &out.summary);
    if (!out.summary.IsSolutionUsable()) {
      return fail("solver failure: " + out.summary.message);
    }
    if (round == 0) out.initial_cost = out.summary.initial_cost;
    out.iterations += static_cast<int>(out.summary.iterations.size());
    if (round == kMaxOutlierRounds) break;  // keep the problem as solved (the covariance uses it)
    const int marked = mark_outliers(x, rig, o.outlier_px);
    if (marked == 0) break;
    out.outliers += marked;
    prune_landmarks(x);
  }
  out.observations = out.problem->NumResidualBlocks() - static_cast<int>(w.frames.size()) - 2;
  return out;
}

/// 15 x 15 covariance of the newest IMU state in the ImuState order, inflated.
StatusOr<Mat15d> newest_covariance(Variables* x, ceres::Problem* problem, const DynamicInitOptions& o) {
  const std::size_t k = x->q.size() - 1;
  const std::vector<const double*> blocks = {x->q[k].data(), x->p[k].data(), x->v[k].data(), x->bg.data(),
                                             x->ba.data()};
  ceres::Covariance::Options co;
  co.num_threads = 1;
  Eigen::Matrix<double, 15, 15, Eigen::RowMajor> P;
  bool ok = false;
  for (const auto algorithm : {ceres::SPARSE_QR, ceres::DENSE_SVD}) {
    co.algorithm_type = algorithm;
    ceres::Covariance covariance(co);
    ok =
        covariance.Compute(blocks, problem) && covariance.GetCovarianceMatrixInTangentSpace(blocks, P.data());
    if (ok) break;
  }
  if (!ok || !P.allFinite()) return fail("solver failure: the covariance of the result is not computable");
  Vec15d scale = Vec15d::Ones();
  scale.segment<3>(0).setConstant(std::sqrt(o.inflate_orientation));
  scale.segment<3>(6).setConstant(std::sqrt(o.inflate_velocity));
  scale.segment<3>(9).setConstant(std::sqrt(o.inflate_gyro_bias));
  scale.segment<3>(12).setConstant(std::sqrt(o.inflate_accel_bias));
  Mat15d out = scale.asDiagonal() * Mat15d(P) * scale.asDiagonal();
  out = 0.5 * (out + out.transpose());
  if (Eigen::LLT<Mat15d>(out).info() != Eigen::Success) {
    return fail("solver failure: the covariance of the result is not positive definite");
  }
  return out;
}

}  // namespace

StatusOr<InitializationResult> dynamic_initialize(const std::vector<FeatureFrame>& frames,
                                                  const std::vector<io::ImuSample>& imu,
                                                  const config::StereoRigCalibration& rig,
                                                  const ImuNoise& noise, double g,
                                                  const DynamicInitOptions& options,
                                                  const TriangulationOptions& triangulation) {
  MRVS_ASSIGN_OR_RETURN(const Window w, select_window(frames, rig.cameras[0].time_offset_ns, options));
  MRVS_ASSIGN_OR_RETURN(std::vector<Preintegration> pre,
                        preintegrate_window(w, imu, Vec3d::Zero(), Vec3d::Zero(), noise));
  MRVS_ASSIGN_OR_RETURN(const std::vector<SE3d> T_b0_bk, visual_poses(w, pre, rig, options, triangulation));
  MRVS_ASSIGN_OR_RETURN(const Vec3d bg, estimate_gyro_bias(w, imu, T_b0_bk, noise, &pre));
  const double rotation_deg = window_rotation_deg(pre);
  if (rotation_deg < options.min_rotation_deg) {
    return fail(
        fmt::format("not enough rotation: {:.2f} deg within the window, need min_rotation_deg = {:.2f}",
                    rotation_deg, options.min_rotation_deg));
  }
  MRVS_ASSIGN_OR_RETURN(const LinearSolution lin, solve_linear(T_b0_bk, pre, g, options));
  Variables x = initial_variables(T_b0_bk, lin, bg);
  add_landmarks(w, rig, options, triangulation, &x);
  RightQuaternionManifold manifold;
  ceres::HuberLoss loss(1.0);
  MRVS_ASSIGN_OR_RETURN(Refinement r, refine(w, imu, noise, g, rig, options, &manifold, &loss, &x));
  MRVS_ASSIGN_OR_RETURN(const Mat15d P, newest_covariance(&x, r.problem.get(), options));

  const std::size_t k = x.q.size() - 1;
  InitializationResult out;
  out.imu.t_ns = w.t_imu_ns.back();
  out.imu.q_w_b = Quatd(x.q[k].data()).normalized();
  out.imu.p_w_b = Vec3d::Zero();  // every position shifted by -p_k
  out.imu.v_w_b = Vec3d(x.v[k].data());
  out.imu.bg = Vec3d(x.bg.data());
  out.imu.ba = Vec3d(x.ba.data());
  out.P = P;
  out.method = "dynamic";
  const ceres::Solver::Summary& s = r.summary;
  out.detail = fmt::format(
      "{} poses over {:.2f} s, rotation {:.1f} deg, {} features ({} observations, {} outliers), linear |g| "
      "{:.3f}, "
      "ceres {} iterations, cost {:.4g} -> {:.4g} ({})",
      w.frames.size(), to_seconds(w.t_imu_ns.back() - w.t_imu_ns.front()), rotation_deg, x.landmarks.size(),
      r.observations, r.outliers, lin.free_gravity_norm, r.iterations, r.initial_cost, s.final_cost,
      ceres::TerminationTypeToString(s.termination_type));
  return out;
}

}  // namespace mrvs::edge
