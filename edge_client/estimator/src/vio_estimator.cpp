#include "mrvs/edge/vio_estimator.h"
#include "mrvs/core/time.h"

#include <algorithm>
#include <chrono>
#include <set>
#include <unordered_map>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <Eigen/Eigenvalues>

#include "mrvs/geometry/angles.h"

namespace mrvs::edge {
namespace {

using Clock = std::chrono::steady_clock;

/// Map points kept per plane_radius_m cell of the SurfaceMap: a plane needs a few, a fit of
/// more is no better and costs time.
constexpr int kSurfacePointsPerCell = 16;

ImuNoise scaled_noise(const config::ImuCalibration& imu, double k) {
  return {k * imu.gyroscope_noise_density, k * imu.accelerometer_noise_density, k * imu.gyroscope_random_walk,
          k * imu.accelerometer_random_walk};
}

}  // namespace

VioEstimator::VioEstimator(const EstimatorOptions& options, const config::StereoRigCalibration& rig,
                           io::Trajectory groundtruth)
    : options_(options),
      rig_(rig),
      groundtruth_(std::move(groundtruth)),
      noise_(scaled_noise(rig.imu, options.propagator.noise_multiplier)),
      g_w_(0.0, 0.0, -options.propagator.gravity_mps2),
      initializer_(options.initializer, rig, noise_, options.propagator.gravity_mps2, options.triangulation),
      msckf_(options.msckf, options.triangulation),
      stage1_mode_(parse_stage1_mode(options.map.stage1_mode).value_or(Stage1Mode::kKnownLandmark)),
      points_(options.points, options.triangulation),
      map_stage_(options.map, options.triangulation),
      localiser_(options.localisation),
      registered_(options.map.registered_voxel_m, options.map.registered_per_voxel),
      surfaces_(options.map.plane_radius_m, kSurfacePointsPerCell) {}

StatusOr<VioEstimator> VioEstimator::create(const EstimatorOptions& options,
                                            const config::StereoRigCalibration& rig,
                                            io::Trajectory groundtruth) {
  MRVS_RETURN_IF_ERROR(config::validate_options(options));
  for (std::size_t c = 0; c < 2; ++c) {
    if (!rig.cameras[c].model) {
      return absl::InvalidArgumentError(fmt::format("estimator: camera {} has no model (calibration)", c));
    }
  }
  if (!(rig.imu.gyroscope_noise_density > 0.0 && rig.imu.accelerometer_noise_density > 0.0)) {
    return absl::InvalidArgumentError(
        "estimator: the IMU calibration has no noise densities (imu0/sensor.yaml gyroscope_noise_density, "
        "accelerometer_noise_density)");
  }
  return VioEstimator(options, rig, std::move(groundtruth));
}

Status VioEstimator::feed_imu(const io::ImuSample& s) {
  if (!imu_.empty() && s.t_ns <= imu_.back().t_ns) {
    return absl::InvalidArgumentError(
        fmt::format("IMU sample at {} ns is not after the previous one ({} ns)", s.t_ns, imu_.back().t_ns));
  }
  imu_.push_back(s);
  if (!state_) initializer_.feed_imu(s);
  // Keep what the next propagation needs: from just before the state time.
  const TimestampNs keep_from =
      state_ ? state_->imu.t_ns : s.t_ns - from_seconds(options_.initializer.window_s + 1.0);
  while (imu_.size() > 2 && imu_[1].t_ns <= keep_from) imu_.pop_front();
  return absl::OkStatus();
}

std::vector<io::ImuSample> VioEstimator::imu_vector() const { return {imu_.begin(), imu_.end()}; }

std::optional<SE3d> VioEstimator::predict_T_c_cprev(TimestampNs t_cam_ns) const {
  if (!state_ || state_->clones.empty()) return std::nullopt;
  const TimestampNs t_imu = t_cam_ns + from_seconds(state_->time_offset_s);
  const auto prop = propagate(state_->imu, imu_vector(), t_imu, g_w_, noise_);
  if (!prop.ok()) return std::nullopt;
  const SE3d& T_b_c = state_->cams[0].T_b_c;
  const SE3d T_w_c_now = SE3d(prop->state.q_w_b, prop->state.p_w_b) * T_b_c;
  const SE3d T_w_c_prev = state_->T_w_c(state_->newest_clone_ns(), 0);
  return T_w_c_now.inverse() * T_w_c_prev;
}

TimestampNs VioEstimator::imu_time(TimestampNs t_cam_ns) const {
  return t_cam_ns + (state_ ? from_seconds(state_->time_offset_s) : rig_.cameras[0].time_offset_ns);
}

StatusOr<FrameOutput> VioEstimator::feed_frame(const FeatureFrame& frame) {
  if (!imu_.empty() && imu_.back().t_ns < imu_time(frame.t_ns)) {
    return absl::OutOfRangeError(
        fmt::format("IMU data ends at {} ns, before the frame at {} ns", imu_.back().t_ns, frame.t_ns));
  }
  if (state_ && frame.t_ns <= state_->newest_clone_ns()) {
    return absl::InvalidArgumentError(fmt::format("frame at {} ns is not after the previous one ({} ns)",
                                                  frame.t_ns, state_->newest_clone_ns()));
  }
  return state_ ? track(frame) : initialize(frame);
}

StatusOr<FrameOutput> VioEstimator::initialize(const FeatureFrame& frame) {
  FrameOutput out;
  out.t_ns = frame.t_ns;
  initializer_.feed_frame(frame);
  std::optional<InitializationResult> init = initializer_.try_initialize(&waiting_);
  out.status = waiting_;
  if (!init) return out;
  MRVS_RETURN_IF_ERROR(start(*init, frame));
  out.initialized = true;
  out.run = run_;
  out.in_map_frame = in_map_frame_;
  out.T_w_b = SE3d(state_->imu.q_w_b, state_->imu.p_w_b);
  out.t_imu_ns = state_->imu.t_ns;
  out.clones = 1;
  out.status = init_summary_;
  return out;
}

Status VioEstimator::start(const InitializationResult& init, const FeatureFrame& frame) {
  State state(options_.state, rig_);
  state.imu = init.imu;
  state.P.topLeftCorner<15, 15>() = init.P;
  MRVS_ASSIGN_OR_RETURN(const std::optional<SE3d> target,
                        alignment_target(options_.alignment, groundtruth_, state));
  if (target) {
    const AlignmentOptions& a = options_.alignment;
    const bool gt = a.source == "gt";
    const double sigma = gt ? 1e-3 : std::max(1e-3, a.translation_noise_mean_m);
    // A constant pose says nothing of the heading: the initialiser's uncertainty stays.
    const std::optional<double> yaw_sigma =
        a.source == "constant"
            ? std::nullopt
            : std::optional<double>(gt ? 1e-3 : std::max(1e-3, a.rotation_noise_deg * M_PI / 180.0));
    MRVS_RETURN_IF_ERROR(align_state(state, *target, sigma, yaw_sigma));
  }
  // After a restart (map, none) the new odometry frame continues where the last run ended:
  // its first pose is the last pose before the gap (the motion during the gap is lost).
  if (!target && last_pose_) MRVS_RETURN_IF_ERROR(align_state(state, *last_pose_, 1e-3, std::nullopt));
  // Source map: the odometry frame until the cloud places the filter; none: the odometry
  // frame is taken as the map frame (the user's choice).
  in_map_frame_ = options_.alignment.source != "map";
  localiser_.reset();
  run_path_m_ = 0.0;
  run_last_p_ = state.imu.p_w_b;
  odometry_.clear();
  // The body rate at the start (for the clone's time-offset Jacobian).
  const auto rates = propagate(state.imu, imu_vector(), state.imu.t_ns, g_w_, noise_);
  last_w_b_ = rates.ok() ? rates->last_rates.w : Vec3d::Zero();
  MRVS_RETURN_IF_ERROR(augment_clone(state, frame.t_ns, last_w_b_));
  imu_fej_ = state.imu;
  state_ = std::move(state);
  db_ = FeatureDatabase();
  registered_ = RegisteredMap(options_.map.registered_voxel_m, options_.map.registered_per_voxel);
  db_.add(frame);
  init_ns_ = frame.t_ns;
  ++run_;
  const std::optional<localisation::PriorRegion> near_end =
      last_placed_ ? restart_prior(*last_placed_, frame.t_ns, 0.0, options_.localisation) : std::nullopt;
  init_summary_ = fmt::format(
      "initialised ({}) at {} ns: {}; alignment {}{}{}", init.method, frame.t_ns, init.detail,
      options_.alignment.source,
      localises() ? " (plain VIO in the odometry frame until the cloud places it in the map)" : "",
      near_end ? fmt::format("; searched within {:.2f} m (plus the path since) of where the last run ended",
                             near_end->radius_m)
               : std::string());
  waiting_.clear();
  return absl::OkStatus();
}

std::optional<std::string> VioEstimator::imu_gap(TimestampNs from_ns, TimestampNs to_ns) const {
  const DurationNs max_gap = from_seconds(options_.propagator.max_imu_gap_s);
  for (std::size_t i = 1; i < imu_.size(); ++i) {
    if (imu_[i].t_ns <= from_ns || imu_[i - 1].t_ns >= to_ns) continue;
    if (imu_[i].t_ns - imu_[i - 1].t_ns > max_gap) {
      return fmt::format("IMU gap of {:.3f} s between {} and {} ns",
                         to_seconds(imu_[i].t_ns - imu_[i - 1].t_ns), imu_[i - 1].t_ns, imu_[i].t_ns);
    }
  }
  return std::nullopt;
}

void VioEstimator::restart() {
  if (state_) last_pose_ = SE3d(state_->imu.q_w_b, state_->imu.p_w_b);
  if (state_ && in_map_frame_ && localises()) {
    last_placed_ = RunEnd{state_->imu.p_w_b, state_->imu.v_w_b.norm(), state_->imu.t_ns, 0.0};
  } else if (state_ && last_placed_) {
    // A run that began after a placed run and was never placed itself: its end lies within the
    // region its start had grown to; the next run carries that radius on.
    const std::optional<localisation::PriorRegion> reached =
        restart_prior(*last_placed_, init_ns_, run_path_m_, options_.localisation);
    last_placed_ = reached ? std::optional<RunEnd>(RunEnd{reached->centre_m, state_->imu.v_w_b.norm(),
                                                          state_->imu.t_ns, reached->radius_m})
                           : std::nullopt;
  } else if (state_) {
    last_placed_.reset();
  }
  state_.reset();
  in_map_frame_ = false;
  localiser_.reset();
  db_ = FeatureDatabase();
  registered_ = RegisteredMap(options_.map.registered_voxel_m, options_.map.registered_per_voxel);
  initializer_ = Initializer(options_.initializer, rig_, noise_, options_.propagator.gravity_mps2,
                             options_.triangulation);
  // The initialiser starts from the IMU after the gap.
  for (const io::ImuSample& s : imu_) initializer_.feed_imu(s);
}

StatusOr<FrameOutput> VioEstimator::track(const FeatureFrame& frame) {
  FrameOutput out;
  out.t_ns = frame.t_ns;
  out.initialized = true;
  out.run = run_;
  const Clock::time_point t0 = Clock::now();
  deadline_ = t0 + std::chrono::microseconds(static_cast<std::int64_t>(options_.map.frame_budget_ms * 1e3));
  const TimestampNs t_imu = frame.t_ns + from_seconds(state_->time_offset_s);
  if (const auto gap = imu_gap(state_->imu.t_ns, t_imu)) {
    // Drop the samples before the gap: the next initialisation uses what follows it.
    const DurationNs max_gap = from_seconds(options_.propagator.max_imu_gap_s);
    while (imu_.size() > 1 && imu_[1].t_ns - imu_[0].t_ns <= max_gap) imu_.pop_front();
    if (!imu_.empty()) imu_.pop_front();
    restart();
    return absl::DataLossError(*gap + "; the filter restarts and initialises again");
  }
  MRVS_ASSIGN_OR_RETURN(Propagation prop, propagate(state_->imu, imu_vector(), t_imu, g_w_, noise_));
  if (options_.state.use_fej) apply_first_estimates(imu_fej_, prop.state, g_w_, &prop.Phi);
  imu_fej_ = prop.state;  // the estimate this frame's measurements are linearised at
  // Covariance: IMU block by Phi, cross terms with every other variable, noise.
  const int n = state_->dim();
  Eigen::MatrixXd& P = state_->P;
  const Eigen::MatrixXd P_io = P.block(0, 15, 15, n - 15);
  P.block(0, 15, 15, n - 15) = prop.Phi * P_io;
  P.block(15, 0, n - 15, 15) = P.block(0, 15, 15, n - 15).transpose();
  P.topLeftCorner<15, 15>() = prop.Phi * P.topLeftCorner<15, 15>() * prop.Phi.transpose() + prop.Qd;
  state_->imu = prop.state;
  last_w_b_ = prop.last_rates.w;
  MRVS_RETURN_IF_ERROR(augment_clone(*state_, frame.t_ns, last_w_b_));
  db_.add(frame);
  out.timing.propagate_ms = ms_since(t0);
  std::vector<std::pair<FeatureId, Vec3d>> triangulated;
  const bool localising = localises() && localiser_.active();
  update(frame, &out, localising && localiser_.gathering(frame.t_ns) ? &triangulated : nullptr);
  if (localising) localise(frame, triangulated, &out);
  out.in_map_frame = in_map_frame_;
  out.T_w_b = SE3d(state_->imu.q_w_b, state_->imu.p_w_b);
  out.t_imu_ns = state_->imu.t_ns;
  out.clones = static_cast<int>(state_->clones.size());
  out.slam_points = static_cast<int>(state_->points.size());
  out.timing.total_ms = ms_since(t0);
  spdlog::debug(
      "frame {}: msckf {} used / {} gated / {} untriangulated, points {} updated / {} gated / {} new / {} "
      "removed, {} in the state, {:.2f} ms",
      frame.t_ns, out.msckf.used, out.msckf.gated, out.msckf.triangulation_failed, out.points.updated,
      out.points.gated, out.points.initialized, out.points.removed, out.slam_points, out.timing.total_ms);
  return out;
}

void VioEstimator::update(const FeatureFrame& frame, FrameOutput* out,
                          std::vector<std::pair<FeatureId, Vec3d>>* triangulated) {
  State& s = *state_;
  const bool full = static_cast<int>(s.clones.size()) > options_.state.max_clones;
  const TimestampNs marg_ns = full ? clone_to_marginalize(s, db_, options_.keyframe) : 0;
  const bool marg_oldest = full && marg_ns == s.clones.begin()->first;
  const bool use_map = map_ != nullptr && options_.map.enabled && in_map_frame_;
  // Triangulated points in the state: without the map, with it when asked to, and as the
  // fallback while the cloud does not answer.
  const bool points_from_tracks = !use_map || options_.map.points_from_tracks || !map_answering_;
  // MSCKF features: tracks that ended, and (when the oldest clone goes) those it saw; long
  // ones of the latter still tracked become points when there is room.
  std::vector<FeatureId> msckf_ids, point_ids;
  for (FeatureId id : db_.lost_before(frame.t_ns)) {
    if (s.points.count(id) == 0) msckf_ids.push_back(id);
  }
  if (marg_oldest) {
    const bool points_allowed =
        points_from_tracks && to_seconds(frame.t_ns - init_ns_) >= options_.points.delay_s;
    for (FeatureId id : db_.seen_at(marg_ns)) {
      const FeatureTrack* t = db_.find(id);
      if (s.points.count(id) != 0 || !t->seen_at(frame.t_ns)) continue;
      const bool long_track = t->frames() >= options_.state.max_clones;
      (long_track && points_allowed ? point_ids : msckf_ids).push_back(id);
    }
  }
  // Stage 1: the MSCKF update, with the features' map points where the cloud has them.
  std::map<FeatureId, MapPoint> map_points;
  if (use_map)
    map_points =
        map_stage_.associate(s, db_, groundtruth_, &msckf_ids, *map_, deadline_, &out->map, surfaces());
  Clock::time_point t0 = Clock::now();
  out->msckf = msckf_.update(s, db_, msckf_ids, map_points, stage1_mode_, triangulated);
  out->timing.msckf_ms = ms_since(t0);
  update_points(frame, point_ids, use_map, out);
  if (out->map.requests > 0) map_answering_ = out->map.answered > 0;
  // Used MSCKF features leave the database.
  for (FeatureId id : msckf_ids) db_.erase(id);
  for (FeatureId id : point_ids) {
    if (s.points.count(id) == 0) db_.erase(id);  // failed to initialise: used up as MSCKF would be
  }
  if (full) marginalize(marg_ns, out);
}

void VioEstimator::update_points(const FeatureFrame& frame, const std::vector<FeatureId>& point_ids,
                                 bool use_map, FrameOutput* out) {
  State& s = *state_;
  Clock::time_point t0 = Clock::now();
  // Stage 2: the registered map points suitable now, and any triangulated points.
  std::optional<std::vector<FeatureId>> ids;
  if (use_map) {
    ids = map_stage_.suitable(s, db_, registered_, frame.t_ns);
    for (const auto& [id, p] : s.points) {
      if (!p.from_map) ids->push_back(id);
    }
    out->map.selection_ms = ms_since(t0);
  }
  out->points = points_.update(s, db_, frame.t_ns, ids);
  const PointStats init = points_.initialize(s, db_, point_ids, frame.t_ns);
  out->points.initialized = init.initialized;
  out->points.init_failed = init.init_failed;
  const std::vector<FeatureId> removed = points_.remove_stale(s, db_, frame.t_ns);
  for (FeatureId id : removed) registered_.remove(id);
  out->points.removed = static_cast<int>(removed.size());
  if (use_map && options_.map.register_new_features) {
    map_stage_.register_new(s, db_, groundtruth_, frame.t_ns, &registered_, *map_, deadline_, &out->map,
                            surfaces());
  }
  for (const auto& [id, p] : s.points) {
    db_.keep_from(id, frame.t_ns);  // points keep only their newest observations
    if (p.from_map) registered_.move(id, p.p_w);
  }
  out->timing.points_ms = ms_since(t0) - out->map.selection_ms;
}

void VioEstimator::feed_gnss(const io::GnssFix& fix, const SE3d& T_b_antenna) {
  gnss_.push_back(fix);
  gnss_lever_arm_m_ = T_b_antenna.translation().norm();
  while (!gnss_.empty() && gnss_.front().t_ns < fix.t_ns - from_seconds(options_.localisation.max_window_s)) {
    gnss_.pop_front();
  }
}

bool VioEstimator::localises() const {
  return options_.alignment.source == "map" && options_.map.enabled && map_ != nullptr;
}

bool VioEstimator::wants_dense_submap(TimestampNs t_cam_ns) const {
  return state_ && localises() && localiser_.active() && localiser_.wants_dense(t_cam_ns);
}

void VioEstimator::add_dense_submap(TimestampNs t_cam_ns, const std::vector<Eigen::Vector3f>& points_c0,
                                    const std::vector<std::uint8_t>& brightness) {
  if (!state_ || state_->clones.count(t_cam_ns) == 0) return;
  const SE3d T_w_c = state_->T_w_c(t_cam_ns, 0);
  std::vector<Vec3d> points_w;
  points_w.reserve(points_c0.size());
  for (const Eigen::Vector3f& p : points_c0) points_w.push_back(T_w_c * p.cast<double>());
  localiser_.add_points(t_cam_ns, points_w, T_w_c.translation(), brightness);
}

void VioEstimator::localise(const FeatureFrame& frame,
                            const std::vector<std::pair<FeatureId, Vec3d>>& triangulated, FrameOutput* out) {
  State& s = *state_;
  if (localiser_.gathering(frame.t_ns)) {
    const Vec3d camera = s.T_w_c(frame.t_ns, 0).translation();
    std::unordered_map<FeatureId, float> brightness;  // of the features seen in this frame
    for (const FeatureObservation& f : frame.features) brightness[f.id] = f.brightness;
    auto seen = [&](FeatureId id) {
      const auto it = brightness.find(id);
      return it == brightness.end() ? 0.0f : it->second;
    };
    for (const auto& [id, p] : triangulated) localiser_.set_track_point(id, frame.t_ns, p, camera, seen(id));
    for (const auto& [id, p] : s.points) localiser_.set_track_point(id, frame.t_ns, p.p_w, camera, seen(id));
  }
  run_path_m_ += (s.imu.p_w_b - run_last_p_).norm();
  run_last_p_ = s.imu.p_w_b;
  odometry_.push_back({s.imu.t_ns, s.imu.p_w_b});
  while (odometry_.front().t_ns < s.imu.t_ns - from_seconds(options_.localisation.max_window_s + 1.0))
    odometry_.pop_front();
  const std::optional<localisation::PriorRegion> prior = in_map_frame_ ? tracking_prior() : search_prior();
  const std::optional<Alignment> a =
      localiser_.step(frame.t_ns, s.imu.p_w_b, prior, *map_, &out->localisation);
  if (!a) return;
  if (in_map_frame_) {
    apply_fix(*a, &out->localisation);
    return;
  }
  if (!move_to(*a)) return;
  in_map_frame_ = true;
  localiser_.start_tracking(frame.t_ns);
  out->T_m_o = yaw_only(a->T_m_o);
  spdlog::info("{} after {:.1f} s: the filter is in the map frame", localiser_.status(),
               to_seconds(frame.t_ns - init_ns_));
}

bool VioEstimator::move_to(const Alignment& a) {
  if (const Status st = reanchor_state(*state_, a.T_m_o, a.covariance, a.anchor_m); !st.ok()) {
    spdlog::warn("localisation answer not applied: {}", std::string(st.message()));
    return false;
  }
  // The linearisation point of the newest clone moves with the state.
  const SE3d T = yaw_only(a.T_m_o);
  imu_fej_.q_w_b = (T.quaternion() * imu_fej_.q_w_b).normalized();
  imu_fej_.p_w_b = T * imu_fej_.p_w_b;
  imu_fej_.v_w_b = T.rotation_matrix() * imu_fej_.v_w_b;
  for (OdometrySample& o : odometry_) o.p_o = T * o.p_o;
  run_last_p_ = T * run_last_p_;
  registered_ = RegisteredMap(options_.map.registered_voxel_m, options_.map.registered_per_voxel);
  surfaces_ = SurfaceMap(options_.map.plane_radius_m, kSurfacePointsPerCell);
  return true;
}

std::optional<localisation::PriorRegion> VioEstimator::search_prior() const {
  const LocalisationOptions& o = options_.localisation;
  std::optional<localisation::PriorRegion> prior =
      gnss_prior(gnss_, odometry_, state_->imu.t_ns, state_->imu.p_w_b, o.max_window_s, gnss_lever_arm_m_, o);
  if (last_placed_) prior = tighter(prior, restart_prior(*last_placed_, init_ns_, run_path_m_, o));
  return prior;
}

localisation::PriorRegion VioEstimator::tracking_prior() const {
  const State& s = *state_;
  const Mat3d P_p = s.P.block<3, 3>(s.imu_slot.offset + 3, s.imu_slot.offset + 3);
  const double sigma =
      std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Mat3d>(P_p).eigenvalues().maxCoeff()));
  return {s.imu.p_w_b, options_.localisation.track_radius_m + 3.0 * sigma};
}

