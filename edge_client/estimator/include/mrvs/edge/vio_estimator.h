#pragma once
// The edge filter behind a small facade (OpenVINS' VioManager idea): feed IMU samples and
// the tracked features of each stereo frame; it initialises, aligns to the map frame once,
// propagates, clones, runs the MSCKF and point updates and marginalises.
//
//   auto vio = VioEstimator::create(options, rig, groundtruth);
//   vio->feed_imu(sample) ...                 // IMU up to (at least) the frame time
//   auto out = vio->feed_frame(features);     // one stereo frame
//   if (out->pose) write(out->t_ns, *out->pose);
#include <deque>
#include <optional>
#include <string>

#include "mrvs/config/options.h"
#include "mrvs/edge/feature_database.h"
#include "mrvs/edge/global_alignment.h"
#include "mrvs/edge/initializer.h"
#include "mrvs/edge/keyframe_policy.h"
#include "mrvs/edge/map_localiser.h"
#include "mrvs/edge/map_stage.h"
#include "mrvs/edge/msckf_updater.h"
#include "mrvs/edge/point_updater.h"

namespace mrvs::edge {

struct PropagatorOptions : config::OptionsEquality<PropagatorOptions> {
  double gravity_mps2 = 9.81;     ///< |g| (EuRoC 9.81, KAIST 9.80766)
  double noise_multiplier = 1.0;  ///< scales the calibration's IMU noise densities
  double max_imu_gap_s = 0.05;    ///< a longer gap between IMU samples restarts the filter

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("gravity_mps2", gravity_mps2, in_range(9.0, 10.5), "gravity magnitude, m/s^2");
    v("noise_multiplier", noise_multiplier, in_range(0.01, 1000.0), "scale of the calibration's IMU noise");
    v("max_imu_gap_s", max_imu_gap_s, in_range(0.001, 10.0), "longest IMU gap propagated over, s");
  }
};

struct EstimatorOptions : config::OptionsEquality<EstimatorOptions> {
  PropagatorOptions propagator;
  StateOptions state;
  TriangulationOptions triangulation;
  MsckfOptions msckf;
  PointOptions points;
  KeyframeOptions keyframe;
  InitializerOptions initializer;
  AlignmentOptions alignment;
  LocalisationOptions localisation;
  MapOptions map;

  template <class V>
  void visit(V& v) {
    v.section("propagator", propagator, "IMU propagation");
    v.section("state", state, "state layout");
    v.section("triangulation", triangulation, "feature triangulation");
    v.section("msckf", msckf, "MSCKF update");
    v.section("points", points, "point features in the state");
    v.section("keyframe", keyframe, "clone marginalisation");
    v.section("initializer", initializer, "initialisation");
    v.section("alignment", alignment, "how the odometry frame is tied to the map frame");
    v.section("localisation", localisation, "the cloud's localisation service (alignment.source map)");
    v.section("map", map, "the cloud map: stage-1 association, stage-2 registration");
  }
};

/// Wall time of the estimator's steps for one frame, ms.
struct EstimatorTiming {
  double propagate_ms = 0.0;  ///< propagation and cloning
  double msckf_ms = 0.0;      ///< MSCKF update (the paper's state update without map points)
  double points_ms = 0.0;     ///< point update, initialisation, removal
  double marginalize_ms = 0.0;
  double total_ms = 0.0;  ///< the whole filter step, map work included
};

struct FrameOutput {
  TimestampNs t_ns = 0;  ///< camera time of the frame
  bool initialized = false;
  int run = 0;                ///< filter run: 1 from the first initialisation, +1 after each restart
  std::optional<SE3d> T_w_b;  ///< IMU pose at the frame (IMU clock t_ns + t_d), in the frame below
  /// T_w_b is in the map frame (else the odometry frame: alignment.source map before the
  /// cloud placed the filter, or after a restart until it does again).
  bool in_map_frame = false;
  /// Set at the frame the cloud's localisation was applied: earlier odometry-frame poses of
  /// this filter run map into the map frame by it.
  std::optional<SE3d> T_m_o;
  LocalisationFrameStats localisation;
  TimestampNs t_imu_ns = 0;
  std::string status;  ///< why it waits, or what went wrong this frame
  MsckfStats msckf;
  PointStats points;
  MapFrameStats map;
  int clones = 0;
  int slam_points = 0;
  EstimatorTiming timing;
};

