#include "mrvs/sim/photometry.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <fmt/format.h>

namespace mrvs::sim {

std::vector<double> exposure_gains(std::uint64_t seed, std::int64_t num_frames, double sigma, double limit) {
  std::vector<double> gains;
  if (num_frames <= 0) return gains;
  gains.reserve(static_cast<std::size_t>(num_frames));
  const CounterRng rng(seed, Stream::kExposure);
  const double lo = std::log(1.0 - limit);
  const double hi = std::log(1.0 + limit);
  double log_gain = 0.0;
  for (std::int64_t k = 0; k < num_frames; ++k) {
    if (k > 0) log_gain = std::clamp(log_gain + sigma * rng.normal(static_cast<std::uint64_t>(k)), lo, hi);
    gains.push_back(std::exp(log_gain));
  }
  return gains;
}

std::vector<double> exposure_gains(std::uint64_t seed, std::int64_t num_frames,
                                   const RenderOptions& options) {
  if (!options.exposure_walk)
    return std::vector<double>(static_cast<std::size_t>(std::max<std::int64_t>(num_frames, 0)), 1.0);
  return exposure_gains(seed, num_frames, options.exposure_sigma, options.exposure_limit);
}

double camera_gain(int cam, const RenderOptions& options) {
  return cam == 1 ? 1.0 + options.stereo_gain_mismatch : 1.0;
}

StatusOr<AutoExposure> AutoExposure::create(const RenderOptions& options, double frame_interval_ms) {
  if (!(frame_interval_ms > 0.0)) {
    return absl::InvalidArgumentError(
        fmt::format("auto-exposure: the frame interval {} ms is not > 0", frame_interval_ms));
  }
  AutoExposure ae;
  ae.target_dn_ = options.ae_target_dn;
  ae.deadband_ev_ = options.ae_deadband_ev;
  ae.damping_ = options.ae_damping;
  ae.step_ev_ = options.ae_step_ev;
  ae.min_ms_ = options.ae_min_exposure_ms;
  ae.max_exposure_ms_ = std::min(options.ae_max_exposure_ms, frame_interval_ms);
  ae.max_gain_ = options.ae_max_analog_gain;
  ae.reference_ms_ = options.exposure_ms;
  if (ae.min_ms_ > ae.max_exposure_ms_) {
    return absl::InvalidArgumentError(
        fmt::format("render.ae_min_exposure_ms {} is longer than the longest exposure {} ms "
                    "(render.ae_max_exposure_ms or "
                    "the frame interval); lower it",
                    ae.min_ms_, ae.max_exposure_ms_));
  }
  ae.brightness_ms_ = std::clamp(options.exposure_ms, ae.min_ms_, ae.max_exposure_ms_ * ae.max_gain_);
  return ae;
}

ExposureSetting AutoExposure::setting() const {
  const double exposure = std::min(brightness_ms_, max_exposure_ms_);
  return {exposure, brightness_ms_ / exposure};
}

void AutoExposure::observe(double mean_dn) {
  const double error_ev = std::log2(target_dn_ / std::clamp(mean_dn, 0.5, 255.0));
  if (std::abs(error_ev) <= deadband_ev_) return;
  double move_ev = damping_ * error_ev;
  if (step_ev_ > 0.0) {
    const double steps = std::max(1.0, std::round(std::abs(move_ev) / step_ev_));
    move_ev = std::copysign(steps * step_ev_, error_ev);
  }
  brightness_ms_ = std::clamp(brightness_ms_ * std::exp2(move_ev), min_ms_, max_exposure_ms_ * max_gain_);
}

void AutoExposure::settle(double mean_dn_at_reference) {
  for (int i = 0; i < 64; ++i) {
    const double before = brightness_ms_;
    observe(std::min(255.0, mean_dn_at_reference * relative_gain()));
    if (brightness_ms_ == before) return;
  }
}

PixelPhotometry::PixelPhotometry(const RenderOptions& options, const camera::CameraModel& camera, int cam,
                                 std::int64_t frame, double frame_gain, std::uint64_t noise_seed,
                                 double analog_gain)
    : gain_(frame_gain * camera_gain(cam, options)),
      vignetting_(options.vignetting),
      inv_r2_max_(0.0),
      cx_(camera.cx()),
      cy_(camera.cy()),
      read_var_(analog_gain * analog_gain * options.read_noise_sigma * options.read_noise_sigma),
      inv_shot_k_(options.shot_noise ? analog_gain / options.shot_noise_k : 0.0),
      has_noise_(options.read_noise_sigma > 0.0 || options.shot_noise),
      rng_(noise_seed, Stream::kImageNoise),
      cam_(static_cast<std::uint64_t>(cam)),
      frame_(static_cast<std::uint64_t>(frame)),
      pairs_per_row_(static_cast<std::uint64_t>(camera.width() + 1) / 2) {
  // r_max: the farthest pixel-centre corner from the principal point.
  double r2_max = 0.0;
  for (const double u : {0.0, camera.width() - 1.0}) {
    for (const double v : {0.0, camera.height() - 1.0}) {
      r2_max = std::max(r2_max, (u - cx_) * (u - cx_) + (v - cy_) * (v - cy_));
    }
  }
  inv_r2_max_ = r2_max > 0.0 ? 1.0 / r2_max : 0.0;
}

double PixelPhotometry::clean_value(double radiance, int u, int v) const {
  double a = radiance;
  if (vignetting_ != 0.0) {
    const double du = u - cx_, dv = v - cy_;
    a += vignetting_ * (du * du + dv * dv) * inv_r2_max_;
  }
  return gain_ * a * 255.0;
}

double PixelPhotometry::noise_sigma(double clean) const {
  return std::sqrt(read_var_ + std::max(clean, 0.0) * inv_shot_k_);
}

double PixelPhotometry::noise(double clean, int u, int v) const {
  if (!has_noise_) return 0.0;
  const std::uint64_t pair =
      static_cast<std::uint64_t>(v) * pairs_per_row_ + static_cast<std::uint64_t>(u / 2);
  const std::pair<double, double> n = rng_.normal_pair(cam_, frame_, pair);
  return noise_sigma(clean) * (u % 2 == 0 ? n.first : n.second);
}

namespace {

/// A signal in DN rounded and clipped to 8 bits.
std::uint8_t to_dn(double value) {
  return static_cast<std::uint8_t>(std::clamp(std::round(value), 0.0, 255.0));
}

}  // namespace

std::uint8_t PixelPhotometry::dn(double radiance, int u, int v) const {
  const double clean = clean_value(radiance, u, v);
  return to_dn(clean + noise(clean, u, v));
}

void PixelPhotometry::dn_row(const float* radiance, float scale, int v, int width, std::uint8_t* out) const {
  for (int u = 0; u < width; u += 2) {
    const double c0 = clean_value(radiance[u] * scale, u, v);
    if (!has_noise_) {
      out[u] = to_dn(c0);
      if (u + 1 < width) out[u + 1] = to_dn(clean_value(radiance[u + 1] * scale, u + 1, v));
      continue;
    }
    const std::uint64_t pair =
        static_cast<std::uint64_t>(v) * pairs_per_row_ + static_cast<std::uint64_t>(u / 2);
    const std::pair<double, double> n = rng_.normal_pair(cam_, frame_, pair);
    out[u] = to_dn(c0 + noise_sigma(c0) * n.first);
    if (u + 1 < width) {
      const double c1 = clean_value(radiance[u + 1] * scale, u + 1, v);
      out[u + 1] = to_dn(c1 + noise_sigma(c1) * n.second);
    }
  }
}

}  // namespace mrvs::sim