void VioEstimator::apply_fix(const Alignment& a, LocalisationFrameStats* stats) {
  const LocalisationOptions& o = options_.localisation;
  const Eigen::Vector4d floor(o.fix_floor_m, o.fix_floor_m, o.fix_floor_m, o.fix_floor_deg * kDegToRad);
  const StatusOr<PoseFix> fix = apply_pose_fix(*state_, a.T_m_o, a.covariance, a.anchor_m, floor);
  const bool applied = fix.ok() && fix->applied;
  if (localiser_.note_fix(applied)) {
    // The filter's frame is not the map's after all: it is the odometry frame again until the
    // cloud places it anew (rays off meanwhile; the poses since are re-mapped then).
    in_map_frame_ = false;
    stats->doubted = true;
    spdlog::warn("localisation: {}; plain VIO until then", localiser_.status());
  }
  if (!applied) {
    ++stats->fixes_refused;
    spdlog::info(
        "localisation: pose fix not applied: {}",
        fix.ok() ? fmt::format("it moves the filter {:.3f} m / {:.2f} deg, beyond its gate (Mahalanobis^2 "
                               "{:.1f} > {:.1f})",
                               fix->residual.head<3>().norm(), fix->residual(3) * kRadToDeg,
                               fix->mahalanobis2, kChi2Pose4)
                 : std::string(fix.status().message()));
    return;
  }
  ++stats->fixes_applied;
  spdlog::debug("localisation: pose fix applied: {:.3f} m / {:.2f} deg (Mahalanobis^2 {:.1f})",
                fix->residual.head<3>().norm(), fix->residual(3) * kRadToDeg, fix->mahalanobis2);
}

void VioEstimator::marginalize(TimestampNs marg_ns, FrameOutput* out) {
  const Clock::time_point t0 = Clock::now();
  marginalize_clone(*state_, marg_ns);
  db_.erase_at(marg_ns);
  db_.erase_before(state_->clones.begin()->first);
  out->timing.marginalize_ms = ms_since(t0);
}

}  // namespace mrvs::edge
