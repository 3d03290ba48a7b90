#include "mrvs/edge/triangulation.h"

#include <fmt/format.h>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace mrvs::edge {
namespace {

/// T_ci_A for every observation, A = the anchor (last) camera.
std::vector<SE3d> relative_to_anchor(const std::vector<BearingObservation>& obs) {
  const SE3d T_A_w = obs.back().T_w_c.inverse();
  std::vector<SE3d> out;
  out.reserve(obs.size());
  for (const BearingObservation& o : obs) out.push_back(o.T_w_c.inverse() * T_A_w.inverse());
  return out;
}

StatusOr<Vec3d> linear_in_anchor(const std::vector<BearingObservation>& obs, const std::vector<SE3d>& T_ci_A,
                                 const TriangulationOptions& o) {
  Mat3d A = Mat3d::Zero();
  Vec3d b = Vec3d::Zero();
  for (std::size_t i = 0; i < obs.size(); ++i) {
    const SE3d T_A_ci = T_ci_A[i].inverse();
    const Vec3d f = (T_A_ci.rotation_matrix() * Vec3d(obs[i].xn.x(), obs[i].xn.y(), 1.0)).normalized();
    const Mat3d B = Mat3d::Identity() - f * f.transpose();
    A += B;
    b += B * T_A_ci.translation();
  }
  // A is symmetric positive semi-definite: its eigenvalues are its singular values.
  const Eigen::SelfAdjointEigenSolver<Mat3d> eig(A, Eigen::EigenvaluesOnly);
  const Vec3d ev = eig.eigenvalues();
  const double cond = ev(2) / std::max(ev(0), 1e-300);
  if (cond > o.max_cond) {
    return absl::FailedPreconditionError(
        fmt::format("ill-conditioned (cond {:.3g} > {:.3g})", cond, o.max_cond));
  }
  return Vec3d(A.ldlt().solve(b));
}

double cost(const std::vector<BearingObservation>& obs, const std::vector<SE3d>& T_ci_A, const Vec3d& x) {
  double c = 0.0;
  for (std::size_t i = 0; i < obs.size(); ++i) {
    const Vec3d h = T_ci_A[i].rotation_matrix() * Vec3d(x.x(), x.y(), 1.0) + x.z() * T_ci_A[i].translation();
    c += (h.head<2>() / h.z() - obs[i].xn).squaredNorm();
  }
  return c;
}

/// Levenberg-Marquardt on x = (alpha, beta, rho), p_A = (alpha, beta, 1) / rho.
Vec3d refine(const std::vector<BearingObservation>& obs, const std::vector<SE3d>& T_ci_A, Vec3d x,
             const TriangulationOptions& o) {
  double lambda = o.init_lambda, c = cost(obs, T_ci_A, x);
  for (int run = 0; run < o.max_iterations; ++run) {
    Mat3d H = Mat3d::Zero();
    Vec3d g = Vec3d::Zero();
    for (std::size_t i = 0; i < obs.size(); ++i) {
      const Mat3d R = T_ci_A[i].rotation_matrix();
      const Vec3d& t = T_ci_A[i].translation();
      const Vec3d h = R * Vec3d(x.x(), x.y(), 1.0) + x.z() * t;
      Eigen::Matrix<double, 2, 3> dz_dh;
      dz_dh << 1.0 / h.z(), 0.0, -h.x() / (h.z() * h.z()), 0.0, 1.0 / h.z(), -h.y() / (h.z() * h.z());
      Mat3d dh_dx;
      dh_dx << R.col(0), R.col(1), t;
      const Eigen::Matrix<double, 2, 3> Jz = dz_dh * dh_dx;
      const Vec2d r = obs[i].xn - h.head<2>() / h.z();
      H += Jz.transpose() * Jz;
      g += Jz.transpose() * r;
    }
    for (int tries = 0; tries < 10; ++tries) {
      Mat3d Hd = H;
      Hd.diagonal() *= 1.0 + lambda;
      const Vec3d dx = Hd.ldlt().solve(g);
      const double c_new = cost(obs, T_ci_A, x + dx);
      if (c_new < c) {
        x += dx;
        lambda = std::max(lambda / 10.0, 1e-10);
        const bool converged = dx.norm() < 1e-6 || c - c_new < 1e-12;
        c = c_new;
        if (converged) return x;
        break;
      }
      lambda *= 10.0;
      if (lambda > 1e10) return x;
    }
  }
  return x;
}

}  // namespace

StatusOr<Vec3d> triangulate(const std::vector<BearingObservation>& obs, const TriangulationOptions& o) {
  if (obs.size() < 2)
    return absl::FailedPreconditionError(fmt::format("{} observation(s), need 2", obs.size()));
  const std::vector<SE3d> T_ci_A = relative_to_anchor(obs);
  MRVS_ASSIGN_OR_RETURN(const Vec3d p_lin, linear_in_anchor(obs, T_ci_A, o));
  if (p_lin.z() < o.min_dist_m || p_lin.z() > o.max_dist_m) {
    return absl::FailedPreconditionError(fmt::format("linear depth {:.3f} m out of range", p_lin.z()));
  }
  const Vec3d x =
      refine(obs, T_ci_A, Vec3d(p_lin.x() / p_lin.z(), p_lin.y() / p_lin.z(), 1.0 / p_lin.z()), o);
  const Vec3d p_A = Vec3d(x.x(), x.y(), 1.0) / x.z();
  if (!(p_A.z() >= o.min_dist_m && p_A.z() <= o.max_dist_m)) {
    return absl::FailedPreconditionError(fmt::format("refined depth {:.3f} m out of range", p_A.z()));
  }
  // Largest baseline perpendicular to the anchor ray.
  const Vec3d dir = p_A.normalized();
  double baseline = 0.0;
  for (const SE3d& T : T_ci_A) {
    const Vec3d c_A = T.inverse().translation();
    baseline = std::max(baseline, (c_A - c_A.dot(dir) * dir).norm());
  }
  if (baseline <= 0.0 || p_A.norm() / baseline > o.max_baseline_ratio) {
    return absl::FailedPreconditionError(
        fmt::format("baseline {:.4f} m too short for depth {:.2f} m", baseline, p_A.norm()));
  }
  return obs.back().T_w_c * p_A;
}

}  // namespace mrvs::edge
