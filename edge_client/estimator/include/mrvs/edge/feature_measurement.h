#pragma once
// The rows of one feature's observations in the window (algorithm.md 3.5 step 4), shared by
// the MSCKF and the point updater: residual in raw pixels, Jacobians with respect to the
// clones that saw it and the calibration in the state, and H_f with respect to its world
// position.
#include "mrvs/core/status.h"
#include "mrvs/edge/feature_database.h"
#include "mrvs/edge/state_helper.h"
#include "mrvs/edge/triangulation.h"

namespace mrvs::edge {

struct FeatureRows {
  Measurement m;        ///< vars: the clones (and calibration) seen, in covariance order
  Eigen::MatrixXd H_f;  ///< rows x 3
  int observations = 0;
};

/// Rows of the observations of `track` made at clone times. The residual is evaluated at
/// the current estimates and `p_w`; the Jacobians at the clones' first estimates (when the
/// state uses FEJ) and `p_w_lin`. Observations behind a camera are left out;
/// FailedPrecondition when none remains.
StatusOr<FeatureRows> feature_rows(const State& state, const FeatureTrack& track, const Vec3d& p_w,
                                   const Vec3d& p_w_lin, double sigma_px);

/// The track's observations at clone times as bearings for triangulation.
std::vector<BearingObservation> clone_bearings(const State& state, const FeatureTrack& track);

}  // namespace mrvs::edge
