#include "mrvs/edge/state_helper.h"

#include <algorithm>
#include <map>

#include <fmt/format.h>
#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <boost/math/distributions/chi_squared.hpp>

namespace mrvs::edge {
namespace {

int total_size(const std::vector<Slot>& vars) {
  int n = 0;
  for (const Slot& s : vars) n += s.size;
  return n;
}

/// First row and number of rows spanning the non-zero rows of `block` (0 rows when zero).
std::pair<int, int> nonzero_rows(const Eigen::Ref<const Eigen::MatrixXd>& block) {
  int first = -1, last = -1;
  for (int r = 0; r < block.rows(); ++r) {
    if (block.row(r).cwiseAbs().maxCoeff() > 0.0) {
      if (first < 0) first = r;
      last = r;
    }
  }
  return first < 0 ? std::make_pair(0, 0) : std::make_pair(first, last - first + 1);
}

double chi2_q95(int dof) {
  return boost::math::quantile(boost::math::chi_squared_distribution<double>(static_cast<double>(dof)), 0.95);
}

}  // namespace

Eigen::MatrixXd covariance_columns(const State& state, const std::vector<Slot>& vars) {
  Eigen::MatrixXd out(state.dim(), total_size(vars));
  int c = 0;
  for (const Slot& s : vars) {
    out.middleCols(c, s.size) = state.P.middleCols(s.offset, s.size);
    c += s.size;
  }
  return out;
}

Eigen::MatrixXd marginal_covariance(const State& state, const std::vector<Slot>& vars) {
  const int n = total_size(vars);
  Eigen::MatrixXd out(n, n);
  int r = 0;
  for (const Slot& a : vars) {
    int c = 0;
    for (const Slot& b : vars) {
      out.block(r, c, a.size, b.size) = state.P.block(a.offset, b.offset, a.size, b.size);
      c += b.size;
    }
    r += a.size;
  }
  return out;
}

double mahalanobis(const State& state, const Measurement& m) {
  Eigen::MatrixXd S = m.H * marginal_covariance(state, m.vars) * m.H.transpose();
  S.diagonal().array() += m.sigma * m.sigma;
  return m.r.dot(S.llt().solve(m.r));
}

Chi2Table::Chi2Table(int max_dof) {
  q95_.resize(static_cast<std::size_t>(max_dof) + 1, 0.0);
  for (int d = 1; d <= max_dof; ++d) q95_[static_cast<std::size_t>(d)] = chi2_q95(d);
}

double Chi2Table::q95(int dof) const {
  if (dof <= 0) return 0.0;
  if (static_cast<std::size_t>(dof) < q95_.size()) return q95_[static_cast<std::size_t>(dof)];
  return chi2_q95(dof);
}

Status ekf_update(State& state, const Measurement& m) {
  if (m.rows() == 0) return absl::OkStatus();
  // P H^T and S = H P H^T + R from the involved variables' columns, each only over the rows
  // where its block of H is not zero (a point's block covers its own rows only).
  Eigen::MatrixXd PHt = Eigen::MatrixXd::Zero(state.dim(), m.rows());
  std::vector<std::pair<int, int>> rows_of(m.vars.size());
  int c = 0;
  for (std::size_t v = 0; v < m.vars.size(); ++v) {
    const Slot& s = m.vars[v];
    rows_of[v] = nonzero_rows(m.H.middleCols(c, s.size));
    const auto [r0, nr] = rows_of[v];
    if (nr > 0)
      PHt.middleCols(r0, nr).noalias() +=
          state.P.middleCols(s.offset, s.size) * m.H.block(r0, c, nr, s.size).transpose();
    c += s.size;
  }
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(m.rows(), m.rows());
  c = 0;
  for (std::size_t v = 0; v < m.vars.size(); ++v) {
    const Slot& s = m.vars[v];
    const auto [r0, nr] = rows_of[v];
    if (nr > 0)
      S.middleRows(r0, nr).noalias() += m.H.block(r0, c, nr, s.size) * PHt.middleRows(s.offset, s.size);
    c += s.size;
  }
  S.diagonal().array() += m.sigma * m.sigma;
  const Eigen::LLT<Eigen::MatrixXd> llt(S.selfadjointView<Eigen::Lower>());
  if (llt.info() != Eigen::Success) {
    return absl::FailedPreconditionError("EKF update: innovation covariance is not positive definite");
  }
  // With S = L L^T and W = P H^T L^-T: P -= W W^T, dx = W L^-1 r.
  const Eigen::MatrixXd Wt = llt.matrixL().solve(PHt.transpose());  // m x n
  if (((state.P.diagonal() - Wt.colwise().squaredNorm().transpose()).array() < 0.0).any()) {
    return absl::FailedPreconditionError("EKF update: a variance would turn negative; update skipped");
  }
  const Eigen::VectorXd dx = Wt.transpose() * llt.matrixL().solve(m.r);
  state.P.selfadjointView<Eigen::Lower>().rankUpdate(Wt.transpose(), -1.0);
  state.P.triangularView<Eigen::StrictlyUpper>() = state.P.transpose();
  state.apply_correction(dx);
  return absl::OkStatus();
}

Status augment_clone(State& state, TimestampNs t_cam_ns, const Vec3d& w_b) {
  if (state.clones.count(t_cam_ns) != 0) {
    return absl::AlreadyExistsError(fmt::format("a clone at {} ns exists already", t_cam_ns));
  }
  // J: d(clone error) / d(state error): the IMU pose block, and the time offset.
  const int n = state.dim();
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(6, n);
  J.block<6, 6>(0, state.imu_slot.offset).setIdentity();
  if (state.time_offset_slot.active()) {
    J.block<3, 1>(0, state.time_offset_slot.offset) = w_b;
    J.block<3, 1>(3, state.time_offset_slot.offset) = state.imu.v_w_b;
  }
  const Eigen::MatrixXd JP = J * state.P;  // 6 x n
  const Slot slot = state.append(6);
  state.P.block(slot.offset, 0, 6, n) = JP;
  state.P.block(0, slot.offset, n, 6) = JP.transpose();
  state.P.block<6, 6>(slot.offset, slot.offset) = JP * J.transpose();
  CloneState clone;
  clone.T_w_b = SE3d(state.imu.q_w_b, state.imu.p_w_b);
  clone.fej = clone.T_w_b;
  clone.slot = slot;
  state.clones.emplace(t_cam_ns, clone);
  return absl::OkStatus();
}

void marginalize_clone(State& state, TimestampNs t_ns) {
  const auto it = state.clones.find(t_ns);
  if (it == state.clones.end()) return;
  const Slot slot = it->second.slot;
  state.remove(slot);
  state.clones.erase(t_ns);
}

void marginalize_point(State& state, FeatureId id) {
  const auto it = state.points.find(id);
  if (it == state.points.end()) return;
  const Slot slot = it->second.slot;
  state.remove(slot);
  state.points.erase(id);
}

StatusOr<SplitMeasurement> split_by_new_variable(const Measurement& m, const Eigen::MatrixXd& H_f) {
  const int k = static_cast<int>(H_f.cols());
  if (H_f.rows() < k || H_f.rows() != m.rows()) {
    return absl::InvalidArgumentError(
        fmt::format("split: {} rows cannot isolate a {}-value variable", m.rows(), k));
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(H_f);
  const Eigen::MatrixXd R_full = qr.matrixQR().triangularView<Eigen::Upper>();
  Eigen::MatrixXd R_f = R_full.topRows(k);
  if ((R_f.diagonal().array().abs() < 1e-9 * std::max(1.0, R_f.diagonal().cwiseAbs().maxCoeff())).any()) {
    return absl::InvalidArgumentError("split: the new variable is not observable from this measurement");
  }
  Eigen::MatrixXd Hx = m.H;
  Eigen::VectorXd r = m.r;
  Hx.applyOnTheLeft(qr.householderQ().adjoint());
  r.applyOnTheLeft(qr.householderQ().adjoint());
  SplitMeasurement out;
  out.R_f = R_f;
  out.first = Measurement{m.vars, Hx.topRows(k), r.head(k), m.sigma};
  out.rest = Measurement{m.vars, Hx.bottomRows(m.rows() - k), r.tail(m.rows() - k), m.sigma};
  return out;
}

std::pair<Slot, Eigen::VectorXd> add_variable(State& state, const Measurement& first,
                                              const Eigen::MatrixXd& R_f) {
  const int n = state.dim(), k = static_cast<int>(R_f.cols());
  const Eigen::MatrixXd R_inv =
      R_f.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(k, k));  // k x k
  // Cross covariance with every variable: -R^-1 H_x1 P_vx.
  const Eigen::MatrixXd P_vx = covariance_columns(state, first.vars).transpose();  // kv x n
  const Eigen::MatrixXd cross = -R_inv * first.H * P_vx;                           // k x n
  Eigen::MatrixXd S = first.H * marginal_covariance(state, first.vars) * first.H.transpose();
  S.diagonal().array() += first.sigma * first.sigma;
  const Eigen::MatrixXd P_ff = R_inv * S * R_inv.transpose();
  const Slot slot = state.append(k);
  state.P.block(slot.offset, 0, k, n) = cross;
  state.P.block(0, slot.offset, n, k) = cross.transpose();
  state.P.block(slot.offset, slot.offset, k, k) = 0.5 * (P_ff + P_ff.transpose());
  return {slot, R_inv * first.r};
}

void compress(Measurement* m) {
  const int cols = static_cast<int>(m->H.cols());
  if (m->rows() <= cols) return;
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(m->H);
  Eigen::VectorXd r = m->r;
  r.applyOnTheLeft(qr.householderQ().adjoint());
  m->H = qr.matrixQR().topRows(cols).triangularView<Eigen::Upper>();
  m->r = r.head(cols);
}

Measurement stack(const std::vector<Measurement>& parts) {
  // Union of the vars, ordered by offset.
  std::map<int, Slot> by_offset;
  int rows = 0;
  for (const Measurement& p : parts) {
    rows += p.rows();
    for (const Slot& s : p.vars) by_offset[s.offset] = s;
  }
  Measurement out;
  std::map<int, int> column_of;
  int cols = 0;
  for (const auto& [o, s] : by_offset) {
    out.vars.push_back(s);
    column_of[o] = cols;
    cols += s.size;
  }
  out.H = Eigen::MatrixXd::Zero(rows, cols);
  out.r.resize(rows);
  out.sigma = parts.empty() ? 1.0 : parts.front().sigma;
  int row = 0;
  for (const Measurement& p : parts) {
    int c = 0;
    for (const Slot& s : p.vars) {
      out.H.block(row, column_of[s.offset], p.rows(), s.size) = p.H.middleCols(c, s.size);
      c += s.size;
    }
    out.r.segment(row, p.rows()) = p.r;
    row += p.rows();
  }
  return out;
}

}  // namespace mrvs::edge
