#include "mrvs/edge/map_trajectory.h"

namespace mrvs::edge {

void MapTrajectory::keep_unplaced() {
  never_mapped_ += static_cast<int>(held_.size());
  if (doubted_begin_) never_mapped_ += static_cast<int>(trajectory_.size() - *doubted_begin_);
  doubted_begin_.reset();
  if (!trajectory_.empty()) trajectory_.insert(trajectory_.end(), held_.begin(), held_.end());
  held_.clear();
}

void MapTrajectory::add(int run, const io::StampedPose& pose, bool in_map_frame,
                        const std::optional<SE3d>& T_m_o, bool doubted) {
  if (run != run_) {  // a new filter run (restart): a new odometry frame
    keep_unplaced();
    run_ = run;
    lock_begin_ = trajectory_.size();
  }
  if (doubted && !doubted_begin_) doubted_begin_ = lock_begin_;
  if (T_m_o) {  // placed at this frame: the run's held poses follow, and a doubted lock's
    lock_begin_ = trajectory_.size();
    if (doubted_begin_) {
      for (std::size_t i = *doubted_begin_; i < trajectory_.size(); ++i)
        trajectory_[i].T_w_b = *T_m_o * trajectory_[i].T_w_b;
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
