#pragma once
// The trajectory edge_client writes, in the map frame: each filter run's poses are held in its
// odometry frame until the cloud places the run (localisation answer T_map_odom), then join the
// map-frame trajectory moved by it. The poses a lock placed that the edge later doubts (its pose
// fixes refused) are in the filter's frame, which the doubt keeps: the next answer moves them
// with the held ones that follow, in full when it moves them grossly (the lock was wrong: more
// than kGrossM or kGrossDeg at the first of them), else ramped in from none at the first to all
// of it at the last (the lock was right and the filter drifted until the doubt; poses up to the
// lock's own frame keep their placement). Poses never placed (the run
// ended first, or its lock was doubted and not replaced) are kept as the filter had them once the map-frame
// trajectory has begun, and counted.
#include <cstddef>
#include <optional>

#include "mrvs/core/time.h"
#include "mrvs/geometry/se3.h"
#include "mrvs/io/trajectory_io.h"

namespace mrvs::edge {

class MapTrajectory {
 public:
  /// The IMU pose of filter run `run` in the filter's frame (the map frame when `in_map_frame`);
  /// `T_m_o` when the cloud placed the run at this frame; `doubted` when the lock was doubted.
  void add(int run, const io::StampedPose& pose, bool in_map_frame, const std::optional<SE3d>& T_m_o,
           bool doubted);
  /// The end of the data: the poses still held join as they are (keep_unplaced).
  void finish() { keep_unplaced(); }

  /// Map frame (empty when the cloud never placed any run).
  const io::Trajectory& trajectory() const { return trajectory_; }
  /// Every pose in its run's odometry frame, until placed (the output without any lock).
  const io::Trajectory& odometry() const { return odometry_; }
  /// Poses written as the filter had them, never placed by the cloud.
  int never_mapped() const { return never_mapped_; }
  /// The pose each lock placed at its own frame (map frame), as accepted: never moved later
  /// (a doubted lock's poses in trajectory() are; this is what the lock itself got right).
  const io::Trajectory& locks() const { return locks_; }

  /// A correction moving a doubted lock's first pose farther or turning more than this replaced
  /// a wrong lock: applied in full.
  static constexpr double kGrossM = 0.5;
  static constexpr double kGrossDeg = 5.0;

 private:
  void keep_unplaced();
  void replace_doubted(const SE3d& correction);

  io::Trajectory trajectory_, odometry_, held_, locks_;
  std::size_t lock_begin_ = 0;  ///< trajectory_ index of the first pose the current lock placed
  /// From here on trajectory_ holds what a doubted lock placed (the filter's frame, as held_).
  std::optional<std::size_t> doubted_begin_;
  TimestampNs lock_t_ns_ = 0;          ///< the current lock's frame
  TimestampNs doubted_lock_t_ns_ = 0;  ///< the doubted lock's frame
  int run_ = -1;
  int never_mapped_ = 0;
};

}  // namespace mrvs::edge
