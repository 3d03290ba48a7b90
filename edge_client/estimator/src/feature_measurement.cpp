#include "mrvs/edge/feature_measurement.h"

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
  out.observations = static_cast<int>(used.size());
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

}  // namespace mrvs::edge
