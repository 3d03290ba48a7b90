#include "mrvs/camera/pinhole_radtan.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace mrvs::camera {
namespace {

constexpr int kUndistortMaxIterations = 50;
constexpr int kUndistortMaxHalvings = 30;
constexpr double kUndistortStepTolerance = 1e-14;    // normalised units, relative to max(1, |xn|)
constexpr double kUndistortMaxPixelResidual = 1e-9;  // pixels

// Smallest radius r > 0 where d/dr [r (1 + k1 r^2 + k2 r^4)] = 1 + 3 k1 s + 5 k2 s^2 (s = r^2)
// vanishes; +infinity when it stays positive.
double fold_radius(double k1, double k2) {
  const double a = 5.0 * k2, b = 3.0 * k1;
  double s = std::numeric_limits<double>::infinity();
  if (a == 0.0) {
    if (b < 0.0) s = -1.0 / b;
  } else {
    const double disc = b * b - 4.0 * a;
    if (disc >= 0.0) {
      // Stable roots of a s^2 + b s + 1: q = -(b + sign(b) sqrt(disc)) / 2, roots q / a, 1 / q.
      const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
      for (double root : {q / a, q != 0.0 ? 1.0 / q : -1.0}) {
        if (root > 0.0) s = std::min(s, root);
      }
    }
  }
  return std::sqrt(s);
}

}  // namespace

PinholeRadtan::PinholeRadtan(int width, int height, const Params& params)
    : CameraModel(width, height, params), max_radius_(fold_radius(params[4], params[5])) {}

StatusOr<std::unique_ptr<PinholeRadtan>> PinholeRadtan::create(int width, int height, const Params& params) {
  MRVS_RETURN_IF_ERROR(validate_camera(DistortionModel::kRadTan, width, height, params));
  return std::unique_ptr<PinholeRadtan>(new PinholeRadtan(width, height, params));
}

std::unique_ptr<CameraModel> PinholeRadtan::clone() const {
  return std::unique_ptr<CameraModel>(new PinholeRadtan(width(), height(), params()));
}

Vec2d PinholeRadtan::distort_normalized(const Vec2d& xn, const Eigen::Vector4d& dist, Mat2d* J_xn) {
  const double k1 = dist[0], k2 = dist[1], p1 = dist[2], p2 = dist[3];
  const double x = xn.x(), y = xn.y();
  const double x2 = x * x, y2 = y * y, xy = x * y;
  const double r2 = x2 + y2;
  const double radial = 1.0 + r2 * (k1 + k2 * r2);
  const Vec2d xd(x * radial + 2.0 * p1 * xy + p2 * (r2 + 2.0 * x2),
                 y * radial + p1 * (r2 + 2.0 * y2) + 2.0 * p2 * xy);
  if (J_xn != nullptr) {
    // d radial / d x = 2 x (k1 + 2 k2 r2), likewise for y.
    const double dradial_dr2 = k1 + 2.0 * k2 * r2;
    const double drad_dx = 2.0 * x * dradial_dr2;
    const double drad_dy = 2.0 * y * dradial_dr2;
    (*J_xn)(0, 0) = radial + x * drad_dx + 2.0 * p1 * y + 6.0 * p2 * x;
    (*J_xn)(0, 1) = x * drad_dy + 2.0 * p1 * x + 2.0 * p2 * y;
    (*J_xn)(1, 0) = y * drad_dx + 2.0 * p1 * x + 2.0 * p2 * y;
    (*J_xn)(1, 1) = radial + y * drad_dy + 6.0 * p1 * y + 2.0 * p2 * x;
  }
  return xd;
}

Vec2d PinholeRadtan::distort(const Vec2d& xn, Mat2d* J_xn, Eigen::Matrix<double, 2, 8>* J_params) const {
  const Params& p = params();
  const Eigen::Vector4d dist = p.tail<4>();
  const Vec2d xd = distort_normalized(xn, dist, J_xn);
  if (J_xn != nullptr) {
    J_xn->row(0) *= fx();
    J_xn->row(1) *= fy();
  }
  if (J_params != nullptr) {
    const double x = xn.x(), y = xn.y();
    const double r2 = x * x + y * y;
    J_params->setZero();
    (*J_params)(0, 0) = xd.x();
    (*J_params)(1, 1) = xd.y();
    (*J_params)(0, 2) = 1.0;
    (*J_params)(1, 3) = 1.0;
    // d xd / d [k1, k2, p1, p2]
    Eigen::Matrix<double, 2, 4> d_dist;
    d_dist << x * r2, x * r2 * r2, 2.0 * x * y, r2 + 2.0 * x * x,  //
        y * r2, y * r2 * r2, r2 + 2.0 * y * y, 2.0 * x * y;
    J_params->block<1, 4>(0, 4) = fx() * d_dist.row(0);
    J_params->block<1, 4>(1, 4) = fy() * d_dist.row(1);
  }
  return Vec2d(fx() * xd.x() + cx(), fy() * xd.y() + cy());
}

StatusOr<Vec2d> PinholeRadtan::undistort(const Vec2d& uv) const {
  if (!uv.allFinite()) {
    return absl::InvalidArgumentError(
        fmt::format("undistort (radtan): pixel ({}, {}) is not finite", uv.x(), uv.y()));
  }
  const Eigen::Vector4d dist = params().tail<4>();
  const Vec2d target((uv.x() - cx()) / fx(), (uv.y() - cy()) / fy());
  Vec2d xn = target;
  Mat2d J;
  Vec2d residual = distort_normalized(xn, dist, &J) - target;
  for (int iter = 0; iter < kUndistortMaxIterations; ++iter) {
    const double det = J.determinant();
    if (!(std::abs(det) > 0.0) || !std::isfinite(det)) break;
    const Vec2d step = -J.inverse() * residual;
    // Newton step, halved while it makes the residual grow (far from the image centre).
    double scale = 1.0;
    Vec2d candidate = xn + step;
    Mat2d J_candidate;
    Vec2d r_candidate = distort_normalized(candidate, dist, &J_candidate) - target;
    for (int h = 0; h < kUndistortMaxHalvings && !(r_candidate.norm() <= residual.norm()); ++h) {
      scale *= 0.5;
      candidate = xn + scale * step;
      r_candidate = distort_normalized(candidate, dist, &J_candidate) - target;
    }
    if (!candidate.allFinite()) break;
    xn = candidate;
    J = J_candidate;
    residual = r_candidate;
    if (scale * step.norm() <= kUndistortStepTolerance * std::max(1.0, xn.norm())) break;
  }
  if (xn.allFinite() && !(xn.norm() < max_radius_)) {
    return absl::InvalidArgumentError(fmt::format(
        "undistort (radtan): pixel ({}, {}) maps beyond the radius where the distortion folds over "
        "(|xn| = {} >= {}): outside the valid image area",
        uv.x(), uv.y(), xn.norm(), max_radius_));
  }
  const double pixel_error = (distort(xn) - uv).norm();
  if (!(pixel_error < kUndistortMaxPixelResidual)) {
    return absl::InvalidArgumentError(fmt::format(
        "undistort (radtan): pixel ({}, {}) did not converge (re-distortion error {} px > {} px); "
        "it is probably far outside the valid image area",
        uv.x(), uv.y(), pixel_error, kUndistortMaxPixelResidual));
  }
  return xn;
}

}  // namespace mrvs::camera
