#pragma once
// Triangulation of a feature from its observations in the window (algorithm.md 3.5 step 2):
// a linear solve in the anchor camera (the newest observation), then Levenberg-Marquardt
// on the anchored inverse depth (alpha, beta, rho), with the reference code's checks.
#include <vector>

#include "mrvs/config/options.h"
#include "mrvs/core/status.h"
#include "mrvs/geometry/se3.h"

namespace mrvs::edge {

struct TriangulationOptions : config::OptionsEquality<TriangulationOptions> {
  double max_cond = 1e4;     ///< condition number of the linear system
  double min_dist_m = 0.10;  ///< anchor depth bounds
  double max_dist_m = 60.0;
  double max_baseline_ratio = 40.0;  ///< |p_A| / largest baseline perpendicular to the ray
  int max_iterations = 5;            ///< Levenberg-Marquardt runs
  double init_lambda = 1e-3;

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("max_cond", max_cond, in_range(1.0, 1e12), "largest condition number of the linear system");
    v("min_dist_m", min_dist_m, in_range(0.0, 1e4), "nearest accepted depth, m");
    v("max_dist_m", max_dist_m, in_range(0.01, 1e6), "farthest accepted depth, m");
    v("max_baseline_ratio", max_baseline_ratio, in_range(1.0, 1e6), "largest depth / baseline");
    v("max_iterations", max_iterations, in_range(0, 100), "Levenberg-Marquardt iterations");
    v("init_lambda", init_lambda, in_range(1e-12, 1e6), "initial damping");
  }
};

/// One observation: the camera pose and the undistorted normalised coordinates.
struct BearingObservation {
  SE3d T_w_c;
  Vec2d xn = Vec2d::Zero();
};

/// The world point seen by `obs` (at least 2). FailedPrecondition naming the check that
/// failed (too few views, ill-conditioned, depth out of range, baseline too short).
StatusOr<Vec3d> triangulate(const std::vector<BearingObservation>& obs, const TriangulationOptions& options);

}  // namespace mrvs::edge
