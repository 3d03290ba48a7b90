#pragma once
// Trajectory evaluation: timestamp association of an estimated trajectory with ground
// truth, rigid / similarity alignment, absolute trajectory error (ATE) and relative pose
// error (RPE), in the spirit of the TUM RGB-D and KITTI evaluation tools.
//
// Frames: an estimate pose is T_west_b (body into the estimator's world), a ground-truth
// pose is T_wgt_b (body into the ground-truth world). Alignment finds the transform
// T_gt_est (estimate world into ground-truth world, plus a scale for Sim(3)).
// Units: timestamps int64 ns, positions metres, reported angles degrees.
#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/geometry/se3.h"
#include "mrvs/io/types.h"

namespace mrvs::eval {

// ---------------------------------------------------------------------------------------
// Association
// ---------------------------------------------------------------------------------------

/// Options of associate().
struct AssociationOptions {
  /// Tolerance (ns): a ground-truth sample serves an estimate at time t only when
  /// |t_gt - t| <= max_dt_ns. Must be >= 0.
  DurationNs max_dt_ns = 10'000'000;
  /// Added to every estimate stamp before matching (ns): t = t_est + time_offset_ns.
  DurationNs time_offset_ns = 0;
};

/// How the ground-truth pose of a match was obtained.
enum class MatchKind {
  kExact,         ///< a ground-truth sample has exactly the estimate's stamp
  kInterpolated,  ///< between two bracketing samples, both within tolerance
  kNearest,       ///< the nearest sample within tolerance (no usable bracket)
};

/// One estimate pose with the ground truth at the same (offset-corrected) time.
struct Match {
  TimestampNs t_ns = 0;  ///< estimate stamp + time_offset_ns
  SE3d T_west_b;         ///< estimated pose (estimate world)
  SE3d T_wgt_b;          ///< ground-truth pose at t_ns (ground-truth world)
  MatchKind kind = MatchKind::kExact;
};

/// Result of associate(): matches in estimate order plus counters.
struct Association {
  std::vector<Match> matches;
  std::size_t num_exact = 0;
  std::size_t num_interpolated = 0;
  std::size_t num_nearest = 0;
  std::size_t num_unmatched = 0;  ///< estimates without ground truth within tolerance
};

/// Pose between a (alpha = 0) and b (alpha = 1): linear in position, slerp in rotation.
SE3d interpolate_pose(const SE3d& a, const SE3d& b, double alpha);

/// Pairs each estimate pose with ground truth at its stamp (+ time_offset_ns): interpolated
/// when samples bracketing it lie within max_dt_ns, else the nearest sample within
/// max_dt_ns, else it is counted as unmatched. Both trajectories must be non-empty, finite
/// and strictly increasing in time. Returns NotFound when no estimate pose matches.
StatusOr<Association> associate(const io::Trajectory& estimate, const io::Trajectory& ground_truth,
                                const AssociationOptions& options);

// ---------------------------------------------------------------------------------------
// Alignment
// ---------------------------------------------------------------------------------------

/// How the estimate world is aligned to the ground-truth world.
enum class AlignmentMethod {
  kNone,       ///< identity
  kSE3,        ///< least-squares rigid transform of the positions (Umeyama, no scale)
  kSim3,       ///< least-squares similarity transform (Umeyama with scale)
  kFirstPose,  ///< makes the first matched estimate pose equal its ground truth
};

/// "none", "se3", "sim3" or "first".
std::string alignment_name(AlignmentMethod method);

/// Inverse of alignment_name; InvalidArgument for other text.
StatusOr<AlignmentMethod> parse_alignment_method(const std::string& name);

/// Minimum number of matched poses for kSE3 / kSim3.
inline constexpr std::size_t kMinPosesForAlignment = 3;

/// Similarity transform from the estimate world into the ground-truth world:
/// p_gt = scale * (R_gt_est * p_est) + t_gt_est.
struct Alignment {
  AlignmentMethod method = AlignmentMethod::kNone;
  SE3d T_gt_est;       ///< rotation and translation (metres)
  double scale = 1.0;  ///< 1 except for kSim3