class VioEstimator {
 public:
  /// `groundtruth` feeds the alignment source (may be empty for source none / constant).
  static StatusOr<VioEstimator> create(const EstimatorOptions& options,
                                       const config::StereoRigCalibration& rig,
                                       io::Trajectory groundtruth = {});

  /// IMU samples in time order (InvalidArgument for a sample not after the previous one).
  Status feed_imu(const io::ImuSample& sample);
  /// One frame of tracked features. OutOfRange when the IMU does not cover the frame yet
  /// (feed more IMU and call again); DataLoss when the IMU has a gap longer than
  /// propagator.max_imu_gap_s before it (the filter restarts: it initialises again from the
  /// data after the gap); other errors are the filter's (the frame is skipped, the state
  /// kept).
  StatusOr<FrameOutput> feed_frame(const FeatureFrame& frame);
  /// The IMU-clock time of camera stamp t_cam_ns, t_cam + t_d, with t_d the filter's estimate
  /// while it runs (it moves under estimator.state.calib_time_offset) and the calibration's
  /// before: feed the IMU through the first sample at or after it before the frame.
  TimestampNs imu_time(TimestampNs t_cam_ns) const;

  /// The motion of cam0 from the previous frame to a frame at `t_cam_ns` predicted by the
  /// IMU (for the tracker's KLT prior); nullopt before initialisation or without IMU.
  std::optional<SE3d> predict_T_c_cprev(TimestampNs t_cam_ns) const;

  /// The cloud map to use (not owned; nullptr: none). Without it, or with map.enabled false,
  /// the filter is plain VIO.
  void set_map_service(MapService* service) { map_ = service; }

  /// A GNSS fix (antenna position in the map frame, IMU clock): only the prior region of the
  /// localisation requests comes from it. `T_b_antenna` is where the antenna sits on the body.
  void feed_gnss(const io::GnssFix& fix, const SE3d& T_b_antenna);
  /// Whether the submap wants a dense stereo pair of the frame at t_cam_ns.
  bool wants_dense_submap(TimestampNs t_cam_ns) const;
  /// Dense stereo points (cam0 frame, m) of the newest frame, fed after feed_frame() for it.
  void add_dense_submap(TimestampNs t_cam_ns, const std::vector<Eigen::Vector3f>& points_c0,
                        const std::vector<std::uint8_t>& brightness = {});
  /// Whether the state is in the map frame.
  bool in_map_frame() const { return in_map_frame_; }
  /// What localisation is doing (alignment.source map).
  const std::string& localisation_status() const { return localiser_.status(); }

  bool initialized() const { return state_.has_value(); }
  const State* state() const { return state_ ? &*state_ : nullptr; }
  const EstimatorOptions& options() const { return options_; }
  /// Why the initialisation still waits (empty once initialised).
  const std::string& waiting_reason() const { return waiting_; }
  /// Initialisation method and detail line once initialised.
  const std::string& initialization_summary() const { return init_summary_; }

