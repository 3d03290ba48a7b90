#pragma once
// EKF operations on a State (OpenVINS' StateHelper idea: free functions, no hidden state):
// update with a measurement of some of the variables, chi-square gating, stochastic
// cloning, marginalisation, and delayed initialisation of a new variable.
//
// A Measurement involves `vars` (slots, in the order of H's column blocks):
//   r = H [dx_vars] + n,  n ~ N(0, sigma^2 I).
#include <vector>

#include <Eigen/Core>

#include "mrvs/core/status.h"
#include "mrvs/edge/state.h"

namespace mrvs::edge {

struct Measurement {
  std::vector<Slot> vars;
  Eigen::MatrixXd H;  ///< rows x (sum of the vars' sizes)
  Eigen::VectorXd r;
  double sigma = 1.0;  ///< noise standard deviation of every row
  int rows() const { return static_cast<int>(r.size()); }
};

/// Columns of P for `vars`, concatenated (dim x sum of sizes).
Eigen::MatrixXd covariance_columns(const State& state, const std::vector<Slot>& vars);
/// The marginal covariance of `vars` (sum of sizes, square).
Eigen::MatrixXd marginal_covariance(const State& state, const std::vector<Slot>& vars);

/// Mahalanobis distance r^T (H P H^T + sigma^2 I)^-1 r.
double mahalanobis(const State& state, const Measurement& m);

/// The 95 % quantiles of chi-square with 1..max_dof degrees of freedom.
class Chi2Table {
 public:
  explicit Chi2Table(int max_dof = 1000);
  /// The 95 % quantile for `dof` (computed on the fly above the table).
  double q95(int dof) const;

 private:
  std::vector<double> q95_;
};

/// Standard EKF update (Cholesky of S, symmetric covariance update). FailedPrecondition,
/// with the state unchanged, when S is not positive definite or a variance would turn
/// negative.
Status ekf_update(State& state, const Measurement& m);

/// Appends a clone of the IMU pose at the camera time `t_cam_ns` (the IMU state must be at
/// t_cam_ns + t_d), with its covariance; with the time offset in the state, the clone's
/// dependence on it ([w_b; v_w] per second) is included. `w_b` is the bias-corrected body
/// rate at that time.
Status augment_clone(State& state, TimestampNs t_cam_ns, const Vec3d& w_b);

/// Removes clone `t_ns` from the state (its rows and columns).
void marginalize_clone(State& state, TimestampNs t_ns);
/// Removes point `id` from the state.
void marginalize_point(State& state, FeatureId id);

/// A measurement split so that a new variable f (k values) of H_f is isolated:
/// `first` = k rows r1 = H_x1 dx + R_f df + n (R_f upper triangular), `rest` = the rows
/// that do not see f (H_f projected out).
struct SplitMeasurement {
  Measurement first;
  Eigen::MatrixXd R_f;
  Measurement rest;
};
/// Splits by a Householder QR of H_f (rows > k, H_f full column rank). InvalidArgument when
/// H_f is rank deficient.
StatusOr<SplitMeasurement> split_by_new_variable(const Measurement& m, const Eigen::MatrixXd& H_f);

/// Adds a new variable of size R_f.cols() whose error df is determined by
/// first = H_x1 dx + R_f df + n: appends its slot with covariance
/// R_f^-1 (H_x1 P H_x1^T + sigma^2 I) R_f^-T and cross terms -R_f^-1 H_x1 P, and returns
/// the slot and the mean correction R_f^-1 r1 to add to its value.
std::pair<Slot, Eigen::VectorXd> add_variable(State& state, const Measurement& first,
                                              const Eigen::MatrixXd& R_f);

/// Thin QR: when the measurement has more rows than columns, replaces (H, r) by the square
/// system with the same information.
void compress(Measurement* m);

/// Stacks measurements (their vars merged; H blocks placed by slot).
Measurement stack(const std::vector<Measurement>& parts);

}  // namespace mrvs::edge
