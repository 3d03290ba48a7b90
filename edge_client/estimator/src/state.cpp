#include "mrvs/edge/state.h"

#include <algorithm>

#include "mrvs/geometry/quaternion.h"
#include "mrvs/geometry/so3.h"

namespace mrvs::edge {

State::State(const StateOptions& options, const config::StereoRigCalibration& rig) : options_(options) {
  P = Eigen::MatrixXd::Zero(15, 15);
  for (std::size_t c = 0; c < 2; ++c) {
    cams[c].T_b_c = rig.cameras[c].T_b_c;
    cams[c].model = rig.cameras[c].model;
  }
  time_offset_s = 1e-9 * static_cast<double>(rig.cameras[0].time_offset_ns);
  if (options_.calib_time_offset) {
    time_offset_slot = append(1);
    P(time_offset_slot.offset, time_offset_slot.offset) = std::pow(options_.init_time_offset_sigma, 2);
  }
  for (CameraState& cam : cams) {
    if (options_.calib_extrinsics) {
      cam.extrinsic_slot = append(6);
      const int o = cam.extrinsic_slot.offset;
      P.block<3, 3>(o, o) = Mat3d::Identity() * std::pow(options_.init_extrinsic_rot_sigma, 2);
      P.block<3, 3>(o + 3, o + 3) = Mat3d::Identity() * std::pow(options_.init_extrinsic_pos_sigma, 2);
    }
    if (options_.calib_intrinsics) {
      cam.intrinsic_slot = append(8);
      const int o = cam.intrinsic_slot.offset;
      for (int i = 0; i < 8; ++i) {
        P(o + i, o + i) = std::pow(i < 4 ? options_.init_focal_sigma : options_.init_distortion_sigma, 2);
      }
    }
  }
}

Slot State::append(int size) {
  const int n = dim();
  Eigen::MatrixXd grown = Eigen::MatrixXd::Zero(n + size, n + size);
  grown.topLeftCorner(n, n) = P;
  P.swap(grown);
  return Slot{n, size};
}

std::vector<Slot*> State::all_slots() {
  std::vector<Slot*> out = {&imu_slot, &time_offset_slot};
  for (CameraState& c : cams) out.push_back(&c.extrinsic_slot), out.push_back(&c.intrinsic_slot);
  for (auto& [t, c] : clones) out.push_back(&c.slot);
  for (auto& [id, p] : points) out.push_back(&p.slot);
  return out;
}

std::vector<Slot> State::slots() const {
  std::vector<Slot> out;
  for (Slot* s : const_cast<State*>(this)->all_slots()) {
    if (s->active()) out.push_back(*s);
  }
  std::sort(out.begin(), out.end(), [](const Slot& a, const Slot& b) { return a.offset < b.offset; });
  return out;
}

void State::remove(const Slot& slot) {
  const int n = dim(), o = slot.offset, k = slot.size, tail = n - o - k;
  Eigen::MatrixXd shrunk(n - k, n - k);
  shrunk.topLeftCorner(o, o) = P.topLeftCorner(o, o);
  shrunk.topRightCorner(o, tail) = P.topRightCorner(o, tail);
  shrunk.bottomLeftCorner(tail, o) = P.bottomLeftCorner(tail, o);
  shrunk.bottomRightCorner(tail, tail) = P.bottomRightCorner(tail, tail);
  P.swap(shrunk);
  for (Slot* s : all_slots()) {
    if (!s->active()) continue;
    if (s->offset == o) {
      *s = Slot{};
    } else if (s->offset > o) {
      s->offset -= k;
    }
  }
}

void State::apply_correction(const Eigen::VectorXd& dx) {
  imu = imu.boxplus(dx.segment<15>(imu_slot.offset));
  if (time_offset_slot.active()) time_offset_s += dx[time_offset_slot.offset];
  for (CameraState& c : cams) {
    if (c.extrinsic_slot.active()) {
      const int o = c.extrinsic_slot.offset;
      c.T_b_c = SE3d(quat::plus_right(c.T_b_c.quaternion(), Vec3d(dx.segment<3>(o))),
                     c.T_b_c.translation() + dx.segment<3>(o + 3));
    }
    if (c.intrinsic_slot.active()) {
      const camera::Params params = c.model->params() + dx.segment<8>(c.intrinsic_slot.offset);
      auto updated = camera::make_camera(c.model->model(), c.model->width(), c.model->height(), params);
      if (updated.ok()) c.model = std::move(*updated);  // an invalid step (fx <= 0) is not taken
    }
  }
  for (auto& [t, c] : clones) {
    const int o = c.slot.offset;
    c.T_w_b = SE3d(quat::plus_right(c.T_w_b.quaternion(), Vec3d(dx.segment<3>(o))),
                   c.T_w_b.translation() + dx.segment<3>(o + 3));
  }
  for (auto& [id, p] : points) p.p_w += dx.segment<3>(p.slot.offset);
}

SE3d State::T_w_c(TimestampNs t_ns, int cam) const {
  return clones.at(t_ns).T_w_b * cams[static_cast<std::size_t>(cam)].T_b_c;
}

}  // namespace mrvs::edge