 private:
  VioEstimator(const EstimatorOptions& options, const config::StereoRigCalibration& rig,
               io::Trajectory groundtruth);
  StatusOr<FrameOutput> initialize(const FeatureFrame& frame);
  Status start(const InitializationResult& init, const FeatureFrame& frame);
  StatusOr<FrameOutput> track(const FeatureFrame& frame);
  /// `triangulated` receives the MSCKF features' triangulated points (for the submap).
  void update(const FeatureFrame& frame, FrameOutput* out,
              std::vector<std::pair<FeatureId, Vec3d>>* triangulated);
  void update_points(const FeatureFrame& frame, const std::vector<FeatureId>& point_ids, bool use_map,
                     FrameOutput* out);
  void marginalize(TimestampNs marg_ns, FrameOutput* out);
  std::vector<io::ImuSample> imu_vector() const;
  /// The first gap longer than max_imu_gap_s in (from_ns, to_ns], as a message.
  std::optional<std::string> imu_gap(TimestampNs from_ns, TimestampNs to_ns) const;
  void restart();
  /// alignment.source map with the map on: the cloud's localisation ties the frames.
  bool localises() const;
  /// Feeds the submap with this frame's points, runs the localiser, applies its answer.
  void localise(const FeatureFrame& frame, const std::vector<std::pair<FeatureId, Vec3d>>& triangulated,
                FrameOutput* out);
  /// Before a lock: where the submap is searched (the tighter of the GNSS prior and, after a
  /// restart from a placed pose, restart_prior), nullopt for anywhere in the map.
  std::optional<localisation::PriorRegion> search_prior() const;
  /// Tracking: where the pose fix's submap is searched (the filter's position, the radius
  /// track_radius_m plus 3 sigma of it).
  localisation::PriorRegion tracking_prior() const;
  /// Tracking: a pose fix from the cloud into the state, if the gate lets it.
  void apply_fix(const Alignment& a, LocalisationFrameStats* stats);
  /// Moves the state (and the newest clone's first estimate) into the map frame by `a`; the
  /// registered-point grid and the surfaces start over. False (logged) when it cannot.
  bool move_to(const Alignment& a);

  EstimatorOptions options_;
  config::StereoRigCalibration rig_;
  io::Trajectory groundtruth_;
  ImuNoise noise_;
  Vec3d g_w_;
  Initializer initializer_;
  MsckfUpdater msckf_;
  Stage1Mode stage1_mode_;  ///< options_.map.stage1_mode (validated by create)
  PointUpdater points_;
  MapStage map_stage_;
  MapService* map_ = nullptr;
  MapLocaliser localiser_;
  std::deque<io::GnssFix> gnss_;  ///< the last max_window_s of fixes
  double gnss_lever_arm_m_ = 0.0;
  /// This run's IMU positions (the state's frame), the last max_window_s: the GNSS prior's track.
  std::deque<OdometrySample> odometry_;
  bool in_map_frame_ = false;  ///< the state is in the map frame (aligned at start or localised)
  RegisteredMap registered_;
  SurfaceMap surfaces_;  ///< every map point the cloud answered (stage1_mode plane's planes)
  /// The surfaces to feed and fit: only stage1_mode plane uses them.
  SurfaceMap* surfaces() { return stage1_mode_ == Stage1Mode::kPlane ? &surfaces_ : nullptr; }
  MapStage::Clock::time_point deadline_;
  bool map_answering_ = false;  ///< the cloud answered the last request (else: triangulated points)
  std::optional<State> state_;
  /// The last IMU pose of the previous filter run: a restart's odometry frame continues from it.
  std::optional<SE3d> last_pose_;
  /// Where the previous run ended when it was placed in the map (restart_prior's centre), the
  /// path length of this run since it began, and its last position (path accounting).
  std::optional<RunEnd> last_placed_;
  double run_path_m_ = 0.0;
  Vec3d run_last_p_ = Vec3d::Zero();
  ImuState imu_fej_;  ///< first estimate of the IMU at the newest clone (before its update)
  FeatureDatabase db_;
  std::deque<io::ImuSample> imu_;
  TimestampNs init_ns_ = 0;
  int run_ = 0;  ///< initialisations so far
  Vec3d last_w_b_ = Vec3d::Zero();
  std::string waiting_;
  std::string init_summary_;
};

}  // namespace mrvs::edge
