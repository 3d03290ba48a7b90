#include "mrvs/edge/feature_measurement.h"

#include <algorithm>
#include <map>

#include "mrvs/edge/camera_measurement.h"

namespace mrvs::edge {
namespace {

/// Column blocks of the rows: every slot once, in covariance order.
struct Columns {
  std::map<int, Slot> slots;
  void add(const Slot& s) {
    if (s.active()) slots[s.offset] = s;
  }
  std::map<int, int> start;  ///< offset -> first column
  int finish(std::vector<Slot>* vars) {
    int c = 0;
    for (const auto& [o, s] : slots) vars->push_back(s), start[o] = c, c += s.size;
    return c;
  }
};

}  // namespace

std::vector<BearingObservation> clone_bearings(const State& state, const FeatureTrack& track) {
  std::vector<BearingObservation> out;
  for (const CameraObservation& o : track.obs) {
    if (state.clones.count(o.t_ns) == 0) continue;
    out.push_back({state.T_w_c(o.t_ns, o.cam), o.xn});
  }
  return out;
}

StatusOr<FeatureRows> feature_rows(const State& state, const FeatureTrack& track, const Vec3d& p_w,
                                   const Vec3d& p_w_lin, double sigma_px) {
  std::vector<const CameraObservation*> used;
  Columns cols;
  for (const CameraObservation& o : track.obs) {
    const auto it = state.clones.find(o.t_ns);
    if (it == state.clones.end()) continue;
    const CameraState& cam = state.cams[static_cast<std::size_t>(o.cam)];
    if (!project_point(it->second.T_w_b, cam.T_b_c, *cam.model, p_w)) continue;
    used.push_back(&o);
    cols.add(it->second.slot);
    cols.add(cam.extrinsic_slot);
    cols.add(cam.intrinsic_slot);
  }
  if (used.empty()) {
    return absl::FailedPreconditionError("no observation at a clone sees the point in front of the camera");
  }
  FeatureRows out;
  const int n_cols = cols.finish(&out.m.vars);
  const int rows = 2 * static_cast<int>(used.size());
  out.m.H = Eigen::MatrixXd::Zero(rows, n_cols);
  out.m.r.resize(rows);
  out.m.sigma = sigma_px;
  out.H_f.resize(rows, 3);
  for (const CameraObservation* o : used) out.used.emplace_back(o->t_ns, o->cam);
  const bool fej = state.options().use_fej;
  for (std::size_t k = 0; k < used.size(); ++k) {
    const CameraObservation& o = *used[k];
    const CloneState& clone = state.clones.at(o.t_ns);
    const CameraState& cam = state.cams[static_cast<std::size_t>(o.cam)];
    const int row = 2 * static_cast<int>(k);
    out.m.r.segment<2>(row) = o.uv - *project_point(clone.T_w_b, cam.T_b_c, *cam.model, p_w);
    ProjectionJacobians J;
    const auto lin = project_point(fej ? clone.fej : clone.T_w_b, cam.T_b_c, *cam.model, p_w_lin, &J, -1e9);
    if (!lin) continue;  // cannot happen with min_depth -1e9 unless p_c.z is NaN
    out.m.H.block<2, 6>(row, cols.start.at(clone.slot.offset)) = J.clone;
    if (cam.extrinsic_slot.active())
      out.m.H.block<2, 6>(row, cols.start.at(cam.extrinsic_slot.offset)) = J.extrinsic;
    if (cam.intrinsic_slot.active())
      out.m.H.block<2, 8>(row, cols.start.at(cam.intrinsic_slot.offset)) = J.intrinsic;
    out.H_f.block<2, 3>(row, 0) = J.point;
  }
  return out;
}

std::optional<Vec3d> anchored_point(const State& state, const RayAnchor& anchor) {
  if (state.clones.count(anchor.t_ns) == 0) return std::nullopt;
  return state.T_w_c(anchor.t_ns, anchor.cam) * anchor.p_c;
}

std::optional<AnchorJacobian> anchor_jacobian(const State& state, const RayAnchor& anchor) {
  const auto it = state.clones.find(anchor.t_ns);
  if (it == state.clones.end()) return std::nullopt;
  // R_w_b <- R_w_b Exp(dtheta), R_b_c <- R_b_c Exp(dtheta_c) for the point fixed in the
  // camera, then only across the ray: along it the map's surface holds the point (taken as
  // facing the camera), wherever the camera is.
  const CloneState& clone = it->second;
  const CameraState& cam = state.cams[static_cast<std::size_t>(anchor.cam)];
  const Mat3d R_w_b = clone.T_w_b.rotation_matrix();
  const Vec3d v = (R_w_b * cam.T_b_c.rotation_matrix() * anchor.p_c).normalized();
  const Mat3d across = Mat3d::Identity() - v * v.transpose();
  AnchorJacobian out;
  out.vars.push_back(clone.slot);
  if (cam.extrinsic_slot.active()) out.vars.push_back(cam.extrinsic_slot);
  out.J = Eigen::MatrixXd::Zero(3, 6 * static_cast<int>(out.vars.size()));
  out.J.block<3, 3>(0, 0) = -across * R_w_b * skew(Vec3d(cam.T_b_c * anchor.p_c));
  out.J.block<3, 3>(0, 3) = across;
  if (cam.extrinsic_slot.active()) {
    out.J.block<3, 3>(0, 6) = -across * R_w_b * cam.T_b_c.rotation_matrix() * skew(anchor.p_c);
    out.J.block<3, 3>(0, 9) = across * R_w_b;
  }
  return out;
}

Mat3d anchored_covariance(const State& state, const RayAnchor& anchor, double depth_variance,
                          double sigma_px) {
  const SE3d T_w_c = state.T_w_c(anchor.t_ns, anchor.cam);
  const Vec3d v = (T_w_c.rotation_matrix() * anchor.p_c).normalized();
  const auto& model = *state.cams[static_cast<std::size_t>(anchor.cam)].model;
  const double across = anchor.p_c.norm() * sigma_px / (0.5 * (model.fx() + model.fy()));
  const Mat3d vv = v * v.transpose();
  return depth_variance * vv + across * across * (Mat3d::Identity() - vv);
}

StatusOr<FeatureRows> anchored_feature_rows(const State& state, const FeatureTrack& track,
                                            const RayAnchor& anchor, double sigma_px) {
  const std::optional<Vec3d> p_w = anchored_point(state, anchor);
  const std::optional<AnchorJacobian> aj = anchor_jacobian(state, anchor);
  if (!p_w || !aj) return absl::FailedPreconditionError("the anchor clone has left the window");
  StatusOr<FeatureRows> rows = feature_rows(state, track, *p_w, *p_w, sigma_px);
  if (!rows.ok()) return rows.status();
  const auto self = std::find(rows->used.begin(), rows->used.end(), std::make_pair(anchor.t_ns, anchor.cam));
  if (self == rows->used.end())
    return absl::FailedPreconditionError("the anchor observation is not in the track");
  // The anchor's slots are among the rows' (its own observation put them there).
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, rows->m.H.cols());
  int col = 0;
  for (const Slot& s : rows->m.vars) {
    for (std::size_t k = 0; k < aj->vars.size(); ++k) {
      if (aj->vars[k].offset == s.offset)
        J.middleCols(col, s.size) = aj->J.middleCols(6 * static_cast<int>(k), 6);
    }
    col += s.size;
  }
  rows->m.H += rows->H_f * J;
  // Without the anchor's own pair of rows (it defines the direction of the point).
  const int k = 2 * static_cast<int>(self - rows->used.begin()), n = rows->m.rows();
  const int tail = n - k - 2;
  rows->m.H.middleRows(k, tail) = rows->m.H.bottomRows(tail).eval();
  rows->m.r.segment(k, tail) = rows->m.r.tail(tail).eval();
  rows->H_f.middleRows(k, tail) = rows->H_f.bottomRows(tail).eval();
  rows->m.H.conservativeResize(n - 2, Eigen::NoChange);
  rows->m.r.conservativeResize(n - 2);
  rows->H_f.conservativeResize(n - 2, Eigen::NoChange);
  rows->used.erase(self);
  return rows;
}

}  // namespace mrvs::edge
