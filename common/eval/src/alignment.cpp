// Alignment of the estimate world to the ground-truth world (Umeyama / first pose).
#include <cmath>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "mrvs/eval/trajectory_eval.h"

namespace mrvs::eval {
namespace {

/// Spread (m, RMS distance to the centroid) below which a point set counts as coincident.
constexpr double kCoincidentSpreadM = 1e-9;
/// Ratio of the second to the first principal standard deviation below which a point set
/// counts as collinear (the rotation about the line is then undetermined).
constexpr double kCollinearRatio = 1e-6;

/// Rejects coincident or collinear point sets (3 x N, N >= 1).
Status check_geometry(const Eigen::Matrix3Xd& points, const char* what) {
  const Eigen::Matrix3Xd centred = points.colwise() - points.rowwise().mean();
  const Mat3d covariance = centred * centred.transpose() / static_cast<double>(points.cols());
  const Eigen::SelfAdjointEigenSolver<Mat3d> solver(covariance, Eigen::EigenvaluesOnly);
  // Eigenvalues are sorted increasingly; clamp round-off negatives.
  const Vec3d sigma = solver.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  if (sigma.norm() <= kCoincidentSpreadM) {
    return absl::FailedPreconditionError(
        fmt::format("degenerate geometry: the {} positions are all the same point; cannot align", what));
  }
  if (sigma(1) <= kCollinearRatio * sigma(2)) {
    return absl::FailedPreconditionError(
        fmt::format("degenerate geometry: the {} positions are collinear (principal std devs {:.3g}, {:.3g}, "
                    "{:.3g} m); the "
                    "rotation about the line is undetermined, cannot align",
                    what, sigma(2), sigma(1), sigma(0)));
  }
  return absl::OkStatus();
}

StatusOr<Alignment> align_umeyama(const Association& association, bool with_scale) {
  const std::size_t n = association.matches.size();
  if (n < kMinPosesForAlignment) {
    return absl::FailedPreconditionError(
        fmt::format("{} alignment needs at least {} associated poses, got {}",
                    with_scale ? "Sim(3)" : "SE(3)", kMinPosesForAlignment, n));
  }
  Eigen::Matrix3Xd est(3, static_cast<Eigen::Index>(n));
  Eigen::Matrix3Xd gt(3, static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    est.col(static_cast<Eigen::Index>(i)) = association.matches[i].T_west_b.translation();
    gt.col(static_cast<Eigen::Index>(i)) = association.matches[i].T_wgt_b.translation();
  }
  MRVS_RETURN_IF_ERROR(check_geometry(est, "estimate"));
  MRVS_RETURN_IF_ERROR(check_geometry(gt, "ground-truth"));
  // dst = T * src with T = [c R, t; 0, 1].
  const Mat4d T = Eigen::umeyama(est, gt, with_scale);
  const Mat3d cR = T.topLeftCorner<3, 3>();
  const double scale = std::cbrt(cR.determinant());
  if (!std::isfinite(scale) || scale <= 0.0) {
    return absl::FailedPreconditionError(fmt::format("alignment failed: invalid scale {}", scale));
  }
  Alignment out;
  out.method = with_scale ? AlignmentMethod::kSim3 : AlignmentMethod::kSE3;
  out.scale = with_scale ? scale : 1.0;
  out.T_gt_est = SE3d(Mat3d(cR / scale), Vec3d(T.topRightCorner<3, 1>()));
  return out;
}

}  // namespace

std::string alignment_name(AlignmentMethod method) {
  switch (method) {
    case AlignmentMethod::kNone:
      return "none";
    case AlignmentMethod::kSE3:
      return "se3";
    case AlignmentMethod::kSim3:
      return "sim3";
    case AlignmentMethod::kFirstPose:
      return "first";
  }
  return "unknown";
}

StatusOr<AlignmentMethod> parse_alignment_method(const std::string& name) {
  for (AlignmentMethod m :
       {AlignmentMethod::kNone, AlignmentMethod::kSE3, AlignmentMethod::kSim3, AlignmentMethod::kFirstPose}) {
    if (alignment_name(m) == name) return m;
  }
  return absl::InvalidArgumentError(
      fmt::format("unknown alignment '{}' (expected one of none, se3, sim3, first)", name));
}

SE3d Alignment::apply(const SE3d& T_west_b) const {
  const Quatd q = T_gt_est.quaternion() * T_west_b.quaternion();
  const Vec3d p = scale * (T_gt_est.quaternion() * T_west_b.translation()) + T_gt_est.translation();
  return SE3d(q, p);
}

StatusOr<Alignment> align(const Association& association, AlignmentMethod method) {
  switch (method) {
    case AlignmentMethod::kNone:
      return Alignment{};
    case AlignmentMethod::kSE3:
      return align_umeyama(association, false);
    case AlignmentMethod::kSim3:
      return align_umeyama(association, true);
    case AlignmentMethod::kFirstPose: {
      if (association.matches.empty()) {
        return absl::FailedPreconditionError("first-pose alignment needs at least 1 associated pose, got 0");
      }
      const Match& first = association.matches.front();
      Alignment out;
      out.method = AlignmentMethod::kFirstPose;
      out.T_gt_est = first.T_wgt_b * first.T_west_b.inverse();
      return out;
    }
  }
  return absl::InvalidArgumentError("unknown alignment method");
}

}  // namespace mrvs::eval
