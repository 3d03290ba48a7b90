#include "mrvs/camera/pinhole_equidistant.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace mrvs::camera {
namespace {

constexpr double kHalfPi = 1.57079632679489661923;
constexpr int kThetaMaxIterations = 100;
constexpr double kThetaStepTolerance = 1e-14;    // radians, relative to max(1, theta)
constexpr double kThetaMaxPixelResidual = 1e-9;  // pixels
// Below these radii the closed forms lose precision (0/0 at r = 0); series are used.
constexpr double kSeriesRadiusThetaOverR = 1e-6;
constexpr double kSeriesRadiusG = 1e-2;

// P(t2) = 1 + k1 t2 + k2 t2^2 + k3 t2^3 + k4 t2^4 with t2 = theta^2.
double poly(double t2, const Eigen::Vector4d& k) {
  return 1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])));
}

// dP / d t2.
double poly_derivative(double t2, const Eigen::Vector4d& k) {
  return k[0] + t2 * (2.0 * k[1] + t2 * (3.0 * k[2] + t2 * 4.0 * k[3]));
}

// atan(r) / r, smooth through r = 0.
double theta_over_r(double r) {
  if (r < kSeriesRadiusThetaOverR) {
    const double r2 = r * r;
    return 1.0 - r2 / 3.0 + r2 * r2 / 5.0;
  }
  return std::atan(r) / r;
}

// g(r) = (r / (1 + r^2) - atan(r)) / r^3 = d(atan(r) / r)/dr / r, smooth through r = 0:
// g = sum_{m >= 1} (-1)^m 2m / (2m + 1) r^(2m - 2).
double g_of_r(double r) {
  const double r2 = r * r;
  if (r < kSeriesRadiusG) {
    return -2.0 / 3.0 + r2 * (4.0 / 5.0 + r2 * (-6.0 / 7.0 + r2 * (8.0 / 9.0 - r2 * (10.0 / 11.0))));
  }
  return (r / (1.0 + r2) - std::atan(r)) / (r2 * r);
}

// d theta_d / d theta = 1 + 3 k1 t2 + 5 k2 t2^2 + 7 k3 t2^3 + 9 k4 t2^4 with t2 = theta^2.
double theta_d_derivative(double theta, const Eigen::Vector4d& k) {
  const double t2 = theta * theta;
  return 1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
}

// First zero of d theta_d / d theta in (0, pi/2] (scan, then bisection), or pi/2.
double fold_theta(const Eigen::Vector4d& k) {
  constexpr int kScanSteps = 2000;
  double lo = 0.0;
  for (int i = 1; i <= kScanSteps; ++i) {
    const double hi = kHalfPi * i / kScanSteps;
    if (theta_d_derivative(hi, k) > 0.0) {
      lo = hi;
      continue;
    }
    double bad = hi;
    for (int it = 0; it < 100 && bad - lo > 1e-15; ++it) {
      const double mid = 0.5 * (lo + bad);
      (theta_d_derivative(mid, k) > 0.0 ? lo : bad) = mid;
    }
    return lo;
  }
  return kHalfPi;
}

Status undistort_error(const Vec2d& uv, const std::string& why) {
  return absl::InvalidArgumentError(
      fmt::format("undistort (equidistant): pixel ({}, {}) {}", uv.x(), uv.y(), why));
}

}  // namespace

PinholeEquidistant::PinholeEquidistant(int width, int height, const Params& params)
    : CameraModel(width, height, params), max_theta_(fold_theta(params.tail<4>())) {}

StatusOr<std::unique_ptr<PinholeEquidistant>> PinholeEquidistant::create(int width, int height,
                                                                         const Params& params) {
  MRVS_RETURN_IF_ERROR(validate_camera(DistortionModel::kEquidistant, width, height, params));
  return std::unique_ptr<PinholeEquidistant>(new PinholeEquidistant(width, height, params));
}

std::unique_ptr<CameraModel> PinholeEquidistant::clone() const {
  return std::unique_ptr<CameraModel>(new PinholeEquidistant(width(), height(), params()));
}

double PinholeEquidistant::theta_d(double theta, const Eigen::Vector4d& dist) {
  return theta * poly(theta * theta, dist);
}

