#pragma once
// Image formation from radiance to 8-bit DN (simulator.md section 4.3):
//
//   DN = clip(round(g_k * c_cam * (a + eps_vig(r)) * 255 + n), 0, 255)
//
// a: radiance in [0, 1] (albedo times light; the sky radiance for rays that hit nothing),
// g_k: frame gain (exposure walk times the auto-exposure's exposure / exposure_ms times its
// analog gain A_k, shared by both cameras), c_cam: per-camera gain,
// eps_vig(r) = vignetting * (r / r_max)^2 with r the distance (pixels) from the principal
// point and r_max its largest value over the image corners,
// n ~ N(0, A_k^2 sigma_r^2 + A_k S / K): Gaussian read noise plus shot noise of the clean
// signal S = g_k c_cam (a + eps) 255 (DN), both amplified by the analog gain A_k (1 without
// auto-exposure), one draw per (camera, frame, pixel) from CounterRng(seed, Stream::kImageNoise).
#include <cstdint>
#include <vector>

#include "mrvs/core/status.h"

#include "mrvs/camera/camera_model.h"
#include "mrvs/sim/render_options.h"
#include "mrvs/sim/rng.h"

namespace mrvs::sim {

/// Frame gains g_k for frames 0 .. num_frames - 1 of the exposure walk: g_0 = 1 and
/// log g_{k+1} = clamp(log g_k + sigma * n_k, log(1 - limit), log(1 + limit)) with
/// n_k = CounterRng(seed, Stream::kExposure).normal(k). Empty for num_frames <= 0.
std::vector<double> exposure_gains(std::uint64_t seed, std::int64_t num_frames, double sigma = 0.02,
                                   double limit = 0.3);

/// The same with options.exposure_sigma and options.exposure_limit; all 1 when
/// options.exposure_walk is false.
std::vector<double> exposure_gains(std::uint64_t seed, std::int64_t num_frames, const RenderOptions& options);

/// Per-camera gain c_cam: 1 for cam0, 1 + options.stereo_gain_mismatch for cam1.
double camera_gain(int cam, const RenderOptions& options);

/// One frame's exposure: how long the global shutter is open and the analog gain after it.
struct ExposureSetting {
  double exposure_ms = 5.0;
  double analog_gain = 1.0;
};

/// Auto-exposure of a global-shutter camera (render.auto_exposure). Its state is the
/// brightness b = exposure * analog gain, ms, kept in [min_exposure, max_exposure *
/// max_analog_gain] where max_exposure = min(ae_max_exposure_ms, frame interval). The
/// exposure is min(b, max_exposure); the analog gain makes up the rest. After each image
/// with mean DN m, e = log2(ae_target_dn / m): nothing while |e| <= ae_deadband_ev,
/// otherwise log2 b moves by ae_damping * e rounded to whole steps of ae_step_ev (at least
/// one step towards the target; any amount when the step is 0), then clamped.
class AutoExposure {
 public:
  /// InvalidArgument when ae_min_exposure_ms > the longest exposure or the interval is not > 0.
  static StatusOr<AutoExposure> create(const RenderOptions& options, double frame_interval_ms);

  /// The setting of the next image.
  ExposureSetting setting() const;
  /// DN scale of the next image relative to options.exposure_ms at gain 1: b / exposure_ms.
  double relative_gain() const { return brightness_ms_ / reference_ms_; }
  double brightness_ms() const { return brightness_ms_; }
  double max_exposure_ms() const { return max_exposure_ms_; }
  /// One control step after an image of mean DN `mean_dn` (clamped to [0.5, 255]).
  void observe(double mean_dn);
  /// Starts converged: runs up to 64 control steps on the mean DN the scene would give,
  /// mean_dn_at_reference * relative_gain() clipped to 255, `mean_dn_at_reference` being
  /// its mean at options.exposure_ms and gain 1.
  void settle(double mean_dn_at_reference);

 private:
  AutoExposure() = default;
  double target_dn_ = 110.0, deadband_ev_ = 0.1, damping_ = 0.5, step_ev_ = 0.125;
  double min_ms_ = 0.05, max_exposure_ms_ = 20.0, max_gain_ = 4.0, reference_ms_ = 5.0;
  double brightness_ms_ = 5.0;
};

/// The DN mapping of one camera in one frame (cheap to construct; thread-safe).
class PixelPhotometry {
 public:
  /// `frame_gain` = g_k, `analog_gain` = A_k; `frame` indexes the noise (with `cam` and the pixel).
  PixelPhotometry(const RenderOptions& options, const camera::CameraModel& camera, int cam,
                  std::int64_t frame, double frame_gain, std::uint64_t noise_seed, double analog_gain = 1.0);

  /// Noise-free signal g_k c_cam (a + eps_vig) 255 at pixel (u, v), DN (not rounded or clipped).
  double clean_value(double radiance, int u, int v) const;
  /// Standard deviation of the pixel noise for a clean signal (DN): sqrt(A^2 sigma_r^2 + A max(S, 0) / K).
  double noise_sigma(double clean) const;
  /// The noise draw n of pixel (u, v) for clean signal `clean`, DN (0 when noise is off).
  /// Pixels 2j and 2j+1 of a row share one Box-Muller draw (its two independent outputs).
  double noise(double clean, int u, int v) const;
  /// Final 8-bit value of pixel (u, v) for `radiance`.
  std::uint8_t dn(double radiance, int u, int v) const;
  /// Row v: out[u] = dn(radiance[u] * scale, u, v) for u in [0, width), one draw per pixel pair.
  void dn_row(const float* radiance, float scale, int v, int width, std::uint8_t* out) const;
  /// True when read or shot noise is on.
  bool has_noise() const { return has_noise_; }

 private:
  double gain_;        ///< g_k * c_cam
  double vignetting_;  ///< eps at r = r_max
  double inv_r2_max_;  ///< 1 / r_max^2, 1/px^2
  double cx_, cy_;     ///< principal point, px
  double read_var_;    ///< A^2 sigma_r^2, DN^2
  double inv_shot_k_;  ///< A / K (0 without shot noise)
  bool has_noise_;
  CounterRng rng_;
  std::uint64_t cam_;
  std::uint64_t frame_;
  std::uint64_t pairs_per_row_;  ///< ceil(width / 2)
};

}  // namespace mrvs::sim
