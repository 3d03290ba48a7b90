#include "mrvs/edge/map_trajectory.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace mrvs::edge {

void MapTrajectory::keep_unplaced() {
  never_mapped_ += static_cast<int>(held_.size());
  if (doubted_begin_) never_mapped_ += static_cast<int>(trajectory_.size() - *doubted_begin_);
  doubted_begin_.reset();
  if (!trajectory_.empty()) trajectory_.insert(trajectory_.end(), held_.begin(), held_.end());
  held_.clear();
}

void MapTrajectory::replace_doubted(const SE3d& correction) {
  const std::size_t begin = *doubted_begin_, end = trajectory_.size();
  if (begin >= end) return;
  const Vec3d p0 = trajectory_[begin].T_w_b.translation();
  const bool gross = (correction * p0 - p0).norm() > kGrossM ||
                     Eigen::AngleAxisd(correction.quaternion()).angle() > kGrossDeg * M_PI / 180.0;
  const Vec6d xi = correction.log();
  const TimestampNs t0 = doubted_lock_t_ns_, t1 = trajectory_[end - 1].t_ns;
  for (std::size_t i = begin; i < end; ++i) {
    const double ramp = static_cast<double>(trajectory_[i].t_ns - t0) / static_cast<double>(t1 - t0);
    const double f = gross || t1 <= t0 ? 1.0 : std::clamp(ramp, 0.0, 1.0);
    trajectory_[i].T_w_b = SE3d::exp(f * xi) * trajectory_[i].T_w_b;
  }
}

void MapTrajectory::add(int run, const io::StampedPose& pose, bool in_map_frame,
                        const std::optional<SE3d>& T_m_o, bool doubted) {
  if (run != run_) {  // a new filter run (restart): a new odometry frame
    keep_unplaced();
    run_ = run;
    lock_begin_ = trajectory_.size();
  }
  if (doubted && !doubted_begin_) {
    doubted_begin_ = lock_begin_;
    doubted_lock_t_ns_ = lock_t_ns_;
  }
  if (T_m_o) {  // placed at this frame: the run's held poses follow, and a doubted lock's
    lock_begin_ = trajectory_.size();
    lock_t_ns_ = pose.t_ns;
    if (doubted_begin_) {
      replace_doubted(*T_m_o);
      lock_begin_ = *doubted_begin_;
      doubted_begin_.reset();
    }
    for (const io::StampedPose& p : held_) trajectory_.push_back({p.t_ns, *T_m_o * p.T_w_b});
    held_.clear();
  }
  if (T_m_o && in_map_frame) locks_.push_back(pose);
  if (in_map_frame) {
    trajectory_.push_back(pose);
  } else {
    held_.push_back(pose);
    odometry_.push_back(pose);
  }
}

}  // namespace mrvs::edge