Vec2d PinholeEquidistant::distort_normalized(const Vec2d& xn, const Eigen::Vector4d& dist, Mat2d* J_xn) {
  const double r2 = xn.squaredNorm();
  const double r = std::sqrt(r2);
  const double t_over_r = theta_over_r(r);
  const double theta = t_over_r * r;
  const double t2 = theta * theta;
  const double p = poly(t2, dist);
  const double s = t_over_r * p;  // theta_d / r
  if (J_xn != nullptr) {
    // xd = s(r) xn  =>  d xd / d xn = s I + (ds/dr / r) xn xn^T, with
    // ds/dr / r = g(r) P + 2 (theta / r)^2 P'(theta^2) / (1 + r^2).
    const double c = g_of_r(r) * p + 2.0 * t_over_r * t_over_r * poly_derivative(t2, dist) / (1.0 + r2);
    *J_xn = s * Mat2d::Identity() + c * xn * xn.transpose();
  }
  return s * xn;
}

Vec2d PinholeEquidistant::distort(const Vec2d& xn, Mat2d* J_xn, Eigen::Matrix<double, 2, 8>* J_params) const {
  const Eigen::Vector4d dist = params().tail<4>();
  const Vec2d xd = distort_normalized(xn, dist, J_xn);
  if (J_xn != nullptr) {
    J_xn->row(0) *= fx();
    J_xn->row(1) *= fy();
  }
  if (J_params != nullptr) {
    J_params->setZero();
    (*J_params)(0, 0) = xd.x();
    (*J_params)(1, 1) = xd.y();
    (*J_params)(0, 2) = 1.0;
    (*J_params)(1, 3) = 1.0;
    // d xd / d k_i = xn (theta / r) theta^(2 i), i = 1..4.
    const double r = xn.norm();
    const double t_over_r = theta_over_r(r);
    const double theta = t_over_r * r;
    const double t2 = theta * theta;
    double power = t_over_r;
    for (int i = 0; i < 4; ++i) {
      power *= t2;
      (*J_params)(0, 4 + i) = fx() * xn.x() * power;
      (*J_params)(1, 4 + i) = fy() * xn.y() * power;
    }
  }
  return Vec2d(fx() * xd.x() + cx(), fy() * xd.y() + cy());
}

StatusOr<Vec2d> PinholeEquidistant::undistort(const Vec2d& uv) const {
  if (!uv.allFinite()) return undistort_error(uv, "is not finite");
  const Eigen::Vector4d k = params().tail<4>();
  const Vec2d xd((uv.x() - cx()) / fx(), (uv.y() - cy()) / fy());
  const double td = xd.norm();
  // theta_d(theta) increases on [0, max_theta_]: a solution exists there iff
  // theta_d(max_theta_) >= td.
  if (!(theta_d(max_theta_, k) >= td)) {
    if (max_theta_ >= kHalfPi) {
      return undistort_error(uv, fmt::format("looks 90 degrees or more off the optical axis (theta_d = {} > "
                                             "{} at 90 degrees): it has no normalised coordinates",
                                             td, theta_d(kHalfPi, k)));
    }
    return undistort_error(uv, fmt::format("lies beyond {} degrees off axis, where the distortion folds over",
                                           max_theta_ * 90.0 / kHalfPi));
  }
  // Safeguarded 1D Newton on f(theta) = theta_d(theta) - td inside the bracket [lo, hi].
  double lo = 0.0, hi = max_theta_;
  double theta = std::min(td, hi);
  for (int iter = 0; iter < kThetaMaxIterations; ++iter) {
    const double f = theta_d(theta, k) - td;
    if (f == 0.0) break;
    (f < 0.0 ? lo : hi) = theta;
    const double newton = theta - f / theta_d_derivative(theta, k);
    if (std::abs(newton - theta) <= kThetaStepTolerance * std::max(1.0, theta)) {
      theta = newton;
      break;
    }
    theta = (newton > lo && newton < hi) ? newton : 0.5 * (lo + hi);  // bisection fallback
  }
  if (!(theta < kHalfPi)) return undistort_error(uv, "looks 90 degrees off the optical axis");
  const double scale = td > 0.0 ? std::tan(theta) / td : 1.0;
  const Vec2d xn = scale * xd;
  const double pixel_error = (distort(xn) - uv).norm();
  if (!(pixel_error < kThetaMaxPixelResidual)) {
    return undistort_error(uv, fmt::format("did not converge (re-distortion error {} px > {} px)",
                                           pixel_error, kThetaMaxPixelResidual));
  }
  return xn;
}

}  // namespace mrvs::camera
