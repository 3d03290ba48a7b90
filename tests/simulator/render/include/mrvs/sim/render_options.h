#pragma once
// Tuning of the stereo image renderer (simulator.md section 4.3 and the photometric knobs
// of section 7). Defaults: adaptive anti-aliasing, no noise, no vignetting, equal camera
// gains, fixed exposure, no motion blur.
#include "mrvs/config/options.h"

namespace mrvs::sim {

/// Anti-aliasing scheme.
enum class AntiAliasing {
  kAdaptive,  ///< 1 ray per pixel with trilinear mip filtering, then 2x2 level-0 subsamples
              ///< on pixels next to a face change (4-neighbourhood)
  kFull,      ///< 2x2 level-0 subsamples on every pixel (4x the cost)
  kNone,      ///< 1 ray per pixel, level-0 texture (point sampling: aliases)
};

struct RenderOptions : config::OptionsEquality<RenderOptions> {
  AntiAliasing aa = AntiAliasing::kAdaptive;  ///< anti-aliasing scheme
  double max_distance_m = 300.0;              ///< rays hitting nothing closer see the sky, m
  double min_cos_incidence = 0.2;             ///< floor of |n . d| in the mip footprint
  double stereo_gain_mismatch = 0.0;          ///< cam1 gain = 1 + this (cam0 gain is 1)
  double vignetting = 0.0;                    ///< eps_vig at the farthest image corner (e.g. -0.3)
  double read_noise_sigma = 0.0;              ///< Gaussian read noise, DN
  bool shot_noise = false;                    ///< add shot noise of variance DN / K
  double shot_noise_k = 4.0;                  ///< K, DN per photo-electron
  bool exposure_walk = false;                 ///< per-frame log-gain random walk (exposure_gains)
  double exposure_sigma = 0.02;               ///< log-gain step per frame
  double exposure_limit = 0.3;                ///< gain stays within 1 -+ this
  bool motion_blur = false;   ///< integrate each image over its exposure along the true motion
  double exposure_ms = 5.0;   ///< exposure (global shutter), centred on the frame's time, ms
  double blur_step_px = 1.0;  ///< the exposure's sub-samples move the image at most this far apart, px
  int blur_max_samples = 32;  ///< at most this many sub-samples per image

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("aa", aa,
      enum_names<AntiAliasing>({{"adaptive", AntiAliasing::kAdaptive},
                                {"full", AntiAliasing::kFull},
                                {"none", AntiAliasing::kNone}}),
      "anti-aliasing: adaptive | full | none");
    v("max_distance_m", max_distance_m, in_range(0.01, 1.0e5), "sky beyond this ray length, m");
    v("min_cos_incidence", min_cos_incidence, in_range(0.01, 1.0), "floor of |n.d| in the mip footprint");
    v("stereo_gain_mismatch", stereo_gain_mismatch, in_range(-0.5, 0.5), "cam1 gain = 1 + this");
    v("vignetting", vignetting, in_range(-1.0, 1.0), "albedo offset at the farthest corner, * (r/r_max)^2");
    v("read_noise_sigma", read_noise_sigma, in_range(0.0, 64.0), "Gaussian read noise, DN");
    v("shot_noise", shot_noise, any(), "shot noise of variance DN / K");
    v("shot_noise_k", shot_noise_k, in_range(0.01, 1000.0), "K, DN per photo-electron");
    v("exposure_walk", exposure_walk, any(), "per-frame log-gain random walk shared by both cameras");
    v("exposure_sigma", exposure_sigma, in_range(0.0, 1.0), "log-gain step per frame");
    v("exposure_limit", exposure_limit, in_range(0.0, 0.9), "gain stays within 1 -+ this");
    v("motion_blur", motion_blur, any(), "integrate each image over its exposure along the true motion");
    v("exposure_ms", exposure_ms, in_range(0.01, 50.0), "exposure, centred on the frame's time, ms");
    v("blur_step_px", blur_step_px, in_range(0.05, 10.0), "image motion between two sub-samples at most, px");
    v("blur_max_samples", blur_max_samples, in_range(1, 256), "sub-samples per image at most");
  }
};

}  // namespace mrvs::sim
