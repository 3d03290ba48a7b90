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
  std::vector<std::pair<TimestampNs, int>> used;  ///< (t_ns, cam) of each pair of rows
};

/// Rows of the observations of `track` made at clone times. The residual is evaluated at
/// the current estimates and `p_w`; the Jacobians at the clones' first estimates (when the
/// state uses FEJ) and `p_w_lin`. Observations behind a camera are left out;
/// FailedPrecondition when none remains.
StatusOr<FeatureRows> feature_rows(const State& state, const FeatureTrack& track, const Vec3d& p_w,
                                   const Vec3d& p_w_lin, double sigma_px);

/// A point fixed in the camera `cam` of the clone at `t_ns`: p_w = T_w_b(t) T_b_c p_c (a
/// map point anchored on the ray it was found along: its depth from the map, its direction
/// from that observation).
struct RayAnchor {
  TimestampNs t_ns = 0;
  int cam = 0;
  Vec3d p_c = Vec3d::Zero();
};

/// The anchor's world point; nullopt when the anchor clone is not in the state.
std::optional<Vec3d> anchored_point(const State& state, const RayAnchor& anchor);

/// d p_w / d[anchor clone [dtheta_b, dp_w_b], and its camera's extrinsics [dtheta_b_c,
/// dp_b_c] when in the state] of the anchored point, across the ray only: across it the point
/// moves with the anchor camera, along it the map's surface holds it (taken as facing the
/// camera). nullopt when the anchor clone is not in the state.
struct AnchorJacobian {
  std::vector<Slot> vars;
  Eigen::MatrixXd J;  ///< 3 x 6 per var
};
std::optional<AnchorJacobian> anchor_jacobian(const State& state, const RayAnchor& anchor);

/// Covariance of an anchored point: `depth_variance` along the ray (the map), the anchor
/// pixel's noise `sigma_px` across it.
Mat3d anchored_covariance(const State& state, const RayAnchor& anchor, double depth_variance,
                          double sigma_px);

/// The rows of `track` with its position tied to the anchor: every observation except the
/// anchor's own, with the anchor's columns gaining H_f anchor_jacobian. H_f is kept for the
/// anchor's own noise (anchored_covariance).
/// FailedPrecondition when the anchor clone is gone or its observation is not in the track.
StatusOr<FeatureRows> anchored_feature_rows(const State& state, const FeatureTrack& track,
                                            const RayAnchor& anchor, double sigma_px);

/// The track's observations at clone times as bearings for triangulation.
std::vector<BearingObservation> clone_bearings(const State& state, const FeatureTrack& track);

}  // namespace mrvs::edge
