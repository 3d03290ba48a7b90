#include "mrvs/sim/ray_table.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include <fmt/format.h>

namespace mrvs::sim {
namespace {

// Normalised point of pixel position uv, Newton-solved on distort() from `guess` (the
// solution of a neighbouring position, so 2-3 steps suffice); falls back to the model's own
// undistort() (robust, with its validity checks) when that does not converge to 1e-9 px on
// the unfolded branch.
// The error message on failure.
bool solve_normalized(const camera::CameraModel& camera, const Vec2d& uv, const Vec2d* guess, Vec2d* xn,
                      std::string* error) {
  constexpr int kMaxSteps = 8;
  constexpr double kTolerancePx = 1e-9;
  if (guess != nullptr) {
    Vec2d x = *guess;
    for (int i = 0; i < kMaxSteps && x.allFinite(); ++i) {
      Mat2d J;
      const Vec2d r = camera.distort(x, &J) - uv;
      const double det = J.determinant();
      // det > 0: the orientation-preserving branch (not beyond a fold of the distortion).
      if (r.norm() < kTolerancePx && det > 0.0) {
        *xn = x;
        return true;
      }
      if (!(std::abs(det) > 0.0)) break;
      x -= J.inverse() * r;
    }
  }
  const StatusOr<Vec2d> solved = camera.undistort(uv);
  if (!solved.ok()) {
    *error = std::string(solved.status().message());
    return false;
  }
  *xn = *solved;
  return true;
}

Eigen::Vector3f unit_ray(const Vec2d& xn) { return Vec3d(xn.x(), xn.y(), 1.0).normalized().cast<float>(); }

// Angle between two unit vectors, radians (atan2 form: accurate for small angles).
double angle_between(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  const Vec3d da = a.cast<double>();
  const Vec3d db = b.cast<double>();
  return std::atan2(da.cross(db).norm(), da.dot(db));
}

}  // namespace

Vec2d RayTable::subsample_offset(int k) {
  return Vec2d((k & 1) != 0 ? 0.25 : -0.25, (k & 2) != 0 ? 0.25 : -0.25);
}

StatusOr<RayTable> RayTable::build(const camera::CameraModel& camera) {
  RayTable table;
  table.width_ = camera.width();
  table.height_ = camera.height();
  const std::size_t n = static_cast<std::size_t>(table.width_) * static_cast<std::size_t>(table.height_);
  table.centers_.resize(n);
  table.subsamples_.resize(kSubsamples * n);
  table.angles_.resize(n);
  // First failing row (its message), found without depending on the thread count.
  std::vector<std::string> row_errors(static_cast<std::size_t>(table.height_));
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < table.height_; ++v) {
    std::string& error = row_errors[static_cast<std::size_t>(v)];
    Vec2d previous = Vec2d::Zero();  // centre solution of the previous pixel of this row
    for (int u = 0; u < table.width_ && error.empty(); ++u) {
      const std::size_t i = table.index(u, v);
      const Vec2d centre(u, v);
      Vec2d xn;
      if (!solve_normalized(camera, centre, u > 0 ? &previous : nullptr, &xn, &error)) break;
      previous = xn;
      table.centers_[i] = unit_ray(xn);
      for (int k = 0; k < kSubsamples && error.empty(); ++k) {
        Vec2d xs;
        if (solve_normalized(camera, centre + subsample_offset(k), &previous, &xs, &error)) {
          table.subsamples_[kSubsamples * i + static_cast<std::size_t>(k)] = unit_ray(xs);
        }
      }
      if (!error.empty()) break;
      const Eigen::Vector3f* s = &table.subsamples_[kSubsamples * i];
      // Subsamples are half a pixel apart: double the mean spacing in u and in v.
      const double width = angle_between(s[0], s[1]) + angle_between(s[2], s[3]);
      const double height = angle_between(s[0], s[2]) + angle_between(s[1], s[3]);
      table.angles_[i] = static_cast<float>(std::sqrt(width * height));
    }
  }
  for (int v = 0; v < table.height_; ++v) {
    const std::string& error = row_errors[static_cast<std::size_t>(v)];
    if (!error.empty()) {
      return absl::InvalidArgumentError(
          fmt::format("ray table for {}: row {}: {}", camera.describe(), v, error));
    }
  }
  return table;
}

double RayTable::max_round_trip_error(const camera::CameraModel& camera) const {
  std::vector<double> row_max(static_cast<std::size_t>(height_), 0.0);
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < height_; ++v) {
    double worst = 0.0;
    for (int u = 0; u < width_; ++u) {
      for (int k = -1; k < kSubsamples; ++k) {
        const Eigen::Vector3f& ray = k < 0 ? center(u, v) : subsample(u, v, k);
        const Vec2d expected = Vec2d(u, v) + (k < 0 ? Vec2d::Zero() : subsample_offset(k));
        const std::optional<Vec2d> uv = camera.project(ray.cast<double>());
        const double err = uv ? (*uv - expected).norm() : std::numeric_limits<double>::infinity();
        worst = std::max(worst, std::isfinite(err) ? err : std::numeric_limits<double>::infinity());
      }
    }
    row_max[static_cast<std::size_t>(v)] = worst;
  }
  return row_max.empty() ? 0.0 : *std::max_element(row_max.begin(), row_max.end());
}

}  // namespace mrvs::sim