  /// An estimate pose T_west_b expressed in the ground-truth world (position scaled).
  SE3d apply(const SE3d& T_west_b) const;
};

/// Computes the alignment of the matched estimate positions onto the ground truth.
/// kSE3 / kSim3 need kMinPosesForAlignment matches and return FailedPrecondition when
/// either position set is coincident or collinear (the rotation is then undetermined).
StatusOr<Alignment> align(const Association& association, AlignmentMethod method);

// ---------------------------------------------------------------------------------------
// Error statistics, ATE and RPE
// ---------------------------------------------------------------------------------------

/// Summary of a set of non-negative errors (same unit as the errors).
struct ErrorStats {
  std::size_t count = 0;
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;  ///< mean of the two middle values for an even count
  double std = 0.0;     ///< population standard deviation around the mean
  double min = 0.0;
  double max = 0.0;
};

/// Statistics of `errors`; InvalidArgument when empty.
StatusOr<ErrorStats> compute_stats(const std::vector<double>& errors);

/// Absolute trajectory error after an alignment.
struct AteResult {
  Alignment alignment;
  ErrorStats position_m;                    ///< |p_gt - (scale R p_est + t)|, metres
  ErrorStats rotation_deg;                  ///< angle of R_gt_b^-1 * R_gt_est * R_est_b, degrees
  std::vector<double> position_errors_m;    ///< per match
  std::vector<double> rotation_errors_deg;  ///< per match
  /// Heading error, the one rotation visual-inertial odometry cannot observe: the angle about
  /// the ground-truth world's z axis (up in EuRoC, KAIST and the generated worlds) of the world
  /// rotation error R_gt_b * R_est_b^-1 (its twist about z), per match, signed (truth's heading
  /// minus the estimate's, in (-180, 180]); the statistics are of its magnitude.
  ErrorStats heading_deg;
  std::vector<double> heading_errors_deg;
};

/// The signed angle, in degrees, about the z axis of the rotation `q` (the twist of its
/// swing-twist decomposition about z: exact for rotations about z, and the tilt of any swing
/// does not leak into it), in (-180, 180].
double heading_about_z_deg(const Quatd& q);

/// ATE of the matches after `alignment`. InvalidArgument when there are no matches.
StatusOr<AteResult> compute_ate(const Association& association, const Alignment& alignment);

/// What the RPE step `delta` measures.
enum class RpeUnit {
  kMetres,   ///< ground-truth path length travelled between the two poses
  kSeconds,  ///< time between the two poses
};

/// Options of compute_rpe().
struct RpeOptions {
  double delta = 1.0;  ///< step, metres or seconds (see unit); must be > 0
  RpeUnit unit = RpeUnit::kMetres;
};

/// Relative pose error over pose pairs separated by about `delta`.
struct RpeResult {
  RpeOptions options;
  std::size_t num_pairs = 0;
  double mean_pair_delta = 0.0;  ///< mean actual separation of the pairs (unit of delta)
  ErrorStats translation_m;      ///< |translation of E|, metres
  ErrorStats rotation_deg;       ///< angle of E, degrees
};

/// Pairs (i, j), i < j, for RPE: for each i the j whose key[j] - key[i] is closest to
/// delta, among the j where key[j] >= key[i] + delta is reached (so the last stretch
/// shorter than delta gives no pair). `key` must be non-decreasing (path length or time).
std::vector<std::pair<std::size_t, std::size_t>> select_rpe_pairs(const std::vector<double>& key,
                                                                  double delta);

/// Cumulative ground-truth path length (metres) at each match, starting at 0.
std::vector<double> ground_truth_path_length(const Association& association);

/// RPE with E = (T_gt_i^-1 T_gt_j)^-1 (T_est_i^-1 T_est_j); estimate translations are
/// multiplied by `scale` (1, or the Sim(3) scale). RPE is invariant to a rigid alignment.
/// FailedPrecondition when the trajectory is shorter than delta (no pair).
StatusOr<RpeResult> compute_rpe(const Association& association, const RpeOptions& options,
                                double scale = 1.0);

}  // namespace mrvs::eval
