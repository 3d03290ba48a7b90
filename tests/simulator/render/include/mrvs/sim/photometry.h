#pragma once
// Image formation from radiance to 8-bit DN (simulator.md section 4.3):
//
//   DN = clip(round(g_k * c_cam * (a + eps_vig(r)) * 255 + n), 0, 255)
//
// a: radiance in [0, 1] (the albedo; the sky radiance for rays that hit nothing),
// g_k: frame gain (exposure walk, shared by both cameras), c_cam: per-camera gain,
// eps_vig(r) = vignetting * (r / r_max)^2 with r the distance (pixels) from the principal
// point and r_max its largest value over the image corners,
// n ~ N(0, sigma_r^2 + S / K): Gaussian read noise plus shot noise of the clean signal
// S = g_k c_cam (a + eps) 255 (DN), one draw per (camera, frame, pixel) from
// CounterRng(seed, Stream::kImageNoise).
#include <cstdint>
#include <vector>

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

/// The DN mapping of one camera in one frame (cheap to construct; thread-safe).
class PixelPhotometry {
 public:
  /// `frame_gain` = g_k; `frame` indexes the noise (with `cam` and the pixel).
  PixelPhotometry(const RenderOptions& options, const camera::CameraModel& camera, int cam,
                  std::int64_t frame, double frame_gain, std::uint64_t noise_seed);

  /// Noise-free signal g_k c_cam (a + eps_vig) 255 at pixel (u, v), DN (not rounded or clipped).
  double clean_value(double radiance, int u, int v) const;
  /// Standard deviation of the pixel noise for a clean signal (DN): sqrt(sigma_r^2 + max(S, 0) / K).
  double noise_sigma(double clean) const;
  /// The noise draw n of pixel (u, v) for clean signal `clean`, DN (0 when noise is off).
  double noise(double clean, int u, int v) const;
  /// Final 8-bit value of pixel (u, v) for `radiance`.
  std::uint8_t dn(double radiance, int u, int v) const;
  /// True when read or shot noise is on.
  bool has_noise() const { return has_noise_; }

 private:
  double gain_;        ///< g_k * c_cam
  double vignetting_;  ///< eps at r = r_max
  double inv_r2_max_;  ///< 1 / r_max^2, 1/px^2
  double cx_, cy_;     ///< principal point, px
  double read_var_;    ///< sigma_r^2, DN^2
  double inv_shot_k_;  ///< 1 / K (0 without shot noise)
  bool has_noise_;
  CounterRng rng_;
  std::uint64_t cam_;
  std::uint64_t frame_;
  std::uint64_t width_;
};

}  // namespace mrvs::sim
