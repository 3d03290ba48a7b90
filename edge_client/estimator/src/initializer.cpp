#include "mrvs/edge/initializer.h"

#include <cmath>
#include <unordered_map>

#include <fmt/format.h>

namespace mrvs::edge {
namespace {

/// R_w_b with R_w_b * up_b = e_z and the body x axis in the world x-z plane.
Mat3d gravity_aligned(const Vec3d& up_b) {
  const Vec3d z = up_b.normalized();
  Vec3d x = Vec3d::UnitX() - z * z.x();
  if (x.norm() < 1e-6) x = Vec3d::UnitY() - z * z.y();
  x.normalize();
  const Vec3d y = z.cross(x);
  Mat3d R;
  R.row(0) = x.transpose();
  R.row(1) = y.transpose();
  R.row(2) = z.transpose();
  return R;
}

double accel_std(const std::vector<io::ImuSample>& s) {
  Vec3d mean = Vec3d::Zero();
  for (const auto& x : s) mean += x.accel_mps2;
  mean /= static_cast<double>(s.size());
  double var = 0.0;
  for (const auto& x : s) var += (x.accel_mps2 - mean).squaredNorm();
  return std::sqrt(var / static_cast<double>(s.size()));
}

}  // namespace

StatusOr<InitializationResult> static_initialize(const std::vector<io::ImuSample>& samples, TimestampNs t_ns,
                                                 double g, const InitializerOptions& o) {
  if (samples.size() < 10) {
    return absl::InvalidArgumentError(fmt::format("static init: {} IMU samples, need 10", samples.size()));
  }
  Vec3d a = Vec3d::Zero(), w = Vec3d::Zero();
  for (const auto& s : samples) a += s.accel_mps2, w += s.gyro_radps;
  a /= static_cast<double>(samples.size());
  w /= static_cast<double>(samples.size());
  InitializationResult r;
  r.method = "static";
  r.imu.t_ns = t_ns;
  const Mat3d R_w_b = gravity_aligned(a);
  r.imu.q_w_b = Quatd(R_w_b).normalized();
  r.imu.bg = w;
  r.imu.ba = a - R_w_b.transpose() * Vec3d(0.0, 0.0, g);  // only the part along gravity
  r.P.setZero();
  r.P.diagonal() << Vec3d::Constant(o.sigma_orientation * o.sigma_orientation),
      Vec3d::Constant(o.sigma_position * o.sigma_position),
      Vec3d::Constant(o.sigma_velocity * o.sigma_velocity),
      Vec3d::Constant(o.sigma_gyro_bias * o.sigma_gyro_bias),
      Vec3d::Constant(o.sigma_accel_bias * o.sigma_accel_bias);
  r.detail = fmt::format("{} samples, |a| {:.4f} m/s^2, bg [{:.5f} {:.5f} {:.5f}] rad/s", samples.size(),
                         a.norm(), w.x(), w.y(), w.z());
  return r;
}

Initializer::Initializer(const InitializerOptions& options, const config::StereoRigCalibration& rig,
                         const ImuNoise& noise, double g, const TriangulationOptions& triangulation)
    : options_(options), rig_(rig), noise_(noise), g_(g), triangulation_(triangulation) {}

void Initializer::feed_imu(const io::ImuSample& s) {
  imu_.push_back(s);
  // Keep the window plus a margin for interpolation at its start.
  const DurationNs keep = from_seconds(options_.window_s + 0.5);
  while (!imu_.empty() && imu_.back().t_ns - imu_.front().t_ns > keep) imu_.pop_front();
}

void Initializer::feed_frame(const FeatureFrame& frame) {
  frames_.push_back(frame);
  const DurationNs keep = from_seconds(options_.window_s);
  while (!frames_.empty() && frames_.back().t_ns - frames_.front().t_ns > keep) frames_.pop_front();
}

double Initializer::mean_disparity(double since_s) const {
  // Mean pixel motion of the features seen both in the first frame of the span and now.
  if (frames_.size() < 2) return 0.0;
  const TimestampNs from = frames_.back().t_ns - from_seconds(since_s);
  const FeatureFrame* first = &frames_.front();
  for (const FeatureFrame& f : frames_) {
    if (f.t_ns >= from) {
      first = &f;
      break;
    }
  }
  std::unordered_map<FeatureId, Vec2d> start;
  for (const auto& o : first->features) start[o.id] = o.uv_left;
  double sum = 0.0;
  int n = 0;
  for (const auto& o : frames_.back().features) {
    const auto it = start.find(o.id);
    if (it != start.end()) sum += (o.uv_left - it->second).norm(), ++n;
  }
  return n > 0 ? sum / n : 0.0;
}

std::vector<io::ImuSample> Initializer::imu_between(TimestampNs from_ns, TimestampNs to_ns) const {
  std::vector<io::ImuSample> out;
  for (const auto& s : imu_) {
    if (s.t_ns >= from_ns && s.t_ns <= to_ns) out.push_back(s);
  }
  return out;
}

std::optional<InitializationResult> Initializer::try_initialize(std::string* why) {
  if (frames_.empty()) {
    *why = "waiting for images";
    return std::nullopt;
  }
  const TimestampNs t_imu = frames_.back().t_ns + rig_.cameras[0].time_offset_ns;
  if (imu_.empty() || imu_.back().t_ns < t_imu) {
    *why = "waiting for IMU data up to the newest image";
    return std::nullopt;
  }
  const double have_s = to_seconds(t_imu - std::max(imu_.front().t_ns, frames_.front().t_ns));
  const std::vector<io::ImuSample> still = imu_between(t_imu - from_seconds(options_.static_window_s), t_imu);
  const double spread = still.size() >= 10 ? accel_std(still) : 1e9;
  const double disparity = mean_disparity(options_.static_window_s);
  if (have_s >= options_.static_window_s && spread <= options_.max_accel_std &&
      disparity <= options_.max_static_disparity_px) {
    auto r = static_initialize(still, t_imu, g_, options_);
    if (r.ok()) return std::move(*r);
  }
  const double window_disparity = mean_disparity(options_.window_s);
  if (!options_.dynamic || window_disparity < options_.min_dynamic_disparity_px) {
    *why = fmt::format(
        "waiting: {:.2f} s of data, accel spread {:.3f} m/s^2 (still below {:.3f}), disparity {:.1f} px over "
        "{:.1f} s "
        "(still below {:.1f}, moving above {:.1f}{})",
        have_s, spread, options_.max_accel_std, disparity, options_.static_window_s,
        options_.max_static_disparity_px, options_.min_dynamic_disparity_px,
        options_.dynamic ? "" : ", dynamic initialisation off");
    return std::nullopt;
  }
  const std::vector<FeatureFrame> frames(frames_.begin(), frames_.end());
  const std::vector<io::ImuSample> imu(imu_.begin(), imu_.end());
  auto r = dynamic_initialize(frames, imu, rig_, noise_, g_, options_.dynamic_options, triangulation_);
  if (!r.ok()) {
    *why = fmt::format("moving ({:.1f} px over {:.1f} s); dynamic initialisation: {}", window_disparity,
                       options_.window_s, std::string(r.status().message()));
    return std::nullopt;
  }
  return std::move(*r);
}

}  // namespace mrvs::edge
